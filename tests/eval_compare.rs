//! `compare` with a fake runner: every report file is written, `report.json` parses with
//! the documented fields and ratios, the CSV has one row per render, and the figures
//! decode at the expected sizes. Runner failures and NaN renders are clear errors.

use std::path::Path;

use lanterna::eval::compare::{
    run_compare, Budget, CompareConfig, CompareError, Crop, MethodResult, MethodRunner, METHODS,
    REPORT_FILES,
};
use lanterna::eval::grid::panel_size;
use lanterna::eval::plot::PLOT_SIZE;
use lanterna::eval::BoxError;
use lanterna::image_io::{read_exr, Image, RenderMeta};

const W: u32 = 48;
const H: u32 = 32;

fn reference() -> Image {
    let rgb = (0..W * H)
        .map(|i| {
            let (x, y) = ((i % W) as f32 / W as f32, (i / W) as f32 / H as f32);
            [0.2 + 0.6 * x, 0.3 + 0.5 * y, 0.5 * (1.0 - x * y)]
        })
        .collect();
    let mut image = Image::new(W, H, rgb).unwrap();
    image.meta.spp = Some(65536);
    image
}

/// Noise ∝ 1/√spp with a per-method constant; equal time reaches spp = rate · seconds.
struct FakeRunner {
    reference: Image,
    calls: Vec<(String, Budget)>,
    nan_for: Option<&'static str>,
    fail_for: Option<&'static str>,
}

fn hash(a: u64) -> f32 {
    let mut x = a.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    ((x >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
}

impl MethodRunner for FakeRunner {
    fn render(&mut self, method: &str, budget: Budget) -> Result<MethodResult, BoxError> {
        self.calls.push((method.to_string(), budget));
        if self.fail_for == Some(method) {
            return Err("out of device memory (simulated)".into());
        }
        let (noise, rate) = match method {
            "pt" => (1.0, 400.0),
            "ris" => (0.6, 300.0),
            "guided" => (0.5, 200.0),
            _ => (0.3, 150.0),
        };
        let spp = match budget {
            Budget::Spp(n) => n,
            Budget::Seconds(s) => ((s * rate) as u64).max(1),
        };
        let sigma = noise / (spp as f32).sqrt();
        let m = METHODS.iter().position(|x| *x == method).unwrap() as u64;
        let mut rgb: Vec<[f32; 3]> = self
            .reference
            .rgb
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let k = (m << 50) ^ (spp << 24) ^ (i as u64) << 2;
                [0, 1, 2].map(|c| (p[c] + sigma * hash(k + c as u64)).max(0.0))
            })
            .collect();
        if self.nan_for == Some(method) {
            rgb[W as usize + 3][1] = f32::NAN;
        }
        let mut image = Image::new(W, H, rgb).unwrap();
        image.meta = RenderMeta {
            spp: Some(spp),
            method: Some(method.into()),
            ..RenderMeta::new()
        };
        Ok(MethodResult {
            spp,
            render_seconds: spp as f64 / rate,
            setup_seconds: 0.25,
            gpu_seconds: Some(spp as f64 / rate * 0.9),
            training_seconds: method
                .starts_with("guided")
                .then_some(spp as f64 / rate * 0.1),
            image,
        })
    }
}

fn runner() -> FakeRunner {
    FakeRunner {
        reference: reference(),
        calls: Vec::new(),
        nan_for: None,
        fail_for: None,
    }
}

fn config(dir: &Path) -> CompareConfig {
    CompareConfig {
        methods: METHODS.iter().map(|m| m.to_string()).collect(),
        spp: vec![1, 4, 16, 64],
        seconds: vec![0.05, 0.2],
        crop: Some(Crop {
            x: 8,
            y: 4,
            w: 16,
            h: 12,
        }),
        exposure: 0.0,
        out_dir: dir.to_path_buf(),
        save_images: true,
        scene: "scenes/fake.gltf".into(),
        reference: "fake-ref.exr".into(),
    }
}

#[test]
fn writes_every_file_with_sensible_contents() {
    let dir = tempfile::tempdir().unwrap();
    // Set LANTERNA_TEST_OUT=DIR to keep the report for looking at the figures.
    let out = match std::env::var_os("LANTERNA_TEST_OUT") {
        Some(d) => std::path::PathBuf::from(d),
        None => dir.path().join("report"),
    };
    let cfg = config(&out);
    let mut r = runner();
    let report = run_compare(&mut r, &reference(), &cfg).unwrap();
    assert_eq!(r.calls.len(), 4 * 6);
    assert_eq!(r.calls[0], ("pt".to_string(), Budget::Spp(1)));
    assert_eq!(
        r.calls[23],
        ("guided-ris".to_string(), Budget::Seconds(0.2))
    );
    for f in REPORT_FILES {
        assert!(out.join(f).is_file(), "{f} missing");
    }

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["scene"], "scenes/fake.gltf");
    assert_eq!(json["reference_spp"], 65536);
    assert_eq!(json["width"], W);
    assert_eq!(json["grid_budget"], "0.2 s");
    let records = json["records"].as_array().unwrap();
    assert_eq!(records.len(), 24);
    for field in [
        "method",
        "budget_kind",
        "budget",
        "spp",
        "render_seconds",
        "setup_seconds",
        "gpu_seconds",
        "training_seconds",
        "mae",
        "relmse",
        "mae_ratio_to_pt",
        "relmse_ratio_to_pt",
        "image",
    ] {
        assert!(
            records.iter().all(|r| r.get(field).is_some()),
            "field {field}"
        );
    }
    for r in &report.records {
        if r.method == "pt" {
            assert_eq!(r.mae_ratio_to_pt, Some(1.0));
        } else {
            let pt = report
                .records
                .iter()
                .find(|p| {
                    p.method == "pt" && p.budget_kind == r.budget_kind && p.budget == r.budget
                })
                .unwrap();
            assert_eq!(r.mae_ratio_to_pt, Some(r.mae / pt.mae));
            assert_eq!(r.relmse_ratio_to_pt, Some(r.relmse / pt.relmse));
        }
        assert!(r.mae > 0.0 && r.relmse > 0.0);
        // The saved render reads back with the same error.
        let image = read_exr(&out.join(r.image.as_ref().unwrap())).unwrap();
        assert_eq!(image.meta.spp, Some(r.spp));
    }
    // Less noise, less error: guided-ris at 64 spp beats pt at 64 spp by ~1/0.3.
    let at = |m: &str, n: f64| {
        report
            .records
            .iter()
            .find(|r| r.method == m && r.budget_kind == "spp" && r.budget == n)
            .unwrap()
    };
    let ratio = at("guided-ris", 64.0).mae_ratio_to_pt.unwrap();
    assert!((0.2..0.45).contains(&ratio), "{ratio}");
    assert!(at("pt", 64.0).mae < at("pt", 1.0).mae / 4.0);
    // Equal time: the spp reached is recorded.
    let t = report
        .records
        .iter()
        .find(|r| r.method == "pt" && r.budget_kind == "time" && r.budget == 0.2)
        .unwrap();
    assert_eq!(t.spp, 80);

    let csv = std::fs::read_to_string(out.join("report.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 25);
    assert!(lines[0].starts_with("method,budget_kind,budget,spp,"));
    assert_eq!(lines[1].split(',').count(), lines[0].split(',').count());
    assert!(lines[1].starts_with("pt,spp,1,1,"));

    for plot in ["mae_vs_spp.png", "mae_vs_time.png"] {
        let img = image::open(out.join(plot)).unwrap();
        assert_eq!((img.width(), img.height()), PLOT_SIZE, "{plot}");
    }
    let grid = image::open(out.join("grid.png")).unwrap();
    let (pw, ph) = panel_size(W, H);
    assert!(
        grid.width() > 5 * pw && grid.width() < 5 * pw + 250,
        "{}",
        grid.width()
    );
    assert!(
        grid.height() > 3 * ph,
        "three rows of panels (images, errors, crops): {}",
        grid.height()
    );

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert_eq!(html.matches("data:image/png;base64,").count(), 3);
    assert!(html.contains("guided-ris") && html.contains("<table>"));
    assert!(
        !html.contains("src=\"mae"),
        "figures are inlined, not linked"
    );
}

#[test]
fn spp_only_without_crop_or_pt() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config(dir.path());
    cfg.methods = vec!["guided".into(), "ris".into()];
    cfg.seconds.clear();
    cfg.crop = None;
    cfg.save_images = false;
    let report = run_compare(&mut runner(), &reference(), &cfg).unwrap();
    assert_eq!(report.grid_budget, "64 spp");
    assert!(report
        .records
        .iter()
        .all(|r| r.mae_ratio_to_pt.is_none() && r.image.is_none()));
    for f in REPORT_FILES {
        assert!(dir.path().join(f).is_file(), "{f} missing");
    }
    assert!(!dir.path().join("images").exists());
    let grid = image::open(dir.path().join("grid.png")).unwrap();
    let (pw, _) = panel_size(W, H);
    assert!(grid.width() > 3 * pw && grid.width() < 3 * pw + 250);
}

#[test]
fn runner_failure_and_nan_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path());
    let mut r = runner();
    r.fail_for = Some("guided");
    let e = run_compare(&mut r, &reference(), &cfg).unwrap_err();
    assert!(matches!(e, CompareError::Runner { .. }));
    let chain = format!("{e}: {}", std::error::Error::source(&e).unwrap());
    assert!(
        chain.contains("guided at 1 spp") && chain.contains("out of device memory"),
        "{chain}"
    );

    let mut r = runner();
    r.nan_for = Some("ris");
    let e = run_compare(&mut r, &reference(), &cfg).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("ris at 1 spp") && msg.contains("(3, 1)") && msg.contains("NaN"),
        "{msg}"
    );

    let mut bad_ref = reference();
    bad_ref.rgb[0][0] = f32::INFINITY;
    let msg = run_compare(&mut runner(), &bad_ref, &cfg)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("fake-ref.exr") && msg.contains("(0, 0)"),
        "{msg}"
    );

    let mut cfg2 = config(dir.path());
    cfg2.crop = Some(Crop {
        x: 40,
        y: 0,
        w: 16,
        h: 4,
    });
    let msg = run_compare(&mut runner(), &reference(), &cfg2)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("does not fit") && msg.contains("48x32"),
        "{msg}"
    );
}
