//! `lanterna compare SCENE --reference ref.exr --out-dir DIR`: renders each method at each
//! equal-spp and equal-time budget, scores it against the reference, and writes the report
//! (JSON, CSV, plots, image grid, HTML). The loop and the report live in
//! `lanterna::eval::compare`; this file parses and checks the arguments.

use std::path::PathBuf;

use anyhow::Context;
use lanterna::eval::compare::{run_compare, CompareConfig, Crop, MethodRunner, METHODS};
use lanterna::image_io::{read_exr, Image};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene (glTF).
    pub scene: PathBuf,
    /// Reference EXR of the same scene, max depth and resolution.
    #[arg(long)]
    pub reference: PathBuf,
    /// Methods to compare, comma-separated, in display order.
    #[arg(long, value_delimiter = ',', default_values_t = METHODS.map(String::from))]
    pub methods: Vec<String>,
    /// Equal-spp budgets, comma-separated, strictly increasing
    /// (default 1,2,4,…,1024 when no --time is given).
    #[arg(long, value_delimiter = ',')]
    pub spp: Vec<u64>,
    /// Equal-time budgets in seconds of rendering (setup excluded), comma-separated,
    /// strictly increasing.
    #[arg(long = "time", value_delimiter = ',')]
    pub seconds: Vec<f64>,
    /// Region of the zoomed crop row: x,y,w,h in reference pixels.
    #[arg(long)]
    pub crop: Option<Crop>,
    /// Exposure (stops) for the tonemapped images.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Also save every render as DIR/images/<method>_<budget>.exr.
    #[arg(long)]
    pub save_images: bool,
    /// Path segments (1 = emitters seen directly); must match the reference's.
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Seed of the per-(pixel, sample) random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where the report goes (created if missing).
    #[arg(long)]
    pub out_dir: PathBuf,
}

/// The default equal-spp budgets: powers of two up to 1024.
pub fn default_spp() -> Vec<u64> {
    (0..=10).map(|k| 1u64 << k).collect()
}

/// The comparison settings from the arguments (not yet checked against the reference).
pub fn config(args: &Args) -> CompareConfig {
    let spp = if args.spp.is_empty() && args.seconds.is_empty() {
        default_spp()
    } else {
        args.spp.clone()
    };
    CompareConfig {
        methods: args.methods.iter().map(|m| m.trim().to_string()).collect(),
        spp,
        seconds: args.seconds.clone(),
        crop: args.crop,
        exposure: args.exposure,
        out_dir: args.out_dir.clone(),
        save_images: args.save_images,
        scene: args.scene.display().to_string(),
        reference: args.reference.display().to_string(),
    }
}

/// Reads and checks the reference against the arguments.
pub fn load_reference(args: &Args, config: &CompareConfig) -> anyhow::Result<Image> {
    let reference = read_exr(&args.reference).context("reading the reference")?;
    config.validate(&reference)?;
    reference.check_finite(&args.reference.display().to_string())?;
    if let Some(depth) = reference.meta.max_depth {
        if depth != args.max_depth {
            anyhow::bail!(
                "{} was rendered with max depth {depth}, but --max-depth is {}",
                args.reference.display(),
                args.max_depth
            );
        }
    }
    Ok(reference)
}

/// The renderer behind the comparison. The GPU renderer implements `MethodRunner`;
/// until it is wired in here, this command stops with an error after checking its inputs.
fn open_runner(args: &Args, _reference: &Image) -> anyhow::Result<Box<dyn MethodRunner>> {
    anyhow::bail!(
        "cannot render {}: the GPU renderer is not connected to `lanterna compare` yet",
        args.scene.display()
    )
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let config = config(&args);
    let reference = load_reference(&args, &config)?;
    if !args.scene.exists() {
        anyhow::bail!("scene {} not found", args.scene.display());
    }
    let mut runner = open_runner(&args, &reference)?;
    let report = run_compare(runner.as_mut(), &reference, &config)?;
    log::info!(
        "{} renders compared; report in {}",
        report.records.len(),
        config.out_dir.join("index.html").display()
    );
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
        Cli::try_parse_from(std::iter::once("compare").chain(line.iter().copied())).map(|c| c.args)
    }

    #[test]
    fn parses_lists_and_crop() {
        let a = parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--methods",
            "pt,guided-ris",
            "--spp",
            "1,4,16",
            "--time",
            "0.5,2",
            "--crop",
            "10,20,30,40",
            "--out-dir",
            "out",
        ])
        .unwrap();
        assert_eq!(a.methods, ["pt", "guided-ris"]);
        assert_eq!(a.spp, [1, 4, 16]);
        assert_eq!(a.seconds, [0.5, 2.0]);
        assert_eq!(
            a.crop,
            Some(Crop {
                x: 10,
                y: 20,
                w: 30,
                h: 40
            })
        );
        let c = config(&a);
        assert_eq!(c.spp, [1, 4, 16]);
    }

    #[test]
    fn defaults() {
        let a = parse(&["s.gltf", "--reference", "r.exr", "--out-dir", "o"]).unwrap();
        assert_eq!(a.methods, METHODS);
        let c = config(&a);
        assert_eq!(c.spp.len(), 11);
        assert_eq!(*c.spp.last().unwrap(), 1024);
        assert!(c.seconds.is_empty());
        // With only --time, no spp budgets are added.
        let a = parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--time",
            "1",
            "--out-dir",
            "o",
        ])
        .unwrap();
        assert!(config(&a).spp.is_empty());
    }

    #[test]
    fn rejects_bad_values() {
        assert!(parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--out-dir",
            "o",
            "--crop",
            "1,2,3"
        ])
        .is_err());
        assert!(parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--out-dir",
            "o",
            "--spp",
            "4,x"
        ])
        .is_err());
        assert!(
            parse(&["s.gltf", "--out-dir", "o"]).is_err(),
            "--reference is required"
        );
        let a = parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--out-dir",
            "o",
            "--methods",
            "pt,foo",
        ])
        .unwrap();
        let reference = Image::new(4, 4, vec![[0.0; 3]; 16]).unwrap();
        let e = config(&a).validate(&reference).unwrap_err();
        assert!(e.to_string().contains("unknown method \"foo\""), "{e}");
        let a = parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--out-dir",
            "o",
            "--crop",
            "2,2,3,3",
        ])
        .unwrap();
        let e = config(&a).validate(&reference).unwrap_err();
        assert!(e.to_string().contains("does not fit"), "{e}");
        let a = parse(&[
            "s.gltf",
            "--reference",
            "r.exr",
            "--out-dir",
            "o",
            "--spp",
            "4,2",
        ])
        .unwrap();
        assert!(config(&a).validate(&reference).is_err());
    }
}
