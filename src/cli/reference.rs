//! `lanterna reference SCENE --spp N -o ref.exr [--checkpoint-every S] [--resume]`: a long
//! render of samples `[K, K + N)` in chunks with exact film sums, checkpointed to
//! `ref.checkpoint.exr` and resumable bit-exactly; Ctrl-C saves a checkpoint and stops.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use super::common::{self, DeviceArgs, MethodArgs, SceneArgs};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use lanterna::eval::reference::{
    checkpoint_path, render_reference, ChunkPolicy, ProgressEvent, ReferenceError, ReferenceJob,
    SampleRenderer,
};
use lanterna::eval::BoxError;
use lanterna::image_io::RenderMeta;
use lanterna::render::{session, RenderStats, Renderer};

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub method: MethodArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
    /// Samples per pixel of the reference.
    #[arg(long)]
    pub spp: u64,
    /// Output EXR (with exact film sums and metadata).
    #[arg(short, long)]
    pub output: PathBuf,
    /// First sample index K: renders samples [K, K + spp), so separate runs with
    /// disjoint ranges can be merged with `lanterna merge`.
    #[arg(long, default_value_t = 0)]
    pub sample_offset: u64,
    /// Seconds between checkpoints (OUTPUT's stem + `.checkpoint.exr`); 0 = after every chunk.
    #[arg(long, default_value_t = 300.0)]
    pub checkpoint_every: f64,
    /// Continue from the checkpoint next to OUTPUT, if there is one (same scene, method,
    /// seed, depth and sample offset), with no sample lost or repeated.
    #[arg(long)]
    pub resume: bool,
    /// Samples per chunk (default: adapt chunks to about 2 s each).
    #[arg(long)]
    pub chunk_spp: Option<u64>,
}

/// The GPU renderer behind the reference loop: exact film sums of sample ranges.
struct GpuSamples {
    renderer: Renderer,
    meta: RenderMeta,
    cancel: AtomicBool,
}

impl SampleRenderer for GpuSamples {
    fn resolution(&self) -> (u32, u32) {
        (self.renderer.settings.width, self.renderer.settings.height)
    }

    fn metadata(&self) -> RenderMeta {
        self.meta.clone()
    }

    fn render_samples(&mut self, first: u64, count: u64) -> Result<Vec<[u64; 3]>, BoxError> {
        self.renderer.clear_film()?;
        let mut stats = RenderStats::default();
        let done = self.renderer.render_samples(
            first,
            count,
            false,
            &self.cancel,
            &mut |_| {},
            &mut stats,
        )?;
        if done != count {
            return Err(format!("rendered {done} of {count} samples").into());
        }
        if stats.clamped_samples > 0 {
            log::warn!(
                "{} samples above {:e} clamped",
                stats.clamped_samples,
                lanterna::gpu::FILM_MAX_SAMPLE
            );
        }
        if stats.nonfinite_samples > 0 {
            log::warn!("{} non-finite samples dropped", stats.nonfinite_samples);
        }
        let film = self.renderer.film()?;
        Ok(film
            .sums
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect())
    }
}

fn open_renderer(args: &Args) -> anyhow::Result<Box<dyn SampleRenderer>> {
    anyhow::ensure!(
        !args.method.method.uses_guiding(),
        "a reference is rendered with pt or ris: guided methods train on their own samples, so \
         disjoint sample ranges would not be independent"
    );
    let (loaded, camera, settings) = common::prepare(&args.scene, args.method.settings())?;
    let checkpoint = checkpoint_path(&args.output);
    common::check_outputs(
        &args.scene,
        &loaded,
        &[],
        &[
            ("the reference (-o)", &args.output),
            ("its checkpoint", &checkpoint),
        ],
    )?;
    let device =
        session::open_device(&args.device.options()).context("cannot open a Vulkan device")?;
    let mut renderer = Renderer::new(
        device.clone(),
        &loaded.scene,
        &loaded.lights,
        camera,
        settings,
        args.device.shaders(),
    )?;
    renderer.prepare()?;
    let meta = common::render_meta(&renderer.settings, &args.scene, &loaded.scene, &device);
    Ok(Box::new(GpuSamples {
        renderer,
        meta,
        cancel: AtomicBool::new(false),
    }))
}

fn job(args: &Args) -> anyhow::Result<ReferenceJob> {
    if args.spp == 0 {
        anyhow::bail!("--spp must be at least 1");
    }
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        anyhow::bail!("--checkpoint-every must be a non-negative number of seconds");
    }
    if args.chunk_spp == Some(0) {
        anyhow::bail!("--chunk-spp must be at least 1");
    }
    lanterna::render::run::Budget::Spp(args.spp).check(args.sample_offset)?;
    Ok(ReferenceJob {
        output: args.output.clone(),
        checkpoint: checkpoint_path(&args.output),
        spp: args.spp,
        sample_offset: args.sample_offset,
        // Beyond what a Duration holds means never (but on interruption).
        checkpoint_every: Duration::try_from_secs_f64(args.checkpoint_every).ok(),
        chunk: match args.chunk_spp {
            Some(n) => ChunkPolicy::Fixed(n),
            None => ChunkPolicy::Adaptive {
                target_seconds: 2.0,
            },
        },
        resume: args.resume,
    })
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let job = job(&args)?;
    // Signals from here on stop the run cleanly (the default would kill it unsaved).
    let cancel = common::cancel_flag();
    let mut renderer = open_renderer(&args)?;

    let bar = ProgressBar::new(job.spp);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} spp  ETA {eta}  {msg}",
        )
        .expect("valid template"),
    );
    let mut on_progress = |event: &ProgressEvent| match event {
        ProgressEvent::Started { done, .. } => {
            bar.set_position(*done);
            bar.reset_eta();
        }
        ProgressEvent::Chunk { done, .. } => bar.set_position(*done),
        ProgressEvent::Checkpoint { path, next_sample } => {
            bar.set_message(format!("checkpoint at sample {next_sample}"));
            bar.suspend(|| log::info!("checkpoint {} (next sample {next_sample})", path.display()));
        }
    };
    let result = render_reference(renderer.as_mut(), &job, cancel, &mut on_progress);
    bar.finish_and_clear();
    let outcome = match result {
        Ok(o) => o,
        Err(ReferenceError::Interrupted {
            checkpoint: Some(path),
            next_sample,
        }) => {
            return Err(common::Interrupted::Saved(format!(
                "progress up to sample {next_sample} is in {}; continue with --resume",
                path.display()
            ))
            .into())
        }
        Err(ReferenceError::Interrupted {
            checkpoint: None, ..
        }) => return Err(common::Interrupted::Nothing.into()),
        Err(e) => return Err(e.into()),
    };
    log::info!(
        "{}: {} spp (samples {}..{}), {} resumed from a checkpoint, {} chunks",
        job.output.display(),
        job.spp,
        job.sample_offset,
        job.sample_offset + job.spp,
        outcome.resumed_samples,
        outcome.chunks
    );
    Ok(())
}
