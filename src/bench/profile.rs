//! Where the time goes: the cost per camera path of the render kernel under settings
//! that switch its parts on one at a time — `pt` at max depth 1, 2, 3, 4 (camera ray and
//! first hit, then one vertex more each), an "AO-like" depth 2 with direction sampling
//! only (one bounce ray, no light sampling), `ris` with M = 1, 8, 32 candidates, and the
//! guided methods' training and render passes — all from GPU timestamps. Differences
//! between neighbouring settings attribute the time to camera rays, bounces, NEE, RIS
//! candidates and guiding; the gap between wall and GPU time, and the film read-back
//! timed alone, are the host's share. Then, with the lane-statistics kernel, how much
//! of the device's SIMD width each method keeps busy in the traversal and path loops.

use super::harness::{RunSample, Session};
use super::spread::Spread;
use super::throughput::open_size;
use super::{Bench, Result};
use crate::render::run::Budget;
use crate::render::{GuideBuffers, Method, RenderSettings, RenderStats, Strategy};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// One configuration.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ProfileEntry {
    /// Key of the configuration (`pt-d4`, `ao-d2`, `ris-m32`, `guided-train`, …).
    pub name: String,
    pub method: String,
    pub max_depth: u32,
    pub ris_candidates: Option<u32>,
    pub strategy: String,
    /// `all`, `training` or `render`.
    pub phase: String,
    pub spp: u64,
    /// GPU nanoseconds per camera path.
    pub gpu_ns_per_sample: Spread,
    /// Wall nanoseconds per camera path.
    pub wall_ns_per_sample: Spread,
    pub camera_rays_per_sample: f64,
    pub bounce_rays_per_sample: f64,
    pub shadow_rays_per_sample: f64,
}

/// A part of a method's cost, from differences of configurations.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Part {
    /// The method whose time it divides (`pt` or `ris` at the full depth, …).
    pub of: String,
    pub part: String,
    /// GPU nanoseconds per camera path (from each configuration's fastest run).
    pub ns_per_sample: f64,
    /// Share of the method's GPU time.
    pub share: f64,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Profile {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub entries: Vec<ProfileEntry>,
    /// Reading the film back (the per-render host cost besides submission), milliseconds.
    pub film_readback_ms: Spread,
    pub parts: Vec<Part>,
    /// SIMD lane utilisation per method (one run each of the lane-statistics kernel).
    #[serde(default)]
    pub lanes: Vec<LaneEntry>,
}

/// How much of the SIMD width one method keeps busy (see `shaders_glsl/inc/lane_stats.glsl`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct LaneEntry {
    pub method: String,
    pub max_depth: u32,
    /// Steps of the software traversal loop that did work, over the lane slots they ran
    /// in (None with ray queries: the driver's traversal is not counted).
    pub traversal: Option<f64>,
    /// Path-loop steps that did work over the slots (lanes whose path ended wait).
    pub path: Option<f64>,
    /// Software traversal loop steps (inner nodes and leaves visited) per ray.
    #[serde(default)]
    pub steps_per_ray: Option<f64>,
    /// The raw counts, all passes (training included) summed.
    pub counts: crate::render::LaneCounts,
}

fn entry(
    name: &str,
    s: &RenderSettings,
    phase: &str,
    pixels: u64,
    runs: &[RunSample],
) -> ProfileEntry {
    let paths = |r: &RunSample| (r.total_spp() * pixels).max(1) as f64;
    ProfileEntry {
        name: name.into(),
        method: s.method.name().into(),
        max_depth: s.max_depth,
        ris_candidates: s.method.uses_ris().then_some(s.ris_candidates),
        strategy: format!("{:?}", s.strategy).to_lowercase(),
        phase: phase.into(),
        spp: runs.first().map(|r| r.total_spp()).unwrap_or(0),
        gpu_ns_per_sample: Spread::over(runs, |r| r.stats.gpu_seconds / paths(r) * 1e9),
        wall_ns_per_sample: Spread::over(runs, |r| r.seconds / paths(r) * 1e9),
        camera_rays_per_sample: Spread::over(runs, |r| r.stats.camera_rays as f64 / paths(r))
            .median,
        bounce_rays_per_sample: Spread::over(runs, |r| r.stats.bounce_rays as f64 / paths(r))
            .median,
        shadow_rays_per_sample: Spread::over(runs, |r| r.stats.shadow_rays as f64 / paths(r))
            .median,
    }
}

/// Passes of the guided kernel with one trained tree, frozen: render passes, and training
/// passes that trace the very same paths and also record them.
fn guided_passes(
    session: &mut Session,
    settings: &RenderSettings,
    bench: &Bench,
    spp: u64,
) -> Result<(Vec<RunSample>, Vec<RunSample>)> {
    session.configure(settings.clone())?;
    session.run(Budget::Spp(bench.sizes.warmup_spp), 0, false)?;
    let trained = session.run(Budget::Spp(spp * 4), 0, false)?;
    let tree = trained.tree.expect("guided runs return their tree");
    let device = session.renderer.device.clone();
    session.renderer.set_guide_buffers(
        GuideBuffers::upload(&device, &tree).map_err(crate::render::RenderError::from)?,
    );
    let cancel = AtomicBool::new(false);
    let pass = |session: &mut Session, training: bool| -> Result<RunSample> {
        session.renderer.clear_film()?;
        let mut stats = RenderStats::default();
        let t = Instant::now();
        session.renderer.render_samples(
            1 << 20,
            spp,
            training,
            &cancel,
            &mut |_| {},
            &mut stats,
        )?;
        Ok(RunSample {
            seconds: t.elapsed().as_secs_f64(),
            training_seconds: 0.0,
            stats,
            film_spp: spp,
            iterations: Vec::new(),
            image: None,
            tree: None,
        })
    };
    pass(session, false)?;
    pass(session, true)?;
    let (mut render, mut training) = (Vec::new(), Vec::new());
    for _ in 0..bench.repeat.max(1) {
        render.push(pass(session, false)?);
        training.push(pass(session, true)?);
    }
    Ok((render, training))
}

/// The parts of `pt` and `ris` at full depth and of guiding, from whichever entries exist.
/// Differences of small numbers amplify noise, so they use each configuration's fastest
/// run: the one least disturbed by other work on the machine.
pub fn parts(entries: &[ProfileEntry], depth: u32) -> Vec<Part> {
    let ns = |name: &str| {
        entries
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.gpu_ns_per_sample.min)
    };
    let mut out = Vec::new();
    let mut push = |of: &str, part: &str, v: f64, total: f64| {
        out.push(Part {
            of: of.into(),
            part: part.into(),
            ns_per_sample: v,
            share: v / total,
        })
    };
    let full = format!("pt-d{depth}");
    if let Some(total) = ns(&full) {
        let of = format!("pt (depth {depth})");
        let mut prev = 0.0;
        let mut prev_depth = 0;
        for d in 1..=depth {
            let Some(t) = ns(&format!("pt-d{d}")) else {
                continue;
            };
            if d == 1 {
                push(&of, "camera ray, first hit, film", t, total);
            } else if d == 2 && prev_depth == 1 {
                if let Some(ao) = ns("ao-d2") {
                    push(
                        &of,
                        "vertex 1: direction sample, bounce ray, hit",
                        ao - prev,
                        total,
                    );
                    push(
                        &of,
                        "vertex 1: NEE (light sample, shadow ray, MIS)",
                        t - ao,
                        total,
                    );
                } else {
                    push(&of, "vertex 1: bounce and NEE", t - prev, total);
                }
            } else {
                let what = if d == prev_depth + 1 {
                    format!("vertex {}: bounce and NEE", d - 1)
                } else {
                    format!("vertices {}–{}: bounces and NEE", prev_depth, d - 1)
                };
                push(&of, &what, t - prev, total);
            }
            prev = t;
            prev_depth = d;
        }
        // RIS: t(M) = a + b·shadow rays + c·M·vertices, fitted over the M values; more
        // candidates find a light worth a shadow ray more often, so the shadow rays must
        // be separated from the candidates' own cost.
        let ris: Vec<&ProfileEntry> = entries
            .iter()
            .filter(|e| e.method == "ris" && e.max_depth == depth && e.ris_candidates.is_some())
            .collect();
        let pt = entries.iter().find(|e| e.name == full);
        if let (Some(hi), Some(pt)) = (ris.iter().max_by_key(|e| e.ris_candidates), pt) {
            let m_hi = hi.ris_candidates.unwrap_or(1);
            let t_hi = hi.gpu_ns_per_sample.min;
            let of = format!("ris (M = {m_hi}, depth {depth})");
            let rows: Vec<[f64; 4]> = ris
                .iter()
                .map(|e| {
                    let m = e.ris_candidates.unwrap_or(1) as f64;
                    [
                        1.0,
                        e.shadow_rays_per_sample,
                        m * e.bounce_rays_per_sample,
                        e.gpu_ns_per_sample.min,
                    ]
                })
                .collect();
            push(
                &of,
                "pt's work (camera, bounces, pt's shadow rays)",
                total,
                t_hi,
            );
            match least_squares3(&rows) {
                Some([_, per_shadow, per_candidate])
                    if rows.len() >= 3 && per_shadow > 0.0 && per_candidate > 0.0 =>
                {
                    let candidates = per_candidate * m_hi as f64 * hi.bounce_rays_per_sample;
                    let shadow =
                        per_shadow * (hi.shadow_rays_per_sample - pt.shadow_rays_per_sample);
                    push(
                        &of,
                        &format!(
                            "RIS candidates ({m_hi} per vertex, {} ns each)",
                            super::number::num(per_candidate)
                        ),
                        candidates,
                        t_hi,
                    );
                    push(
                        &of,
                        &format!(
                            "shadow rays beyond pt's ({} ns each)",
                            super::number::num(per_shadow)
                        ),
                        shadow,
                        t_hi,
                    );
                    push(
                        &of,
                        "rest (RIS bookkeeping, direction candidate, fit error)",
                        t_hi - total - candidates - shadow,
                        t_hi,
                    );
                }
                _ => push(
                    &of,
                    "RIS candidates and the extra shadow rays they lead to",
                    t_hi - total,
                    t_hi,
                ),
            }
        }
        for method in ["guided", "guided-ris"] {
            let unguided = if method == "guided" {
                Some(full.clone())
            } else {
                ris.iter()
                    .max_by_key(|e| e.ris_candidates)
                    .map(|e| e.name.clone())
            };
            let per_ray = |name: &str| {
                entries.iter().find(|e| e.name == name).map(|e| {
                    let rays = e.camera_rays_per_sample
                        + e.bounce_rays_per_sample
                        + e.shadow_rays_per_sample;
                    (e.gpu_ns_per_sample.min / rays.max(1e-9), rays)
                })
            };
            let (Some(base), Some((render, rays)), Some(train)) = (
                unguided.as_deref().and_then(per_ray),
                per_ray(&format!("{method}-render")),
                ns(&format!("{method}-training")),
            ) else {
                continue;
            };
            let render_total = render * rays;
            push(
                &format!("{method} render pass"),
                &format!(
                    "guiding (tree lookup, mixture sampling and pdfs), per ray over {}",
                    unguided.unwrap_or_default()
                ),
                (render - base.0) * rays,
                render_total,
            );
            push(
                &format!("{method} training pass"),
                "recording (path records, atomic splats), same paths as the render pass",
                train - render_total,
                train,
            );
        }
    }
    out
}

/// Least-squares fit of y = x·β over rows [x0, x1, x2, y] (normal equations, Gaussian
/// elimination with partial pivoting); None when singular.
pub fn least_squares3(rows: &[[f64; 4]]) -> Option<[f64; 3]> {
    let mut a = [[0.0f64; 4]; 3];
    for r in rows {
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += r[i] * r[j];
            }
            a[i][3] += r[i] * r[3];
        }
    }
    for col in 0..3 {
        let pivot = (col..3).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        let pivot_row = a[col];
        for (row, r) in a.iter_mut().enumerate() {
            if row != col {
                let f = r[col] / pivot_row[col];
                for (x, p) in r.iter_mut().zip(pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    Some([a[0][3] / a[0][0], a[1][3] / a[1][1], a[2][3] / a[2][2]])
}

pub fn run(bench: &Bench) -> Result<Profile> {
    let size = &bench.sizes.profile;
    let depth = bench.sizes.max_depth;
    log::info!("profile: {} at width {}", size.scene, size.width);
    let mut session = open_size(bench, size, Method::Pt)?;
    let pixels = session.pixels();
    let warmup = Budget::Spp(bench.sizes.warmup_spp);
    let budget = Budget::Spp(size.spp);
    let mut entries = Vec::new();
    let mut configs: Vec<(String, RenderSettings)> = Vec::new();
    for &d in &bench.sizes.profile_depths {
        let mut s = session.settings(Method::Pt);
        s.max_depth = d;
        configs.push((format!("pt-d{d}"), s));
    }
    if bench.sizes.profile_depths.contains(&2) {
        let mut s = session.settings(Method::Pt);
        s.max_depth = 2;
        s.strategy = Strategy::Bsdf;
        configs.push(("ao-d2".into(), s));
    }
    for &m in &bench.sizes.profile_ris_candidates {
        let mut s = session.settings(Method::Ris);
        s.max_depth = depth;
        s.ris_candidates = m;
        configs.push((format!("ris-m{m}"), s));
    }
    for (name, s) in configs {
        let runs = session.measure(s.clone(), warmup, budget, bench.repeat)?;
        entries.push(entry(&name, &s, "all", pixels, &runs));
    }
    // Guided: a tree trained with 4× the profile's spp, then passes with it frozen.
    for method in [Method::Guided, Method::GuidedRis] {
        let mut s = session.settings(method);
        s.max_depth = depth;
        let (render, training) = guided_passes(&mut session, &s, bench, size.spp)?;
        entries.push(entry(
            &format!("{method}-render"),
            &s,
            "render",
            pixels,
            &render,
        ));
        entries.push(entry(
            &format!("{method}-training"),
            &s,
            "training",
            pixels,
            &training,
        ));
    }
    // SIMD lane utilisation: one run of each method with the counting kernel (its time
    // is not reported: the counters cost time).
    let mut lanes = Vec::new();
    for name in &bench.sizes.profile_lane_methods {
        let method: Method = name
            .parse()
            .map_err(|e| super::BenchError::Other(format!("profile lane method `{name}`: {e}")))?;
        let mut s = session.settings(method);
        s.max_depth = depth;
        s.lane_stats = true;
        let runs = session.measure(s, Budget::Spp(1), budget, 1)?;
        let counts = runs[0].stats.lanes;
        lanes.push(LaneEntry {
            method: method.name().into(),
            max_depth: depth,
            traversal: counts.traversal_utilisation(),
            path: counts.path_utilisation(),
            steps_per_ray: counts.traversal_steps_per_ray(runs[0].stats.rays()),
            counts,
        });
    }
    let mut readback = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        let _ = session.renderer.film()?;
        readback.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let parts = parts(&entries, depth);
    Ok(Profile {
        scene: size.scene.clone(),
        width: session.width,
        height: session.height,
        entries,
        film_readback_ms: Spread::of(&readback),
        parts,
        lanes,
    })
}

#[cfg(test)]
mod tests {
    use super::least_squares3;

    #[test]
    fn fits_exact_and_overdetermined() {
        let f = |x1: f64, x2: f64| 5.0 + 2.0 * x1 + 0.5 * x2;
        let rows: Vec<[f64; 4]> = [(1.0, 2.0), (3.0, 1.0), (0.5, 7.0), (2.0, 2.0)]
            .iter()
            .map(|&(a, b)| [1.0, a, b, f(a, b)])
            .collect();
        for n in [3, 4] {
            let b = least_squares3(&rows[..n]).unwrap();
            assert!(
                (b[0] - 5.0).abs() < 1e-9 && (b[1] - 2.0).abs() < 1e-9 && (b[2] - 0.5).abs() < 1e-9,
                "{b:?}"
            );
        }
        assert!(least_squares3(&rows[..2]).is_none());
    }
}
