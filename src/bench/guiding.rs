//! Suite 3, guiding overhead: what each SD-tree training iteration costs — the training
//! pass on the GPU, reading the training quadtrees back ("record transfer"), the CPU
//! refit and the upload of the refitted tree — and how large the tree grows (nodes,
//! bytes). The goal is that refit + upload stay within 5 % of the training time, so that
//! the CPU side of guiding does not eat the GPU's throughput.

use super::harness::RunSample;
use super::spread::Spread;
use super::throughput::open_size;
use super::{Bench, Result};
use crate::render::run::Budget;
use crate::render::Method;

/// The share of training time that refit + upload may take.
pub const GOAL_SHARE: f64 = 0.05;

/// One training iteration over the repetitions.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct IterationSummary {
    pub iteration: usize,
    pub spp: u64,
    /// Wall seconds of the training pass's dispatches.
    pub pass_seconds: Spread,
    pub gpu_seconds: Spread,
    pub readback_seconds: Spread,
    pub refit_seconds: Spread,
    pub upload_seconds: Spread,
    /// After the refit (median run).
    pub leaves: usize,
    pub sampling_nodes: usize,
    pub training_nodes: usize,
    pub gpu_bytes: u64,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MethodGuiding {
    pub method: String,
    /// spp budget of each run; `training_spp` of it trains.
    pub spp: u64,
    pub training_spp: u64,
    /// Wall seconds of the whole training phase.
    pub training_seconds: Spread,
    pub training_gpu_seconds: Spread,
    /// Read-back seconds / training seconds.
    pub readback_share: Spread,
    /// (refit + upload) seconds / training seconds.
    pub refit_upload_share: Spread,
    /// The median share is within [`GOAL_SHARE`].
    pub goal_met: bool,
    pub iterations: Vec<IterationSummary>,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct GuidingOverhead {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub goal_share: f64,
    pub methods: Vec<MethodGuiding>,
}

fn median_of<T: Copy + Into<f64>>(values: impl Iterator<Item = T>) -> f64 {
    Spread::of(&values.map(Into::into).collect::<Vec<f64>>()).median
}

fn summarise(method: Method, spp: u64, runs: &[RunSample]) -> MethodGuiding {
    let count = runs.iter().map(|r| r.iterations.len()).min().unwrap_or(0);
    let iterations = (0..count)
        .map(|k| {
            let its: Vec<_> = runs.iter().map(|r| &r.iterations[k]).collect();
            IterationSummary {
                iteration: k,
                spp: its[0].spp,
                pass_seconds: Spread::over(&its, |i| i.render_seconds),
                gpu_seconds: Spread::over(&its, |i| i.gpu_seconds),
                readback_seconds: Spread::over(&its, |i| i.readback_seconds),
                refit_seconds: Spread::over(&its, |i| i.refit_seconds),
                upload_seconds: Spread::over(&its, |i| i.upload_seconds),
                leaves: median_of(its.iter().map(|i| i.leaves as f64)) as usize,
                sampling_nodes: median_of(its.iter().map(|i| i.sampling_nodes as f64)) as usize,
                training_nodes: median_of(its.iter().map(|i| i.training_nodes as f64)) as usize,
                gpu_bytes: median_of(its.iter().map(|i| i.gpu_bytes as f64)) as u64,
            }
        })
        .collect();
    let sum = |r: &RunSample, f: fn(&crate::render::IterationStats) -> f64| -> f64 {
        r.iterations.iter().map(f).sum()
    };
    let share = Spread::over(runs, |r| {
        (sum(r, |i| i.refit_seconds) + sum(r, |i| i.upload_seconds)) / r.training_seconds
    });
    MethodGuiding {
        method: method.name().into(),
        spp,
        training_spp: runs
            .first()
            .map(|r| r.iterations.iter().map(|i| i.spp).sum())
            .unwrap_or(0),
        training_seconds: Spread::over(runs, |r| r.training_seconds),
        training_gpu_seconds: Spread::over(runs, |r| r.training_gpu_seconds()),
        readback_share: Spread::over(runs, |r| {
            sum(r, |i| i.readback_seconds) / r.training_seconds
        }),
        refit_upload_share: share,
        goal_met: share.median <= GOAL_SHARE,
        iterations,
    }
}

pub fn run(bench: &Bench) -> Result<GuidingOverhead> {
    let size = &bench.sizes.guiding;
    log::info!("guiding: {} at width {}", size.scene, size.width);
    let mut session = open_size(bench, size, Method::Guided)?;
    let mut methods = Vec::new();
    for method in [Method::Guided, Method::GuidedRis] {
        let mut settings = session.settings(method);
        settings.max_depth = bench.sizes.max_depth;
        let runs = session.measure(
            settings,
            Budget::Spp(bench.sizes.warmup_spp),
            Budget::Spp(size.spp),
            bench.repeat,
        )?;
        methods.push(summarise(method, size.spp, &runs));
    }
    Ok(GuidingOverhead {
        scene: size.scene.clone(),
        width: session.width,
        height: session.height,
        goal_share: GOAL_SHARE,
        methods,
    })
}
