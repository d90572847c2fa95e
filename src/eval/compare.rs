//! The method comparison: every method is rendered at every budget (equal spp, then equal
//! wall-clock time) through a [`MethodRunner`], scored against the reference, and the
//! results written as a report (`report.json`, `report.csv`, `mae_vs_spp.png`,
//! `mae_vs_time.png`, `grid.png`, `index.html`) into the output directory. Rendering is
//! behind the trait so the whole pipeline runs with a fake runner in tests.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use super::metrics::{self, Named};
use super::report::{self, Record, Report};
use super::BoxError;
use crate::image_io::{write_exr, Image, ImageError};

/// The methods lanterna implements, in their canonical order.
pub const METHODS: [&str; 4] = ["pt", "ris", "guided", "guided-ris"];

/// How much work one render may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Exactly this many samples per pixel.
    Spp(u64),
    /// Render (after setup) until this many wall-clock seconds have passed; the runner
    /// reports the spp it reached.
    Seconds(f64),
}

impl Budget {
    /// `spp` or `time`, as in the report's `budget_kind`.
    pub fn kind(&self) -> &'static str {
        match self {
            Budget::Spp(_) => "spp",
            Budget::Seconds(_) => "time",
        }
    }

    pub fn value(&self) -> f64 {
        match *self {
            Budget::Spp(n) => n as f64,
            Budget::Seconds(s) => s,
        }
    }

    /// A file-name-safe tag: `spp16`, `t2.5s`.
    pub fn tag(&self) -> String {
        match *self {
            Budget::Spp(n) => format!("spp{n}"),
            Budget::Seconds(s) => format!("t{s}s"),
        }
    }
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Budget::Spp(n) => write!(f, "{n} spp"),
            Budget::Seconds(s) => write!(f, "{s} s"),
        }
    }
}

/// What a runner returns for one render.
#[derive(Clone, Debug)]
pub struct MethodResult {
    /// Samples per pixel in `image` (for time budgets, how many the time allowed).
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
}

/// A rectangle of the reference, in pixels: `x,y,w,h` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl FromStr for Crop {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let values: Vec<u32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
        if parts.len() != 4 || values.len() != 4 {
            return Err(format!(
                "crop {s:?} should be four non-negative integers x,y,w,h"
            ));
        }
        if values[2] == 0 || values[3] == 0 {
            return Err(format!("crop {s:?} has zero width or height"));
        }
        Ok(Crop {
            x: values[0],
            y: values[1],
            w: values[2],
            h: values[3],
        })
    }
}

impl Crop {
    /// An error unless the crop lies inside a `width` × `height` image.
    pub fn check_inside(&self, width: u32, height: u32) -> Result<(), String> {
        let fits = u64::from(self.x) + u64::from(self.w) <= u64::from(width)
            && u64::from(self.y) + u64::from(self.h) <= u64::from(height);
        if fits {
            Ok(())
        } else {
            Err(format!(
                "crop {},{},{},{} does not fit in the {width}x{height} reference",
                self.x, self.y, self.w, self.h
            ))
        }
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

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error("invalid comparison settings: {0}")]
    Config(String),
    #[error("rendering {method} at {budget} failed")]
    Runner {
        method: String,
        budget: Budget,
        source: BoxError,
    },
    #[error("{method} at {budget}: {problem}")]
    BadResult {
        method: String,
        budget: Budget,
        problem: String,
    },
    #[error(transparent)]
    Metric(#[from] metrics::MetricError),
    #[error(transparent)]
    Image(#[from] ImageError),
    // `error` is not a `source`: the message already includes it, once.
    #[error("{}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{}: {problem}", path.display())]
    Figure { path: PathBuf, problem: String },
    #[error("{0}")]
    Reference(String),
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
    report::write_all(&report, reference, &grid_images, config)?;
    Ok(report)
}
