//! The reference loop with a deterministic fake renderer: chunked renders equal one-shot
//! renders bit for bit, an interrupted-then-resumed reference equals an uninterrupted
//! one with no sample lost or repeated, and checkpoints are validated before resuming.

use std::ops::Range;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use lanterna::eval::merge::merge;
use lanterna::eval::reference::{
    checkpoint_path, render_reference, ChunkPolicy, ProgressEvent, ReferenceError, ReferenceJob,
    SampleRenderer,
};
use lanterna::eval::BoxError;
use lanterna::image_io::{read_exr, Image, RenderMeta};

struct Fake {
    seed: u64,
    calls: Vec<Range<u64>>,
    fail_on_call: Option<usize>,
}

impl Fake {
    fn new(seed: u64) -> Self {
        Fake {
            seed,
            calls: Vec::new(),
            fail_on_call: None,
        }
    }
}

const W: u32 = 6;
const H: u32 = 4;

fn value(seed: u64, pixel: usize, c: usize, s: u64) -> u64 {
    let mut x =
        seed ^ (pixel as u64) << 40 ^ (c as u64) << 36 ^ s.wrapping_mul(0x2545_F491_4F6C_DD1D);
    x ^= x >> 31;
    x = x.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    (x >> 40) & 0xFF_FFFF
}

impl SampleRenderer for Fake {
    fn resolution(&self) -> (u32, u32) {
        (W, H)
    }
    fn metadata(&self) -> RenderMeta {
        let mut m = RenderMeta::new();
        m.method = Some("pt".into());
        m.seed = Some(self.seed);
        m.max_depth = Some(4);
        m.scene_hash = Some("fake-scene".into());
        m.device = Some("fake".into());
        m
    }
    fn render_samples(&mut self, first: u64, count: u64) -> Result<Vec<[u64; 3]>, BoxError> {
        if self.fail_on_call == Some(self.calls.len()) {
            return Err("device lost (simulated)".into());
        }
        self.calls.push(first..first + count);
        let n = (W * H) as usize;
        Ok((0..n)
            .map(|p| {
                [0, 1, 2].map(|c| {
                    (first..first + count)
                        .map(|s| value(self.seed, p, c, s))
                        .sum()
                })
            })
            .collect())
    }
}

fn job(dir: &Path, name: &str, spp: u64, chunk: ChunkPolicy) -> ReferenceJob {
    let output = dir.join(name);
    ReferenceJob {
        checkpoint: checkpoint_path(&output),
        output,
        spp,
        sample_offset: 0,
        checkpoint_every: None,
        chunk,
        resume: false,
    }
}

fn no_progress() -> impl FnMut(&ProgressEvent) {
    |_| {}
}

fn bits(i: &Image) -> (Vec<[u32; 3]>, Option<Vec<[u64; 3]>>) {
    (
        i.rgb.iter().map(|p| p.map(f32::to_bits)).collect(),
        i.sums.clone(),
    )
}

fn one_shot(dir: &Path, spp: u64) -> Image {
    let mut r = Fake::new(3);
    let j = job(dir, "oneshot.exr", spp, ChunkPolicy::Fixed(spp));
    let out = render_reference(&mut r, &j, &AtomicBool::new(false), &mut no_progress()).unwrap();
    assert_eq!(r.calls, vec![0..spp]);
    out.image
}

#[test]
fn chunked_equals_one_shot() {
    let dir = tempfile::tempdir().unwrap();
    let reference = one_shot(dir.path(), 23);
    for chunk in [
        ChunkPolicy::Fixed(1),
        ChunkPolicy::Fixed(5),
        ChunkPolicy::Adaptive {
            target_seconds: 0.01,
        },
    ] {
        let mut r = Fake::new(3);
        let mut j = job(dir.path(), "chunked.exr", 23, chunk);
        j.checkpoint_every = Some(Duration::ZERO);
        let mut checkpoints = 0;
        let out = render_reference(
            &mut r,
            &j,
            &AtomicBool::new(false),
            &mut |e: &ProgressEvent| {
                if matches!(e, ProgressEvent::Checkpoint { .. }) {
                    checkpoints += 1;
                }
            },
        )
        .unwrap();
        assert_eq!(bits(&out.image), bits(&reference), "{chunk:?}");
        // The chunks tile [0, 23) exactly.
        let mut next = 0;
        for c in &r.calls {
            assert_eq!(c.start, next);
            next = c.end;
        }
        assert_eq!(next, 23);
        assert_eq!(
            checkpoints,
            r.calls.len() - 1,
            "a checkpoint after every chunk but the last"
        );
        // The file holds the same bits, and the checkpoint is gone.
        assert_eq!(bits(&read_exr(&j.output).unwrap()), bits(&reference));
        assert!(!j.checkpoint.exists());
        let m = &out.image.meta;
        assert_eq!(
            (m.spp, m.sample_offset, m.seed),
            (Some(23), Some(0), Some(3))
        );
    }
}

#[test]
fn failure_then_resume_equals_uninterrupted() {
    let dir = tempfile::tempdir().unwrap();
    let reference = one_shot(dir.path(), 20);
    let mut first = Fake::new(3);
    first.fail_on_call = Some(3);
    let mut j = job(dir.path(), "ref.exr", 20, ChunkPolicy::Fixed(4));
    let e =
        render_reference(&mut first, &j, &AtomicBool::new(false), &mut no_progress()).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            ReferenceError::Render {
                first: 12,
                end: 16,
                checkpoint: Some(_),
                ..
            }
        ),
        "{msg}"
    );
    assert!(
        msg.contains("--resume") && msg.contains("ref.checkpoint.exr"),
        "{msg}"
    );
    assert!(!j.output.exists());
    let cp = read_exr(&j.checkpoint).unwrap();
    assert_eq!((cp.meta.spp, cp.meta.sample_offset), (Some(12), Some(0)));
    assert_eq!(
        cp.meta.extra.get("next_sample").map(String::as_str),
        Some("12")
    );
    assert_eq!(
        cp.meta.extra.get("target_spp").map(String::as_str),
        Some("20")
    );

    // Without --resume an existing checkpoint is refused rather than overwritten.
    let e = render_reference(
        &mut Fake::new(3),
        &j,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(matches!(e, ReferenceError::CheckpointExists { .. }), "{e}");

    j.resume = true;
    let mut second = Fake::new(3);
    let mut started = None;
    let out = render_reference(
        &mut second,
        &j,
        &AtomicBool::new(false),
        &mut |e: &ProgressEvent| {
            if let ProgressEvent::Started { done, total } = e {
                started = Some((*done, *total));
            }
        },
    )
    .unwrap();
    assert_eq!(started, Some((12, 20)));
    assert_eq!(out.resumed_samples, 12);
    assert_eq!(
        second.calls,
        vec![12..16, 16..20],
        "no sample lost or repeated"
    );
    assert_eq!(bits(&out.image), bits(&reference));
    assert!(!j.checkpoint.exists());
    assert!(
        out.image.meta.extra.is_empty(),
        "checkpoint-only keys stay out of the result"
    );
}

#[test]
fn cancel_writes_checkpoint_and_resume_finishes_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let reference = one_shot(dir.path(), 17);
    let cancel = AtomicBool::new(false);
    let mut r = Fake::new(3);
    let mut j = job(dir.path(), "ref.exr", 17, ChunkPolicy::Fixed(3));
    let e = render_reference(&mut r, &j, &cancel, &mut |e: &ProgressEvent| {
        if let ProgressEvent::Chunk { done: 6, .. } = e {
            cancel.store(true, Ordering::Relaxed);
        }
    })
    .unwrap_err();
    assert!(
        matches!(
            e,
            ReferenceError::Interrupted {
                next_sample: 6,
                checkpoint: Some(_)
            }
        ),
        "{e}"
    );
    // Resume in two more interrupted steps, then finish.
    j.resume = true;
    let mut all_calls = r.calls.clone();
    for stop_at in [9u64, 15] {
        let cancel = AtomicBool::new(false);
        let mut r = Fake::new(3);
        let e = render_reference(&mut r, &j, &cancel, &mut |e: &ProgressEvent| {
            if let ProgressEvent::Chunk { done, .. } = e {
                if *done == stop_at {
                    cancel.store(true, Ordering::Relaxed);
                }
            }
        })
        .unwrap_err();
        assert!(
            matches!(e, ReferenceError::Interrupted { next_sample, .. } if next_sample == stop_at)
        );
        all_calls.extend(r.calls);
    }
    let mut r = Fake::new(3);
    let out = render_reference(&mut r, &j, &AtomicBool::new(false), &mut no_progress()).unwrap();
    all_calls.extend(r.calls);
    assert_eq!(bits(&out.image), bits(&reference));
    let covered: Vec<u64> = all_calls.iter().flat_map(|c| c.clone()).collect();
    assert_eq!(
        covered,
        (0..17).collect::<Vec<_>>(),
        "every sample exactly once"
    );
}

#[test]
fn resume_refuses_a_checkpoint_of_another_render() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = Fake::new(3);
    r.fail_on_call = Some(1);
    let mut j = job(dir.path(), "ref.exr", 8, ChunkPolicy::Fixed(2));
    assert!(render_reference(&mut r, &j, &AtomicBool::new(false), &mut no_progress()).is_err());
    j.resume = true;
    let e = render_reference(
        &mut Fake::new(4),
        &j,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, ReferenceError::BadCheckpoint { .. }) && msg.contains("seed"),
        "{msg}"
    );
    assert!(msg.contains("ref.checkpoint.exr"), "{msg}");
    let mut k = j.clone();
    k.sample_offset = 100;
    let msg = render_reference(
        &mut Fake::new(3),
        &k,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap_err()
    .to_string();
    assert!(msg.contains("starts at sample 0"), "{msg}");
    let mut k = j.clone();
    k.spp = 1;
    let msg = render_reference(
        &mut Fake::new(3),
        &k,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap_err()
    .to_string();
    assert!(msg.contains("already holds 2 spp"), "{msg}");
    // --resume without a checkpoint starts afresh.
    std::fs::remove_file(&j.checkpoint).unwrap();
    let out = render_reference(
        &mut Fake::new(3),
        &j,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap();
    assert_eq!(out.resumed_samples, 0);
    assert_eq!(out.image.meta.spp, Some(8));
}

#[test]
fn sample_offset_ranges_merge_to_the_full_reference() {
    let dir = tempfile::tempdir().unwrap();
    let reference = one_shot(dir.path(), 16);
    let mut lo = job(dir.path(), "lo.exr", 6, ChunkPolicy::Fixed(4));
    lo.sample_offset = 0;
    let mut hi = job(dir.path(), "hi.exr", 10, ChunkPolicy::Fixed(3));
    hi.sample_offset = 6;
    let a = render_reference(
        &mut Fake::new(3),
        &lo,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap()
    .image;
    let mut r = Fake::new(3);
    let b = render_reference(&mut r, &hi, &AtomicBool::new(false), &mut no_progress())
        .unwrap()
        .image;
    assert_eq!(r.calls.first().unwrap().start, 6);
    assert_eq!(b.meta.sample_offset, Some(6));
    let merged = merge(&[("lo.exr", &read_exr(&lo.output).unwrap()), ("hi.exr", &b)]).unwrap();
    assert!(merged.exact);
    assert_eq!(bits(&merged.image), bits(&reference));
    let _ = a;
}

#[test]
fn zero_spp_and_bad_sums_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let j = job(dir.path(), "z.exr", 0, ChunkPolicy::Fixed(1));
    assert!(matches!(
        render_reference(
            &mut Fake::new(1),
            &j,
            &AtomicBool::new(false),
            &mut no_progress()
        ),
        Err(ReferenceError::ZeroSpp)
    ));
    struct Short;
    impl SampleRenderer for Short {
        fn resolution(&self) -> (u32, u32) {
            (2, 2)
        }
        fn metadata(&self) -> RenderMeta {
            RenderMeta::new()
        }
        fn render_samples(&mut self, _: u64, _: u64) -> Result<Vec<[u64; 3]>, BoxError> {
            Ok(vec![[0; 3]; 3])
        }
    }
    let j = job(dir.path(), "s.exr", 2, ChunkPolicy::Fixed(1));
    let e =
        render_reference(&mut Short, &j, &AtomicBool::new(false), &mut no_progress()).unwrap_err();
    assert!(
        matches!(
            e,
            ReferenceError::BadSums {
                got: 3,
                expected: 4,
                ..
            }
        ),
        "{e}"
    );
}

/// `--resume` with a finished reference and no checkpoint continues from the file's exact
/// sums (bit-identical to rendering the larger count at once), does nothing to a complete
/// one, and refuses, untouched, one of another render. Guards the defect of issue 14: the
/// resume started over and overwrote a 4096-spp reference with 64 spp (injected once:
/// with the finished output skipped when there is no checkpoint, the first resume
/// renders samples 0..4 again and the test fails).
#[test]
fn resume_continues_a_finished_reference_or_leaves_it_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mut j = job(dir.path(), "ref.exr", 4, ChunkPolicy::Fixed(4));
    render_reference(
        &mut Fake::new(3),
        &j,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap();
    let four = std::fs::read(&j.output).unwrap();

    // Same count: complete already, the file is not rewritten.
    j.resume = true;
    let mut r = Fake::new(3);
    let out = render_reference(&mut r, &j, &AtomicBool::new(false), &mut no_progress()).unwrap();
    assert!(r.calls.is_empty(), "rendered {:?}", r.calls);
    assert_eq!(out.resumed_samples, 4);
    assert_eq!(std::fs::read(&j.output).unwrap(), four);

    // Another seed: refused, the file untouched.
    let e = render_reference(
        &mut Fake::new(9),
        &j,
        &AtomicBool::new(false),
        &mut no_progress(),
    )
    .unwrap_err();
    assert!(
        matches!(e, ReferenceError::BadCheckpoint { .. }) && e.to_string().contains("seed"),
        "{e}"
    );
    assert_eq!(std::fs::read(&j.output).unwrap(), four);

    // More samples: only the new ones are rendered, and the result is the one-shot's.
    j.spp = 10;
    let mut r = Fake::new(3);
    let out = render_reference(&mut r, &j, &AtomicBool::new(false), &mut no_progress()).unwrap();
    assert_eq!(out.resumed_samples, 4);
    assert_eq!(r.calls, vec![4..8, 8..10]);
    assert_eq!(bits(&out.image), bits(&one_shot(dir.path(), 10)));
}
