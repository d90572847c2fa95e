//! `lanterna bench`: a fixed suite of timed measurements — throughput per method, light
//! count scaling, guiding overhead, quality at equal spp and time, an optional peer
//! comparison with Mitsuba 3, and a profile of where the kernel's time goes — written as
//! `<out>/<date>-<device>.json` and a Markdown table beside it. Speed goals live here and
//! are reported, never asserted: the test suite only checks that `--quick` runs and writes
//! well-formed results. Every configuration runs once to warm up and then `repeat` times
//! with fixed seeds; timings are min / median / max over those runs.

pub mod date;
pub mod guiding;
pub mod harness;
pub mod machine;
pub mod markdown;
pub mod mitsuba;
pub mod number;
pub mod profile;
pub mod quality;
pub mod report;
pub mod scaling;
pub mod sizes;
pub mod spread;
pub mod throughput;
pub mod traversal;
pub mod trend;

use crate::render::{Method, RenderSettings, Traversal};
use crate::shaders::ShaderSource;
use crate::vk::Device;
use harness::Session;
use report::BenchReport;
use sizes::Sizes;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

/// Errors of a bench run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    #[error(transparent)]
    Scene(crate::scene::SceneError),
    #[error(transparent)]
    Generate(crate::scene::generate::GenerateError),
    #[error(transparent)]
    Compare(#[from] crate::eval::compare::CompareError),
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    // `error` is not a `source`: the message already includes it, once.
    #[error("{}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("scene {} not found (give the shipped scenes' directory with --scenes)", .0.display())]
    MissingScene(PathBuf),
    #[error("Mitsuba comparison: {0}")]
    Mitsuba(String),
    #[error("{0}")]
    Other(String),
}

impl BenchError {
    pub fn io(path: &Path, error: std::io::Error) -> BenchError {
        BenchError::Io {
            path: path.to_path_buf(),
            error,
        }
    }
}

pub type Result<T> = std::result::Result<T, BenchError>;

/// The parts of the suite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Suite {
    Throughput,
    Scaling,
    Guiding,
    Quality,
    Mitsuba,
    Profile,
    Traversal,
    Trend,
}

impl Suite {
    pub const ALL: [Suite; 8] = [
        Suite::Traversal,
        Suite::Throughput,
        Suite::Scaling,
        Suite::Guiding,
        Suite::Quality,
        Suite::Mitsuba,
        Suite::Profile,
        Suite::Trend,
    ];

    /// What `lanterna bench` runs without `--suite`: all but the long `trend`.
    pub const DEFAULT: [Suite; 7] = [
        Suite::Traversal,
        Suite::Throughput,
        Suite::Scaling,
        Suite::Guiding,
        Suite::Quality,
        Suite::Mitsuba,
        Suite::Profile,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Suite::Throughput => "throughput",
            Suite::Scaling => "scaling",
            Suite::Guiding => "guiding",
            Suite::Quality => "quality",
            Suite::Mitsuba => "mitsuba",
            Suite::Profile => "profile",
            Suite::Traversal => "traversal",
            Suite::Trend => "trend",
        }
    }
}

impl fmt::Display for Suite {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Suite {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        Suite::ALL
            .into_iter()
            .find(|x| x.name() == s.trim())
            .ok_or_else(|| {
                let names: Vec<&str> = Suite::ALL.iter().map(|x| x.name()).collect();
                format!("unknown suite `{s}` (expected {})", names.join(", "))
            })
    }
}

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Tiny sizes, one repetition: proves the bench works.
    pub quick: bool,
    /// Where the JSON and Markdown go.
    pub out_dir: PathBuf,
    /// Recorded runs per configuration.
    pub repeat: usize,
    pub suites: Vec<Suite>,
    pub skip_mitsuba: bool,
    /// Directory of the shipped scenes (`street.gltf`, `cornell-lights.gltf`).
    pub scenes_dir: PathBuf,
    /// `scripts/mitsuba_compare.py`.
    pub mitsuba_script: PathBuf,
    /// Python interpreter with `mitsuba`.
    pub python: String,
    /// Scratch space (generated scenes, exports, comparison reports); removed afterwards.
    pub work_dir: Option<PathBuf>,
    /// The command line, for the Markdown.
    pub command: String,
    pub shaders: ShaderSource,
    /// `trend`: skip points with more training paths than this.
    pub trend_max_paths: Option<u64>,
}

impl BenchConfig {
    /// The repository's defaults: scenes and the script from the working directory when
    /// it is a checkout, else from the source tree this binary was built from.
    pub fn new(quick: bool) -> BenchConfig {
        BenchConfig {
            quick,
            out_dir: PathBuf::from("bench/results"),
            repeat: if quick { 1 } else { 3 },
            suites: Suite::DEFAULT.to_vec(),
            skip_mitsuba: false,
            scenes_dir: repo_path("scenes"),
            mitsuba_script: repo_path("scripts/mitsuba_compare.py"),
            python: "python3".into(),
            work_dir: None,
            command: "lanterna bench".into(),
            shaders: ShaderSource::Builtin,
            trend_max_paths: None,
        }
    }
}

fn repo_path(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        here
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
    }
}

/// A running bench: the device and what every suite needs.
pub struct Bench {
    pub device: Arc<Device>,
    pub sizes: Sizes,
    pub repeat: usize,
    pub seed: u32,
    pub work_dir: PathBuf,
    pub scenes_dir: PathBuf,
    pub mitsuba_script: PathBuf,
    pub python: String,
    pub shaders: ShaderSource,
    /// `trend`: skip points with more training paths than this.
    pub trend_max_paths: Option<u64>,
}

impl Bench {
    pub fn scene_path(&self, name: &str) -> Result<PathBuf> {
        let p = self.scenes_dir.join(name);
        if p.is_file() {
            Ok(p)
        } else {
            Err(BenchError::MissingScene(p))
        }
    }

    pub fn open(
        &self,
        path: &Path,
        width: u32,
        height: Option<u32>,
        method: Method,
    ) -> Result<Session> {
        self.open_with(path, width, height, method, Traversal::Auto)
    }

    /// Like [`open`](Self::open) with a given traversal.
    pub fn open_with(
        &self,
        path: &Path,
        width: u32,
        height: Option<u32>,
        method: Method,
        traversal: Traversal,
    ) -> Result<Session> {
        Session::open(
            &self.device,
            &self.shaders,
            path,
            width,
            height,
            RenderSettings {
                traversal,
                ..harness::base_settings(method, 0, 0, self.seed)
            },
        )
    }
}

/// The files a run wrote.
#[derive(Clone, Debug)]
pub struct BenchOutput {
    pub json: PathBuf,
    pub markdown: PathBuf,
    pub report: BenchReport,
}

/// `<date>-<device>` (and `-quick`): the results' file stem.
pub fn file_stem(date: &str, device_slug: &str, quick: bool) -> String {
    format!("{date}-{device_slug}{}", if quick { "-quick" } else { "" })
}

/// Run the suites of `config` on `device` and write the results.
pub fn run(config: &BenchConfig, device: Arc<Device>) -> Result<BenchOutput> {
    let started = Instant::now();
    let date = date::today();
    let unix_time = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let machine = machine::Machine::describe(&device);
    let load_start = machine::load_average();
    let own_work_dir = config.work_dir.is_none();
    let work_dir = config.work_dir.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(format!("lanterna-bench-{}", std::process::id()))
    });
    std::fs::create_dir_all(&work_dir).map_err(|e| BenchError::io(&work_dir, e))?;
    std::fs::create_dir_all(&config.out_dir).map_err(|e| BenchError::io(&config.out_dir, e))?;
    let bench = Bench {
        device,
        sizes: if config.quick {
            Sizes::quick()
        } else {
            Sizes::full()
        },
        repeat: config.repeat.max(1),
        seed: 0,
        work_dir: work_dir.clone(),
        scenes_dir: config.scenes_dir.clone(),
        mitsuba_script: config.mitsuba_script.clone(),
        python: config.python.clone(),
        shaders: config.shaders.clone(),
        trend_max_paths: config.trend_max_paths,
    };
    let result = run_suites(config, &bench);
    if own_work_dir {
        let _ = std::fs::remove_dir_all(&work_dir);
    }
    let mut report = result?;
    report.date = date.clone();
    report.unix_time = unix_time;
    report.machine = machine;
    report.total_seconds = started.elapsed().as_secs_f64();
    report.load_average_start = load_start;
    report.load_average_end = machine::load_average();

    let stem = file_stem(&date, &report.machine.device_slug(), config.quick);
    let json = config.out_dir.join(format!("{stem}.json"));
    let markdown = config.out_dir.join(format!("{stem}.md"));
    let text = serde_json::to_string_pretty(&report).expect("the report serializes");
    crate::image_io::write_atomically(&json, format!("{text}\n").as_bytes())?;
    crate::image_io::write_atomically(&markdown, markdown::render(&report).as_bytes())?;
    if let Some(t) = &report.trend {
        let csv = config.out_dir.join(format!("{stem}-trend.csv"));
        crate::image_io::write_atomically(&csv, t.csv().as_bytes())?;
        t.write_plot(&config.out_dir.join(format!("{stem}-trend.png")))?;
    }
    log::info!(
        "bench finished in {:.0} s: {} and {}",
        report.total_seconds,
        json.display(),
        markdown.display()
    );
    Ok(BenchOutput {
        json,
        markdown,
        report,
    })
}

fn run_suites(config: &BenchConfig, bench: &Bench) -> Result<BenchReport> {
    let wants = |s: Suite| config.suites.contains(&s);
    let mut report = BenchReport {
        schema: report::SCHEMA,
        date: String::new(),
        unix_time: 0,
        quick: config.quick,
        command: config.command.clone(),
        machine: machine::Machine::describe(&bench.device),
        repeat: bench.repeat,
        seed: bench.seed,
        sizes: bench.sizes.clone(),
        suites: Vec::new(),
        throughput: None,
        scaling: None,
        guiding: None,
        quality: None,
        mitsuba: None,
        mitsuba_skipped: None,
        profile: None,
        traversal: None,
        trend: None,
        load_average_start: None,
        load_average_end: None,
        total_seconds: 0.0,
    };
    for suite in Suite::ALL.into_iter().filter(|s| wants(*s)) {
        let t = Instant::now();
        log::info!("bench: {suite}");
        match suite {
            Suite::Throughput => report.throughput = Some(throughput::run(bench)?),
            Suite::Scaling => report.scaling = Some(scaling::run(bench)?),
            Suite::Guiding => report.guiding = Some(guiding::run(bench)?),
            Suite::Quality => report.quality = Some(quality::run(bench)?),
            Suite::Profile => report.profile = Some(profile::run(bench)?),
            Suite::Traversal => report.traversal = Some(traversal::run(bench)?),
            Suite::Trend => report.trend = Some(trend::run(bench)?),
            Suite::Mitsuba => {
                if config.skip_mitsuba {
                    report.mitsuba_skipped = Some("--skip-mitsuba".into());
                    continue;
                }
                if !mitsuba::available(&bench.python) {
                    report.mitsuba_skipped = Some(format!(
                        "`{} -c \"import mitsuba\"` fails: Mitsuba 3 is not installed",
                        bench.python
                    ));
                    log::warn!("Mitsuba 3 is not installed: skipping the peer comparison");
                    continue;
                }
                match mitsuba::run(bench) {
                    Ok(p) => report.mitsuba = Some(p),
                    Err(e) => {
                        // The peer check is optional: a failure is reported, not fatal.
                        log::error!("{e}");
                        report.mitsuba_skipped = Some(format!("failed: {e}"));
                        continue;
                    }
                }
            }
        }
        report.suites.push(suite.name().to_string());
        log::info!("bench: {suite} took {:.0} s", t.elapsed().as_secs_f64());
    }
    Ok(report)
}
