//! The method comparison: every method is rendered at every budget (equal spp, then equal
//! wall-clock time) through a [`MethodRunner`], scored against the reference, and the
//! results written as a report (`report.json`, `report.csv`, `mae_vs_spp.png`,
//! `mae_vs_time.png`, `grid.png`, `index.html`) into the output directory. Rendering is
//! behind the trait so the whole pipeline runs with a fake runner in tests.

use std::path::{Path, PathBuf};

pub use super::compare_types::{Budget, CompareError, Crop};
use super::metrics::{self, Named};
use super::report::{self, Record, Report};
use super::BoxError;
use super::{grid, html, plot};
use crate::image_io::{write_atomically, write_exr, Image};

/// The methods lanterna implements, in their canonical order.
pub const METHODS: [&str; 4] = ["pt", "ris", "guided", "guided-ris"];

/// What a runner returns for one render.
#[derive(Clone, Debug)]
pub struct MethodResult {
    /// Samples per pixel the method rendered within the budget (for time budgets, how
    /// many the time allowed); guided methods count their training passes, of which
    /// the image may keep only some (`GuidedOutput`).
    pub spp: u64,
    /// Wall-clock seconds of rendering only, including guided training passes.
    pub render_seconds: f64,
    /// Scene load + acceleration-structure build seconds (not part of the budget).
    pub setup_seconds: f64,
    /// Seconds of GPU work (timestamp queries), when measured.
    pub gpu_seconds: Option<f64>,
    /// Seconds spent training the guiding structure (guided methods), part of `render_seconds`.
    pub training_seconds: Option<f64>,
    /// The rendered image, same resolution as the reference.
    pub image: Image,
}

/// The renderer as the comparison sees it. The lead implements this over the GPU
/// renderer; tests use a fake.
pub trait MethodRunner {
    /// Renders `method` (one of [`METHODS`]) within `budget`. For [`Budget::Spp`] the
    /// result must hold exactly that many spp; for [`Budget::Seconds`] rendering stops
    /// once the wall-clock budget is used up (whole passes) and `spp` says how far it got.
    fn render(&mut self, method: &str, budget: Budget) -> Result<MethodResult, BoxError>;

    /// Called once before the first render with every method the comparison will run
    /// (e.g. to compile their kernels side by side). Does nothing unless implemented.
    fn prepare(&mut self, _methods: &[String]) -> Result<(), BoxError> {
        Ok(())
    }
}

/// Everything the comparison needs besides the runner and the reference.
#[derive(Clone, Debug)]
pub struct CompareConfig {
    /// Methods in the order they are run and shown (need not include `pt`, but ratios
    /// are relative to it).
    pub methods: Vec<String>,
    /// Equal-spp budgets, ascending.
    pub spp: Vec<u64>,
    /// Equal-time budgets in seconds, ascending.
    pub seconds: Vec<f64>,
    pub crop: Option<Crop>,
    /// Tonemapping exposure (stops) for the grid.
    pub exposure: f32,
    pub out_dir: PathBuf,
    /// Also write every render as `images/<method>_<budget>.exr`.
    pub save_images: bool,
    /// Scene path, reference path: shown in the report.
    pub scene: String,
    pub reference: String,
}

impl CompareConfig {
    /// Checks the settings against the reference's size.
    pub fn validate(&self, reference: &Image) -> Result<(), CompareError> {
        let bad = |m: String| Err(CompareError::Config(m));
        if self.methods.is_empty() {
            return bad("no methods given".into());
        }
        for (i, m) in self.methods.iter().enumerate() {
            if !METHODS.contains(&m.as_str()) {
                return bad(format!(
                    "unknown method {m:?}; known: {}",
                    METHODS.join(", ")
                ));
            }
            if self.methods[..i].contains(m) {
                return bad(format!("method {m} listed twice"));
            }
        }
        if self.spp.is_empty() && self.seconds.is_empty() {
            return bad("no budgets: give --spp and/or --time".into());
        }
        if self.spp.contains(&0) {
            return bad("spp budgets must be at least 1".into());
        }
        if !self.spp.windows(2).all(|w| w[0] < w[1]) {
            return bad("spp budgets must be strictly increasing".into());
        }
        let max = crate::render::run::MAX_SECONDS;
        if self.seconds.iter().any(|s| !(*s > 0.0 && *s <= max)) {
            return bad(format!(
                "time budgets must be positive numbers of seconds, at most {max:e}"
            ));
        }
        if !self.seconds.windows(2).all(|w| w[0] < w[1]) {
            return bad("time budgets must be strictly increasing".into());
        }
        if !self.exposure.is_finite() {
            return bad("exposure must be finite".into());
        }
        if let Some(crop) = &self.crop {
            crop.check_inside(reference.width, reference.height)
                .map_err(CompareError::Config)?;
        }
        Ok(())
    }

    /// Checks the reference (named `self.reference`): the settings against its size, its
    /// values finite, and the max depth it was rendered with (when it says) against the
    /// runs' `max_depth`.
    pub fn check_reference(&self, reference: &Image, max_depth: u32) -> Result<(), CompareError> {
        self.validate(reference)?;
        reference.check_finite(&self.reference)?;
        match reference.meta.max_depth {
            Some(depth) if depth != max_depth => Err(CompareError::Reference(format!(
                "{} was rendered with max depth {depth}, but --max-depth is {max_depth}",
                self.reference
            ))),
            _ => Ok(()),
        }
    }

    /// The budget whose images the grid shows: the longest equal-time budget if there is
    /// one (the paper's headline comparison), else the largest spp budget.
    pub fn grid_budget(&self) -> Budget {
        match (self.seconds.last(), self.spp.last()) {
            (Some(&s), _) => Budget::Seconds(s),
            (None, Some(&n)) => Budget::Spp(n),
            (None, None) => Budget::Spp(1),
        }
    }

    fn budgets(&self) -> Vec<Budget> {
        let spp = self.spp.iter().map(|&n| Budget::Spp(n));
        spp.chain(self.seconds.iter().map(|&s| Budget::Seconds(s)))
            .collect()
    }
}

/// The output files of a comparison, relative to `out_dir`.
pub const REPORT_FILES: [&str; 6] = [
    "report.json",
    "report.csv",
    "mae_vs_spp.png",
    "mae_vs_time.png",
    "grid.png",
    "index.html",
];

impl CompareConfig {
    /// Every file the comparison writes (so that none of them is one of its inputs).
    pub fn output_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = REPORT_FILES.iter().map(|f| self.out_dir.join(f)).collect();
        if self.save_images {
            for budget in self.budgets() {
                for method in &self.methods {
                    files.push(
                        self.out_dir
                            .join(format!("images/{method}_{}.exr", budget.tag())),
                    );
                }
            }
        }
        files
    }
}

/// Runs every method at every budget, scores them and writes the report. The reference
/// must be finite; its name in errors is `config.reference`.
pub fn run_compare(
    runner: &mut dyn MethodRunner,
    reference: &Image,
    config: &CompareConfig,
) -> Result<Report, CompareError> {
    config.validate(reference)?;
    let ref_view = Named::new(&config.reference, reference);
    ref_view.check_finite()?;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| CompareError::Io { path, error }
    };
    std::fs::create_dir_all(&config.out_dir).map_err(io(&config.out_dir))?;
    if config.save_images {
        let dir = config.out_dir.join("images");
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    }

    runner
        .prepare(&config.methods)
        .map_err(|source| CompareError::Runner {
            method: config.methods.join(", "),
            budget: config.budgets()[0],
            source,
        })?;
    let grid_budget = config.grid_budget();
    let mut records = Vec::new();
    let mut grid_images: Vec<(String, Image)> = Vec::new();
    for budget in config.budgets() {
        for method in &config.methods {
            log::info!("{method} at {budget}");
            let result = runner
                .render(method, budget)
                .map_err(|source| CompareError::Runner {
                    method: method.clone(),
                    budget,
                    source,
                })?;
            let bad = |problem: String| CompareError::BadResult {
                method: method.clone(),
                budget,
                problem,
            };
            if (result.image.width, result.image.height) != (reference.width, reference.height) {
                return Err(bad(format!(
                    "image is {}x{} but the reference is {}x{}",
                    result.image.width, result.image.height, reference.width, reference.height
                )));
            }
            if result.spp == 0 {
                return Err(bad("no sample was completed within the budget".into()));
            }
            if let Budget::Spp(n) = budget {
                if result.spp != n {
                    log::warn!(
                        "{method} at {budget}: the runner reports {} spp",
                        result.spp
                    );
                }
            }
            let label = format!("{method} at {budget}");
            let errors = metrics::errors(&Named::new(&label, &result.image), &ref_view)?;
            let image_file = if config.save_images {
                let rel = format!("images/{method}_{}.exr", budget.tag());
                // RGB was checked finite above; write_exr logs any non-finite AOV values.
                let _ = write_exr(&config.out_dir.join(&rel), &result.image)?;
                Some(rel)
            } else {
                None
            };
            records.push(Record {
                method: method.clone(),
                budget_kind: budget.kind().to_string(),
                budget: budget.value(),
                spp: result.spp,
                render_seconds: result.render_seconds,
                setup_seconds: result.setup_seconds,
                gpu_seconds: result.gpu_seconds,
                training_seconds: result.training_seconds,
                mae: errors.mae,
                relmse: errors.relmse,
                mae_ratio_to_pt: None,
                relmse_ratio_to_pt: None,
                image: image_file,
            });
            if budget == grid_budget {
                grid_images.push((method.clone(), result.image));
            }
        }
    }
    report::fill_ratios(&mut records);
    let report = Report {
        version: crate::image_io::VERSION.to_string(),
        scene: config.scene.clone(),
        reference: config.reference.clone(),
        reference_spp: reference.meta.spp,
        width: reference.width,
        height: reference.height,
        methods: config.methods.clone(),
        grid_budget: grid_budget.to_string(),
        crop: config.crop,
        records,
    };
    write_report_files(&report, reference, &grid_images, config)?;
    Ok(report)
}

fn write_text(path: &Path, text: &str) -> Result<(), CompareError> {
    write_atomically(path, text.as_bytes()).map_err(CompareError::from)
}

/// Writes every file of [`REPORT_FILES`] into `config.out_dir`.
/// `grid_images` are the renders at the grid budget, in method order.
fn write_report_files(
    report: &Report,
    reference: &Image,
    grid_images: &[(String, Image)],
    config: &CompareConfig,
) -> Result<(), CompareError> {
    let dir = &config.out_dir;
    let json = serde_json::to_string_pretty(report).expect("report serializes");
    write_text(&dir.join("report.json"), &json)?;
    write_text(&dir.join("report.csv"), &report::to_csv(report))?;
    plot::write_error_plot(&dir.join("mae_vs_spp.png"), report, plot::Axis::Spp)?;
    plot::write_error_plot(&dir.join("mae_vs_time.png"), report, plot::Axis::Seconds)?;
    let columns: Vec<grid::Column> = grid_images
        .iter()
        .map(|(method, image)| {
            let mae = report
                .records
                .iter()
                .rev()
                .find(|r| &r.method == method && report.grid_budget == report::budget_label(r))
                .map(|r| r.mae);
            grid::Column {
                label: method.clone(),
                image,
                mae,
            }
        })
        .collect();
    let title = format!("{} — {}", report.scene, report.grid_budget);
    grid::write_grid(
        &dir.join("grid.png"),
        &title,
        reference,
        &columns,
        config.crop,
        config.exposure,
    )?;
    html::write_index(&dir.join("index.html"), report, dir)?;
    Ok(())
}
