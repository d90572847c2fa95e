//! Guided methods: train the SD-tree over iterations of doubling sample counts, refitting
//! it on the CPU between passes, then render the rest of the budget with it frozen.

use super::run::{Budget, RunOutcome};
use super::{RenderError, Renderer, Result};
use std::sync::atomic::AtomicBool;

pub fn run_guided(
    _renderer: &mut Renderer,
    _budget: Budget,
    _first: u64,
    _cancel: &AtomicBool,
    _progress: &mut dyn FnMut(u64),
) -> Result<RunOutcome> {
    Err(RenderError::Invalid(
        "guided methods are being integrated".into(),
    ))
}
