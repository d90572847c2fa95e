//! `lanterna bench`: the fixed performance suite (throughput, light-count scaling,
//! guiding overhead, quality, the Mitsuba 3 peer comparison, a profile), written as
//! `<out>/<date>-<device>.json` and `.md`. The suites live in `lanterna::bench`; this file
//! parses the arguments and opens the device.

use super::common::DeviceArgs;
use anyhow::Context;
use lanterna::bench::{self, BenchConfig, Suite};
use lanterna::render::session;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Tiny sizes and one repetition: proves the bench works (CI), measures nothing.
    #[arg(long)]
    pub quick: bool,
    /// Directory of the results (`<date>-<device>.json` and `.md`).
    #[arg(long, value_name = "DIR", default_value = "bench/results")]
    pub out: PathBuf,
    /// Recorded runs per configuration, after one warm-up run (default 3; 1 with --quick).
    #[arg(long, value_name = "N")]
    pub repeat: Option<usize>,
    /// Skip the Mitsuba 3 peer comparison even when Mitsuba is installed.
    #[arg(long)]
    pub skip_mitsuba: bool,
    /// Suites to run, comma-separated: traversal, throughput, scaling, guiding, quality,
    /// mitsuba, profile, trend (default: all but trend, which takes hours at full size).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub suite: Vec<Suite>,
    /// Directory of the shipped scenes (default: ./scenes, else the source tree's).
    #[arg(long, value_name = "DIR")]
    pub scenes: Option<PathBuf>,
    /// Python interpreter that can import mitsuba.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Keep generated scenes, exports and comparison reports in DIR (default: a temporary
    /// directory, removed afterwards).
    #[arg(long, value_name = "DIR")]
    pub work_dir: Option<PathBuf>,
    /// trend: skip the points with more training paths (pixels × training spp) than N.
    #[arg(long, value_name = "N")]
    pub max_training_paths: Option<f64>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The command line as typed, for the results' "made by" line.
fn command_line() -> String {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quoted: Vec<String> = args
        .iter()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || c == '\'') {
                format!("'{}'", a.replace('\'', r"'\''"))
            } else {
                a.clone()
            }
        })
        .collect();
    format!("lanterna {}", quoted.join(" "))
}

pub fn config(args: &Args) -> anyhow::Result<BenchConfig> {
    let mut c = BenchConfig::new(args.quick);
    c.out_dir = args.out.clone();
    if let Some(n) = args.repeat {
        anyhow::ensure!(n >= 1, "--repeat must be at least 1");
        c.repeat = n;
    }
    if !args.suite.is_empty() {
        c.suites = args.suite.clone();
    }
    c.skip_mitsuba = args.skip_mitsuba;
    if let Some(d) = &args.scenes {
        c.scenes_dir = d.clone();
    }
    c.python = args.python.clone();
    c.work_dir = args.work_dir.clone();
    c.command = command_line();
    c.shaders = args.device.shaders();
    if let Some(n) = args.max_training_paths {
        anyhow::ensure!(
            n.is_finite() && n >= 1.0,
            "--max-training-paths must be a number ≥ 1 (e.g. 1e6)"
        );
        c.trend_max_paths = Some(n as u64);
    }
    Ok(c)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let config = config(&args)?;
    let device =
        session::open_device(&args.device.options()).context("cannot open a Vulkan device")?;
    let out = bench::run(&config, device).context("the bench failed")?;
    println!("{}", out.json.display());
    println!("{}", out.markdown.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(line: &[&str]) -> Result<Args, clap::Error> {
        Cli::try_parse_from(std::iter::once("bench").chain(line.iter().copied())).map(|c| c.args)
    }

    #[test]
    fn defaults_and_lists() {
        let a = parse(&[]).unwrap();
        let c = config(&a).unwrap();
        assert!(!c.quick);
        assert_eq!(c.repeat, 3);
        assert_eq!(c.suites, Suite::DEFAULT);
        assert_eq!(c.out_dir, PathBuf::from("bench/results"));
        let a = parse(&["--quick", "--suite", "throughput,quality", "--out", "x"]).unwrap();
        let c = config(&a).unwrap();
        assert_eq!(c.repeat, 1);
        assert_eq!(c.suites, [Suite::Throughput, Suite::Quality]);
        assert!(parse(&["--suite", "speed"]).is_err());
        let a = parse(&["--repeat", "0"]).unwrap();
        assert!(config(&a).is_err());
    }
}
