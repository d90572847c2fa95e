//! Guided methods: train the SD-tree over iterations of doubling sample counts (1, 2, 4,
//! … spp), refitting it on the CPU between passes, then render the rest of the budget
//! with the tree frozen. Training and the final render use disjoint sample indices, so
//! the final image's samples are independent of the data the tree learned from.
//!
//! The final image is the render phase alone. (Müller et al. also offer combining the
//! last training iterations weighted by inverse variance; here the training passes
//! record into the tree with the previous iteration's distribution, and their images are
//! discarded.)

use super::run::{Budget, RunOutcome};
use super::{GuideBuffers, RenderError, RenderStats, Renderer, Result};
use crate::guiding::{
    DirectionalFilter, GuidingConfig, SdTree, SpatialFilter, SppSchedule, TimeSchedule,
};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What one training iteration cost and produced.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct IterationStats {
    pub iteration: usize,
    pub spp: u64,
    /// Wall seconds of the training pass's dispatches.
    pub render_seconds: f64,
    pub gpu_seconds: f64,
    /// Reading the training quadtrees back.
    pub readback_seconds: f64,
    /// The CPU refit.
    pub refit_seconds: f64,
    /// Flattening and uploading the refitted tree.
    pub upload_seconds: f64,
    pub leaves: usize,
    pub sampling_nodes: usize,
    pub training_nodes: usize,
    pub gpu_bytes: u64,
    pub split_threshold: f32,
    pub splits: u32,
    pub refused_splits: u32,
}

/// The guiding side of a run.
pub struct GuidingOutcome {
    pub iterations: Vec<IterationStats>,
    /// The trained (or loaded) tree, as the final render used it.
    pub tree: SdTree,
}

/// Pixels of the 1280×720 images Müller et al. tuned the spatial threshold c for.
const REFERENCE_PIXELS: f64 = 1280.0 * 720.0;

/// The SD-tree configuration a render's settings ask for.
///
/// The spatial split threshold c·√(spp/4) counts records in a leaf, and records per
/// iteration grow with the pixel count as well as with spp. Müller et al.'s c = 12000
/// was set for 1280×720 images; scaling it by √(pixels / 921 600) keeps the tree's
/// refinement the same function of the total number of samples at any resolution
/// (at 64×48 the unscaled threshold leaves the scene in a handful of leaves and guiding
/// gains nothing; scaled, guiding halves the error of `pt` on the gap scene).
pub fn guiding_config(renderer: &Renderer) -> GuidingConfig {
    let s = &renderer.settings;
    let pixels = s.width as f64 * s.height as f64;
    GuidingConfig {
        spatial_threshold: (s.guiding.spatial_threshold as f64 * (pixels / REFERENCE_PIXELS).sqrt())
            .max(1.0) as f32,
        memory_cap_bytes: s.guiding.memory_cap_bytes,
        spatial_filter: if s.spatial_jitter {
            SpatialFilter::StochasticBox
        } else {
            SpatialFilter::Nearest
        },
        directional_filter: if s.directional_box {
            DirectionalFilter::Box
        } else {
            DirectionalFilter::Nearest
        },
        record_nee: s.record_nee,
        bsdf_fraction: s.bsdf_fraction,
        ..GuidingConfig::default()
    }
}

fn guiding_error(e: crate::guiding::GuidingError) -> RenderError {
    RenderError::Invalid(e.to_string())
}

pub fn run_guided(
    renderer: &mut Renderer,
    budget: Budget,
    first: u64,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(u64),
) -> Result<RunOutcome> {
    let started = Instant::now();
    let config = guiding_config(renderer);
    config.validate().map_err(guiding_error)?;
    let mut stats = RenderStats::default();
    let mut iterations = Vec::new();
    let mut sample = first;

    let tree = match renderer.preloaded_tree.take() {
        Some(mut t) => {
            // A loaded tree renders with this run's sampling options.
            t.set_config(&config).map_err(guiding_error)?;
            t
        }
        None => {
            let (lo, hi) = renderer.bounds;
            let mut tree = SdTree::new(lo, hi, &config).map_err(guiding_error)?;
            let train_fraction = renderer.settings.train_fraction as f64;
            match budget {
                Budget::Spp(n) => {
                    let schedule = SppSchedule::new(n.min(u32::MAX as u64) as u32, train_fraction);
                    for (k, &spp) in schedule.training.iter().enumerate() {
                        if cancel.load(Ordering::SeqCst) {
                            break;
                        }
                        let it = train_iteration(
                            renderer,
                            &mut tree,
                            k,
                            spp as u64,
                            schedule.spp_after(k),
                            sample,
                            cancel,
                            &mut stats,
                        )?;
                        sample += it.spp;
                        progress(sample - first);
                        iterations.push(it);
                    }
                }
                Budget::Seconds(total) => {
                    let mut schedule = TimeSchedule::new(total, train_fraction);
                    let mut next = schedule.first();
                    let mut k = 0;
                    while let Some(spp) = next {
                        if cancel.load(Ordering::SeqCst) {
                            break;
                        }
                        let t = Instant::now();
                        // The refit prepares the tree for twice the samples, as the
                        // schedule predicts; the final pass may render fewer.
                        let it = train_iteration(
                            renderer,
                            &mut tree,
                            k,
                            spp as u64,
                            spp * 2,
                            sample,
                            cancel,
                            &mut stats,
                        )?;
                        sample += it.spp;
                        progress(sample - first);
                        iterations.push(it);
                        next = schedule.next(t.elapsed().as_secs_f64());
                        k += 1;
                    }
                }
            }
            tree
        }
    };
    let training_seconds = started.elapsed().as_secs_f64();
    let upload = Instant::now();
    renderer.set_guide_buffers(GuideBuffers::upload(&renderer.device, &tree.gpu_arrays())?);
    log::debug!(
        "final SD-tree uploaded in {:.3} s",
        upload.elapsed().as_secs_f64()
    );

    // The render phase: the rest of the budget with the tree frozen.
    renderer.clear_film()?;
    let trained = sample - first;
    let mut render_progress = |done: u64| progress(trained + done);
    match budget {
        Budget::Spp(n) => {
            let left = n.saturating_sub(trained).max(1);
            renderer.render_samples(
                sample,
                left,
                false,
                cancel,
                &mut render_progress,
                &mut stats,
            )?;
        }
        Budget::Seconds(total) => {
            let deadline = started + Duration::from_secs_f64(total);
            renderer.render_until(
                sample,
                None,
                Some(deadline),
                false,
                cancel,
                &mut render_progress,
                &mut stats,
            )?;
            if renderer.film_spp() == 0 && !cancel.load(Ordering::SeqCst) {
                // Training used the whole budget: render at least one sample.
                renderer.render_samples(
                    sample,
                    1,
                    false,
                    cancel,
                    &mut render_progress,
                    &mut stats,
                )?;
            }
        }
    }
    let film = renderer.film()?;
    let out = RunOutcome {
        film,
        stats,
        seconds: started.elapsed().as_secs_f64(),
        training_seconds,
        guiding: Some(GuidingOutcome { iterations, tree }),
    };
    Ok(out)
}

/// One training iteration: render `spp` samples from `sample` recording into the training
/// trees, read them back, refit for `next_spp`, upload.
#[allow(clippy::too_many_arguments)]
fn train_iteration(
    renderer: &mut Renderer,
    tree: &mut SdTree,
    k: usize,
    spp: u64,
    next_spp: u32,
    sample: u64,
    cancel: &AtomicBool,
    stats: &mut RenderStats,
) -> Result<IterationStats> {
    let t = Instant::now();
    renderer.set_guide_buffers(GuideBuffers::upload(&renderer.device, &tree.gpu_arrays())?);
    let mut upload_seconds = t.elapsed().as_secs_f64();

    renderer.clear_film()?;
    let gpu_before = stats.gpu_seconds;
    let t = Instant::now();
    let done = renderer.render_samples(sample, spp, true, cancel, &mut |_| {}, stats)?;
    let render_seconds = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let training = renderer.guide_buffers().read_training()?;
    let readback_seconds = t.elapsed().as_secs_f64();

    let t = Instant::now();
    tree.load_training_readback(&training)
        .map_err(guiding_error)?;
    let refit = tree.refit(next_spp);
    let refit_seconds = t.elapsed().as_secs_f64();

    let t = Instant::now();
    renderer.set_guide_buffers(GuideBuffers::upload(&renderer.device, &tree.gpu_arrays())?);
    upload_seconds += t.elapsed().as_secs_f64();
    let it = IterationStats {
        iteration: k,
        spp: done,
        render_seconds,
        gpu_seconds: stats.gpu_seconds - gpu_before,
        readback_seconds,
        refit_seconds,
        upload_seconds,
        leaves: refit.leaves,
        sampling_nodes: refit.sampling_nodes,
        training_nodes: refit.training_nodes,
        gpu_bytes: refit.gpu_bytes,
        split_threshold: refit.split_threshold,
        splits: refit.splits,
        refused_splits: refit.refused_splits,
    };
    log::debug!(
        "guiding iteration {k}: {done} spp in {:.2} s (GPU {:.2} s), read-back {:.3} s, refit {:.3} s, upload {:.3} s; {} leaves, {} + {} nodes, {:.1} KiB",
        it.render_seconds,
        it.gpu_seconds,
        it.readback_seconds,
        it.refit_seconds,
        it.upload_seconds,
        it.leaves,
        it.sampling_nodes,
        it.training_nodes,
        it.gpu_bytes as f64 / 1024.0
    );
    Ok(it)
}
