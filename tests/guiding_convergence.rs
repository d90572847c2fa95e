//! The learned directional distributions converge to the incident radiance. On the gap
//! scene, SD-trees are trained with growing budgets (default options: NEE records,
//! nearest spatial filter, directional box, learned selection); a brute-force probe
//! (`SdTree::probe`: 4096 uniform spatial leaves, an 8×8 grid over the direction
//! square, sampling from the BSDF and the uniform sphere, no NEE records, so
//! direction-sampled hits alone measure the direct light) records a plain path tracer's
//! estimates of the incident radiance. At four query points (in the busiest cells of a
//! 4×4×4 grid over the scene) the learned leaf's sampling distribution is compared with
//! the probe's energy summed over the region that distribution was learned from (the
//! leaf, or the ancestor whose tree it still shares after a split at the last refit), in
//! relative L1 distance Σ|p − q| (0: equal, 2: disjoint).
//!
//! Training is not deterministic (float atomics; the learned selection sees records in
//! device order), so each budget is trained `RUNS` times from different samples. The
//! mean distance must fall from 4 to 32 spp by more than twice the standard error of the
//! difference (from the runs' spread), not rise by more than that (plus the plateau's
//! wobble, `PLATEAU_WOBBLE`) after, and end below 0.5.
//!
//! Measured (32×24, seed 41, 4 runs): mean L1 0.65 (sd 0.10), 0.415 (sd 0.05), 0.407
//! (sd 0.01) after 4, 32, 256 spp; with the stochastic box filter (the default before
//! 2026-11-23) 0.81, 0.466, 0.427. The probe's own noise (two halves against each other)
//! is 0.2–0.44 per region. The level from 32 spp on is not the probe's: with 4× its
//! samples its noise halves (0.12–0.19) and the distances stay 0.39 and 0.40. So the
//! learned distributions stop approaching the brute-force ones at about 0.4; what is
//! left is systematic. Most of it comes from training with guided paths: with the BSDF
//! fraction fixed at 0.2, 0.5, 0.9, 0.99 and 1 (training paths not guided at all) the
//! 256-spp distance is 0.406, 0.397, 0.329, 0.303, 0.299 (learned α: 0.414).
//!
//! What that level is (2026-11-23; fixed fractions through
//! `LANTERNA_CONVERGENCE_BSDF_FRACTION`, 4 runs, the test prints both numbers below):
//! - Bias against the probe, not noise. At 256 spp (fraction 0.5) the runs' learned
//!   distributions are 0.07–0.28 L1 from each other (mean 0.15), and their average is as
//!   far from the truth as one run is (0.39 against 0.40); unguided (1.0): 0.16–0.30
//!   apart, average 0.27 against 0.30 for one run.
//! - It comes from where guided paths put their vertices, not from sampling little where
//!   the tree has little mass. With training and probe records restricted to first hits
//!   (`record_path` in raygen.glsl recording only k = 0, injected through
//!   LANTERNA_TEST_SHADER_DIR), whose positions the camera decides for guided and
//!   unguided training alike, fraction 0.5 and 1.0 end equally far from the truth:
//!   0.344 (sd 0.033) and 0.348 (sd 0.018) at 256 spp. With whole paths, a region's
//!   records are weighted by where guided paths arrive in it, the probe's by where its
//!   BSDF and uniform-sphere paths arrive: 0.40 against 0.30. The guided weighting is
//!   the one the render phase's guided paths meet, so the distance to this probe
//!   overstates how far guiding is from what it should learn.
//!
//! The directional filter matters little (nearest:
//! 0.83, 0.45, 0.39). Comparing with the probe leaf at the query point
//! instead of the region the distribution was learned from made the test flaky
//! (0.56–0.61 against a bound of 0.6, and 1.09 for one leaf split three times at the last
//! refit).
//!
//! Defects this test was seen to fail on (injected once, then reverted, through
//! LANTERNA_TEST_SHADER_DIR):
//! - NEE records splatted toward the opposite direction (`r.dir = -rec[k].nee_dir` in
//!   raygen.glsl's `record_path`): mean L1 1.24, 1.25, 1.37 (box filter: 1.35, 1.29,
//!   1.37).
//! - NEE records dropped (`nee_record` always false): 1.03, 0.72, 0.82 (box: 1.19,
//!   0.79, 0.84).

use lanterna::guiding::{DirectionalFilter, GuidingConfig, SdTree, SpatialFilter};
use lanterna::lights::LightTable;
use lanterna::render::run::Budget;
use lanterna::render::{train, GuideBuffers, Method, RenderStats, Renderer, TrainingPlan};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing;
use std::sync::atomic::AtomicBool;

const GRID_LEVEL: u32 = 3; // 8 × 8 cells
const GRID: usize = 8;
/// Independent trainings per budget.
const RUNS: u64 = 4;

/// How far the plateau's level moves between budgets beyond the runs' own spread: with
/// stratified path decisions (2026-11-24) the 32-spp point fell to 0.383 (sd 0.026)
/// while 256 spp stayed at 0.421 (sd 0.020), against 0.412 and 0.417 with independent
/// numbers: 0.038 apart, 2.2 standard errors.
const PLATEAU_WOBBLE: f64 = 0.05;

fn l1(p: &[f64], q: &[f64]) -> f64 {
    p.iter().zip(q).map(|(a, b)| (a - b).abs()).sum()
}

/// The cell-wise mean of histograms.
fn mean_histogram<'a>(hists: impl Iterator<Item = &'a Vec<f64>>) -> Vec<f64> {
    let mut sum = vec![0.0; GRID * GRID];
    let mut n = 0;
    for h in hists {
        for (s, x) in sum.iter_mut().zip(h) {
            *s += x;
        }
        n += 1;
    }
    sum.iter().map(|s| s / n as f64).collect()
}

#[test]
fn learned_distributions_approach_the_incident_radiance() {
    let t = testing::generated(Kind::Gap, &Options::default());
    let lights = LightTable::build(&t.scene).unwrap();
    let (w, h) = (32, 24);
    let mut s = testing::settings(Method::Guided, w, h);
    s.seed = 41;
    // The paper's target: all incident radiance, what the probe measures.
    s.guiding.target = lanterna::guiding::GuideTarget::All;
    // For experiments (see the module comment): a fixed BSDF fraction instead of the
    // learned selection.
    if let Ok(f) = std::env::var("LANTERNA_CONVERGENCE_BSDF_FRACTION") {
        s.guiding.bsdf_fraction = f.parse().expect("a BSDF fraction in [0, 1]");
        s.guiding.learn_selection = false;
    }
    let mut r = Renderer::new(
        testing::device(),
        &t.scene,
        &lights,
        t.camera.clone(),
        s,
        testing::shader_source(),
    )
    .unwrap();
    let cancel = AtomicBool::new(false);
    let mut stats = RenderStats::default();

    // The brute-force probe: two independent halves, to see its own noise.
    let probe_depth = 12;
    let (lo, hi) = r.bounds;
    let probe_config = GuidingConfig {
        spatial_filter: SpatialFilter::Nearest,
        directional_filter: DirectionalFilter::Nearest,
        record_nee: false,
        bsdf_fraction: 0.5,
        ..GuidingConfig::default()
    };
    let mut halves = Vec::new();
    let probe_spp = 4096;
    for half in 0..2u64 {
        let mut probe = SdTree::probe(lo, hi, &probe_config, probe_depth, GRID_LEVEL).unwrap();
        r.set_guide_buffers(GuideBuffers::upload(&r.device, &probe).unwrap());
        r.clear_film().unwrap();
        let first = 1 << 30;
        r.render_samples(
            first + half * probe_spp,
            probe_spp,
            true,
            &cancel,
            &mut |_| {},
            &mut stats,
        )
        .unwrap();
        let training = r.guide_buffers().read_training(&r.device).unwrap();
        probe.load_training_readback(&training).unwrap();
        halves.push(probe);
    }
    // Unnormalised energy per grid cell of each probe leaf, per half.
    let energy: Vec<Vec<Vec<f64>>> = halves
        .iter()
        .map(|h| {
            (0..h.leaves().len() as u32)
                .map(|i| {
                    let (p, total) = h.training_histogram(i, GRID);
                    p.iter().map(|x| x * total).collect()
                })
                .collect()
        })
        .collect();
    let boxes: Vec<(glam::Vec3, glam::Vec3)> = halves[0]
        .leaves()
        .iter()
        .map(|l| (l.box_min, l.box_min + l.box_size))
        .collect();
    // The truth over a region: the probe's energy summed over the probe leaves inside it
    // (or the probe leaf containing `point` where the region is smaller), normalised;
    // per half and averaged.
    let region_truth = |bmin: glam::Vec3, bmax: glam::Vec3, point: glam::Vec3| {
        let inside =
            |a: glam::Vec3, b: glam::Vec3, p: glam::Vec3| p.cmpge(a).all() && p.cmplt(b).all();
        let mut picked: Vec<usize> = (0..boxes.len())
            .filter(|&i| inside(bmin, bmax, 0.5 * (boxes[i].0 + boxes[i].1)))
            .collect();
        if picked.is_empty() {
            picked = (0..boxes.len())
                .filter(|&i| inside(boxes[i].0, boxes[i].1, point))
                .collect();
        }
        let sum = |h: usize| {
            let mut acc = vec![0.0f64; GRID * GRID];
            for &i in &picked {
                for (a, e) in acc.iter_mut().zip(&energy[h][i]) {
                    *a += e;
                }
            }
            let t: f64 = acc.iter().sum();
            acc.iter().map(|a| a / t).collect::<Vec<f64>>()
        };
        let (a, b) = (sum(0), sum(1));
        let noise = l1(&a, &b);
        (
            a.iter()
                .zip(&b)
                .map(|(x, y)| 0.5 * (x + y))
                .collect::<Vec<f64>>(),
            noise,
        )
    };
    // Query points: in each of the 4 cells of a 4 × 4 × 4 grid over the SD-tree's root
    // cube (its leaves at depth 6) that recorded the most energy, the centre of the probe
    // leaf there that recorded the most.
    let cube = (hi - lo).max_element();
    let cell = |p: glam::Vec3| {
        let c = ((p - lo) / cube * 4.0)
            .floor()
            .clamp(glam::Vec3::ZERO, glam::Vec3::splat(3.0));
        (c.x as usize) + 4 * (c.y as usize) + 16 * (c.z as usize)
    };
    let leaf_energy = |i: usize| {
        let a: f64 = energy[0][i].iter().sum();
        let b: f64 = energy[1][i].iter().sum();
        a.min(b)
    };
    let mut cells = vec![(0.0f64, usize::MAX, 0.0f64); 64];
    for i in 0..boxes.len() {
        let e = leaf_energy(i);
        let c = &mut cells[cell(0.5 * (boxes[i].0 + boxes[i].1))];
        c.0 += e;
        if e > c.2 {
            c.1 = i;
            c.2 = e;
        }
    }
    cells.sort_by(|a, b| b.0.total_cmp(&a.0));
    let points: Vec<glam::Vec3> = cells
        .iter()
        .take(4)
        .map(|&(_, i, _)| 0.5 * (boxes[i].0 + boxes[i].1))
        .collect();

    // Learned trees of growing budgets, each trained from scratch.
    let mut means = Vec::new();
    for spp in [4u64, 32, 256] {
        let mut per_run = Vec::new();
        // Per run and query point: the learned histogram and the truth of its region.
        let mut learned: Vec<Vec<(Vec<f64>, Vec<f64>)>> = Vec::new();
        for run in 0..RUNS {
            let trained = train(
                &mut r,
                TrainingPlan::whole(Budget::Spp(spp)),
                run << 24,
                &cancel,
                &mut |_| {},
                &mut stats,
                None,
            )
            .unwrap();
            let mut noise = Vec::new();
            let mut depth = Vec::new();
            let pairs = points
                .iter()
                .map(|&p| {
                    let leaf = trained.tree.find_leaf(p);
                    let l = trained.tree.leaf(leaf);
                    // The region its sampling tree learned from: leaves split at the last
                    // refit share their ancestor's tree (refit.rs), so the union of the
                    // leaves sharing it.
                    let (mut bmin, mut bmax) = (l.box_min, l.box_min + l.box_size);
                    for o in trained.tree.leaves() {
                        if std::sync::Arc::ptr_eq(&o.sampling, &l.sampling) {
                            bmin = bmin.min(o.box_min);
                            bmax = bmax.max(o.box_min + o.box_size);
                        }
                    }
                    let (truth, n) = region_truth(bmin, bmax, p);
                    noise.push(n);
                    let shared = ((bmax - bmin).element_product() / l.box_size.element_product())
                        .log2()
                        .round() as u32;
                    depth.push(l.depth - shared);
                    (trained.tree.sampling_histogram(leaf, GRID), truth)
                })
                .collect::<Vec<_>>();
            let d: Vec<f64> = pairs.iter().map(|(h, t)| l1(h, t)).collect();
            learned.push(pairs);
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            eprintln!("training {spp:>3} spp run {run}: L1 per chosen leaf {d:.3?}, mean {mean:.3}; region depth {depth:?}, probe noise {noise:.3?}");
            per_run.push(mean);
        }
        // Noise or bias: how far the runs' distributions are from each other, and how
        // far their average is from the truth (noise shrinks in the average, bias not).
        for pi in 0..points.len() {
            let mut between = Vec::new();
            for (a, ra) in learned.iter().enumerate() {
                for rb in &learned[a + 1..] {
                    between.push(l1(&ra[pi].0, &rb[pi].0));
                }
            }
            let h = mean_histogram(learned.iter().map(|r| &r[pi].0));
            let t = mean_histogram(learned.iter().map(|r| &r[pi].1));
            eprintln!(
                "training {spp:>3} spp point {pi}: L1 between runs {:.3}, of the runs' average {:.3}",
                between.iter().sum::<f64>() / between.len() as f64,
                l1(&h, &t)
            );
        }
        let (m, var) = lanterna::stats::mean_var(&per_run);
        eprintln!(
            "training {spp:>3} spp: mean L1 {m:.3}, sd {:.3}",
            var.sqrt()
        );
        means.push((m, var));
    }
    // It falls from the smallest budget to the next, and never rises beyond the runs'
    // noise after that (it levels off; see the module comment).
    for (k, pair) in means.windows(2).enumerate() {
        let ((m0, v0), (m1, v1)) = (pair[0], pair[1]);
        let se = ((v0 + v1) / RUNS as f64).sqrt();
        if k == 0 {
            assert!(
                m0 - m1 > 2.0 * se,
                "L1 distance does not fall with the training budget: {m0:.3} -> {m1:.3} \
                 (standard error of the difference {se:.3})"
            );
        } else {
            // Past the first step the distance sits on the systematic plateau (about 0.4,
            // see the module comment), where budgets differ by a few hundredths whichever
            // way: the check is for a rise beyond that.
            assert!(
                m1 - m0 < 2.0 * se + PLATEAU_WOBBLE,
                "L1 distance rises with the training budget: {m0:.3} -> {m1:.3} \
                 (standard error of the difference {se:.3})"
            );
        }
    }
    let last = means.last().unwrap().0;
    assert!(
        last < 0.5,
        "L1 distance after the largest budget {last:.3}, expected < 0.5"
    );
    testing::assert_no_validation_errors();
}
