//! `lanterna compare SCENE --reference ref.exr --out-dir DIR`: renders each method at each
//! equal-spp and equal-time budget, scores it against the reference, and writes the report
//! (JSON, CSV, plots, image grid, HTML). The loop and the report live in
//! `lanterna::eval::compare`; this file parses and checks the arguments.

use std::path::PathBuf;
use std::time::Instant;

use super::common::{self, DeviceArgs, EstimatorArgs, SceneArgs};
use anyhow::Context;
use lanterna::eval::compare::{run_compare, CompareConfig, Crop, METHODS};
use lanterna::image_io::{read_exr, Image};
use lanterna::render::runner::CompareRunner;
use lanterna::render::{session, Method, RenderSettings, Renderer};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub view: SceneArgs,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
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
        scene: args.view.scene.display().to_string(),
        reference: args.reference.display().to_string(),
    }
}

/// Reads and checks the reference against the arguments.
pub fn load_reference(args: &Args, config: &CompareConfig) -> anyhow::Result<Image> {
    let reference = read_exr(&args.reference).context("reading the reference")?;
    config.validate(&reference)?;
    reference.check_finite(&args.reference.display().to_string())?;
    if let Some(depth) = reference.meta.max_depth {
        if depth != args.estimator.max_depth {
            anyhow::bail!(
                "{} was rendered with max depth {depth}, but --max-depth is {}",
                args.reference.display(),
                args.estimator.max_depth
            );
        }
    }
    Ok(reference)
}

/// The scene on the device, ready for the comparison's runs.
struct Prepared {
    renderer: Renderer,
    /// The settings of every run, but for the method.
    settings: RenderSettings,
    setup_seconds: f64,
    meta: lanterna::image_io::RenderMeta,
}

fn prepare(args: &Args, reference: &Image) -> anyhow::Result<Prepared> {
    let started = Instant::now();
    let mut view = args.view.clone();
    view.width = Some(view.width.unwrap_or(reference.width));
    view.height = Some(view.height.unwrap_or(reference.height));
    let first = args
        .methods
        .first()
        .map(|m| m.parse::<Method>())
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let mut settings = args.estimator.settings(first.unwrap_or(Method::Pt), 0, 0);
    settings.exposure = args.exposure;
    let (loaded, camera, settings) = common::prepare(&view, settings)?;
    let outputs = config(args).output_files();
    let outputs: Vec<(&str, &std::path::Path)> = outputs
        .iter()
        .map(|p| ("a report file", p.as_path()))
        .collect();
    common::check_outputs(
        &view,
        &loaded,
        &[("--reference", &args.reference)],
        &outputs,
    )?;
    if let Some(hash) = &reference.meta.scene_hash {
        if *hash != loaded.scene.hash {
            log::warn!(
                "{} was rendered from a different scene content (hash {hash}, this scene {}); errors compare unlike images",
                args.reference.display(),
                loaded.scene.hash
            );
        }
    }
    let device =
        session::open_device(&args.device.options()).context("cannot open a Vulkan device")?;
    let renderer = Renderer::new(
        device.clone(),
        &loaded.scene,
        &loaded.lights,
        camera,
        settings.clone(),
        args.device.shaders(),
    )?;
    let meta = common::render_meta(&renderer.settings, &view, &loaded.scene, &device);
    Ok(Prepared {
        renderer,
        settings,
        setup_seconds: started.elapsed().as_secs_f64(),
        meta,
    })
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let config = config(&args);
    let reference = load_reference(&args, &config)?;
    if !args.view.scene.exists() {
        anyhow::bail!("scene {} not found", args.view.scene.display());
    }
    let mut prepared = prepare(&args, &reference)?;
    let mut runner = CompareRunner {
        renderer: &mut prepared.renderer,
        base: prepared.settings,
        setup_seconds: prepared.setup_seconds,
        meta: prepared.meta,
        cancel: common::cancel_flag(),
        progress: &mut |_| {},
    };
    let report = run_compare(&mut runner, &reference, &config)?;
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
