//! Suite 1, throughput: every method on every shipped scene at a fixed spp, with each
//! traversal the device has (ray queries, software); samples per
//! second of wall time, rays per second by kind from the kernel's counters, and GPU time
//! from timestamp queries against wall time (their gap is the host: submission, waits,
//! film clears and read-backs, and for guided methods the SD-tree's read-back, refit and
//! upload).

use super::harness::{RunSample, Session};
use super::spread::Spread;
use super::{Bench, Result};
use crate::render::run::Budget;
use crate::render::{Method, Traversal};

/// One method on one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MethodThroughput {
    pub method: String,
    /// The spp budget of each run (training included for guided methods).
    pub spp: u64,
    /// Camera paths traced per second of wall time (all passes).
    pub samples_per_s: Spread,
    /// Camera paths per second of GPU time.
    pub samples_per_gpu_s: Spread,
    pub camera_rays_per_s: Spread,
    pub bounce_rays_per_s: Spread,
    pub shadow_rays_per_s: Spread,
    pub rays_per_s: Spread,
    /// Rays per camera path, by kind (median run).
    pub camera_rays_per_sample: f64,
    pub bounce_rays_per_sample: f64,
    pub shadow_rays_per_sample: f64,
    /// Probes of the stretch a bounce ray's origin skips (`bounce_origin` in
    /// shaders_glsl/inc/trace.glsl); absent from results written before 2026-12-08.
    #[serde(default)]
    pub probe_rays_per_sample: f64,
    pub wall_seconds: Spread,
    pub gpu_seconds: Spread,
    /// GPU time / wall time.
    pub gpu_share: Spread,
    /// Guided methods: wall seconds of the training phase.
    pub training_seconds: Option<Spread>,
    pub nonfinite_samples: u64,
}

/// One scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneThroughput {
    pub scene: String,
    /// `ray-query` or `software`.
    #[serde(default)]
    pub traversal: String,
    pub width: u32,
    pub height: u32,
    pub triangles: u64,
    pub emissive_triangles: u64,
    pub light_models: u64,
    pub setup_seconds: f64,
    pub methods: Vec<MethodThroughput>,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Throughput {
    pub scenes: Vec<SceneThroughput>,
}

/// Summarise the recorded runs of one method.
pub fn summarise(method: Method, spp: u64, pixels: u64, runs: &[RunSample]) -> MethodThroughput {
    let paths = |r: &RunSample| (r.total_spp() * pixels) as f64;
    let per_sample =
        |f: fn(&RunSample) -> u64| Spread::over(runs, |r| f(r) as f64 / paths(r).max(1.0)).median;
    MethodThroughput {
        method: method.name().into(),
        spp,
        samples_per_s: Spread::over(runs, |r| paths(r) / r.seconds),
        samples_per_gpu_s: Spread::over(runs, |r| paths(r) / r.stats.gpu_seconds),
        camera_rays_per_s: Spread::over(runs, |r| r.stats.camera_rays as f64 / r.seconds),
        bounce_rays_per_s: Spread::over(runs, |r| r.stats.bounce_rays as f64 / r.seconds),
        shadow_rays_per_s: Spread::over(runs, |r| r.stats.shadow_rays as f64 / r.seconds),
        rays_per_s: Spread::over(runs, |r| r.stats.rays() as f64 / r.seconds),
        camera_rays_per_sample: per_sample(|r| r.stats.camera_rays),
        bounce_rays_per_sample: per_sample(|r| r.stats.bounce_rays),
        shadow_rays_per_sample: per_sample(|r| r.stats.shadow_rays),
        probe_rays_per_sample: per_sample(|r| r.stats.probe_rays),
        wall_seconds: Spread::over(runs, |r| r.seconds),
        gpu_seconds: Spread::over(runs, |r| r.stats.gpu_seconds),
        gpu_share: Spread::over(runs, |r| r.stats.gpu_seconds / r.seconds),
        training_seconds: method
            .uses_guiding()
            .then(|| Spread::over(runs, |r| r.training_seconds)),
        nonfinite_samples: runs.iter().map(|r| r.stats.nonfinite_samples).sum(),
    }
}

pub fn run(bench: &Bench) -> Result<Throughput> {
    let mut scenes = Vec::new();
    for size in &bench.sizes.throughput {
        let path = bench.scene_path(&size.scene)?;
        let mut traversals = vec![Traversal::Software];
        if bench.device.info.features.ray_queries() {
            traversals.insert(0, Traversal::RayQuery);
        }
        for traversal in traversals {
            log::info!(
                "throughput: {} at width {}, {traversal:?} traversal",
                size.scene,
                size.width
            );
            let mut session =
                bench.open_with(&path, size.width, size.height, Method::Pt, traversal)?;
            let pixels = session.pixels();
            let mut methods = Vec::new();
            for method in Method::ALL {
                let mut settings = session.settings(method);
                settings.max_depth = bench.sizes.max_depth;
                let runs = session.measure(
                    settings,
                    Budget::Spp(bench.sizes.warmup_spp),
                    Budget::Spp(size.spp),
                    bench.repeat,
                )?;
                methods.push(summarise(method, size.spp, pixels, &runs));
            }
            scenes.push(SceneThroughput {
                scene: size.scene.clone(),
                traversal: session.renderer.traversal.kind.name().into(),
                width: session.width,
                height: session.height,
                triangles: session.loaded.scene.triangle_count(),
                emissive_triangles: session.loaded.lights.triangles.len() as u64,
                light_models: session.loaded.lights.models.len() as u64,
                setup_seconds: session.setup_seconds,
                methods,
            });
        }
    }
    Ok(Throughput { scenes })
}

/// Shared by the other suites: a scene's session at a suite's size.
pub fn open_size(bench: &Bench, size: &super::sizes::SceneSize, method: Method) -> Result<Session> {
    let path = bench.scene_path(&size.scene)?;
    bench.open(&path, size.width, size.height, method)
}
