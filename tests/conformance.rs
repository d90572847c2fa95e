//! Light-transport conformance: every method and strategy against an independent
//! reference on small adversarial scenes (`lanterna scene generate sconces |
//! punctual-near | alpha-lights`, see src/scene/generate/conformance.rs).
//!
//! The reference is Mitsuba 3's `path` integrator on the exported scene, rendered live
//! by `scripts/conformance_reference.py` when Python can import mitsuba (CI installs it;
//! `LANTERNA_REQUIRE_MITSUBA=1` makes its absence a failure), else the committed
//! references in `tests/data/conformance/` made by the same script (`make
//! conformance-references`). Both sides leave out emission seen directly by the camera
//! (lanterna `--hide-emitters`; Mitsuba max_depth D minus max_depth 1 with the same
//! seeds): it is the same for every method, and its anti-aliasing noise around small
//! bright lamps would otherwise dominate the image mean's variance.
//!
//! Each configuration renders independent batches (guided ones train their own tree per
//! batch), and must pass two checks against the reference:
//! - per 8×8 block and channel, Welch's t-test on the batch means vs. the reference's
//!   run means, family-wise α = 10⁻⁴ over all blocks, channels and configurations of the
//!   scene (Šidák);
//! - the image mean within 0.5 % of the reference's, plus 3.9 standard errors of the
//!   difference (the same family-wise level; the standard error, printed, is about
//!   0.2–0.4 % at these budgets).
//!
//! Defects each test was seen to fail on (injected once through
//! `LANTERNA_TEST_SHADER_DIR`, or in the Rust code, and reverted):
//! - `sconces_direct_light_every_method`: the shadow ray aimed from an offset origin along
//!   the unmoved direction with `tmax = dist·(1 − 10⁻⁴)` (the code before
//!   `visible_between`): `pt --strategy nee`, block at (8, 8) 0.262 vs 0.368, p = 1e-7;
//!   the MIS weight of emission hits computed with half the light pdf: `pt`, p = 1e-14.
//!   Not caught at this power: a light pdf off by 2 for two-sided emitters in the MIS
//!   weights alone (one small fin: smallest block p 5e-6 for `guided`).
//! - `punctual_lights_near_surfaces`: the spot falloff squared once more: p = 1e-16.
//! - `lamp_behind_alpha_masked_screen`: shadow rays that treat alpha-masked geometry as
//!   opaque: block (8, 0) 0.00001 vs 0.029, p = 2e-16.
//! - `sconces_guiding_options` (learned and fixed selection probability, `indirect` and
//!   `contribution` targets, `--guide-density variance-aware`, the stochastic box
//!   spatial filter): the mixture pdf
//!   evaluated with the header's α while directions are drawn with the leaf's learned α
//!   (2026-11-23): `guided` image mean +5.64 % against an allowance of ±5.35 %; with
//!   `--guide-history 1`, light tables merged with the earlier iteration's but normalised
//!   to 1.25 (2026-11-24): block (0, 8) 0.229 vs 0.266, p = 4e-29.
//! - `sconces_light_reuse`: world-space light reuse with both targets of its MIS weights
//!   evaluated at the reading vertex instead of the writer's rebuilt surface (2026-11-28):
//!   `ris`, block (16, 16) 0.143 vs 0.153, p = 3e-10.
//! - `sconces_far_from_origin`: no rebasing of the scene toward the origin (256-ulp ray
//!   offsets are 0.24 m at 10⁴): block (8, 8) 0.147 vs 0.368, p = 7e-32.

use lanterna::guiding::{GuideDensity, GuideTarget, SelectionLearner, SpatialFilter};
use lanterna::lights::LightTable;
use lanterna::render::{LightSource, Method, RenderSettings, Strategy};
use lanterna::scene::export_mitsuba::{self, ExportOptions};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing::{self, Batches, TestScene};
use std::path::PathBuf;
use std::process::Command;

const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;
const BLOCK: u32 = 8;
/// Family-wise significance of each scene's test family.
const ALPHA: f64 = 1e-4;
/// Allowed relative difference of the image mean beyond its statistical allowance.
const MEAN_TOLERANCE: f64 = 0.005;

/// One configuration of lanterna to check.
#[derive(Clone, Copy, Debug)]
struct Config {
    name: &'static str,
    method: Method,
    strategy: Strategy,
    learn_lights: bool,
    /// None: the BSDF selection probability learned per leaf (the default); Some(x):
    /// fixed (`--bsdf-fraction x`).
    bsdf_fraction: Option<f32>,
    /// How a learned selection probability is learned (`--selection-learner`).
    selection_learner: SelectionLearner,
    target: GuideTarget,
    density: GuideDensity,
    spatial_filter: SpatialFilter,
    /// `--guide-history`.
    history: f32,
    /// `--light-reuse world` (RIS methods).
    light_reuse: bool,
    /// `--light-visibility learned` (RIS methods).
    light_visibility: bool,
    /// `--source`.
    source: LightSource,
}

const fn config(name: &'static str, method: Method, strategy: Strategy) -> Config {
    Config {
        name,
        method,
        strategy,
        learn_lights: false,
        bsdf_fraction: None,
        selection_learner: SelectionLearner::Variance,
        target: GuideTarget::All,
        density: GuideDensity::Radiance,
        spatial_filter: SpatialFilter::Nearest,
        history: 0.0,
        light_reuse: false,
        light_visibility: false,
        source: LightSource::Uniform,
    }
}

const PT: Config = config("pt", Method::Pt, Strategy::Mis);
const PT_NEE: Config = config("pt --strategy nee", Method::Pt, Strategy::Nee);
const PT_BSDF: Config = config("pt --strategy bsdf", Method::Pt, Strategy::Bsdf);
const RIS: Config = config("ris", Method::Ris, Strategy::Mis);
const RIS_NEE: Config = config("ris --strategy nee", Method::Ris, Strategy::Nee);
const GUIDED: Config = config("guided", Method::Guided, Strategy::Mis);
const GUIDED_RIS: Config = config("guided-ris", Method::GuidedRis, Strategy::Mis);
const GUIDED_RIS_LEARN: Config = Config {
    name: "guided-ris --learn-lights",
    learn_lights: true,
    ..GUIDED_RIS
};
// Learned light tables with each leaf's learned mix (`guided`'s defaults).
const GUIDED_LEARN: Config = Config {
    name: "guided --learn-lights",
    learn_lights: true,
    ..GUIDED
};
const GUIDED_FIXED: Config = Config {
    name: "guided --bsdf-fraction 0.5",
    bsdf_fraction: Some(0.5),
    ..GUIDED
};
const GUIDED_KL_ADAM: Config = Config {
    name: "guided --selection-learner kl-adam",
    selection_learner: SelectionLearner::KlAdam,
    ..GUIDED
};
const GUIDED_INDIRECT: Config = Config {
    name: "guided --guide-target indirect",
    target: GuideTarget::Indirect,
    ..GUIDED
};
const GUIDED_RIS_INDIRECT: Config = Config {
    name: "guided-ris --guide-target indirect",
    target: GuideTarget::Indirect,
    ..GUIDED_RIS
};
const GUIDED_CONTRIBUTION: Config = Config {
    name: "guided --guide-target contribution",
    target: GuideTarget::Contribution,
    ..GUIDED
};
// With the paper's target, so that NEE's second-moment records (their pdfs) are used.
const GUIDED_VARIANCE_AWARE: Config = Config {
    name: "guided --guide-density variance-aware --guide-target all",
    density: GuideDensity::VarianceAware,
    ..GUIDED
};
const GUIDED_RIS_VARIANCE_AWARE: Config = Config {
    name: "guided-ris --guide-density variance-aware --guide-target all",
    density: GuideDensity::VarianceAware,
    ..GUIDED_RIS
};

// World-space light reuse (opt-in): reservoirs of earlier samples combined by GRIS.
const RIS_REUSE: Config = Config {
    name: "ris --light-reuse world",
    light_reuse: true,
    ..RIS
};
const GUIDED_RIS_REUSE: Config = Config {
    name: "guided-ris --light-reuse world",
    light_reuse: true,
    ..GUIDED_RIS
};

// Learned light visibility in RIS's target (opt-in), at its default cells and floor.
const RIS_VISIBILITY: Config = Config {
    name: "ris --light-visibility learned",
    light_visibility: true,
    ..RIS
};
const GUIDED_RIS_VISIBILITY: Config = Config {
    name: "guided-ris --light-visibility learned",
    light_visibility: true,
    ..GUIDED_RIS
};
// The light tree's source (`--source tree`).
const PT_TREE: Config = Config {
    name: "pt --source tree",
    source: LightSource::Tree,
    ..PT
};
const RIS_TREE: Config = Config {
    name: "ris --source tree",
    source: LightSource::Tree,
    ..RIS
};
const GUIDED_TREE: Config = Config {
    name: "guided --source tree",
    source: LightSource::Tree,
    ..GUIDED_LEARN
};

// The reference implementation's stochastic box filter (the default is nearest).
const GUIDED_RIS_JITTER: Config = Config {
    name: "guided-ris --spatial-filter jitter",
    spatial_filter: SpatialFilter::StochasticBox,
    ..GUIDED_RIS
};

// Every training record so far in each refit, quadtrees and learned light tables.
const GUIDED_RIS_HISTORY: Config = Config {
    name: "guided-ris --learn-lights --guide-history 1",
    history: 1.0,
    ..GUIDED_RIS_LEARN
};

/// The reference: block and image means with their standard errors.
struct Reference {
    runs: usize,
    mean: [f64; 3],
    mean_se: [f64; 3],
    /// [block row][block column][channel]
    block_mean: Vec<Vec<[f64; 3]>>,
    block_se: Vec<Vec<[f64; 3]>>,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn parse_reference(v: &serde_json::Value) -> Reference {
    let triple = |x: &serde_json::Value| -> [f64; 3] {
        let a = x.as_array().expect("three channels");
        [0, 1, 2].map(|c| a[c].as_f64().unwrap())
    };
    let grid = |x: &serde_json::Value| -> Vec<Vec<[f64; 3]>> {
        x.as_array()
            .unwrap()
            .iter()
            .map(|row| row.as_array().unwrap().iter().map(triple).collect())
            .collect()
    };
    Reference {
        runs: v["runs"].as_u64().unwrap() as usize,
        mean: triple(&v["mean"]),
        mean_se: triple(&v["mean_stderr"]),
        block_mean: grid(&v["block_mean"]),
        block_se: grid(&v["block_stderr"]),
    }
}

/// The reference for `ts` at `max_depth`: rendered live by Mitsuba when available (and
/// then also written to `tests/data/conformance/` when `LANTERNA_WRITE_REFERENCES=1`),
/// else the committed one, which must be of the same scene.
fn reference(name: &str, ts: &TestScene, max_depth: u32) -> Reference {
    let lights = LightTable::build(&ts.scene).expect("light table");
    let export_dir = ts.dir.0.join("mitsuba");
    let summary = export_mitsuba::export(
        &ts.scene,
        &lights,
        &ts.camera,
        &ExportOptions {
            width: WIDTH,
            height: HEIGHT,
            max_depth,
            spp: 1,
            seed: 0,
            hide_emitters: false,
        },
        &export_dir,
    )
    .expect("export to Mitsuba");
    assert!(
        summary.approximations.is_empty(),
        "{name}: the export is not exact: {:?}",
        summary.approximations
    );
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(export_dir.join(export_mitsuba::MANIFEST)).unwrap(),
    )
    .unwrap();
    let hash = manifest["scene_hash"].as_str().unwrap().to_string();
    let committed = root().join(format!("tests/data/conformance/{name}.json"));
    if let Some(python) = testing::mitsuba_python() {
        let out = ts.dir.0.join("reference.json");
        let status = Command::new(python)
            .arg(root().join("scripts/conformance_reference.py"))
            .arg(&export_dir)
            .arg("-o")
            .arg(&out)
            .args([
                "--runs",
                "16",
                "--spp",
                "2048",
                "--block",
                &BLOCK.to_string(),
            ])
            .status()
            .expect("run scripts/conformance_reference.py");
        assert!(status.success(), "conformance_reference.py failed");
        let text = std::fs::read_to_string(&out).unwrap();
        if writing_references() {
            std::fs::create_dir_all(committed.parent().unwrap()).unwrap();
            std::fs::write(&committed, &text).unwrap();
        }
        println!("{name}: live Mitsuba reference");
        return parse_reference(&serde_json::from_str(&text).unwrap());
    }
    assert!(
        std::env::var("LANTERNA_REQUIRE_MITSUBA").map_or(true, |v| v != "1"),
        "LANTERNA_REQUIRE_MITSUBA=1 but no Python here imports mitsuba"
    );
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&committed)
            .unwrap_or_else(|e| panic!("{}: {e}", committed.display())),
    )
    .unwrap();
    assert_eq!(
        v["scene_hash"].as_str(),
        Some(hash.as_str()),
        "{name}: the generated scene changed; regenerate the committed reference \
         (LANTERNA_WRITE_REFERENCES=1 cargo test --release --test conformance)"
    );
    println!("{name}: committed Mitsuba reference (python cannot import mitsuba)");
    parse_reference(&v)
}

/// `LANTERNA_WRITE_REFERENCES=1`: only render and write the committed references.
fn writing_references() -> bool {
    std::env::var("LANTERNA_WRITE_REFERENCES").is_ok_and(|v| v == "1")
}

fn scene(kind: Kind, offset: Option<[f32; 3]>) -> TestScene {
    testing::generated(
        kind,
        &Options {
            offset,
            ..Options::default()
        },
    )
}

fn render(ts: &TestScene, c: Config, max_depth: u32, batches: u32, spp: u64) -> Batches {
    let settings = RenderSettings {
        max_depth,
        strategy: c.strategy,
        hide_emitters: true,
        guiding: lanterna::render::GuidingSettings {
            learn_lights: c.learn_lights,
            learn_selection: c.bsdf_fraction.is_none(),
            bsdf_fraction: c.bsdf_fraction.unwrap_or(0.5),
            selection_learner: c.selection_learner,
            target: c.target,
            density: c.density,
            spatial_filter: c.spatial_filter,
            history: c.history,
            ..Default::default()
        },
        light_reuse: lanterna::render::LightReuse {
            world: c.light_reuse,
            ..Default::default()
        },
        light_visibility: lanterna::render::LightVisibility {
            learned: c.light_visibility,
            ..Default::default()
        },
        source: c.source,
        ..testing::settings(c.method, WIDTH, HEIGHT)
    };
    testing::run_batches(&ts.scene, &ts.camera, settings, batches, spp)
}

/// Checks `b` against `r` (see the module comment); `tests` is the size of the scene's
/// test family. Returns a line for the log.
fn check(name: &str, c: Config, b: &Batches, r: &Reference, tests: usize) -> String {
    let n = b.images.len();
    let per_test = lanterna::stats::sidak(ALPHA, tests);
    // Blocks.
    let est = b.block_estimates(BLOCK);
    let bx = WIDTH.div_ceil(BLOCK) as usize;
    let mut worst = (1.0f64, 0usize);
    for (i, e) in est.iter().enumerate() {
        let (blk, ch) = (i / 3, i % 3);
        let (row, col) = (blk / bx, blk % bx);
        let (m, v) = lanterna::stats::mean_var(e);
        let rm = r.block_mean[row][col][ch];
        let rse = r.block_se[row][col][ch];
        if m == 0.0 && rm == 0.0 {
            continue;
        }
        let p = lanterna::stats::welch_summary((m, v / n as f64, n), (rm, rse * rse, r.runs));
        if p < worst.0 {
            worst = (p, i);
        }
    }
    let (p, i) = worst;
    let (blk, ch) = (i / 3, i % 3);
    let (row, col) = (blk / bx, blk % bx);
    let (m, _) = lanterna::stats::mean_var(&est[i]);
    assert!(
        p >= per_test,
        "{name}, {}: block ({}, {}) channel {ch}: lanterna {m:.5} vs reference {:.5} ± {:.5}, \
         p = {p:.2e} < {per_test:.2e}",
        c.name,
        col as u32 * BLOCK,
        row as u32 * BLOCK,
        r.block_mean[row][col][ch],
        r.block_se[row][col][ch]
    );
    // Image mean.
    let z = {
        // Two-sided normal quantile of the per-test level, by bisection.
        let (mut lo, mut hi) = (0.0f64, 10.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if 2.0 * (1.0 - lanterna::stats::normal_cdf(mid)) > per_test {
                lo = mid
            } else {
                hi = mid
            }
        }
        hi
    };
    let means = b.channel_means();
    let mut line = format!("{name}, {}: block p_min {p:.2e}, mean rel. diff", c.name);
    for ch in 0..3 {
        let (m, v) = lanterna::stats::mean_var(&means.iter().map(|x| x[ch]).collect::<Vec<_>>());
        let rel = (m - r.mean[ch]) / r.mean[ch];
        let se = ((v / n as f64) + r.mean_se[ch].powi(2)).sqrt() / r.mean[ch];
        assert!(
            rel.abs() <= MEAN_TOLERANCE + z * se,
            "{name}, {}: image mean channel {ch}: lanterna {m:.5} vs reference {:.5}: \
             {:+.2} % (allowed ±{:.2} % = 0.5 % + {z:.1} × s.e. {:.2} %)",
            c.name,
            r.mean[ch],
            100.0 * rel,
            100.0 * (MEAN_TOLERANCE + z * se),
            100.0 * se
        );
        line += &format!(" {:+.2}±{:.2}%", 100.0 * rel, 100.0 * se);
    }
    line
}

/// A reference made of lanterna's own batches (for scenes Mitsuba cannot express).
fn reference_from_batches(b: &Batches) -> Reference {
    let n = b.images.len() as f64;
    let bx = WIDTH.div_ceil(BLOCK) as usize;
    let by = HEIGHT.div_ceil(BLOCK) as usize;
    let mut block_mean = vec![vec![[0.0; 3]; bx]; by];
    let mut block_se = vec![vec![[0.0; 3]; bx]; by];
    for (i, e) in b.block_estimates(BLOCK).iter().enumerate() {
        let (m, v) = lanterna::stats::mean_var(e);
        let (blk, ch) = (i / 3, i % 3);
        block_mean[blk / bx][blk % bx][ch] = m;
        block_se[blk / bx][blk % bx][ch] = (v / n).sqrt();
    }
    let means = b.channel_means();
    let (mut mean, mut mean_se) = ([0.0; 3], [0.0; 3]);
    for ch in 0..3 {
        let (m, v) = lanterna::stats::mean_var(&means.iter().map(|x| x[ch]).collect::<Vec<_>>());
        mean[ch] = m;
        mean_se[ch] = (v / n).sqrt();
    }
    Reference {
        runs: b.images.len(),
        mean,
        mean_se,
        block_mean,
        block_se,
    }
}

fn run_suite(
    name: &str,
    ts: &TestScene,
    max_depth: u32,
    configs: &[Config],
    batches: u32,
    spp: u64,
) {
    let r = reference(name, ts, max_depth);
    if writing_references() {
        return;
    }
    let blocks = (WIDTH.div_ceil(BLOCK) * HEIGHT.div_ceil(BLOCK) * 3) as usize;
    let tests = configs.len() * (blocks + 3);
    for &c in configs {
        let b = render(ts, c, max_depth, batches, spp);
        println!("{}", check(name, c, &b, &r, tests));
    }
    testing::assert_no_validation_errors();
}

/// Lamps on, near and inside walls and ledges, direct light (max depth 2): where the
/// shadow ray's geometry matters most. Every method and strategy.
#[test]
fn sconces_direct_light_every_method() {
    let ts = scene(Kind::Sconces, None);
    run_suite(
        "sconces-d2",
        &ts,
        2,
        &[
            PT,
            PT_NEE,
            PT_BSDF,
            RIS,
            RIS_NEE,
            GUIDED,
            GUIDED_RIS,
            GUIDED_RIS_LEARN,
        ],
        16,
        128,
    );
}

/// The same room with three more bounces (the paper's max path length).
#[test]
fn sconces_global_illumination() {
    let ts = scene(Kind::Sconces, None);
    run_suite("sconces-d4", &ts, 4, &[PT, RIS, GUIDED_RIS], 16, 128);
}

/// World-space light reuse (`--light-reuse world`) with indirect light: `ris` and
/// `guided-ris` reusing earlier samples' reservoirs, at the default cap and cells.
#[test]
fn sconces_light_reuse() {
    let ts = scene(Kind::Sconces, None);
    run_suite(
        "sconces-d4",
        &ts,
        4,
        &[RIS_REUSE, GUIDED_RIS_REUSE],
        16,
        128,
    );
}

/// Learned light visibility (`--light-visibility learned`) with indirect light: `ris` and
/// `guided-ris` with each light's target weighted by its learned unoccluded share, at the
/// default cells and floor.
#[test]
fn sconces_learned_visibility() {
    let ts = scene(Kind::Sconces, None);
    run_suite(
        "sconces-d4",
        &ts,
        4,
        &[RIS_VISIBILITY, GUIDED_RIS_VISIBILITY],
        16,
        128,
    );
}

/// The light tree's source (`--source tree`) with indirect light: lamps on, near and
/// inside walls and ledges, whose bounds put some emitters behind the shading point.
#[test]
fn sconces_light_tree() {
    let ts = scene(Kind::Sconces, None);
    run_suite(
        "sconces-d4",
        &ts,
        4,
        &[PT_TREE, RIS_TREE, GUIDED_TREE],
        16,
        128,
    );
}

/// Point and spot lights centimetres from surfaces under the light tree's source: a spot
/// whose cone bound must hold every direction it lights.
#[test]
fn punctual_lights_near_surfaces_light_tree() {
    let ts = scene(Kind::PunctualNear, None);
    run_suite("punctual-near-d2", &ts, 2, &[PT_TREE, RIS_TREE], 16, 128);
}

/// The guiding options (selection probability learned by either learner or fixed, what the tree learns,
/// which statistic of it)
/// with indirect light, where the guide samples more than direct light.
#[test]
fn sconces_guiding_options() {
    let ts = scene(Kind::Sconces, None);
    run_suite(
        "sconces-d4",
        &ts,
        4,
        &[
            GUIDED,
            GUIDED_LEARN,
            GUIDED_FIXED,
            GUIDED_KL_ADAM,
            GUIDED_INDIRECT,
            GUIDED_RIS_INDIRECT,
            GUIDED_CONTRIBUTION,
            GUIDED_VARIANCE_AWARE,
            GUIDED_RIS_VARIANCE_AWARE,
            GUIDED_RIS_JITTER,
            GUIDED_RIS_HISTORY,
        ],
        16,
        128,
    );
}

/// The room 10⁴ units from the origin, against the reference of the room at the origin:
/// ray offsets must scale with the coordinates without losing the lamps 1–5 cm from
/// the walls.
#[test]
fn sconces_far_from_origin() {
    let at_origin = scene(Kind::Sconces, None);
    let r = reference("sconces-d2", &at_origin, 2);
    if writing_references() {
        return;
    }
    let far = scene(Kind::Sconces, Some([1.0e4, 0.0, 1.0e4]));
    let configs = [PT, RIS];
    let blocks = (WIDTH.div_ceil(BLOCK) * HEIGHT.div_ceil(BLOCK) * 3) as usize;
    for c in configs {
        let b = render(&far, c, 2, 16, 128);
        println!(
            "{}",
            check("sconces-far", c, &b, &r, configs.len() * (blocks + 3))
        );
    }
}

/// Point and spot lights 1–5 cm from walls, a box top and the ceiling corner; the guided
/// methods also with learned light tables, which hold these punctual lights since
/// 2026-11-27 (seen to fail with a table-chosen punctual light weighted by the source
/// pmf alone).
#[test]
fn punctual_lights_near_surfaces() {
    let ts = scene(Kind::PunctualNear, None);
    run_suite(
        "punctual-near-d2",
        &ts,
        2,
        &[PT, RIS, GUIDED_RIS, GUIDED_LEARN, GUIDED_RIS_LEARN],
        16,
        128,
    );
}

/// A lantern, a lamp inside an alpha-masked lattice cage: Mitsuba has no exact alpha test, so direct
/// light found by direction sampling alone (`--strategy bsdf`, no shadow rays) is the
/// reference, rendered with 4× the samples.
#[test]
fn lamp_behind_alpha_masked_screen() {
    let ts = scene(Kind::AlphaLights, None);
    if writing_references() {
        return;
    }
    let r = reference_from_batches(&render(&ts, PT_BSDF, 2, 16, 512));
    let configs = [PT, PT_NEE, RIS, GUIDED_RIS];
    let blocks = (WIDTH.div_ceil(BLOCK) * HEIGHT.div_ceil(BLOCK) * 3) as usize;
    for c in configs {
        let b = render(&ts, c, 2, 16, 128);
        println!(
            "{}",
            check("alpha-lights-d2", c, &b, &r, configs.len() * (blocks + 3))
        );
    }
    testing::assert_no_validation_errors();
}
