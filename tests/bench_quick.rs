//! `lanterna bench --quick` runs end to end (with validation layers on) into a temporary
//! directory and writes a well-formed results file and its Markdown table. Nothing here
//! judges speed: timings are only checked to be positive, finite and ordered
//! (min ≤ median ≤ max); the counters are checked where they are exact (one camera ray
//! per sample, `pt`'s MAE ratio to itself is 1). The Mitsuba part is checked when Python
//! can import mitsuba, and must say why it was skipped otherwise.

use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn mitsuba_available() -> bool {
    Command::new("python3")
        .args(["-c", "import mitsuba"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

fn num(v: &Value, what: &str) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("{what} is not a number: {v}"))
}

/// A min/median/max spread of positive finite values, in order.
fn check_spread(v: &Value, what: &str) {
    let (lo, mid, hi) = (
        num(&v["min"], what),
        num(&v["median"], what),
        num(&v["max"], what),
    );
    assert!(
        lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= mid && mid <= hi,
        "{what}: bad spread {v}"
    );
}

fn methods(list: &Value, what: &str) -> Vec<String> {
    list.as_array()
        .unwrap_or_else(|| panic!("{what} is not a list"))
        .iter()
        .map(|m| m["method"].as_str().expect("method name").to_string())
        .collect()
}

#[test]
fn quick_bench_writes_results() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lanterna"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "--quick", "--validation", "--out"])
        .arg(dir.path())
        .output()
        .expect("run lanterna bench");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "lanterna bench --quick failed:\n{stderr}"
    );

    // One JSON and one Markdown file, named <date>-<device>-quick.
    let mut json_files = Vec::new();
    let mut md_files = Vec::new();
    for e in std::fs::read_dir(dir.path()).unwrap() {
        let p = e.unwrap().path();
        match p.extension().and_then(|x| x.to_str()) {
            Some("json") => json_files.push(p),
            Some("md") => md_files.push(p),
            _ => {}
        }
    }
    assert_eq!(json_files.len(), 1, "{json_files:?}");
    assert_eq!(md_files.len(), 1, "{md_files:?}");
    let json_path = &json_files[0];
    let stem = json_path.file_stem().unwrap().to_str().unwrap();
    assert!(stem.ends_with("-quick"), "{stem}");
    assert_eq!(
        md_files[0],
        json_path.with_extension("md"),
        "the Markdown sits beside the JSON"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(&json_path.display().to_string()),
        "{stdout}"
    );

    let r: Value = serde_json::from_str(&std::fs::read_to_string(json_path).unwrap()).unwrap();
    assert_eq!(r["schema"], 1);
    assert_eq!(r["quick"], true);
    assert_eq!(r["repeat"], 1);
    let date = r["date"].as_str().unwrap();
    assert!(
        date.len() == 10 && date.as_bytes()[4] == b'-' && date.as_bytes()[7] == b'-',
        "{date}"
    );
    assert!(stem.starts_with(date), "{stem} vs {date}");
    assert!(r["command"].as_str().unwrap().starts_with("lanterna bench"));
    let machine = &r["machine"];
    assert!(machine["cpu_cores"].as_u64().unwrap() >= 1);
    assert!(!machine["device"].as_str().unwrap().is_empty());
    assert!(num(&r["total_seconds"], "total_seconds") > 0.0);

    // Traversal: both shipped scenes, four ray sets each, software always timed.
    let tscenes = r["traversal"]["scenes"].as_array().unwrap();
    assert_eq!(tscenes.len(), 2);
    for s in tscenes {
        let sets = s["sets"].as_array().unwrap();
        let names: Vec<&str> = sets.iter().map(|x| x["set"].as_str().unwrap()).collect();
        assert_eq!(names, ["camera", "bounce", "shadow", "probed"]);
        for x in sets {
            let what = format!("traversal {} {}", s["scene"], x["set"]);
            assert!(x["rays"].as_u64().unwrap() > 0, "{what}");
            check_spread(&x["software_mrays_per_s"], &what);
        }
    }

    // Throughput: both shipped scenes with each traversal the device has (software
    // always), every method, exact camera-ray counts.
    let scenes = r["throughput"]["scenes"].as_array().unwrap();
    assert!(
        scenes.len() == 2 || scenes.len() == 4,
        "{} scenes",
        scenes.len()
    );
    assert!(scenes.iter().any(|s| s["traversal"] == "software"));
    for s in scenes {
        assert!(matches!(
            s["traversal"].as_str(),
            Some("software" | "ray-query")
        ));
        let ms = &s["methods"];
        assert_eq!(
            methods(ms, "throughput"),
            ["pt", "ris", "guided", "guided-ris"]
        );
        for m in ms.as_array().unwrap() {
            let what = format!("{} {}", s["scene"], m["method"]);
            check_spread(&m["samples_per_s"], &what);
            check_spread(&m["rays_per_s"], &what);
            check_spread(&m["wall_seconds"], &what);
            check_spread(&m["gpu_seconds"], &what);
            // One camera ray per sample, and one more in pixels with small emitters.
            let camera = num(&m["camera_rays_per_sample"], &what);
            assert!((1.0..=2.0).contains(&camera), "{what}: {camera}");
            assert!(num(&m["bounce_rays_per_sample"], &what) > 0.0, "{what}");
            assert!(num(&m["shadow_rays_per_sample"], &what) > 0.0, "{what}");
            assert_eq!(m["nonfinite_samples"], 0, "{what}");
        }
    }

    // Scaling: two light counts near their targets, growth for every method.
    let scaling = &r["scaling"];
    let points = scaling["points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    for p in points {
        let target = num(&p["target_emissive_triangles"], "target");
        let got = num(&p["emissive_triangles"], "emissive triangles");
        assert!(
            (got - target).abs() <= 0.1 * target,
            "{got} for target {target}"
        );
        assert_eq!(
            methods(&p["methods"], "scaling"),
            ["pt", "ris", "guided", "guided-ris", "pt-d1"]
        );
        for m in p["methods"].as_array().unwrap() {
            check_spread(&m["gpu_seconds_per_spp"], "scaling");
        }
    }
    let growth = scaling["growth"].as_array().unwrap();
    assert_eq!(growth.len(), 5);
    for g in growth {
        assert!(num(&g["gpu"], "growth") > 0.0);
    }

    // Guiding overhead: both guided methods, at least one iteration with a tree.
    let gm = r["guiding"]["methods"].as_array().unwrap();
    assert_eq!(
        methods(&r["guiding"]["methods"], "guiding"),
        ["guided", "guided-ris"]
    );
    for m in gm {
        check_spread(&m["training_seconds"], "training seconds");
        let share = num(&m["refit_upload_share"]["median"], "share");
        assert!((0.0..1.0).contains(&share), "{share}");
        let its = m["iterations"].as_array().unwrap();
        assert!(!its.is_empty());
        for i in its {
            assert!(i["gpu_bytes"].as_u64().unwrap() > 0);
            assert!(i["leaves"].as_u64().unwrap() >= 1);
        }
    }

    // Quality: every method at each budget, ratios to pt.
    let q = &r["quality"]["scenes"][0];
    let records = q["records"].as_array().unwrap();
    assert_eq!(records.len(), 8, "4 methods × (1 spp + 1 time budget)");
    for rec in records {
        check_spread(&rec["mae"], "mae");
        check_spread(&rec["mae_ratio_to_pt"], "ratio");
        if rec["method"] == "pt" {
            assert_eq!(num(&rec["mae_ratio_to_pt"]["median"], "pt ratio"), 1.0);
        }
    }
    assert!(num(&q["reference_mae"], "reference MAE") > 0.0);

    // Mitsuba: measured when installed, else the reason it was skipped.
    if mitsuba_available() {
        let p = &r["mitsuba"]["scenes"][0];
        assert!(
            r["mitsuba"].is_object(),
            "Mitsuba is installed but the suite did not run: {}",
            r["mitsuba_skipped"]
        );
        assert_eq!(p["exact"], true);
        assert_eq!(p["mean_rel_diff"].as_array().unwrap().len(), 3);
        assert!(num(&p["mitsuba_samples_per_s"], "mitsuba rate") > 0.0);
        check_spread(&p["lanterna_samples_per_s"], "lanterna rate");
        assert_eq!(
            methods(&p["lanterna_equal_time"], "equal time"),
            ["pt", "ris", "guided", "guided-ris", "ris --emission-rays 4"],
            "every method, and ris with four camera rays per sample"
        );
        assert!(num(&p["mitsuba_equal_time_mae"], "mitsuba MAE") > 0.0);
        // Both sides report the time their equal-time renders took.
        assert!(num(&p["mitsuba_equal_time_seconds"], "mitsuba seconds") > 0.0);
        for m in p["lanterna_equal_time"].as_array().unwrap() {
            check_spread(&m["seconds"], "lanterna equal-time seconds");
        }
    } else {
        assert!(r["mitsuba_skipped"].is_string(), "{}", r["mitsuba_skipped"]);
    }

    // Profile: the configurations and the parts derived from them.
    let p = &r["profile"];
    let names: Vec<&str> = p["entries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    for want in [
        "pt-d1",
        "pt-d4",
        "ris-m1",
        "ris-m32",
        "guided-render",
        "guided-training",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    assert!(!p["parts"].as_array().unwrap().is_empty());

    let md = std::fs::read_to_string(&md_files[0]).unwrap();
    for heading in [
        "## Throughput",
        "## Light-count scaling",
        "## Guiding overhead",
        "## Quality at equal spp and equal time",
        "## Where the time goes",
    ] {
        assert!(md.contains(heading), "{heading} missing from the Markdown");
    }
    assert!(md.contains("| pt |"), "the tables list the methods");
    assert!(!Path::new(&md_files[0]).with_extension("md.tmp").exists());
}

/// `lanterna bench --quick --suite trend` measures the MAE ratios of the guided methods
/// against training paths on `bistro-night` and writes them as JSON, CSV and a plot.
/// Only the output's shape is checked: every method at every point, the four ratios,
/// training paths that grow with the budget, and a CSV row per point and method.
#[test]
fn quick_trend_writes_ratios_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lanterna"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "--quick", "--suite", "trend", "--out"])
        .arg(dir.path())
        .output()
        .expect("run lanterna bench");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "bench --suite trend failed:\n{stderr}"
    );
    let json_path = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "json"))
        .expect("a results file");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    assert_eq!(r["suites"], serde_json::json!(["trend"]));
    let t = &r["trend"];
    let points = t["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "two spp budgets in quick mode");
    let mut last_paths = 0.0;
    for p in points {
        assert_eq!(p["scene"], "bistro-night.gltf");
        assert_eq!(
            methods(&p["methods"], "trend"),
            ["pt", "ris", "guided", "guided-ris"]
        );
        let paths = num(&p["training_paths"], "training paths");
        assert!(paths > last_paths, "training paths grow: {paths}");
        last_paths = paths;
        assert!(num(&p["reference_mae"], "reference MAE") > 0.0);
        for m in p["methods"].as_array().unwrap() {
            let what = format!("{}", m["method"]);
            check_spread(&m["mae"], &what);
            check_spread(&m["seconds"], &what);
            let guided = m["method"].as_str().unwrap().starts_with("guided");
            assert_eq!(num(&m["training_spp"], &what) > 0.0, guided, "{what}");
        }
        let names: Vec<&str> = p["ratios"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x["name"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            ["guided/pt", "guided-ris/ris", "guided-ris/pt", "ris/pt"]
        );
        for x in p["ratios"].as_array().unwrap() {
            check_spread(&x["raw"], "ratio");
        }
    }
    let stem = json_path.file_stem().unwrap().to_str().unwrap();
    let csv = std::fs::read_to_string(dir.path().join(format!("{stem}-trend.csv"))).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 1 + 2 * 4, "header + a row per point and method");
    let columns = rows[0].split(',').count();
    assert!(rows.iter().all(|r| r.split(',').count() == columns));
    assert!(rows[0].contains("ratio_guided/pt"));
    let png = std::fs::read(dir.path().join(format!("{stem}-trend.png"))).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "{} bytes",
        png.len()
    );
    let md = std::fs::read_to_string(json_path.with_extension("md")).unwrap();
    assert!(md.contains("## Guiding against training paths"));
}
