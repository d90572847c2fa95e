//! `lanterna reference` killed mid-run (SIGKILL, no chance to clean up) and resumed
//! equals an uninterrupted run bit for bit: the checkpoint holds the exact film sums and
//! the next sample index.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

fn reference(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lanterna"));
    c.args([
        "reference",
        concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-lights.gltf"),
    ])
    .args([
        "--width",
        "48",
        "--spp",
        "1024",
        "--chunk-spp",
        "16",
        "--checkpoint-every",
        "0",
        "-o",
    ])
    .arg(out)
    .args(extra);
    c
}

#[test]
fn killed_and_resumed_equals_uninterrupted() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.exr");
    let st = reference(&whole, &[]).output().unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );

    let resumed = dir.path().join("resumed.exr");
    let checkpoint = dir.path().join("resumed.checkpoint.exr");
    let mut child = reference(&resumed, &[])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while !checkpoint.exists() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint appeared"
        );
        if child.try_wait().unwrap().is_some() {
            panic!("the render finished before it could be killed; make it longer");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(!resumed.exists(), "the killed run wrote its output");

    let st = reference(&resumed, &["--resume"]).output().unwrap();
    let log = String::from_utf8_lossy(&st.stderr);
    assert!(st.status.success(), "{log}");
    assert!(!log.contains(" 0 resumed"), "nothing was resumed:\n{log}");
    let a = lanterna::image_io::read_exr(&whole).unwrap();
    let b = lanterna::image_io::read_exr(&resumed).unwrap();
    assert_eq!(a.meta.spp, b.meta.spp);
    assert_eq!(
        a.sums, b.sums,
        "the resumed reference differs from the uninterrupted one"
    );
    assert_eq!(a.rgb, b.rgb);
}
