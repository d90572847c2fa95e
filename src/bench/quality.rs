//! Suite 4, quality: the MAE of every method against a reference at equal spp and at
//! equal time, as ratios to `pt`, through the comparison of `lanterna compare`
//! ([`crate::eval::compare::run_compare`]) with this module's runner. The reference is a
//! `pt` render with a seed no run uses, made of two independent halves: half the MAE
//! between the halves estimates the reference's own error (the floor under every MAE).
//! Each repetition renders the methods with another seed, so the ratios' spread is the
//! estimators' noise as well as the timing's.

use super::harness::Session;
use super::sizes::QualitySize;
use super::spread::Spread;
use super::{Bench, BenchError, Result};
use crate::eval::compare::{run_compare, Budget, CompareConfig, MethodResult, MethodRunner};
use crate::eval::metrics::{self, Named};
use crate::eval::BoxError;
use crate::image_io::{Image, RenderMeta};
use crate::render::{run, Film, Method};

/// The reference's seed: no method run uses it.
pub const REFERENCE_SEED: u32 = 0x5eed_0001;

/// One method at one budget over the repetitions.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct QualityRecord {
    pub method: String,
    /// `spp` or `time`.
    pub budget_kind: String,
    pub budget: f64,
    /// spp rendered within the budget (guided methods: training included).
    pub spp: Spread,
    pub render_seconds: Spread,
    pub mae: Spread,
    pub mae_ratio_to_pt: Spread,
    pub relmse_ratio_to_pt: Spread,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneQuality {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub reference_spp: u64,
    pub reference_seconds: f64,
    /// Estimated MAE of the reference itself (half the MAE between its two halves).
    pub reference_mae: f64,
    /// Seeds of the repetitions.
    pub seeds: Vec<u32>,
    pub records: Vec<QualityRecord>,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Quality {
    pub scenes: Vec<SceneQuality>,
}

/// The comparison's renderer: one session, the method and seed switched per render.
struct Runner<'a> {
    session: &'a mut Session,
    seed: u32,
    max_depth: u32,
}

impl MethodRunner for Runner<'_> {
    fn render(
        &mut self,
        method: &str,
        budget: Budget,
    ) -> std::result::Result<MethodResult, BoxError> {
        let method: Method = method.parse()?;
        let mut settings = self.session.settings(method);
        settings.seed = self.seed;
        settings.max_depth = self.max_depth;
        self.session.configure(settings)?;
        let budget = match budget {
            Budget::Spp(n) => run::Budget::Spp(n),
            Budget::Seconds(s) => run::Budget::Seconds(s),
        };
        let out = self.session.run(budget, 0, true)?;
        let spp = out.total_spp();
        let film = out.image.expect("kept");
        let image = film_image(&film, method, self.seed, self.max_depth, out.seconds)?;
        Ok(MethodResult {
            spp,
            render_seconds: out.seconds,
            setup_seconds: self.session.setup_seconds,
            gpu_seconds: Some(out.stats.gpu_seconds),
            training_seconds: method.uses_guiding().then_some(out.training_seconds),
            image,
        })
    }
}

/// An image (mean and exact sums) of a film.
pub fn film_image(
    film: &Film,
    method: Method,
    seed: u32,
    max_depth: u32,
    seconds: f64,
) -> std::result::Result<Image, crate::image_io::ImageError> {
    let mut meta = RenderMeta::new();
    meta.method = Some(method.name().into());
    meta.spp = Some(film.spp);
    meta.sample_offset = Some(film.sample_offset);
    meta.seed = Some(seed as u64);
    meta.max_depth = Some(max_depth);
    meta.render_seconds = Some(seconds);
    let sums = film
        .sums
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    Image::from_sums(film.width, film.height, sums, meta)
}

pub(crate) fn reference(
    bench: &Bench,
    session: &mut Session,
    size: &QualitySize,
) -> Result<(Image, f64, f64)> {
    let mut settings = session.settings(Method::Pt);
    settings.seed = REFERENCE_SEED;
    settings.max_depth = bench.sizes.max_depth;
    session.configure(settings)?;
    let half = (size.reference_spp / 2).max(1);
    log::info!("quality: {} reference, 2 × {half} spp", size.scene);
    let a = session.run(run::Budget::Spp(half), 0, true)?;
    let b = session.run(run::Budget::Spp(half), half, true)?;
    let seconds = a.seconds + b.seconds;
    let (fa, fb) = (a.image.expect("kept"), b.image.expect("kept"));
    let depth = bench.sizes.max_depth;
    let ia = film_image(&fa, Method::Pt, REFERENCE_SEED, depth, a.seconds)?;
    let ib = film_image(&fb, Method::Pt, REFERENCE_SEED, depth, b.seconds)?;
    // For independent halves X, Y of a mean M = (X + Y)/2 with normal errors,
    // E|M − μ| = E|X − Y| / 2.
    let split = metrics::mae(
        &Named::new("reference half 1", &ia),
        &Named::new("reference half 2", &ib),
    )
    .map_err(|e| BenchError::Other(e.to_string()))?;
    let mut full = fa;
    full.merge(&fb);
    let mut image = film_image(&full, Method::Pt, REFERENCE_SEED, depth, seconds)?;
    image.meta.scene_hash = Some(session.loaded.scene.hash.clone());
    Ok((image, seconds, split / 2.0))
}

pub fn run(bench: &Bench) -> Result<Quality> {
    let mut scenes = Vec::new();
    for size in &bench.sizes.quality {
        let path = bench.scene_path(&size.scene)?;
        let mut session = bench.open(&path, size.width, size.height, Method::Pt)?;
        let (reference, reference_seconds, reference_mae) = reference(bench, &mut session, size)?;
        let methods: Vec<String> = Method::ALL.iter().map(|m| m.name().to_string()).collect();
        let seeds: Vec<u32> = (0..bench.repeat.max(1) as u32).collect();
        let mut all = Vec::new();
        for &seed in &seeds {
            let out_dir = bench.work_dir.join("quality").join(format!(
                "{}-seed{seed}",
                size.scene.trim_end_matches(".gltf")
            ));
            let config = CompareConfig {
                methods: methods.clone(),
                spp: size.spp.clone(),
                seconds: size.seconds.clone(),
                crop: None,
                exposure: 0.0,
                out_dir,
                save_images: false,
                scene: path.display().to_string(),
                reference: format!("pt reference, {} spp", size.reference_spp),
            };
            log::info!("quality: {} with seed {seed}", size.scene);
            let mut runner = Runner {
                session: &mut session,
                seed,
                max_depth: bench.sizes.max_depth,
            };
            let report = run_compare(&mut runner, &reference, &config)?;
            all.push(report.records);
        }
        let mut records = Vec::new();
        if let Some(first) = all.first() {
            for (i, r) in first.iter().enumerate() {
                let same: Vec<_> = all.iter().filter_map(|recs| recs.get(i)).collect();
                records.push(QualityRecord {
                    method: r.method.clone(),
                    budget_kind: r.budget_kind.clone(),
                    budget: r.budget,
                    spp: Spread::over(&same, |x| x.spp as f64),
                    render_seconds: Spread::over(&same, |x| x.render_seconds),
                    mae: Spread::over(&same, |x| x.mae),
                    mae_ratio_to_pt: Spread::over(&same, |x| x.mae_ratio_to_pt.unwrap_or(f64::NAN)),
                    relmse_ratio_to_pt: Spread::over(&same, |x| {
                        x.relmse_ratio_to_pt.unwrap_or(f64::NAN)
                    }),
                });
            }
        }
        scenes.push(SceneQuality {
            scene: size.scene.clone(),
            width: session.width,
            height: session.height,
            reference_spp: size.reference_spp,
            reference_seconds,
            reference_mae,
            seeds,
            records,
        });
    }
    Ok(Quality { scenes })
}
