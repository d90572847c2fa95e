//! Running one method under a budget (samples per pixel or seconds) on a prepared
//! renderer: what `render`, `compare` and `bench` share. Guided methods spend the
//! configured share of the budget training the SD-tree first (see `guided.rs`).

pub use super::budget::{deadline_after, Budget, RunOutcome, MAX_SECONDS, SAMPLE_INDEX_END};
use super::{RenderStats, Renderer, Result};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Render `budget` with the renderer's method, starting at sample index `first`.
pub fn run_method(
    renderer: &mut Renderer,
    budget: Budget,
    first: u64,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(u64),
) -> Result<RunOutcome> {
    budget.check(first)?;
    // Learned light visibility starts from nothing in every render (and persists over a
    // guided render's passes).
    renderer.clear_light_visibility()?;
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
            // Rendering stops at the deadline, or where sample indices end.
            renderer.render_until(
                first,
                Some(SAMPLE_INDEX_END - first),
                deadline_after(started, s),
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
