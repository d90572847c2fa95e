//! `lanterna render`: render a scene to a linear EXR (with metadata) and a tonemapped PNG.

use super::common::{self, DeviceArgs, MethodArgs, SceneArgs};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use lanterna::image_io;
use lanterna::render::{run, session, Renderer};
use std::path::PathBuf;
use std::time::Instant;

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
    /// Extra EXR layers of first-hit data, comma-separated: albedo, normal, depth
    /// (distance to the camera), position, light-count (unoccluded NEE connections per
    /// path), ris-weight (mean RIS contribution weight at the first hit), selected-light
    /// (light model NEE picked at the first hit for the first sample; also written as a
    /// false-coloured PNG), guide-fraction (share of guided directions), sample-count.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub aov: Vec<Aov>,
    /// Render only this pixel and print a trace of every path vertex (position, normal,
    /// material, sampled direction and pdfs, MIS weights, RIS candidates, throughput,
    /// contributions) through the validation layer's debug printf.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    pub pixel: Option<(u32, u32)>,
    /// With --pixel: trace only this sample index (reproduces it exactly).
    #[arg(long, value_name = "K", requires = "pixel")]
    pub sample: Option<u32>,
    /// List the N pixels with the largest single-sample contributions and their sample
    /// indices (reproduce one with --pixel X,Y --sample K).
    #[arg(long, value_name = "N")]
    pub report_outliers: Option<usize>,
    /// Guided methods: write the trained SD-tree to FILE.
    #[arg(long, value_name = "FILE")]
    pub save_guiding: Option<PathBuf>,
    /// Guided methods: render with the SD-tree in FILE instead of training (it must come
    /// from the same scene; the whole budget renders with it).
    #[arg(long, value_name = "FILE")]
    pub load_guiding: Option<PathBuf>,
    /// With --shader-dir: after rendering, wait for a kernel file to change, recompile and
    /// render again (until Ctrl-C).
    #[arg(long, requires = "shader_dir")]
    pub watch: bool,
    /// Count SIMD lane utilisation (the kernel's lanes doing work in the software
    /// traversal loop and in the path loop, against the slots their subgroups ran) and
    /// report it: where a CPU device such as lavapipe loses its vector width. Uses a
    /// kernel with subgroup counters: slower, same image.
    #[arg(long, conflicts_with = "pixel")]
    pub lane_stats: bool,
}

/// Saved SD-trees carry the scene's content hash (hex) as a number.
fn scene_hash_u64(hash: &str) -> u64 {
    u64::from_str_radix(hash, 16).unwrap_or(0)
}

fn report_guiding(g: &lanterna::render::GuidingOutcome, training_seconds: f64) {
    for it in &g.iterations {
        log::info!(
            "training iteration {}: {} spp, render {:.2} s, read-back {:.3} s, refit {:.3} s, upload {:.3} s; {} leaves, {:.1} KiB",
            it.iteration,
            it.spp,
            it.render_seconds,
            it.readback_seconds,
            it.refit_seconds,
            it.upload_seconds,
            it.leaves,
            it.gpu_bytes as f64 / 1024.0
        );
    }
    if !g.iterations.is_empty() {
        log::info!("training took {training_seconds:.2} s");
    }
}

/// AOV layers (the library's list, shared with the Python module).
pub use lanterna::render::output::Aov;

pub fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s.split_once(',').ok_or("expected X,Y")?;
    Ok((
        x.trim().parse().map_err(|e| format!("`{x}`: {e}"))?,
        y.trim().parse().map_err(|e| format!("`{y}`: {e}"))?,
    ))
}

/// Same text for --report-outliers and --pixel --sample, so one can be checked against
/// the other.
fn describe_sample(x: u32, y: u32, sample: u32, rgb: [f32; 3]) -> String {
    format!(
        "pixel ({x}, {y}) sample {sample}: radiance ({:e}, {:e}, {:e})",
        rgb[0], rgb[1], rgb[2]
    )
}

pub fn run(args: Args) -> Result<()> {
    // Signals from here on stop the run cleanly (the default would kill it unsaved).
    let _ = common::cancel_flag();
    let spp = args
        .spp
        .unwrap_or(if args.time.is_some() { u64::MAX } else { 16 });
    let budget = match args.time {
        Some(t) => run::Budget::Seconds(t),
        None => run::Budget::Spp(spp),
    };
    // Before anything is loaded (run_method checks again).
    if args.pixel.is_none() {
        budget.check(args.sample_offset)?;
    }
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
    let mut settings = args.method.settings();
    settings.exposure = args.exposure;
    settings.lane_stats = args.lane_stats;
    let (loaded, camera, mut settings) = common::prepare(&args.scene, settings)?;
    let (width, height) = (settings.width, settings.height);
    let selected_light_png = args
        .aov
        .contains(&Aov::SelectedLight)
        .then(|| output.with_extension("selected-light.png"));
    let mut outputs = vec![("the EXR (-o)", output.as_path())];
    outputs.extend(png.as_deref().map(|p| ("the PNG (--png)", p)));
    outputs.extend(args.save_guiding.as_deref().map(|p| ("--save-guiding", p)));
    outputs.extend(
        selected_light_png
            .as_deref()
            .map(|p| ("the selected-light PNG", p)),
    );
    let inputs: Vec<(&str, &std::path::Path)> = args
        .load_guiding
        .as_deref()
        .map(|p| ("--load-guiding", p))
        .into_iter()
        .collect();
    common::check_outputs(&args.scene, &loaded, &inputs, &outputs)?;
    let mut device_options = args.device.options();
    device_options.debug_printf = args.pixel.is_some();
    let device = session::open_device(&device_options).context("cannot open a Vulkan device")?;
    settings.aovs = !args.aov.is_empty() || args.pixel.is_some() || args.report_outliers.is_some();
    let mut renderer = Renderer::new(
        device.clone(),
        &loaded.scene,
        &loaded.lights,
        camera,
        settings,
        args.device.shaders(),
    )?;
    if let Some(path) = &args.load_guiding {
        anyhow::ensure!(
            renderer.settings.method.uses_guiding(),
            "--load-guiding needs --method guided or guided-ris"
        );
        let tree = lanterna::guiding::SdTree::load(path, scene_hash_u64(&loaded.scene.hash))?;
        renderer.preloaded_tree = Some(tree);
    }
    if let Some((x, y)) = args.pixel {
        return trace_pixel(&mut renderer, x, y, &args, spp);
    }
    let job = Job {
        args: &args,
        loaded: &loaded,
        device: &device,
        output,
        png,
        width,
        height,
        spp,
    };
    match &args.device.shader_dir {
        Some(dir) if args.watch => watch(&mut renderer, &job, dir),
        _ => render_once(&mut renderer, &job, started),
    }
}

/// What `render_once` needs besides the renderer.
struct Job<'a> {
    args: &'a Args,
    loaded: &'a session::LoadedScene,
    device: &'a std::sync::Arc<lanterna::vk::Device>,
    output: PathBuf,
    png: Option<PathBuf>,
    width: u32,
    height: u32,
    spp: u64,
}

/// `--watch`: render, then wait for a file under the shader directory to change, reload
/// the kernels and render again, until Ctrl-C. Compile errors are printed, not fatal.
fn watch(renderer: &mut Renderer, job: &Job<'_>, dir: &std::path::Path) -> Result<()> {
    let cancel = common::cancel_flag();
    loop {
        if let Err(e) = render_once(renderer, job, Instant::now()) {
            log::error!("{e:#}");
        }
        if cancel.load(std::sync::atomic::Ordering::SeqCst) {
            return Ok(());
        }
        log::info!("watching {} for changes (Ctrl-C to stop)", dir.display());
        let stamp = dir_stamp(dir);
        while dir_stamp(dir) == stamp {
            std::thread::sleep(std::time::Duration::from_millis(300));
            if cancel.load(std::sync::atomic::Ordering::SeqCst) {
                return Ok(());
            }
        }
        log::info!("shaders changed: recompiling");
        renderer.reload_shaders();
    }
}

/// Paths, sizes and modification times of every file below `dir`.
fn dir_stamp(dir: &std::path::Path) -> Vec<(PathBuf, u64, Option<std::time::SystemTime>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            match e.metadata() {
                Ok(m) if m.is_dir() => stack.push(p),
                Ok(m) => out.push((p, m.len(), m.modified().ok())),
                Err(_) => {}
            }
        }
    }
    out.sort();
    out
}

/// Render with the current kernels and write the outputs.
fn render_once(renderer: &mut Renderer, job: &Job<'_>, started: Instant) -> Result<()> {
    let (args, loaded, device) = (job.args, job.loaded, job.device);
    let (output, png) = (&job.output, &job.png);
    let (width, height, spp) = (job.width, job.height, job.spp);
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
    let render_started = Instant::now();
    let mut progress = |done: u64| {
        if args.time.is_some() {
            bar.set_position((render_started.elapsed().as_secs_f64() * 10.0) as u64);
            bar.set_message(format!("{done} spp"));
        } else {
            bar.set_position(done);
        }
    };
    let budget = match args.time {
        Some(t) => run::Budget::Seconds(t),
        None => run::Budget::Spp(spp),
    };
    let outcome = run::run_method(renderer, budget, args.sample_offset, cancel, &mut progress)?;
    bar.finish_and_clear();
    let render_seconds = outcome.seconds;
    let stats = outcome.stats;
    let film = outcome.film.clone();
    let done = film.spp;
    let interrupted = cancel.load(std::sync::atomic::Ordering::SeqCst);
    if done == 0 {
        if interrupted {
            return Err(common::Interrupted::Nothing.into());
        }
        anyhow::bail!("no sample finished within the budget; nothing written");
    }
    if let Some(g) = &outcome.guiding {
        report_guiding(g, outcome.training_seconds);
        if let Some(path) = &args.save_guiding {
            common::ensure_parent(path)?;
            let (lo, hi) = renderer.bounds;
            g.tree
                .save(
                    path,
                    scene_hash_u64(&loaded.scene.hash),
                    (lo.into(), hi.into()),
                )
                .with_context(|| format!("cannot save the SD-tree to {}", path.display()))?;
            log::info!("saved the SD-tree to {}", path.display());
        }
    }
    let mut meta = common::render_meta(&renderer.settings, &args.scene, &loaded.scene, device);
    meta.spp = Some(film.spp);
    meta.sample_offset = Some(film.sample_offset);
    meta.render_seconds = Some(render_seconds);
    meta.extra
        .insert("gpu_seconds".into(), format!("{:.6}", stats.gpu_seconds));
    meta.extra.insert(
        "traversal_used".into(),
        format!(
            "{} ({})",
            renderer.traversal.kind, renderer.traversal.reason
        ),
    );
    if stats.clamped_samples > 0 {
        meta.extra
            .insert("clamped_samples".into(), stats.clamped_samples.to_string());
    }
    let mut image = common::outcome_image(&outcome, width, height, meta)?;
    if !args.aov.is_empty() {
        let data = renderer.aovs()?;
        for aov in &args.aov {
            let layer = match aov.layout() {
                Some((first, channels)) => {
                    let n = lanterna::gpu::AOV_CHANNELS as usize;
                    let values: Vec<f32> = data
                        .chunks_exact(n)
                        .flat_map(|px| {
                            px[first as usize..first as usize + channels.len()]
                                .iter()
                                .copied()
                        })
                        .collect();
                    image_io::Aov::new(aov.name(), channels, values)?
                }
                None => image_io::Aov::new(
                    aov.name(),
                    &["Y"],
                    vec![film.spp as f32; (width * height) as usize],
                )?,
            };
            image.aovs.push(layer);
        }
        if args.aov.contains(&Aov::SelectedLight) {
            let n = lanterna::gpu::AOV_CHANNELS as usize;
            let ids: Vec<f32> = data
                .chunks_exact(n)
                .map(|px| px[lanterna::gpu::AOV_SELECTED_LIGHT as usize])
                .collect();
            let path = output.with_extension("selected-light.png");
            common::ensure_parent(&path)?;
            image_io::write_png_rgb8(&path, width, height, &false_colour(&ids))
                .with_context(|| format!("cannot write {}", path.display()))?;
            log::info!(
                "wrote {} (light model NEE picked at the first hit, false-coloured)",
                path.display()
            );
        }
    }
    common::ensure_parent(output)?;
    let written = image_io::write_exr(output, &image)
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
        let _ = image_io::write_png(p, &image, renderer.settings.exposure)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }

    if let Some(n) = args.report_outliers {
        let list = renderer.outliers(n)?;
        println!("largest single-sample contributions (reproduce with --pixel X,Y --sample K):");
        for o in &list {
            println!(
                "  {}  luminance {:e}",
                describe_sample(o.x, o.y, o.sample, o.rgb),
                o.luminance
            );
        }
    }
    if stats.clamped_samples > 0 {
        log::warn!(
            "{} samples had a value above {:e} and were clamped to it (the image is darker \
             than the scene there; lower the emission or use --exposure)",
            stats.clamped_samples,
            lanterna::gpu::FILM_MAX_SAMPLE
        );
    }
    if stats.nonfinite_samples > 0 {
        log::warn!(
            "{} samples were NaN, infinite or negative and were dropped (a bug: please report with --seed)",
            stats.nonfinite_samples
        );
    }
    let pixels = width as f64 * height as f64;
    log::info!(
        "{} {}×{} {} spp in {:.2} s ({:.2} s setup): {:.3} M samples/s, {:.3} M rays/s (camera {}, bounce {}, shadow {}, probe {}), GPU {:.2} s, host {:.2} s; {} traversal ({})",
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
        stats.probe_rays,
        stats.gpu_seconds,
        (render_seconds - stats.gpu_seconds).max(0.0),
        renderer.traversal.kind,
        renderer.traversal.reason,
    );
    if args.lane_stats {
        let pct = |u: Option<f64>| {
            u.map_or("not measured".to_string(), |u| {
                format!("{:.1} %", u * 100.0)
            })
        };
        log::info!(
            "SIMD lanes doing work: traversal loop {} ({}), path loop {} (lanes whose path ended wait for their subgroup's longest)",
            pct(stats.lanes.traversal_utilisation()),
            if renderer.traversal.kind == lanterna::render::TraversalKind::Software {
                "software traversal, all rays"
            } else {
                "only the software traversal is counted"
            },
            pct(stats.lanes.path_utilisation()),
        );
        if let Some(steps) = stats.lanes.traversal_steps_per_ray(stats.rays()) {
            log::info!(
                "software traversal: {steps:.1} loop steps (nodes and leaves visited) per ray"
            );
        }
    }
    log::info!(
        "wrote {}{}",
        output.display(),
        png.as_ref()
            .map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
    if interrupted && !args.watch {
        let training = outcome
            .guiding
            .as_ref()
            .is_some_and(|g| g.interrupted_in_training);
        return Err(common::Interrupted::Saved(format!(
            "wrote the {} spp finished{} to {}",
            film.spp,
            if training {
                " (of the last training pass)"
            } else {
                ""
            },
            output.display()
        ))
        .into());
    }
    Ok(())
}

/// Distinct colours for light-model indices (black where NEE picked nothing).
fn false_colour(ids: &[f32]) -> Vec<u8> {
    ids.iter()
        .flat_map(|&id| {
            if id < 0.0 {
                return [0, 0, 0];
            }
            // A multiplicative hash spreads neighbouring indices over hue.
            let h = (id as u32).wrapping_mul(2_654_435_761);
            [
                (h >> 24) as u8 | 0x30,
                (h >> 16) as u8 | 0x30,
                (h >> 8) as u8 | 0x30,
            ]
        })
        .collect()
}

/// `--pixel X,Y`: render that pixel alone with the debug kernel and print its trace.
fn trace_pixel(renderer: &mut Renderer, x: u32, y: u32, args: &Args, spp: u64) -> Result<()> {
    let (begin, count) = match args.sample {
        Some(k) => (k as u64, 1),
        None => (args.sample_offset, if args.spp.is_some() { spp } else { 1 }),
    };
    run::Budget::Spp(count).check(begin)?;
    let lines = renderer.trace_pixel(x, y, begin, count, args.sample)?;
    if lines.is_empty() {
        log::warn!("no trace was printed: the validation layer's debug printf is unavailable");
    }
    for line in &lines {
        for l in line.lines() {
            log::info!(target: "trace", "{l}");
        }
    }
    let film = renderer.film()?;
    let i = ((y * film.width + x) * 3) as usize;
    let mean = film.mean();
    log::info!(
        "pixel ({x}, {y}) mean over {count} sample(s): ({:e}, {:e}, {:e})",
        mean[i],
        mean[i + 1],
        mean[i + 2]
    );
    if let Some(k) = args.sample {
        let o = renderer.outliers(usize::MAX)?;
        let rgb = o
            .iter()
            .find(|o| o.x == x && o.y == y)
            .map(|o| o.rgb)
            .unwrap_or([0.0; 3]);
        println!("{}", describe_sample(x, y, k, rgb));
    }
    Ok(())
}
