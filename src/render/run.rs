//! Running one method under a budget (samples per pixel or seconds) on a prepared
//! renderer: what `render`, `compare` and `bench` share. Guided methods spend the
//! configured share of the budget training the SD-tree first (see `guided.rs`).

use super::{Film, RenderError, RenderStats, Renderer, Result};
use std::sync::atomic::AtomicBool;
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
        match (spp, seconds) {
            (Some(_), Some(_)) => invalid("give --spp or --time, not both"),
            (Some(0), None) => invalid("--spp must be at least 1"),
            (Some(n), None) => Ok(Budget::Spp(n)),
            (None, Some(t)) if !(t.is_finite() && t > 0.0) => {
                invalid("--time must be a positive number of seconds")
            }
            (None, Some(t)) => Ok(Budget::Seconds(t)),
            (None, None) => Ok(Budget::Spp(16)),
        }
    }
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

/// Render `budget` with the renderer's method, starting at sample index `first`.
pub fn run_method(
    renderer: &mut Renderer,
    budget: Budget,
    first: u64,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(u64),
) -> Result<RunOutcome> {
    if renderer.settings.method.uses_guiding() {
        return super::guided::run_guided(renderer, budget, first, cancel, progress);
    }
    let started = Instant::now();
    let mut stats = RenderStats::default();
    renderer.clear_film()?;
    match budget {
        Budget::Spp(n) => {
            renderer.render_samples(first, n, false, cancel, progress, &mut stats)?;
        }
        Budget::Seconds(s) => {
            let deadline = started + Duration::from_secs_f64(s);
            renderer.render_until(
                first,
                None,
                Some(deadline),
                false,
                cancel,
                progress,
                &mut stats,
            )?;
        }
    }
    Ok(RunOutcome {
        film: renderer.film()?,
        stats,
        seconds: started.elapsed().as_secs_f64(),
        training_seconds: 0.0,
        guiding: None,
        combined: None,
    })
}
