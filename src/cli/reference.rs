//! `lanterna reference SCENE --spp N -o ref.exr [--checkpoint-every S] [--resume]`: a long
//! render of samples `[K, K + N)` in chunks with exact film sums, checkpointed to
//! `ref.checkpoint.exr` and resumable bit-exactly; Ctrl-C saves a checkpoint and stops.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use lanterna::eval::reference::{
    checkpoint_path, render_reference, ChunkPolicy, ProgressEvent, ReferenceJob, SampleRenderer,
};

#[derive(clap::Args)]
pub struct Args {
    /// The scene (glTF).
    pub scene: PathBuf,
    /// Samples per pixel of the reference.
    #[arg(long)]
    pub spp: u64,
    /// Output EXR (with exact film sums and metadata).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Method: pt, ris, guided, guided-ris.
    #[arg(long, default_value = "pt")]
    pub method: String,
    /// Path segments (1 = emitters seen directly).
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Seed of the per-(pixel, sample) random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
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

/// The renderer behind the reference loop. The GPU renderer implements
/// `SampleRenderer`; until it is wired in here, this command stops with an error.
fn open_renderer(args: &Args) -> anyhow::Result<Box<dyn SampleRenderer>> {
    anyhow::bail!(
        "cannot render {}: the GPU renderer is not connected to `lanterna reference` yet",
        args.scene.display()
    )
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
    if args.sample_offset.checked_add(args.spp).is_none() {
        anyhow::bail!("--sample-offset + --spp overflows");
    }
    Ok(ReferenceJob {
        output: args.output.clone(),
        checkpoint: checkpoint_path(&args.output),
        spp: args.spp,
        sample_offset: args.sample_offset,
        checkpoint_every: Some(Duration::from_secs_f64(args.checkpoint_every)),
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
    let mut renderer = open_renderer(&args)?;

    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        ctrlc::set_handler(move || cancel.store(true, Ordering::Relaxed))
            .context("installing the Ctrl-C handler")?;
    }
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
    let result = render_reference(renderer.as_mut(), &job, &cancel, &mut on_progress);
    bar.finish_and_clear();
    let outcome = result?;
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
