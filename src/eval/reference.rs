//! The long-running reference render: samples `[K, K + N)` rendered in chunks whose exact
//! film sums are added on the CPU, with a checkpoint EXR written every so often (and on
//! interruption or a renderer error) that `resume` continues from, so an interrupted and
//! resumed reference is bit-identical to an uninterrupted one. The renderer is behind
//! [`SampleRenderer`]; the loop, chunk sizing, checkpoint validation and progress events
//! live here so they are tested with a deterministic fake.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::BoxError;
use crate::image_io::{read_exr, write_exr, Image, ImageError, RenderMeta, VERSION};

/// What the reference loop needs from a renderer.
pub trait SampleRenderer {
    /// The film size (width, height).
    fn resolution(&self) -> (u32, u32);
    /// The render's identity: `method`, `seed`, `max_depth`, `scene_path`, `scene_hash`,
    /// `device` and any extra keys. The loop fills `spp`, `sample_offset`,
    /// `render_seconds` and `version` itself.
    fn metadata(&self) -> RenderMeta;
    /// Renders sample indices `[first, first + count)` of every pixel and returns the
    /// film's exact fixed-point sums over those samples only, in scan-line order
    /// (`width * height` entries, units of `1 / FILM_SCALE`). Must be a pure function of
    /// the sample range, so that chunks add up to the one-shot sums.
    fn render_samples(&mut self, first: u64, count: u64) -> Result<Vec<[u64; 3]>, BoxError>;
}

/// How many samples each `render_samples` call asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChunkPolicy {
    /// Always this many (the last chunk may be shorter).
    Fixed(u64),
    /// Start at one sample, then size chunks to take about this many seconds (never more
    /// than doubling), so progress and checkpoints stay responsive on any device.
    Adaptive { target_seconds: f64 },
}

#[derive(Clone, Debug)]
pub struct ReferenceJob {
    /// The finished reference.
    pub output: PathBuf,
    /// The checkpoint file (see [`checkpoint_path`] for the usual choice).
    pub checkpoint: PathBuf,
    /// Samples per pixel of the finished reference.
    pub spp: u64,
    /// First sample index K: the reference holds samples `[K, K + spp)`.
    pub sample_offset: u64,
    /// Write a checkpoint when this much time has passed since the last one; `None`
    /// checkpoints only on interruption or error. `Some(ZERO)` checkpoints every chunk.
    pub checkpoint_every: Option<Duration>,
    pub chunk: ChunkPolicy,
    /// Continue from `checkpoint` if it exists (else start afresh). Without it an existing
    /// checkpoint is an error, so progress is never thrown away by accident.
    pub resume: bool,
}

/// Extra metadata of a checkpoint: the next sample index to render (informational: it
/// equals `sample_offset + spp`).
pub const NEXT_SAMPLE_KEY: &str = "next_sample";
/// Extra metadata of a checkpoint: the spp the finished reference will have.
pub const TARGET_SPP_KEY: &str = "target_spp";

/// `ref.exr` → `ref.checkpoint.exr` next to it.
pub fn checkpoint_path(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}.checkpoint.exr"))
}

/// Progress reported to the caller (for a progress bar and logs).
#[derive(Clone, Debug, PartialEq)]
pub enum ProgressEvent {
    /// Before the first chunk: `done` samples already in hand (from a checkpoint) of `total`.
    Started { done: u64, total: u64 },
    /// After each chunk.
    Chunk {
        done: u64,
        total: u64,
        chunk: u64,
        seconds: f64,
    },
    /// A checkpoint holding samples up to (not including) `next_sample` was written.
    Checkpoint { path: PathBuf, next_sample: u64 },
}

#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error("nothing to render: --spp must be at least 1")]
    ZeroSpp,
    #[error(
        "checkpoint {} already exists: pass --resume to continue it, or delete it to start over",
        path.display()
    )]
    CheckpointExists { path: PathBuf },
    #[error("cannot resume from {}: {problem}", path.display())]
    BadCheckpoint { path: PathBuf, problem: String },
    #[error(
        "the renderer returned {got} film sums for samples {first}..{end}, expected {expected}"
    )]
    BadSums {
        first: u64,
        end: u64,
        got: usize,
        expected: usize,
    },
    #[error("film sums overflow 64 bits at pixel index {pixel}")]
    Overflow { pixel: usize },
    #[error("rendering samples {first}..{end} failed{}", saved_note(checkpoint))]
    Render {
        first: u64,
        end: u64,
        checkpoint: Option<PathBuf>,
        source: BoxError,
    },
    #[error("interrupted at sample {next_sample}{}", saved_note(checkpoint))]
    Interrupted {
        checkpoint: Option<PathBuf>,
        next_sample: u64,
    },
    #[error(transparent)]
    Image(#[from] ImageError),
}

fn saved_note(checkpoint: &Option<PathBuf>) -> String {
    match checkpoint {
        Some(p) => format!(
            " (progress saved in {}; continue with --resume)",
            p.display()
        ),
        None => String::new(),
    }
}

/// The finished reference.
#[derive(Debug)]
pub struct ReferenceOutcome {
    pub image: Image,
    /// Samples taken from a checkpoint rather than rendered in this run.
    pub resumed_samples: u64,
    pub chunks: u64,
}

struct State {
    meta: RenderMeta,
    width: u32,
    height: u32,
    sums: Vec<[u64; 3]>,
    /// Samples in `sums`, starting at the job's sample offset.
    done: u64,
    /// Render seconds already in the checkpoint we resumed from.
    previous_seconds: f64,
}

impl State {
    fn image(&self, job: &ReferenceJob, seconds: f64) -> Result<Image, ImageError> {
        let mut meta = self.meta.clone();
        meta.spp = Some(self.done);
        meta.sample_offset = Some(job.sample_offset);
        meta.render_seconds = Some(self.previous_seconds + seconds);
        meta.version = Some(VERSION.to_string());
        Image::from_sums(self.width, self.height, self.sums.clone(), meta)
    }
}

/// Fields that must agree between a checkpoint and the renderer: the scene, method,
/// seed and depth, and every setting the renderer records among the extra keys (RIS
/// candidates, light source, …) but the exposure, which only the PNG sees.
fn identity(meta: &RenderMeta, keys: &[String]) -> Vec<(String, String)> {
    let show = |v: Option<String>| v.unwrap_or_else(|| "none".into());
    let mut fields = vec![
        ("scene hash".to_string(), show(meta.scene_hash.clone())),
        ("method".to_string(), show(meta.method.clone())),
        ("seed".to_string(), show(meta.seed.map(|s| s.to_string()))),
        (
            "max_depth".to_string(),
            show(meta.max_depth.map(|d| d.to_string())),
        ),
    ];
    for k in keys {
        fields.push((k.clone(), show(meta.extra.get(k).cloned())));
    }
    fields
}

/// Extra keys that describe the render rather than one run of it.
fn identity_keys(meta: &RenderMeta) -> Vec<String> {
    meta.extra
        .keys()
        .filter(|k| {
            !matches!(
                k.as_str(),
                "exposure" | "gpu_seconds" | NEXT_SAMPLE_KEY | TARGET_SPP_KEY
            )
        })
        .cloned()
        .collect()
}

/// Where a resumed reference continues from.
#[derive(Clone, Copy, PartialEq)]
enum Origin {
    /// The checkpoint next to the output.
    Checkpoint,
    /// The finished output of an earlier run (resumed to more samples).
    Finished,
}

/// The state saved in `path` (a checkpoint or a finished reference), after checking it
/// belongs to this render; `None` when there is no such file.
fn load_saved(
    path: &Path,
    job: &ReferenceJob,
    meta: &RenderMeta,
    (width, height): (u32, u32),
) -> Result<Option<State>, ReferenceError> {
    let bad = |problem: String| ReferenceError::BadCheckpoint {
        path: path.to_path_buf(),
        problem,
    };
    let image = match read_exr(path) {
        Ok(image) => image,
        Err(ImageError::NotFound { .. }) => return Ok(None),
        Err(e) => return Err(e.into()),
    };
    if (image.width, image.height) != (width, height) {
        return Err(bad(format!(
            "it is {}x{} but the render is {width}x{height}",
            image.width, image.height
        )));
    }
    let keys = identity_keys(meta);
    for ((field, theirs), (_, ours)) in identity(&image.meta, &keys)
        .into_iter()
        .zip(identity(meta, &keys))
    {
        if theirs != ours {
            return Err(bad(format!(
                "its {field} is {theirs} but this render's is {ours}"
            )));
        }
    }
    let Some(sums) = image.sums else {
        return Err(bad("it has no exact film sums".into()));
    };
    if image
        .meta
        .extra
        .contains_key(crate::image_io::SAMPLE_RANGES_KEY)
    {
        return Err(bad(
            "it holds non-contiguous sample ranges (a merge), not samples from the offset on"
                .into(),
        ));
    }
    if image.meta.sample_offset.unwrap_or(0) != job.sample_offset {
        return Err(bad(format!(
            "it starts at sample {} but this render starts at {}",
            image.meta.sample_offset.unwrap_or(0),
            job.sample_offset
        )));
    }
    let done = image.meta.spp.unwrap_or(0);
    if done > job.spp {
        return Err(bad(format!(
            "it already holds {done} spp, more than the {} asked",
            job.spp
        )));
    }
    Ok(Some(State {
        meta: meta.clone(),
        width,
        height,
        sums,
        done,
        previous_seconds: image.meta.render_seconds.unwrap_or(0.0),
    }))
}

/// Renders (or finishes) the reference described by `job`, writes it to `job.output` and
/// removes the checkpoint. `cancel` is polled between chunks: when set, a checkpoint is
/// written and [`ReferenceError::Interrupted`] returned.
pub fn render_reference(
    renderer: &mut dyn SampleRenderer,
    job: &ReferenceJob,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(&ProgressEvent),
) -> Result<ReferenceOutcome, ReferenceError> {
    if job.spp == 0 {
        return Err(ReferenceError::ZeroSpp);
    }
    let (width, height) = renderer.resolution();
    let meta = renderer.metadata();
    let n = width as usize * height as usize;

    let resumed = if job.resume {
        // The checkpoint, else a finished reference to extend; never start over on top
        // of a finished one.
        let mut state = load_saved(&job.checkpoint, job, &meta, (width, height))?
            .map(|s| (s, Origin::Checkpoint));
        if state.is_none() {
            state = load_saved(&job.output, job, &meta, (width, height))?
                .map(|s| (s, Origin::Finished));
        }
        match state {
            None => {
                log::info!(
                    "no checkpoint at {} and no reference at {}: starting from the beginning",
                    job.checkpoint.display(),
                    job.output.display()
                );
                None
            }
            Some((s, Origin::Finished)) if s.done == job.spp => {
                // Complete already: nothing to render, and the file stays as it is.
                log::info!(
                    "{} already holds the {} spp asked: nothing to do",
                    job.output.display(),
                    job.spp
                );
                let image = read_exr(&job.output)?;
                return Ok(ReferenceOutcome {
                    image,
                    resumed_samples: s.done,
                    chunks: 0,
                });
            }
            Some((s, origin)) => {
                if origin == Origin::Finished {
                    log::info!(
                        "continuing the finished reference {} from {} spp",
                        job.output.display(),
                        s.done
                    );
                }
                Some(s)
            }
        }
    } else if job.checkpoint.exists() {
        return Err(ReferenceError::CheckpointExists {
            path: job.checkpoint.clone(),
        });
    } else {
        None
    };
    let mut state = resumed.unwrap_or(State {
        meta,
        width,
        height,
        sums: vec![[0; 3]; n],
        done: 0,
        previous_seconds: 0.0,
    });
    let resumed_samples = state.done;
    progress(&ProgressEvent::Started {
        done: state.done,
        total: job.spp,
    });

    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let mut checkpointed = state.done;
    let mut chunks = 0u64;
    let mut chunk = match job.chunk {
        ChunkPolicy::Fixed(c) => c.max(1),
        ChunkPolicy::Adaptive { .. } => 1,
    };
    let write_checkpoint = |state: &State, progress: &mut dyn FnMut(&ProgressEvent)| {
        let mut image = state.image(job, start.elapsed().as_secs_f64())?;
        // Self-describing for people reading the header; resuming relies on spp and offset.
        let next_sample = job.sample_offset + state.done;
        image
            .meta
            .extra
            .insert(NEXT_SAMPLE_KEY.into(), next_sample.to_string());
        image
            .meta
            .extra
            .insert(TARGET_SPP_KEY.into(), job.spp.to_string());
        // Non-finite values are logged by write_exr; the final write reports them too.
        let _ = write_exr(&job.checkpoint, &image)?;
        progress(&ProgressEvent::Checkpoint {
            path: job.checkpoint.clone(),
            next_sample,
        });
        Ok::<(), ReferenceError>(())
    };

    while state.done < job.spp {
        if cancel.load(Ordering::Relaxed) {
            if state.done > checkpointed {
                write_checkpoint(&state, progress)?;
            }
            return Err(ReferenceError::Interrupted {
                checkpoint: job.checkpoint.exists().then(|| job.checkpoint.clone()),
                next_sample: job.sample_offset + state.done,
            });
        }
        let count = chunk.min(job.spp - state.done);
        let first = job.sample_offset + state.done;
        let t0 = Instant::now();
        let sums = match renderer.render_samples(first, count) {
            Ok(sums) => sums,
            Err(source) => {
                // Keep what was rendered: the sums so far are exact.
                let checkpoint = if state.done > checkpointed {
                    match write_checkpoint(&state, progress) {
                        Ok(()) => Some(job.checkpoint.clone()),
                        Err(e) => {
                            log::error!("could not save a checkpoint after the failure: {e}");
                            None
                        }
                    }
                } else {
                    job.checkpoint.exists().then(|| job.checkpoint.clone())
                };
                return Err(ReferenceError::Render {
                    first,
                    end: first + count,
                    checkpoint,
                    source,
                });
            }
        };
        let seconds = t0.elapsed().as_secs_f64();
        if sums.len() != n {
            return Err(ReferenceError::BadSums {
                first,
                end: first + count,
                got: sums.len(),
                expected: n,
            });
        }
        for (pixel, (acc, s)) in state.sums.iter_mut().zip(&sums).enumerate() {
            for c in 0..3 {
                acc[c] = acc[c]
                    .checked_add(s[c])
                    .ok_or(ReferenceError::Overflow { pixel })?;
            }
        }
        state.done += count;
        chunks += 1;
        progress(&ProgressEvent::Chunk {
            done: state.done,
            total: job.spp,
            chunk: count,
            seconds,
        });

        if let ChunkPolicy::Adaptive { target_seconds } = job.chunk {
            let per_sample = (seconds / count as f64).max(1e-9);
            let mut target = target_seconds;
            if let Some(every) = job.checkpoint_every {
                target = target.min(every.as_secs_f64().max(per_sample));
            }
            let ideal = (target / per_sample).floor().max(1.0);
            chunk = (ideal as u64).clamp(1, count.saturating_mul(2));
        }
        if state.done < job.spp {
            if let Some(every) = job.checkpoint_every {
                if last_checkpoint.elapsed() >= every {
                    write_checkpoint(&state, progress)?;
                    checkpointed = state.done;
                    last_checkpoint = Instant::now();
                }
            }
        }
    }

    let image = state.image(job, start.elapsed().as_secs_f64())?;
    let summary = write_exr(&job.output, &image)?;
    if summary.nonfinite > 0 {
        log::warn!(
            "{}: the reference has {} non-finite values",
            job.output.display(),
            summary.nonfinite
        );
    }
    match std::fs::remove_file(&job.checkpoint) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => log::warn!(
            "could not remove checkpoint {}: {e}",
            job.checkpoint.display()
        ),
    }
    Ok(ReferenceOutcome {
        image,
        resumed_samples,
        chunks,
    })
}
