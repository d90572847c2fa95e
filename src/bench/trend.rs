//! Suite `trend` (not in the default run; ask for it with `--suite trend`): the paper's
//! claim that guiding improves with training data, measured as the MAE ratios
//! `guided`/`pt`, `guided-ris`/`ris` (and `guided-ris`/`pt`, `ris`/`pt`) at equal total
//! spp as the number of training paths — pixels × training spp of the guided methods —
//! grows. Each point is one image size and spp budget; each image size gets its own `pt`
//! reference, rendered in two independent halves so that its own MAE is known. Because a
//! reference of finite spp pulls every ratio toward 1, each MAE is also reported with the
//! reference's MAE removed in quadrature (`corrected`), which assumes independent,
//! roughly normal errors.
//!
//! The full sizes run from about 10⁴ to 2 × 10⁸ training paths: on lavapipe (≈ 0.01–0.1 M
//! samples/s on two busy cores) the largest points take days, so `--max-training-paths`
//! caps the run and the skipped points are listed in the results. Besides the JSON, the
//! suite writes `<stem>-trend.csv` and `<stem>-trend.png` (ratio against training paths).

use super::harness::Session;
use super::quality::{self, film_image};
use super::sizes::QualitySize;
pub use super::sizes::TrendSize;
use super::spread::Spread;
use super::{Bench, BenchError, Result};
use crate::eval::metrics::{self, Named};
use crate::eval::plot::{self, RatioLine};
use crate::render::{run, Method};
use std::fmt::Write as _;
use std::path::Path;

/// The paper's MAE ratios to `pt` at 1000 spp on Bistro (1024², so about 3 × 10⁸
/// training paths): guided 0.69, guided-ris 0.41.
pub const PAPER_GUIDED_PT: f64 = 0.69;
pub const PAPER_GUIDED_RIS_PT: f64 = 0.41;

/// One method at one point, over the seeds.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TrendMethod {
    pub method: String,
    /// spp of the final image (guided methods: the render phase and the kept training
    /// passes).
    pub film_spp: u64,
    /// spp spent training (0 for `pt` and `ris`).
    pub training_spp: u64,
    /// pixels × training spp.
    pub training_paths: u64,
    pub seconds: Spread,
    pub mae: Spread,
    /// MAE with the reference's own MAE removed in quadrature.
    pub mae_corrected: Spread,
}

/// A ratio of two methods' MAEs at one point, raw and reference-corrected.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TrendRatio {
    /// `guided/pt`, `guided-ris/ris`, `guided-ris/pt` or `ris/pt`.
    pub name: String,
    pub raw: Spread,
    pub corrected: Spread,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TrendPoint {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Total spp of every method.
    pub spp: u64,
    /// Training paths of the guided methods (pixels × training spp).
    pub training_paths: u64,
    pub reference_spp: u64,
    /// Estimated MAE of the reference itself (half the MAE between its halves).
    pub reference_mae: f64,
    pub methods: Vec<TrendMethod>,
    pub ratios: Vec<TrendRatio>,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Trend {
    /// Seeds of the repetitions (one render per method, point and seed).
    pub seeds: Vec<u32>,
    /// `--max-training-paths`: points above it were not run.
    pub max_training_paths: Option<u64>,
    pub points: Vec<TrendPoint>,
    /// Points of the sizes that were not run, with the reason.
    pub skipped: Vec<String>,
}

/// The ratios the suite reports: (name, numerator, denominator).
pub const RATIOS: [(&str, &str, &str); 4] = [
    ("guided/pt", "guided", "pt"),
    ("guided-ris/ris", "guided-ris", "ris"),
    ("guided-ris/pt", "guided-ris", "pt"),
    ("ris/pt", "ris", "pt"),
];

/// Training spp of a guided render of `spp` in total, as the renderer splits it (30 %,
/// in whole passes of 2^k spp) — only for deciding which points a cap skips; the
/// measured value is recorded from the run.
fn expected_training_paths(pixels: u64, spp: u64) -> u64 {
    (pixels as f64 * spp as f64 * 0.3) as u64
}

fn corrected(mae: f64, reference: f64) -> f64 {
    (mae * mae - reference * reference).max(0.0).sqrt()
}

pub fn run(bench: &Bench) -> Result<Trend> {
    let seeds: Vec<u32> = (0..bench.repeat.max(1) as u32).collect();
    let mut points = Vec::new();
    let mut skipped = Vec::new();
    for size in &bench.sizes.trend {
        let path = bench.scene_path(&size.scene)?;
        let mut session = bench.open(&path, size.width, size.height, Method::Pt)?;
        let pixels = session.pixels();
        let (run_spp, skip_spp): (Vec<u64>, Vec<u64>) = size.spp.iter().partition(|&&spp| {
            bench
                .trend_max_paths
                .is_none_or(|cap| expected_training_paths(pixels, spp) <= cap)
        });
        for spp in skip_spp {
            skipped.push(format!(
                "{} {}×{} at {spp} spp (≈ {:.1e} training paths, above --max-training-paths)",
                size.scene,
                session.width,
                session.height,
                expected_training_paths(pixels, spp) as f64
            ));
        }
        if run_spp.is_empty() {
            continue;
        }
        let q = QualitySize {
            scene: size.scene.clone(),
            width: size.width,
            height: size.height,
            reference_spp: size.reference_spp,
            spp: Vec::new(),
            seconds: Vec::new(),
        };
        let (reference, _, reference_mae) = quality::reference(bench, &mut session, &q)?;
        for spp in run_spp {
            points.push(point(
                bench,
                &mut session,
                size,
                spp,
                &seeds,
                &reference,
                reference_mae,
            )?);
        }
    }
    Ok(Trend {
        seeds,
        max_training_paths: bench.trend_max_paths,
        points,
        skipped,
    })
}

fn point(
    bench: &Bench,
    session: &mut Session,
    size: &TrendSize,
    spp: u64,
    seeds: &[u32],
    reference: &crate::image_io::Image,
    reference_mae: f64,
) -> Result<TrendPoint> {
    let depth = bench.sizes.max_depth;
    let pixels = session.pixels();
    // maes[method][seed]
    let mut methods = Vec::new();
    let mut maes: Vec<(String, Vec<f64>)> = Vec::new();
    for method in Method::ALL {
        let mut seconds = Vec::new();
        let mut mae = Vec::new();
        let mut film_spp = 0;
        let mut training_spp = 0;
        for &seed in seeds {
            let mut settings = session.settings(method);
            settings.seed = seed;
            settings.max_depth = depth;
            session.configure(settings)?;
            log::info!(
                "trend: {} {}×{} {} {spp} spp, seed {seed}",
                size.scene,
                session.width,
                session.height,
                method.name()
            );
            let out = session.run(run::Budget::Spp(spp), 0, true)?;
            let film = out.image.as_ref().expect("kept");
            let image = film_image(film, method, seed, depth, out.seconds)?;
            let m = metrics::mae(
                &Named::new(method.name(), &image),
                &Named::new("reference", reference),
            )
            .map_err(|e| BenchError::Other(e.to_string()))?;
            mae.push(m);
            seconds.push(out.seconds);
            film_spp = out.film_spp;
            training_spp = out.iterations.iter().map(|i| i.spp).sum();
        }
        methods.push(TrendMethod {
            method: method.name().into(),
            film_spp,
            training_spp,
            training_paths: pixels * training_spp,
            seconds: Spread::of(&seconds),
            mae: Spread::of(&mae),
            mae_corrected: Spread::of(
                &mae.iter()
                    .map(|&m| corrected(m, reference_mae))
                    .collect::<Vec<_>>(),
            ),
        });
        maes.push((method.name().to_string(), mae));
    }
    let of = |name: &str| &maes.iter().find(|(m, _)| m == name).expect("method").1;
    let ratios = RATIOS
        .iter()
        .map(|&(name, a, b)| {
            let (a, b) = (of(a), of(b));
            let raw: Vec<f64> = a.iter().zip(b).map(|(x, y)| x / y).collect();
            let cor: Vec<f64> = a
                .iter()
                .zip(b)
                .map(|(x, y)| corrected(*x, reference_mae) / corrected(*y, reference_mae))
                .map(|r| if r.is_finite() { r } else { f64::NAN })
                .collect();
            TrendRatio {
                name: name.into(),
                raw: Spread::of(&raw),
                corrected: Spread::of(&cor),
            }
        })
        .collect();
    let training_paths = methods
        .iter()
        .find(|m| m.method == "guided")
        .map_or(0, |m| m.training_paths);
    Ok(TrendPoint {
        scene: size.scene.clone(),
        width: session.width,
        height: session.height,
        spp,
        training_paths,
        reference_spp: size.reference_spp,
        reference_mae,
        methods,
        ratios,
    })
}

impl Trend {
    /// One row per point and method: the measurements and the point's ratios.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "scene,width,height,spp,training_paths,reference_spp,reference_mae,method,film_spp,\
             training_spp,seconds,mae,mae_corrected",
        );
        for (name, _, _) in RATIOS {
            let _ = write!(s, ",ratio_{name},ratio_{name}_corrected");
        }
        s.push('\n');
        for p in &self.points {
            for m in &p.methods {
                let _ = write!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    p.scene,
                    p.width,
                    p.height,
                    p.spp,
                    p.training_paths,
                    p.reference_spp,
                    p.reference_mae,
                    m.method,
                    m.film_spp,
                    m.training_spp,
                    m.seconds.median,
                    m.mae.median,
                    m.mae_corrected.median
                );
                for r in &p.ratios {
                    let _ = write!(s, ",{},{}", r.raw.median, r.corrected.median);
                }
                s.push('\n');
            }
        }
        s
    }

    /// Ratio against training paths: one line per (scene, ratio), the paper's ratios and
    /// 1 as guides.
    pub fn write_plot(&self, path: &Path) -> Result<()> {
        let mut scenes: Vec<&str> = self.points.iter().map(|p| p.scene.as_str()).collect();
        scenes.dedup();
        scenes.sort();
        scenes.dedup();
        let mut lines = Vec::new();
        for (si, scene) in scenes.iter().enumerate() {
            for (ri, (name, _, _)) in RATIOS.iter().enumerate().take(3) {
                let mut points: Vec<(f64, f64)> = self
                    .points
                    .iter()
                    .filter(|p| p.scene == *scene && p.training_paths > 0)
                    .filter_map(|p| {
                        let r = p.ratios.iter().find(|r| r.name == *name)?;
                        Some((p.training_paths as f64, r.corrected.median))
                    })
                    .filter(|(_, y)| y.is_finite() && *y > 0.0)
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                lines.push(RatioLine {
                    label: format!("{name}, {}", scene.trim_end_matches(".gltf")),
                    color: plot::method_color(["guided", "guided-ris", "ris"][ri], ri),
                    marker: si,
                    points,
                });
            }
        }
        let guides = [
            (1.0, "1 (no gain)".to_string()),
            (PAPER_GUIDED_PT, "paper: guided/pt on Bistro".to_string()),
            (PAPER_GUIDED_RIS_PT, "paper: guided-ris/pt".to_string()),
        ];
        plot::write_ratio_plot(
            path,
            "MAE ratio at equal spp vs training paths (reference-corrected)",
            "training paths of the guided methods (pixels × training spp)",
            &lines,
            &guides,
        )
        .map_err(|e| BenchError::Other(e.to_string()))
    }
}
