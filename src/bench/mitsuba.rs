//! Suite 5 (optional), peer comparison with Mitsuba 3: the scene is exported with
//! [`crate::scene::export_mitsuba`] (same triangles, camera, Lambertian materials and
//! area emitters), lanterna renders independent `pt` batches here, and
//! `scripts/mitsuba_compare.py` renders the export with Mitsuba's `path` integrator at the
//! same max depth and resolution. Its report gives (a) the relative difference of the
//! mean radiance and per-block / per-pixel Welch tests — an independent correctness
//! check, meaningful where the export is exact —, (b) samples per second of both, and
//! a higher-spp Mitsuba reference against which (c) every lanterna method is rendered
//! for the time of one `pt` batch, the time Mitsuba's equal-time render also gets, and
//! scored by MAE. Runs only when `python3 -c "import mitsuba"` works.

use super::harness::Session;
use super::quality::film_image;
use super::sizes::PeerSize;
use super::spread::Spread;
use super::{Bench, BenchError, Result};
use crate::eval::metrics::{self, Named};
use crate::image_io::{read_exr, write_exr};
use crate::render::{run::Budget, Method};
use crate::scene::export_mitsuba::{self, ExportOptions};
use crate::scene::CameraOverride;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Camera rays per sample of the extra equal-time row (`ris --emission-rays 4`: 0.68× the
/// MAE of `ris` at equal time on `street-matte`, README "Rendering").
pub const EQUAL_TIME_EMISSION_RAYS: u32 = 4;

/// Where Drjit finds LLVM ≥ 16 for the `llvm_ad_rgb` variant when
/// `DRJIT_LIBLLVM_PATH` is not set.
pub const LLVM_CANDIDATES: [&str; 2] = [
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
];

/// One lanterna method at Mitsuba's equal time.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EqualTimeMethod {
    pub method: String,
    pub spp: Spread,
    pub mae: Spread,
    /// Seconds the renders took (the budget is a deadline; absent in files from before
    /// 2026-11-23).
    #[serde(default)]
    pub seconds: Spread,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PeerScene {
    pub scene: String,
    /// The export matches lanterna's scene exactly (else the agreement test does not apply).
    pub exact: bool,
    pub approximations: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub mitsuba_variant: String,
    pub mitsuba_version: String,
    /// lanterna `pt` batches × spp, Mitsuba runs × spp.
    pub lanterna_batches: u32,
    pub mitsuba_runs: u32,
    pub spp: u64,
    /// lanterna / Mitsuba − 1 of the image mean, per channel, and its standard error.
    pub mean_rel_diff: Vec<f64>,
    pub mean_rel_diff_stderr: Vec<f64>,
    pub blocks_agree: bool,
    pub blocks_min_p: f64,
    pub pixels_agree: bool,
    pub pixels_min_p: f64,
    /// No test family rejects at the script's α.
    pub agree: bool,
    /// Camera paths per second: lanterna `pt` (over its batches) and Mitsuba `path`.
    pub lanterna_samples_per_s: Spread,
    pub mitsuba_samples_per_s: f64,
    /// lanterna `pt` / Mitsuba samples per second (median).
    pub speed_ratio: f64,
    pub reference_spp: u64,
    /// Seconds of the equal-time renders (one lanterna `pt` batch's time).
    pub equal_time_seconds: f64,
    pub mitsuba_equal_time_spp: u64,
    pub mitsuba_equal_time_mae: f64,
    /// Seconds Mitsuba's equal-time render took (0 in files from before 2026-11-23).
    #[serde(default)]
    pub mitsuba_equal_time_seconds: f64,
    pub lanterna_equal_time: Vec<EqualTimeMethod>,
    /// The lanterna method with the lowest median equal-time MAE.
    pub best_method: String,
    /// Its median MAE / Mitsuba's at equal time.
    pub best_mae_ratio_to_mitsuba: f64,
    /// The script's whole report.
    pub script_report: Value,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Peer {
    pub script: String,
    pub scenes: Vec<PeerScene>,
}

/// Can `python` import mitsuba?
pub fn available(python: &str) -> bool {
    Command::new(python)
        .args(["-c", "import mitsuba"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

fn get_f64(v: &Value, path: &[&str]) -> Result<f64> {
    let mut cur = v;
    for key in path {
        cur = cur.get(key).ok_or_else(|| missing(path))?;
    }
    cur.as_f64().ok_or_else(|| missing(path))
}

fn get_vec(v: &Value, path: &[&str]) -> Result<Vec<f64>> {
    let mut cur = v;
    for key in path {
        cur = cur.get(key).ok_or_else(|| missing(path))?;
    }
    cur.as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .ok_or_else(|| missing(path))
}

fn missing(path: &[&str]) -> BenchError {
    BenchError::Mitsuba(format!(
        "the comparison script's report has no `{}`",
        path.join(".")
    ))
}

fn run_script(
    bench: &Bench,
    size: &PeerSize,
    export: &Path,
    batches: &[PathBuf],
    json: &Path,
) -> Result<Value> {
    let mut cmd = Command::new(&bench.python);
    cmd.arg(&bench.mitsuba_script)
        .arg(export)
        .args(batches)
        .args(["--runs", &size.runs.to_string()])
        .args(["--reference-spp", &size.reference_spp.to_string()])
        .arg("--json")
        .arg(json)
        .arg("-o")
        .arg(export.join("mitsuba.exr"));
    if std::env::var_os("DRJIT_LIBLLVM_PATH").is_none() {
        if let Some(p) = LLVM_CANDIDATES.iter().find(|p| Path::new(p).exists()) {
            cmd.env("DRJIT_LIBLLVM_PATH", p);
        }
    }
    log::info!("mitsuba: running {}", bench.mitsuba_script.display());
    let out = cmd
        .output()
        .map_err(|e| BenchError::Mitsuba(format!("cannot run {}: {e}", bench.python)))?;
    if !out.status.success() {
        return Err(BenchError::Mitsuba(format!(
            "{} failed ({}): {}",
            bench.mitsuba_script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let text = std::fs::read_to_string(json).map_err(|e| BenchError::io(json, e))?;
    serde_json::from_str(&text).map_err(|e| BenchError::Mitsuba(format!("{}: {e}", json.display())))
}

fn scene_peer(bench: &Bench, size: &PeerSize) -> Result<PeerScene> {
    let path = bench.scene_path(&size.scene)?;
    // One directory per row: a scene can have several (short and long budgets), and
    // each row's export, batches and reference must not overwrite another's.
    let dir = bench.work_dir.join("mitsuba").join(format!(
        "{}-{}w-{}spp",
        size.scene.trim_end_matches(".gltf"),
        size.width,
        size.spp
    ));
    let export_dir = dir.join("export");
    let batch_dir = dir.join("lanterna");
    std::fs::create_dir_all(&batch_dir).map_err(|e| BenchError::io(&batch_dir, e))?;
    let depth = bench.sizes.max_depth;
    let mut session: Session = bench.open(&path, size.width, size.height, Method::Pt)?;
    let camera = crate::render::session::choose_camera(
        &session.loaded.scene,
        None,
        &CameraOverride::default(),
    )
    .map_err(BenchError::Scene)?;
    let export = export_mitsuba::export(
        &session.loaded.scene,
        &session.loaded.lights,
        &camera,
        &ExportOptions {
            width: session.width,
            height: session.height,
            max_depth: depth,
            spp: size.spp as u32,
            seed: 0,
            hide_emitters: false,
        },
        &export_dir,
    )
    .map_err(|e| BenchError::Mitsuba(format!("export of {}: {e}", path.display())))?;

    // lanterna's independent pt batches: disjoint sample ranges of one seed.
    let mut settings = session.settings(Method::Pt);
    settings.max_depth = depth;
    session.configure(settings)?;
    session.run(Budget::Spp(bench.sizes.warmup_spp), 1 << 30, false)?;
    let mut files = Vec::new();
    let mut rates = Vec::new();
    let mut first_seconds = 0.0;
    for k in 0..size.batches as u64 {
        let r = session.run(Budget::Spp(size.spp), k * size.spp, true)?;
        let film = r.image.expect("kept");
        let mut image = film_image(&film, Method::Pt, 0, depth, r.seconds)?;
        image.meta.scene_hash = Some(session.loaded.scene.hash.clone());
        image.meta.scene_path = Some(path.display().to_string());
        let file = batch_dir.join(format!("pt_{k}.exr"));
        let _ = write_exr(&file, &image)?;
        files.push(file);
        rates.push((film.spp * session.pixels()) as f64 / r.seconds);
        if k == 0 {
            first_seconds = r.seconds;
        }
    }
    let report = run_script(bench, size, &export_dir, &files, &dir.join("report.json"))?;

    // Every method for the equal-time budget, against Mitsuba's reference.
    let t = report
        .pointer("/mae/equal_time/seconds")
        .and_then(Value::as_f64)
        .unwrap_or(first_seconds);
    let reference_path = export_dir.join("mitsuba_reference.exr");
    let reference = read_exr(&reference_path)?;
    let mut equal_time = Vec::new();
    // Every method with its defaults, and `ris` with more camera rays for the emission
    // seen directly (the pixel-coverage noise of small emitters in view).
    let configs = Method::ALL
        .iter()
        .map(|&m| (m, 1))
        .chain([(Method::Ris, EQUAL_TIME_EMISSION_RAYS)]);
    for (method, emission_rays) in configs {
        let mut settings = session.settings(method);
        settings.max_depth = depth;
        settings.emission_rays = emission_rays;
        let name = if emission_rays > 1 {
            format!("{method} --emission-rays {emission_rays}")
        } else {
            method.name().to_string()
        };
        session.configure(settings.clone())?;
        let mut spp = Vec::new();
        let mut mae = Vec::new();
        let mut seconds = Vec::new();
        for seed in 0..bench.repeat.max(1) as u32 {
            settings.seed = 100 + seed;
            session.renderer.set_settings(settings.clone())?;
            let r = session.run(Budget::Seconds(t), 0, true)?;
            let film = r.image.expect("kept");
            let image = film_image(&film, method, settings.seed, depth, r.seconds)?;
            let label = format!("{name} at {t:.2} s");
            let e = metrics::mae(
                &Named::new(&label, &image),
                &Named::new("Mitsuba reference", &reference),
            )
            .map_err(|e| BenchError::Other(e.to_string()))?;
            spp.push(film.spp as f64);
            mae.push(e);
            seconds.push(r.seconds);
        }
        log::info!(
            "mitsuba: {name} at {t:.2} s: {} spp, MAE {:.4}",
            Spread::of(&spp).median,
            Spread::of(&mae).median
        );
        equal_time.push(EqualTimeMethod {
            method: name,
            spp: Spread::of(&spp),
            mae: Spread::of(&mae),
            seconds: Spread::of(&seconds),
        });
    }
    let best = equal_time
        .iter()
        .min_by(|a, b| a.mae.median.total_cmp(&b.mae.median))
        .expect("five configurations");
    let mitsuba_mae = get_f64(&report, &["mae", "equal_time", "mitsuba", "mae"])?;
    let mitsuba_rate = get_f64(&report, &["performance", "mitsuba_samples_per_s"])?;
    let lanterna_rate = Spread::of(&rates);
    Ok(PeerScene {
        scene: size.scene.clone(),
        exact: export.approximations.is_empty(),
        approximations: export.approximations.clone(),
        width: session.width,
        height: session.height,
        max_depth: depth,
        mitsuba_variant: report
            .pointer("/mitsuba/variant")
            .and_then(Value::as_str)
            .unwrap_or("?")
            .into(),
        mitsuba_version: report
            .pointer("/mitsuba/version")
            .and_then(Value::as_str)
            .unwrap_or("?")
            .into(),
        lanterna_batches: size.batches,
        mitsuba_runs: size.runs,
        spp: size.spp,
        mean_rel_diff: get_vec(&report, &["mean", "rel_diff"])?,
        mean_rel_diff_stderr: get_vec(&report, &["mean", "rel_diff_stderr"])?,
        blocks_agree: report
            .pointer("/blocks/agree")
            .and_then(Value::as_bool)
            .unwrap_or(false),
        blocks_min_p: get_f64(&report, &["blocks", "min_p"])?,
        pixels_agree: report
            .pointer("/pixels/agree")
            .and_then(Value::as_bool)
            .unwrap_or(false),
        pixels_min_p: get_f64(&report, &["pixels", "min_p"])?,
        agree: report
            .get("agree")
            .and_then(Value::as_bool)
            .unwrap_or(false),
        lanterna_samples_per_s: lanterna_rate,
        mitsuba_samples_per_s: mitsuba_rate,
        speed_ratio: lanterna_rate.median / mitsuba_rate,
        reference_spp: size.reference_spp,
        equal_time_seconds: t,
        mitsuba_equal_time_spp: report
            .pointer("/mae/equal_time/mitsuba/spp")
            .and_then(Value::as_u64)
            .unwrap_or(0),
        mitsuba_equal_time_mae: mitsuba_mae,
        mitsuba_equal_time_seconds: report
            .pointer("/mae/equal_time/mitsuba/seconds")
            .and_then(Value::as_f64)
            .unwrap_or(0.0),
        best_method: best.method.clone(),
        best_mae_ratio_to_mitsuba: best.mae.median / mitsuba_mae,
        lanterna_equal_time: equal_time,
        script_report: report,
    })
}

pub fn run(bench: &Bench) -> Result<Peer> {
    let mut scenes = Vec::new();
    for size in &bench.sizes.mitsuba {
        log::info!("mitsuba: {} at width {}", size.scene, size.width);
        scenes.push(scene_peer(bench, size)?);
    }
    Ok(Peer {
        script: bench.mitsuba_script.display().to_string(),
        scenes,
    })
}
