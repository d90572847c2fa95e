//! Guided methods: train the SD-tree over iterations of doubling sample counts (1, 2, 4,
//! … spp), refitting it on the CPU between passes, then render the rest of the budget
//! with the tree frozen. Training and the final render use disjoint sample indices, so
//! the final image's samples are independent of the data the tree learned from.
//!
//! By default the final image is every pass's samples, weighted equally
//! (`GuidedOutput::AllPasses`; the others are in `pass_output`). `GuidedOutput::InverseVariance`
//! is Müller et al.'s alternative: every pass (the training iterations too, each rendered
//! with the previous iteration's tree) is rendered as two halves, whose difference gives
//! an unbiased estimate of that pass's mean pixel variance, and the passes' images are
//! averaged with weights proportional to 1/variance. The weights are themselves estimates,
//! so the combination is consistent rather than strictly unbiased (as in the reference
//! implementation); the render phase alone is unbiased.

use super::budget::{deadline_after, Budget, RunOutcome, SAMPLE_INDEX_END};
use super::pass_output::KeptPasses;
use super::{Film, RenderError, RenderStats, Renderer, Result};
use crate::guiding::{GuidingConfig, SdTree, SppSchedule, TimeSchedule};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

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
    /// Learned selection: records the optimisers took in, and their leaves' mean BSDF
    /// selection probability afterwards (weighted by records).
    pub selection_records: u64,
    pub mean_bsdf_fraction: f32,
    /// Learned light selection: the leaves' mean light mix for the next pass
    /// (`SdTree::mean_light_mix`).
    pub mean_light_mix: f32,
}

/// The guiding side of a run.
pub struct GuidingOutcome {
    pub iterations: Vec<IterationStats>,
    /// The trained (or loaded) tree, as the final render used it.
    pub tree: SdTree,
    /// The run was interrupted while training: there was no render phase, and the film
    /// is the training passes the output keeps, so far (the last pass alone for
    /// `RenderPhase`; each pass rendered with one fixed tree, so still a consistent
    /// image of its sample range), the tree the one trained so far.
    pub interrupted_in_training: bool,
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
    let g = &s.guiding;
    GuidingConfig {
        spatial_threshold: (g.spatial_threshold as f64 * (pixels / REFERENCE_PIXELS).sqrt())
            .max(1.0) as f32,
        memory_cap_bytes: g.memory_cap_bytes,
        spatial_filter: g.spatial_filter,
        directional_filter: g.directional_filter,
        record_nee: g.record_nee,
        bsdf_fraction: g.bsdf_fraction,
        learn_lights: g.learn_lights,
        light_mix: g.light_mix,
        learn_light_mix: g.learns_light_mix(s.method),
        learn_selection: g.learn_selection,
        selection_learner: g.selection_learner,
        target: g.target,
        density: g.density,
        history: g.history,
        ..GuidingConfig::default()
    }
}

fn guiding_error(e: crate::guiding::GuidingError) -> RenderError {
    RenderError::Invalid(e.to_string())
}

/// How much to train: a schedule of doubling iterations in samples per pixel, or a
/// share of a time budget.
#[derive(Clone, Debug)]
pub enum TrainingPlan {
    Spp(SppSchedule),
    Seconds(TimeSchedule),
}

impl TrainingPlan {
    /// The training phase of a render of `budget` that trains `train_fraction` of it.
    pub fn for_budget(budget: Budget, train_fraction: f64) -> TrainingPlan {
        match budget {
            Budget::Spp(n) => TrainingPlan::Spp(SppSchedule::new(
                n.min(u32::MAX as u64) as u32,
                train_fraction,
            )),
            Budget::Seconds(total) => {
                TrainingPlan::Seconds(TimeSchedule::new(total, train_fraction))
            }
        }
    }

    /// Training alone, with the whole of `budget` (for a tree that later renders use).
    pub fn whole(budget: Budget) -> TrainingPlan {
        match budget {
            Budget::Spp(n) => {
                TrainingPlan::Spp(SppSchedule::training_only(n.min(u32::MAX as u64) as u32))
            }
            Budget::Seconds(total) => TrainingPlan::Seconds(TimeSchedule::new(total, 1.0)),
        }
    }
}

/// A trained SD-tree and what training it took.
pub struct Training {
    pub tree: SdTree,
    pub iterations: Vec<IterationStats>,
    /// The sample index after the last training sample.
    pub next_sample: u64,
}

/// Train a new SD-tree on samples from `first` on, following `plan`. `progress` gets the
/// samples per pixel done so far; `passes` collects each pass's image and estimated
/// variance (for the inverse-variance combination).
#[allow(clippy::too_many_arguments)]
pub fn train(
    renderer: &mut Renderer,
    plan: TrainingPlan,
    first: u64,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(u64),
    stats: &mut RenderStats,
    mut kept: Option<&mut KeptPasses>,
) -> Result<Training> {
    let config = guiding_config(renderer);
    config.validate().map_err(guiding_error)?;
    let (lo, hi) = renderer.bounds;
    let mut tree = SdTree::new(lo, hi, &config).map_err(guiding_error)?;
    let mut iterations = Vec::new();
    let mut sample = first;
    // One pass: render `spp` samples while recording, then refit for `next_spp`. False
    // when it was interrupted before it rendered anything.
    let mut pass = |k: usize, spp: u64, next_spp: u32| -> Result<bool> {
        let it = train_iteration(
            renderer,
            &mut tree,
            k,
            spp,
            next_spp,
            sample,
            cancel,
            &mut |d| progress(sample - first + d),
            stats,
            kept.as_deref_mut(),
        )?;
        let Some(it) = it else { return Ok(false) };
        sample += it.spp;
        progress(sample - first);
        iterations.push(it);
        Ok(true)
    };
    match plan {
        TrainingPlan::Spp(schedule) => {
            for (k, &spp) in schedule.training.iter().enumerate() {
                if cancel.load(Ordering::SeqCst) || !pass(k, spp as u64, schedule.spp_after(k))? {
                    break;
                }
            }
        }
        TrainingPlan::Seconds(mut schedule) => {
            let mut next = schedule.first();
            let mut k = 0;
            while let Some(spp) = next {
                let t = Instant::now();
                // The refit prepares the tree for twice the samples, as a doubling
                // schedule renders next (the last pass's count is known only then).
                if cancel.load(Ordering::SeqCst) || !pass(k, spp as u64, spp.saturating_mul(2))? {
                    break;
                }
                next = schedule.next(t.elapsed().as_secs_f64(), spp);
                k += 1;
            }
        }
    }
    Ok(Training {
        tree,
        iterations,
        next_sample: sample,
    })
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
    // The training passes the output uses besides the render phase (see pass_output).
    let mut kept = KeptPasses::for_output(renderer.settings.guiding.output);
    let halves = kept.as_ref().is_some_and(|k| k.wants_halves());

    let tree = match renderer.preloaded_tree.take() {
        Some(mut t) => {
            // A loaded tree renders with this run's sampling options.
            t.set_config(&config).map_err(guiding_error)?;
            t
        }
        None => {
            let plan =
                TrainingPlan::for_budget(budget, renderer.settings.guiding.train_fraction as f64);
            let trained = train(
                renderer,
                plan,
                first,
                cancel,
                progress,
                &mut stats,
                kept.as_mut(),
            )?;
            iterations = trained.iterations;
            sample = trained.next_sample;
            trained.tree
        }
    };
    let training_seconds = started.elapsed().as_secs_f64();
    if cancel.load(Ordering::SeqCst) {
        // Keep what is consistent: the film buffer's passes (the last, or with
        // `AllPasses` every one so far) and the tree so far, rather than nothing.
        if iterations.is_empty() {
            renderer.clear_film()?;
        }
        // With `LatePasses`, the passes kept so far (the film's own, the last, among
        // them).
        let film = match kept.as_ref().and_then(|k| k.merged_so_far()) {
            Some(f) => f,
            None => renderer.film()?,
        };
        let combined = kept.as_ref().and_then(|k| k.combined_so_far());
        return Ok(RunOutcome {
            film,
            stats,
            seconds: started.elapsed().as_secs_f64(),
            training_seconds,
            guiding: Some(GuidingOutcome {
                iterations,
                tree,
                interrupted_in_training: true,
            }),
            combined,
        });
    }
    let upload = Instant::now();
    renderer.update_guide_buffers(|b, device| b.refill(device, &tree))?;
    log::debug!(
        "final SD-tree uploaded in {:.3} s",
        upload.elapsed().as_secs_f64()
    );

    // The render phase: the rest of the budget with the tree frozen, in a cleared film
    // unless the film holds the training passes the output keeps.
    if iterations.is_empty() || !kept.as_ref().is_some_and(|k| k.in_device_film()) {
        renderer.clear_film()?;
    }
    let in_film_before = renderer.film_spp();
    let trained = sample - first;
    // With the combination, the render phase is rendered as two halves too.
    let mut half: Option<Film> = None;
    match budget {
        Budget::Spp(n) => {
            let left = n.saturating_sub(trained).max(1);
            let a = if halves && left >= 2 { left / 2 } else { left };
            renderer.render_samples(
                sample,
                a,
                false,
                cancel,
                &mut |d| progress(trained + d),
                &mut stats,
            )?;
            if a < left {
                half = Some(renderer.film()?);
                renderer.render_samples(
                    sample + a,
                    left - a,
                    false,
                    cancel,
                    &mut |d| progress(trained + a + d),
                    &mut stats,
                )?;
            }
        }
        Budget::Seconds(total) => {
            let deadline = deadline_after(started, total);
            let mut a = 0;
            if halves {
                let now = Instant::now();
                let mid = deadline.map(|d| now + d.saturating_duration_since(now) / 2);
                renderer.render_until(
                    sample,
                    Some(SAMPLE_INDEX_END.saturating_sub(sample)),
                    mid,
                    false,
                    cancel,
                    &mut |d| progress(trained + d),
                    &mut stats,
                )?;
                a = renderer.film_spp();
                if a > 0 {
                    half = Some(renderer.film()?);
                }
            }
            renderer.render_until(
                sample + a,
                Some(SAMPLE_INDEX_END.saturating_sub(sample + a)),
                deadline,
                false,
                cancel,
                &mut |d| progress(trained + a + d),
                &mut stats,
            )?;
            if renderer.film_spp() == in_film_before && !cancel.load(Ordering::SeqCst) {
                // Training used the whole budget: render at least one sample.
                renderer.render_samples(
                    sample,
                    1,
                    false,
                    cancel,
                    &mut |d| progress(trained + d),
                    &mut stats,
                )?;
            }
            if half.as_ref().is_some_and(|h| h.spp == renderer.film_spp()) {
                half = None; // nothing after the midpoint: no variance estimate
            }
        }
    }
    let render_phase = renderer.film()?;
    let combined = kept
        .as_ref()
        .and_then(|k| k.combined(&render_phase, half.as_ref()));
    let film = match kept.as_ref() {
        Some(k) => k.merged_film(render_phase),
        None => render_phase,
    };
    let out = RunOutcome {
        film,
        stats,
        seconds: started.elapsed().as_secs_f64(),
        training_seconds,
        guiding: Some(GuidingOutcome {
            iterations,
            tree,
            interrupted_in_training: false,
        }),
        combined,
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
    progress: &mut dyn FnMut(u64),
    stats: &mut RenderStats,
    kept: Option<&mut KeptPasses>,
) -> Result<Option<IterationStats>> {
    let t = Instant::now();
    // Pass k > 0 renders with what the previous pass uploaded after its refit (the same
    // arrays, training sums zero); only the first uploads here.
    if k == 0 {
        renderer.update_guide_buffers(|b, device| b.refill(device, tree))?;
    }
    // As in the reference implementation, the selection probability only learns once
    // the leaves have sampling trees: against the first pass's uniform stand-in every
    // leaf would learn to prefer the BSDF.
    let learn_selection = tree.config().learn_selection && tree.iterations() > 0;
    if learn_selection {
        // Every guided vertex of every path at most; thinned uniformly beyond capacity.
        let s = &renderer.settings;
        let vertices = f64::from(s.width)
            * f64::from(s.height)
            * spp as f64
            * f64::from(s.max_depth.saturating_sub(1).max(1));
        let capacity = crate::guiding::SELECTION_RECORD_CAPACITY;
        let rate = (f64::from(capacity) / vertices).min(1.0) as f32;
        renderer
            .update_guide_buffers(|b, device| b.add_selection_records(device, capacity, rate))?;
    }
    let mut upload_seconds = t.elapsed().as_secs_f64();

    // Interrupted already: keep the film of the previous pass (clearing would lose it).
    if cancel.load(Ordering::SeqCst) {
        return Ok(None);
    }
    // Each pass renders into a cleared film, except with an output that keeps every
    // pass in the device's film (`KeptPasses::in_device_film`): after the first pass
    // it accumulates.
    let in_film = kept.as_ref().is_some_and(|k| k.in_device_film());
    if k == 0 || !in_film {
        renderer.clear_film()?;
    }
    let gpu_before = stats.gpu_seconds;
    let t = Instant::now();
    // For the inverse-variance combination, render two halves: their difference
    // estimates the variance.
    let split = if kept.as_ref().is_some_and(|k| k.wants_halves()) && spp >= 2 {
        spp / 2
    } else {
        spp
    };
    // The first sample is rendered even if an interruption arrives meanwhile, so a pass
    // that cleared the previous pass's film always leaves one of its own (ranges of
    // samples add up exactly, so the split changes nothing in the film).
    let never = AtomicBool::new(false);
    let mut done = renderer.render_samples(sample, 1, true, &never, progress, stats)?;
    if split > 1 {
        done += renderer.render_samples(
            sample + 1,
            split - 1,
            true,
            cancel,
            &mut |d| progress(1 + d),
            stats,
        )?;
    }
    let mut half = None;
    if split < spp {
        half = Some(renderer.film()?);
        done += renderer.render_samples(
            sample + split,
            spp - split,
            true,
            cancel,
            &mut |d| progress(split + d),
            stats,
        )?;
    }
    let keep = Instant::now();
    if let Some(kept) = kept.filter(|_| !in_film) {
        kept.add(renderer.film()?, half.as_ref());
    }
    let keep_seconds = keep.elapsed().as_secs_f64();
    let render_seconds = t.elapsed().as_secs_f64();

    // The read-back's records are taken in where the copy left them (the staging
    // memory): the selection learns from them (before the refit: they name the leaves
    // of the tree that rendered the pass), then the training sums and light tables.
    let t = Instant::now();
    let learn_lights = renderer.settings.guiding.learn_lights;
    let source_pmf = if learn_lights {
        renderer.source_model_pmf()
    } else {
        Vec::new()
    };
    let mut readback_seconds = 0.0;
    let mut selection_seconds = 0.0;
    let taken = renderer
        .guide_buffers()
        .read_pass(&renderer.device, learn_lights, |pass| {
            readback_seconds = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let selection = tree.learn_selection(pass.selection);
            selection_seconds = t.elapsed().as_secs_f64();
            tree.load_training_readback(pass.training)?;
            if learn_lights {
                tree.load_light_readback(pass.lights, &source_pmf)?;
            }
            Ok(selection)
        })?;
    let selection = taken.map_err(guiding_error)?;
    let load_seconds = t.elapsed().as_secs_f64() - readback_seconds - selection_seconds;

    let t = Instant::now();
    let refit = tree.refit(next_spp);
    let refit_seconds = t.elapsed().as_secs_f64() + selection_seconds + load_seconds;

    // Flattened straight into the staging memory and copied to the GPU.
    let t = Instant::now();
    renderer.update_guide_buffers(|b, device| b.refill(device, tree))?;
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
        selection_records: selection.records,
        mean_bsdf_fraction: selection.mean_fraction,
        mean_light_mix: tree.mean_light_mix(),
    };
    log::debug!(
        "guiding iteration {k}: {done} spp in {:.2} s (GPU {:.2} s, film kept in {:.3} s), read-back {:.3} s, refit {:.3} s (selection {:.3}, training sums in {:.3}, refit {:.3}), upload {:.3} s; {} leaves, {} + {} nodes, {:.1} KiB; selection: {} records, mean BSDF fraction {:.3}, mean light mix {:.3}",
        it.render_seconds,
        it.gpu_seconds,
        keep_seconds,
        it.readback_seconds,
        it.refit_seconds,
        selection_seconds,
        load_seconds,
        it.refit_seconds - selection_seconds - load_seconds,
        it.upload_seconds,
        it.leaves,
        it.sampling_nodes,
        it.training_nodes,
        it.gpu_bytes as f64 / 1024.0,
        it.selection_records,
        it.mean_bsdf_fraction,
        it.mean_light_mix
    );
    Ok(Some(it))
}
