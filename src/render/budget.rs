//! The budget of one run (samples per pixel or wall-clock seconds), its limits and
//! checks, and what a run produced. A leaf of `render`: both the plain run (`run.rs`)
//! and the guided run (`guided.rs`) use it.

use super::{Film, RenderError, RenderStats, Result};
use std::time::{Duration, Instant};

/// How much to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Samples per pixel (training included, for guided methods).
    Spp(u64),
    /// Wall-clock seconds (training included); every pixel gets the same spp.
    Seconds(f64),
}

impl Budget {
    /// The budget of a request for `spp` samples per pixel or `seconds` of rendering (the
    /// command line's `--spp` and `--time`; 16 spp when neither is given), checked.
    pub fn from_request(spp: Option<u64>, seconds: Option<f64>) -> Result<Budget> {
        let invalid = |m: &str| Err(RenderError::Invalid(m.into()));
        let budget = match (spp, seconds) {
            (Some(_), Some(_)) => return invalid("give --spp or --time, not both"),
            (Some(n), None) => Budget::Spp(n),
            (None, Some(t)) => Budget::Seconds(t),
            (None, None) => Budget::Spp(16),
        };
        // The command line's checks and messages (from sample index 0).
        budget.check(0)?;
        Ok(budget)
    }
}

/// The longest time budget: about 31 years (a larger one is a typo, not a plan, and
/// would overflow `Instant` arithmetic on some platforms).
pub const MAX_SECONDS: f64 = 1e9;

/// One past the last sample index the kernel can render (indices are 32-bit).
pub const SAMPLE_INDEX_END: u64 = u32::MAX as u64;

impl Budget {
    /// Refuses a budget the renderer cannot honour starting at sample index `first`:
    /// zero spp, a time that is not a positive finite number of seconds up to
    /// [`MAX_SECONDS`], or sample indices past 2^32 (they would wrap around).
    pub fn check(&self, first: u64) -> Result<()> {
        let bad = |m: String| Err(RenderError::Invalid(m));
        match *self {
            Budget::Spp(0) => bad("--spp must be at least 1".into()),
            Budget::Spp(n) if first.checked_add(n).is_none_or(|end| end > SAMPLE_INDEX_END) => {
                bad(format!(
                    "--sample-offset {first} + --spp {n} is past {SAMPLE_INDEX_END}: sample indices are 32-bit"
                ))
            }
            Budget::Seconds(s) if !(s > 0.0 && s <= MAX_SECONDS) => bad(format!(
                "--time {s}: must be a positive number of seconds, at most {MAX_SECONDS:e}"
            )),
            _ if first >= SAMPLE_INDEX_END => bad(format!(
                "--sample-offset {first}: sample indices are 32-bit (below {SAMPLE_INDEX_END})"
            )),
            _ => Ok(()),
        }
    }
}

/// `seconds` after `start`; `None` (no deadline) when that is beyond what `Instant`
/// represents.
pub fn deadline_after(start: Instant, seconds: f64) -> Option<Instant> {
    Duration::try_from_secs_f64(seconds)
        .ok()
        .and_then(|d| start.checked_add(d))
}

/// What a run produced.
pub struct RunOutcome {
    /// The final image's samples (the render phase only, for guided methods).
    pub film: Film,
    pub stats: RenderStats,
    /// Wall seconds of the whole run (training included).
    pub seconds: f64,
    /// Wall seconds spent training (guided methods).
    pub training_seconds: f64,
    /// Training iterations and the tree (guided methods).
    pub guiding: Option<super::GuidingOutcome>,
    /// The image to output instead of the film's mean, when it is not the film alone
    /// (guided methods with `GuidedOutput::InverseVariance`): mean RGB per pixel.
    pub combined: Option<Vec<f32>>,
}

impl RunOutcome {
    /// Mean RGB per pixel of what the run outputs.
    pub fn image(&self) -> Vec<f32> {
        self.combined.clone().unwrap_or_else(|| self.film.mean())
    }
}
