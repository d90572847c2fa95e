//! Suite 2, light-count scaling: the street scene generated with emissive-triangle counts
//! from 64 to 65 536 (the lamp count that comes closest to each target is searched, since
//! a lamp has 4 to 16 triangles depending on its kind), and the cost per spp of `pt`,
//! `ris` (M = 32) and the guided methods' render phase at each. NEE draws lights from
//! alias tables and RIS draws a fixed M candidates, so the goal is a cost per sample that
//! does not grow with the light count; the report gives the growth from the smallest to
//! the largest count. The scene's geometry grows with the lamps too (each lamp is a mesh
//! instance), so some growth is traversal of a larger BVH, not light sampling: the
//! control column, `pt` at max depth 1 (camera rays and first hits, no light sampling),
//! measures that growth alone.

use super::harness::RunSample;
use super::spread::Spread;
use super::{Bench, BenchError, Result};
use crate::render::run::Budget;
use crate::render::Method;
use crate::scene::generate::{self, GenerateSummary, Kind, Options};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Name of the control column: `pt` at max depth 1 (camera rays and first hits only).
pub const CONTROL: &str = "pt-d1";

/// One method at one light count (or the control).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ScalingMethod {
    pub method: String,
    /// `all` (the whole run) or `render` (the guided methods' render phase).
    pub phase: String,
    /// spp of the timed phase (median run).
    pub spp: u64,
    pub wall_seconds_per_spp: Spread,
    pub gpu_seconds_per_spp: Spread,
    /// GPU nanoseconds per camera path (median).
    pub gpu_ns_per_sample: f64,
    pub shadow_rays_per_sample: f64,
}

/// One light count.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ScalingPoint {
    pub target_emissive_triangles: u64,
    pub lamps: u32,
    pub emissive_triangles: u64,
    pub light_models: u64,
    pub triangles: u64,
    pub setup_seconds: f64,
    pub methods: Vec<ScalingMethod>,
}

/// Cost per spp at the largest light count over that at the smallest.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Growth {
    pub method: String,
    pub gpu: f64,
    pub wall: f64,
    /// `gpu` over the control's GPU growth: what remains once traversing the larger
    /// scene is accounted for.
    pub gpu_over_control: f64,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Scaling {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// spp budget of each run (guided: training included; the render phase is timed).
    pub spp: u64,
    pub ris_candidates: u32,
    pub points: Vec<ScalingPoint>,
    pub growth: Vec<Growth>,
}

fn generate_street(lamps: u32, path: &Path) -> Result<GenerateSummary> {
    let options = Options {
        lamps: Some(lamps),
        ..Options::default()
    };
    generate::generate(Kind::Street, &options, path).map_err(BenchError::Generate)
}

/// The lamp count whose street scene has the emissive-triangle count closest to
/// `target` (the count grows with the lamps, so a doubling search then bisection).
pub fn lamps_for(target: u64, scratch: &Path) -> Result<u32> {
    std::fs::create_dir_all(scratch).map_err(|e| BenchError::io(scratch, e))?;
    let path = scratch.join("search.gltf");
    let mut cache: BTreeMap<u32, u64> = BTreeMap::new();
    let mut count = |lamps: u32| -> Result<u64> {
        if let Some(&c) = cache.get(&lamps) {
            return Ok(c);
        }
        let c = generate_street(lamps, &path)?.emissive_triangles;
        cache.insert(lamps, c);
        Ok(c)
    };
    const MAX_LAMPS: u32 = 250_000;
    let mut lo = 0u32; // count(lo) < target, or lo = 0
    let mut hi = ((target / 8) as u32).clamp(1, MAX_LAMPS);
    while count(hi)? < target && hi < MAX_LAMPS {
        lo = hi;
        hi = hi.saturating_mul(2).min(MAX_LAMPS);
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if count(mid)? >= target {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let above = count(hi)?;
    if lo >= 1 && target - count(lo)? < above.saturating_sub(target) {
        Ok(lo)
    } else {
        Ok(hi)
    }
}

fn summarise(method: Method, pixels: u64, runs: &[RunSample]) -> ScalingMethod {
    let guided = method.uses_guiding();
    let spp = |r: &RunSample| r.render_phase_spp().max(1) as f64;
    let wall = |r: &RunSample| {
        if guided {
            r.render_phase_seconds()
        } else {
            r.seconds
        }
    };
    let gpu = |r: &RunSample| {
        if guided {
            r.render_phase_gpu_seconds()
        } else {
            r.stats.gpu_seconds
        }
    };
    let gpu_per_spp = Spread::over(runs, |r| gpu(r) / spp(r));
    ScalingMethod {
        method: method.name().into(),
        phase: if guided { "render" } else { "all" }.into(),
        spp: Spread::over(runs, spp).median as u64,
        wall_seconds_per_spp: Spread::over(runs, |r| wall(r) / spp(r)),
        gpu_seconds_per_spp: gpu_per_spp,
        gpu_ns_per_sample: gpu_per_spp.median / pixels as f64 * 1e9,
        shadow_rays_per_sample: Spread::over(runs, |r| {
            r.stats.shadow_rays as f64 / (r.total_spp() * pixels).max(1) as f64
        })
        .median,
    }
}

pub fn run(bench: &Bench) -> Result<Scaling> {
    let size = &bench.sizes.scaling;
    let dir: PathBuf = bench.work_dir.join("scaling");
    let mut points = Vec::new();
    let (mut width, mut height) = (size.width, size.height.unwrap_or(0));
    for &target in &bench.sizes.scaling_emissive_triangles {
        let lamps = lamps_for(target, &dir.join("search"))?;
        let scene_dir = dir.join(format!("lamps-{lamps}"));
        std::fs::create_dir_all(&scene_dir).map_err(|e| BenchError::io(&scene_dir, e))?;
        let path = scene_dir.join("street.gltf");
        let summary = generate_street(lamps, &path)?;
        log::info!(
            "scaling: {} emissive triangles ({} lamps, {} triangles)",
            summary.emissive_triangles,
            lamps,
            summary.triangles
        );
        let mut session = bench.open(&path, size.width, size.height, Method::Pt)?;
        (width, height) = (session.width, session.height);
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
            methods.push(summarise(method, session.pixels(), &runs));
        }
        // The control: camera rays and first hits only (no light sampling), whose growth
        // is that of traversing the larger scene.
        let mut settings = session.settings(Method::Pt);
        settings.max_depth = 1;
        let runs = session.measure(
            settings,
            Budget::Spp(bench.sizes.warmup_spp),
            Budget::Spp(size.spp),
            bench.repeat,
        )?;
        let mut control = summarise(Method::Pt, session.pixels(), &runs);
        control.method = CONTROL.into();
        methods.push(control);
        points.push(ScalingPoint {
            target_emissive_triangles: target,
            lamps,
            emissive_triangles: session.loaded.lights.triangles.len() as u64,
            light_models: session.loaded.lights.models.len() as u64,
            triangles: session.loaded.scene.triangle_count(),
            setup_seconds: session.setup_seconds,
            methods,
        });
        drop(session);
        let _ = std::fs::remove_dir_all(&scene_dir);
    }
    let mut growth: Vec<Growth> = match (points.first(), points.last()) {
        (Some(a), Some(b)) if points.len() >= 2 => a
            .methods
            .iter()
            .zip(&b.methods)
            .map(|(x, y)| Growth {
                method: x.method.clone(),
                gpu: y.gpu_seconds_per_spp.median / x.gpu_seconds_per_spp.median,
                wall: y.wall_seconds_per_spp.median / x.wall_seconds_per_spp.median,
                gpu_over_control: f64::NAN,
            })
            .collect(),
        _ => Vec::new(),
    };
    if let Some(control) = growth.iter().find(|g| g.method == CONTROL).map(|g| g.gpu) {
        for g in &mut growth {
            g.gpu_over_control = g.gpu / control;
        }
    }
    Ok(Scaling {
        scene: "street (generated)".into(),
        width,
        height,
        spp: size.spp,
        ris_candidates: crate::render::RenderSettings::default().ris_candidates,
        points,
        growth,
    })
}
