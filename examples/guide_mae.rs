//! Measure MAE ratios of guided configurations against their unguided twins at equal
//! total spp (training included), several independent runs each, against a reference
//! EXR. The numbers in the README's "Path guiding" table come from this.
//!
//! cargo run --release --example guide_mae -- SCENE REF.exr W H SPP RUNS CONFIG...
//! CONFIG: a method, then `:`-separated options: `fixed=X` (--bsdf-fraction X),
//! `target=all|indirect|contribution`, `iv` (--guided-output inverse-variance),
//! `no-nee` (--no-record-nee), `train=F`.
//! Each configuration's mean MAE is printed with its ratio to `pt` and to `ris` (when
//! those are among the configurations).

use lanterna::guiding::GuideTarget;
use lanterna::lights::LightTable;
use lanterna::render::run::{run_method, Budget};
use lanterna::render::session::{open_device, DeviceOptions};
use lanterna::render::{GuidedOutput, Method, RenderSettings, Renderer};
use lanterna::scene::Scene;
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn parse(config: &str, w: u32, h: u32) -> RenderSettings {
    let mut parts = config.split(':');
    let method: Method = parts.next().unwrap().parse().unwrap();
    let mut s = RenderSettings {
        method,
        width: w,
        height: h,
        ..RenderSettings::default()
    };
    for p in parts {
        match p.split_once('=') {
            Some(("fixed", x)) => {
                s.guiding.learn_selection = false;
                s.guiding.bsdf_fraction = x.parse().unwrap();
            }
            Some(("target", t)) => {
                s.guiding.target = <GuideTarget as clap::ValueEnum>::from_str(t, false).unwrap()
            }
            Some(("train", f)) => s.guiding.train_fraction = f.parse().unwrap(),
            None if p == "iv" => s.guiding.output = GuidedOutput::InverseVariance,
            None if p == "learned" => s.guiding.learn_selection = true,
            None if p == "no-nee" => s.guiding.record_nee = false,
            _ => panic!("unknown option {p}"),
        }
    }
    s
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = Scene::load(Path::new(&args[0]), &Default::default()).unwrap();
    let reference = lanterna::image_io::read_exr(Path::new(&args[1])).unwrap();
    let (w, h): (u32, u32) = (args[2].parse().unwrap(), args[3].parse().unwrap());
    let spp: u64 = args[4].parse().unwrap();
    let runs: u64 = args[5].parse().unwrap();
    assert_eq!((reference.width, reference.height), (w, h));
    let device = open_device(&DeviceOptions {
        selector: Default::default(),
        validation: false,
        debug_printf: false,
    })
    .unwrap();
    let lights = LightTable::build(&scene).unwrap();
    let camera = scene.cameras[0].clone();
    let cancel = AtomicBool::new(false);
    let mut results: Vec<(String, f64, f64)> = Vec::new();
    for config in &args[6..] {
        let settings = parse(config, w, h);
        let mut r = Renderer::new(
            device.clone(),
            &scene,
            &lights,
            camera.clone(),
            settings,
            Default::default(),
        )
        .unwrap();
        let mut maes = Vec::new();
        for run in 0..runs {
            // Disjoint sample ranges: independent runs.
            let out =
                run_method(&mut r, Budget::Spp(spp), run * spp, &cancel, &mut |_| {}).unwrap();
            let img = out.image();
            let mae: f64 = img
                .chunks_exact(3)
                .zip(&reference.rgb)
                .map(|(x, r)| {
                    (0..3)
                        .map(|c| (x[c] as f64 - r[c] as f64).abs())
                        .sum::<f64>()
                        / 3.0
                })
                .sum::<f64>()
                / reference.rgb.len() as f64;
            maes.push(mae);
        }
        let n = maes.len() as f64;
        let mean = maes.iter().sum::<f64>() / n;
        let sd = (maes.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        eprintln!(
            "{config}: MAE {mean:.5} ± {:.5} (runs {maes:.5?})",
            sd / n.sqrt()
        );
        results.push((config.clone(), mean, sd / n.sqrt()));
    }
    let find = |m: &str| results.iter().find(|r| r.0 == m).map(|r| r.1);
    let (pt, ris) = (find("pt"), find("ris"));
    println!("| configuration | MAE | / pt | / ris |");
    println!("|---|---|---|---|");
    for (c, m, se) in &results {
        let ratio = |b: Option<f64>| b.map_or("–".to_string(), |b| format!("{:.3}", m / b));
        println!(
            "| `{c}` | {m:.5} ± {se:.5} | {} | {} |",
            ratio(pt),
            ratio(ris)
        );
    }
}
