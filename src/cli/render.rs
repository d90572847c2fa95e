//! `lanterna render`: render a scene to a linear EXR (with metadata) and a tonemapped PNG.

use super::common::{self, DeviceArgs, MethodArgs, SceneArgs};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use lanterna::image_io::{self, Image, RenderMeta};
use lanterna::render::{session, RenderStats, Renderer};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub method: MethodArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
    /// Samples per pixel.
    #[arg(long, conflicts_with = "time")]
    pub spp: Option<u64>,
    /// Render for this many seconds instead of a fixed sample count (every pixel gets
    /// the same number of samples; the count reached is in the EXR's metadata).
    #[arg(long, value_name = "SECONDS")]
    pub time: Option<f64>,
    /// First sample index: renders samples [K, K + spp). Renders of disjoint ranges are
    /// independent and `lanterna merge` combines them exactly.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub sample_offset: u64,
    /// Linear EXR output (default: out/<scene>.exr).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Tonemapped sRGB PNG output (default: the EXR's path with .png).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Do not write a PNG.
    #[arg(long, conflicts_with = "png")]
    pub no_png: bool,
    /// Exposure of the PNG in stops (pixel values are multiplied by 2^exposure).
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(t) = args.time {
        anyhow::ensure!(
            t.is_finite() && t > 0.0,
            "--time must be a positive number of seconds"
        );
    }
    let spp = args
        .spp
        .unwrap_or(if args.time.is_some() { u64::MAX } else { 16 });
    anyhow::ensure!(spp > 0, "--spp must be at least 1");
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args
            .scene
            .scene
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or("render".into());
        PathBuf::from("out").join(format!("{stem}.exr"))
    });
    let png = if args.no_png {
        None
    } else {
        Some(
            args.png
                .clone()
                .unwrap_or_else(|| output.with_extension("png")),
        )
    };

    let started = Instant::now();
    let (loaded, camera, width, height) = common::load(&args.scene)?;
    let device =
        session::open_device(&args.device.options()).context("cannot open a Vulkan device")?;
    let settings = args.method.settings(width, height);
    let mut renderer = Renderer::new(
        device.clone(),
        &loaded.scene,
        &loaded.lights,
        camera,
        settings,
        args.device.shaders(),
    )?;
    renderer.prepare()?;
    let setup_seconds = started.elapsed().as_secs_f64();

    let cancel = common::cancel_flag();
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else if let Some(t) = args.time {
        let b = ProgressBar::new((t * 10.0) as u64);
        b.set_style(
            ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {msg}").unwrap(),
        );
        b
    } else {
        let b = ProgressBar::new(spp);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} {elapsed_precise} [{bar:40}] {pos}/{len} spp, ETA {eta}",
            )
            .unwrap(),
        );
        b
    };
    let mut stats = RenderStats::default();
    let render_started = Instant::now();
    let deadline = args
        .time
        .map(|t| render_started + Duration::from_secs_f64(t));
    let mut progress = |done: u64| {
        if args.time.is_some() {
            bar.set_position((render_started.elapsed().as_secs_f64() * 10.0) as u64);
            bar.set_message(format!("{done} spp"));
        } else {
            bar.set_position(done);
        }
    };
    let count = if args.time.is_some() { None } else { Some(spp) };
    let done = renderer.render_until(
        args.sample_offset,
        count,
        deadline,
        false,
        cancel,
        &mut progress,
        &mut stats,
    )?;
    bar.finish_and_clear();
    let render_seconds = render_started.elapsed().as_secs_f64();
    anyhow::ensure!(
        done > 0,
        "interrupted before the first sample finished; nothing written"
    );

    let film = renderer.film()?;
    let mut meta = RenderMeta::new();
    meta.spp = Some(film.spp);
    meta.sample_offset = Some(film.sample_offset);
    meta.method = Some(args.method.method.name().to_string());
    meta.seed = Some(args.method.seed as u64);
    meta.max_depth = Some(args.method.max_depth);
    meta.render_seconds = Some(render_seconds);
    meta.device = Some(device.info.name.clone());
    meta.scene_path = Some(args.scene.scene.display().to_string());
    meta.scene_hash = Some(loaded.scene.hash.clone());
    for (k, v) in [
        ("source", format!("{:?}", args.method.source).to_lowercase()),
        ("ris_candidates", args.method.ris_candidates.to_string()),
        ("rr_depth", args.method.rr_depth.to_string()),
        ("gpu_seconds", format!("{:.6}", stats.gpu_seconds)),
    ] {
        meta.extra.insert(k.to_string(), v);
    }
    let sums: Vec<[u64; 3]> = film
        .sums
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let image = Image::from_sums(width, height, sums, meta)?;
    common::ensure_parent(&output)?;
    let written = image_io::write_exr(&output, &image)
        .with_context(|| format!("cannot write {}", output.display()))?;
    if written.nonfinite > 0 {
        // The kernel drops non-finite samples, so this would be a film bug: say so loudly.
        log::error!(
            "{}: {} non-finite pixel values",
            output.display(),
            written.nonfinite
        );
    }
    if let Some(p) = &png {
        common::ensure_parent(p)?;
        let _ = image_io::write_png(p, &image, args.exposure)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }

    if stats.nonfinite_samples > 0 {
        log::warn!(
            "{} samples were NaN, infinite or negative and were dropped (a bug: please report with --seed)",
            stats.nonfinite_samples
        );
    }
    let pixels = width as f64 * height as f64;
    log::info!(
        "{} {}×{} {} spp in {:.2} s ({:.2} s setup): {:.3} M samples/s, {:.3} M rays/s (camera {}, bounce {}, shadow {}), GPU {:.2} s, host {:.2} s",
        args.method.method,
        width,
        height,
        film.spp,
        render_seconds,
        setup_seconds,
        pixels * done as f64 / render_seconds / 1e6,
        stats.rays() as f64 / render_seconds / 1e6,
        stats.camera_rays,
        stats.bounce_rays,
        stats.shadow_rays,
        stats.gpu_seconds,
        (render_seconds - stats.gpu_seconds).max(0.0),
    );
    log::info!(
        "wrote {}{}",
        output.display(),
        png.as_ref()
            .map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}
