//! Hostile and careless input (issue 14), through the built binary on tiny images: every
//! case ends without a panic, with the documented exit status (0 done, 1 error, 2 bad
//! command line, 75 interrupted with the partial result written, 130 interrupted with
//! nothing written), with its input files byte-identical afterwards and no temporary
//! file left behind; where a case could grow memory, it runs under an address-space cap.
//!
//! Each test says which defect it guards against; each was checked by injecting that
//! defect once and watching the test fail (noted per test). The scene loader's own fuzz
//! loop is `tests/scene_fuzz.rs`.

use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const EXIT_ERROR: i32 = 1;
const EXIT_USAGE: i32 = 2;
const EXIT_INTERRUPTED_SAVED: i32 = 75;
const EXIT_INTERRUPTED_NOTHING: i32 = 130;

struct Run {
    code: i32,
    stderr: String,
}

fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lanterna"));
    c.args(args)
        .env("LANTERNA_VALIDATION", "1")
        .env_remove(lanterna::files::MAX_INPUT_ENV);
    c
}

/// Runs lanterna to the end; a panic or a death by signal fails the test.
fn finish(mut c: Command, what: &str) -> Run {
    let out = c.output().expect("run lanterna");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{what}: panicked:\n{stderr}");
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("{what}: killed by a signal ({:?}):\n{stderr}", out.status));
    Run { code, stderr }
}

fn lanterna(args: &[&str]) -> Run {
    finish(command(args), &args.join(" "))
}

/// Runs lanterna and checks its exit status and that its error message has `needles`.
fn expect(args: &[&str], code: i32, needles: &[&str]) -> Run {
    let r = lanterna(args);
    assert_eq!(
        r.code, code,
        "{args:?}: exit {} ≠ {code}:\n{}",
        r.code, r.stderr
    );
    for n in needles {
        assert!(r.stderr.contains(n), "{args:?}: no `{n}` in:\n{}", r.stderr);
    }
    r
}

/// What is in a directory tree: file bytes, link targets, special files.
#[derive(Debug, PartialEq)]
enum Entry {
    File(Vec<u8>),
    Link(PathBuf),
    Other(String),
}

fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Entry> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            let ft = std::fs::symlink_metadata(&p).unwrap().file_type();
            let entry = if ft.is_symlink() {
                Entry::Link(std::fs::read_link(&p).unwrap())
            } else if ft.is_dir() {
                stack.push(p.clone());
                Entry::Other("dir".into())
            } else if ft.is_file() {
                Entry::File(std::fs::read(&p).unwrap())
            } else {
                Entry::Other(format!("{ft:?}"))
            };
            out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), entry);
        }
    }
    out
}

fn temps(dir: &Path) -> Vec<PathBuf> {
    snapshot(dir)
        .into_keys()
        .filter(|p| p.to_string_lossy().ends_with(".tmp"))
        .collect()
}

/// A one-quad scene with a camera in its own folder: `scene.gltf` and `quad.bin`.
struct Scene {
    dir: tempfile::TempDir,
    gltf: PathBuf,
}

impl Scene {
    fn path(&self) -> &str {
        self.gltf.to_str().unwrap()
    }
    fn file(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
    fn arg(&self, name: &str) -> String {
        self.file(name).to_string_lossy().into_owned()
    }
}

fn quad_json() -> Value {
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": "quad.bin", "byteLength": 60}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "materials": [{"emissiveFactor": [1, 1, 1]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0
    })
}

/// The quad's material as transmitting with `KHR_materials_volume` = `volume`.
fn volume(j: &mut Value, volume: Value) {
    j["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
    j["materials"][0]["extensions"] = json!({
        "KHR_materials_transmission": {"transmissionFactor": 1},
        "KHR_materials_volume": volume
    });
}

fn clearcoat(j: &mut Value, coat: Value) {
    j["extensionsUsed"] = json!(["KHR_materials_clearcoat"]);
    j["materials"][0]["extensions"] = json!({ "KHR_materials_clearcoat": coat });
}

fn quad_bin() -> Vec<u8> {
    let mut bin = Vec::new();
    for v in [
        -1f32, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin
}

/// Gives the quad signed-byte normals (accessor 2, not normalised) over its positions'
/// bytes.
fn byte_normals(j: &mut Value) {
    j["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": 0, "componentType": 5120, "count": 4, "type": "VEC3"}));
    j["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(2);
}

/// The quad scene, its JSON changed by `edit`.
fn scene_with(edit: impl FnOnce(&mut Value)) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("quad.bin"), quad_bin()).unwrap();
    let mut j = quad_json();
    edit(&mut j);
    let gltf = dir.path().join("scene.gltf");
    std::fs::write(&gltf, serde_json::to_vec_pretty(&j).unwrap()).unwrap();
    Scene { dir, gltf }
}

/// The quad scene with its mesh node instanced by `EXT_mesh_gpu_instancing` with
/// `attributes`, the accessors `extra` appended (from index 2).
fn instanced(attributes: Value, extra: &[Value]) -> Scene {
    scene_with(|j| {
        j["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
        j["accessors"]
            .as_array_mut()
            .unwrap()
            .extend_from_slice(extra);
        j["nodes"][0]["extensions"] =
            json!({"EXT_mesh_gpu_instancing": {"attributes": attributes}});
    })
}

fn scene() -> Scene {
    scene_with(|_| {})
}

/// A copy of `tests/data/draco/<file>` (a GLB) with byte `at` of its binary chunk set to
/// `value`.
fn draco_with_byte(file: &str, at: usize, value: u8) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/draco")
        .join(file);
    let mut b = std::fs::read(src).unwrap();
    let json_len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    b[28 + json_len + at] = value;
    let gltf = dir.path().join(file);
    std::fs::write(&gltf, b).unwrap();
    Scene { dir, gltf }
}

/// A tiny EXR written by the library (a reference for `compare`, inputs for `merge`).
fn tiny_exr(path: &Path) {
    let image = lanterna::image_io::Image::new(8, 8, vec![[0.5; 3]; 64]).unwrap();
    let _ = lanterna::image_io::write_exr(path, &image).unwrap();
}

/// Guards "-o equal to the input scene, its .bin, the --png path or the --save-guiding
/// path silently overwrites that file": every output that is an input (by another
/// name, a hard link, a symlink) or another output is refused before any work, and no
/// file changes. Mutation-checked: with `FilePlan::check` returning `Ok(())`, the first
/// case renders over `scene.gltf` and the snapshot assertion fails.
#[test]
fn outputs_never_overwrite_inputs() {
    let s = scene();
    std::fs::hard_link(s.file("scene.gltf"), s.file("hard.exr")).unwrap();
    std::os::unix::fs::symlink(s.file("quad.bin"), s.file("link.exr")).unwrap();
    std::fs::write(s.file("tree.sdt"), b"not a tree").unwrap();
    tiny_exr(&s.file("a.exr"));
    tiny_exr(&s.file("b.exr"));
    std::fs::create_dir(s.file("report")).unwrap();
    tiny_exr(&s.file("report/report.json"));
    let before = snapshot(s.dir.path());
    let p = s.path();
    let (gltf, bin, hard, link) = (
        s.arg("scene.gltf"),
        s.arg("quad.bin"),
        s.arg("hard.exr"),
        s.arg("link.exr"),
    );
    let (a, b, sdt) = (s.arg("a.exr"), s.arg("b.exr"), s.arg("tree.sdt"));
    let dotted = format!("{}/./../{}/scene.gltf", s.dir.path().display(), {
        s.dir.path().file_name().unwrap().to_string_lossy()
    });
    let tiny = ["--spp", "1", "--width", "8"];
    let cases: Vec<Vec<&str>> = vec![
        vec!["render", p, "-o", &gltf],
        vec!["render", p, "-o", &dotted],
        vec!["render", p, "-o", &bin],
        vec!["render", p, "-o", &hard],
        vec!["render", p, "-o", &link],
        vec!["render", p, "-o", &a, "--png", &a],
        vec![
            "render",
            p,
            "--method",
            "guided",
            "-o",
            &a,
            "--save-guiding",
            &gltf,
        ],
        vec![
            "render",
            p,
            "--method",
            "guided",
            "-o",
            &a,
            "--load-guiding",
            &sdt,
            "--save-guiding",
            &sdt,
        ],
        vec!["reference", p, "-o", &gltf],
        vec!["merge", &a, &b, "-o", &a],
        vec![
            "guiding",
            "view",
            p,
            "--load-guiding",
            &sdt,
            "--pixel",
            "0,0",
            "-o",
            &gltf,
        ],
    ];
    for mut args in cases {
        if matches!(args[0], "render" | "reference") {
            args.extend(tiny);
        }
        if args[0] == "render" {
            args.push("--quiet");
        }
        expect(&args, EXIT_ERROR, &["same file", "refusing to overwrite"]);
        assert_eq!(snapshot(s.dir.path()), before, "{args:?} changed a file");
    }
    let report = s.arg("report");
    let reference = s.arg("report/report.json");
    expect(
        &[
            "compare",
            p,
            "--reference",
            &reference,
            "--spp",
            "1",
            "--out-dir",
            &report,
        ],
        EXIT_ERROR,
        &["same file", "--reference"],
    );
    assert_eq!(snapshot(s.dir.path()), before);
}

/// Guards "the temp-file-and-rename write replaces a symlink, a FIFO or a device node
/// with a regular file" and "a killed run leaves .NAME.PID.tmp files forever": special
/// files are refused before the render and stay as they were; a symlink to a regular
/// file is written through and stays a link; temporary files of dead processes next to
/// the output are removed, those of live ones kept. Mutation-checked: with
/// `resolve_target` accepting every path, the FIFO is replaced by a regular file and the
/// test fails; with `remove_stale_temps` a no-op, the dead process's file stays.
#[test]
fn special_outputs_are_refused_and_links_written_through() {
    let s = scene();
    let fifo = s.file("out.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    std::fs::create_dir(s.file("adir")).unwrap();
    std::os::unix::fs::symlink(&fifo, s.file("to-fifo.exr")).unwrap();
    std::os::unix::fs::symlink(s.file("nowhere.exr"), s.file("dangling.exr")).unwrap();
    let before = snapshot(s.dir.path());
    for (out, says) in [
        ("out.fifo", "a FIFO"),
        ("adir", "a directory"),
        ("to-fifo.exr", "symbolic link to a FIFO"),
        ("dangling.exr", "dangling symbolic link"),
    ] {
        let o = s.arg(out);
        let r = expect(
            &[
                "render",
                s.path(),
                "-o",
                &o,
                "--no-png",
                "--spp",
                "1",
                "--width",
                "8",
                "--quiet",
            ],
            EXIT_ERROR,
            &[says, "never replaces"],
        );
        assert!(
            r.stderr.matches("(os error").count() <= 1,
            "an OS error is printed twice:\n{}",
            r.stderr
        );
        assert_eq!(snapshot(s.dir.path()), before, "-o {out} changed a file");
    }

    // A symlink to a regular file: written through, the link kept.
    std::fs::write(s.file("real.exr"), b"old").unwrap();
    std::os::unix::fs::symlink(s.file("real.exr"), s.file("link.exr")).unwrap();
    // No process has id 4294967294 (Linux pids stay below 2^22); pid 1 always runs.
    let dead = s.file(".real.exr.4294967294.tmp");
    let alive = s.file(".real.exr.1.tmp");
    std::fs::write(&dead, b"left by a killed run").unwrap();
    std::fs::write(&alive, b"being written by a live one").unwrap();
    let link = s.arg("link.exr");
    expect(
        &[
            "render",
            s.path(),
            "-o",
            &link,
            "--no-png",
            "--spp",
            "1",
            "--width",
            "8",
            "--quiet",
        ],
        0,
        &[],
    );
    assert!(std::fs::symlink_metadata(s.file("link.exr"))
        .unwrap()
        .file_type()
        .is_symlink());
    let image = lanterna::image_io::read_exr(&s.file("real.exr")).unwrap();
    assert_eq!(image.meta.spp, Some(1));
    assert!(
        !dead.exists(),
        "the dead process's temporary file is still there"
    );
    assert!(
        alive.exists(),
        "a live process's temporary file was removed"
    );
    std::fs::remove_file(&alive).unwrap();
    assert_eq!(temps(s.dir.path()), Vec::<PathBuf>::new());
}

/// Guards the crashes: an out-of-range POSITION accessor panicked inside gltf-json
/// (render, info, scene export-mitsuba); `--time 1e30`/`1e19` and `--checkpoint-every
/// 1e30` panicked in Duration arithmetic; `guiding view --size 100000` aborted on a
/// 40 GB allocation; `/dev/zero` or an endless stream as the scene grew memory without
/// bound (run here under a 2 GiB address-space cap). Mutation-checked: without
/// `gltf_check::precheck` the first three runs panic; with `read_scene_file` reading
/// without a bound the FIFO case hits the cap and fails.
#[test]
fn crashes_are_clear_errors() {
    let s = scene_with(|j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99));
    let before = snapshot(s.dir.path());
    let p = s.path();
    let export = s.arg("export");
    for args in [
        vec!["info", p],
        vec!["render", p, "--spp", "1", "--width", "8", "-o", &export],
        vec!["scene", "export-mitsuba", p, "-o", &export],
    ] {
        expect(&args, EXIT_ERROR, &["accessor 99"]);
    }
    assert_eq!(snapshot(s.dir.path()), before);

    let s = scene();
    let p = s.path();
    let out = s.arg("out.exr");
    let reference = s.arg("ref.exr");
    tiny_exr(&s.file("ref.exr"));
    let report = s.arg("report");
    for t in ["1e30", "1e19", "inf", "0"] {
        expect(
            &["render", p, "--time", t, "--width", "8", "-o", &out],
            EXIT_ERROR,
            &["--time", "seconds"],
        );
        expect(
            &[
                "compare",
                p,
                "--reference",
                &reference,
                "--time",
                t,
                "--out-dir",
                &report,
            ],
            EXIT_ERROR,
            &["time budgets"],
        );
    }
    expect(
        &[
            "reference",
            p,
            "--spp",
            "1",
            "--width",
            "8",
            "--checkpoint-every",
            "1e30",
            "-o",
            &out,
        ],
        0,
        &[],
    );
    assert!(s.file("out.exr").exists());
    std::fs::write(s.file("t.sdt"), b"x").unwrap();
    let png = s.arg("v.png");
    let sdt = s.arg("t.sdt");
    expect(
        &[
            "guiding",
            "view",
            p,
            "--load-guiding",
            &sdt,
            "--pixel",
            "0,0",
            "-o",
            &png,
            "--size",
            "100000",
        ],
        EXIT_USAGE,
        &["4096"],
    );

    // Endless streams, with memory capped at 2 GiB of address space.
    let capped = |args: &str, env: &str| {
        let mut c = Command::new("sh");
        c.arg("-c").arg(format!(
            "ulimit -v 2097152; exec env {env} '{}' {args}",
            env!("CARGO_BIN_EXE_lanterna")
        ));
        finish(c, args)
    };
    let r = capped("info /dev/zero", "");
    assert_eq!(r.code, EXIT_ERROR, "{}", r.stderr);
    assert!(r.stderr.contains("not a glTF scene"), "{}", r.stderr);
    // A FIFO fed `{` and then spaces forever looks like JSON: the read must stop at the
    // input limit (lowered to 16 MiB here).
    let fifo = s.file("endless.gltf");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            use std::io::Write;
            let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&fifo) else {
                return;
            };
            let block = [b' '; 1 << 16];
            let _ = f.write_all(b"{");
            while f.write_all(&block).is_ok() {}
        })
    };
    let r = capped(
        &format!("info '{}'", fifo.display()),
        &format!("{}=16", lanterna::files::MAX_INPUT_ENV),
    );
    {
        // Should lanterna never have opened the FIFO, the writer still waits in open():
        // a non-blocking reader (O_NONBLOCK, 0o4000 on Linux) releases it.
        use std::os::unix::fs::OpenOptionsExt;
        let _release = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(0o4000)
            .open(&fifo);
    }
    writer.join().unwrap();
    assert_eq!(r.code, EXIT_ERROR, "{}", r.stderr);
    assert!(
        r.stderr.contains("larger than 16777216 bytes"),
        "{}",
        r.stderr
    );
    // A tiny file whose sparse accessor of 2^28 vertices would expand to gigabytes:
    // refused before allocating, under the same cap.
    let bomb = scene_with(|j| {
        // Sparse on zeros: one stored value, 2^28 elements implied.
        j["accessors"][0] = json!({
            "componentType": 5126, "count": 1u64 << 28, "type": "VEC3",
            "min": [0, 0, 0], "max": [0, 0, 0],
            "sparse": {"count": 1,
                       "indices": {"bufferView": 1, "componentType": 5123},
                       "values": {"bufferView": 0}}
        });
        j["meshes"][0]["primitives"][0]
            .as_object_mut()
            .unwrap()
            .remove("indices");
    });
    let r = capped(&format!("info '{}'", bomb.path()), "");
    assert_eq!(r.code, EXIT_ERROR, "{}", r.stderr);
    assert!(r.stderr.contains("input limit"), "{}", r.stderr);
    assert_eq!(temps(s.dir.path()), Vec::<PathBuf>::new());
}

/// Guards "buffer and image URIs are followed anywhere: ../../x.bin, absolute paths,
/// file://, and /etc/passwd is read and parsed as geometry": only files inside the scene's
/// folder are read unless --allow-outside-uris, never the network. Mutation-checked: with
/// `UriReader::resolve` skipping the inside check, `../outside.bin` loads and the test
/// fails.
#[test]
fn uris_stay_inside_the_scene_folder() {
    let parent = tempfile::tempdir().unwrap();
    std::fs::write(parent.path().join("outside.bin"), quad_bin()).unwrap();
    let outside = parent.path().join("outside.bin");
    let folder = parent.path().join("scene");
    std::fs::create_dir(&folder).unwrap();
    std::os::unix::fs::symlink(&outside, folder.join("escape.bin")).unwrap();
    let write = |name: &str, uri: &str| {
        let mut j = quad_json();
        j["buffers"][0]["uri"] = json!(uri);
        let p = folder.join(name);
        std::fs::write(&p, serde_json::to_vec(&j).unwrap()).unwrap();
        p.to_string_lossy().into_owned()
    };
    let abs = outside.to_string_lossy().into_owned();
    let file_uri = format!("file://{abs}");
    for (uri, says) in [
        ("../outside.bin", "--allow-outside-uris"),
        (abs.as_str(), "--allow-outside-uris"),
        (file_uri.as_str(), "--allow-outside-uris"),
        ("escape.bin", "--allow-outside-uris"),
        ("/etc/passwd", "--allow-outside-uris"),
        ("http://127.0.0.1:9/quad.bin", "never the network"),
        ("https://example.com/quad.bin", "never the network"),
    ] {
        let scene = write("s.gltf", uri);
        let r = expect(&["info", &scene], EXIT_ERROR, &[says]);
        assert!(
            !r.stderr.contains("root:"),
            "file contents leaked:\n{}",
            r.stderr
        );
    }
    let scene = write("ok.gltf", "../outside.bin");
    expect(&["info", &scene, "--allow-outside-uris"], 0, &[]);
}

/// Guards the silent wrong results and the unvalidated settings: `--fov 180`/NaN
/// rendered black, `--sample-offset` wrapped past 2^32 in `render`, VEC2 or u8 POSITION
/// was read as float VEC3, an index accessor of count 2^31 over a 12-byte view loaded
/// fewer triangles, a buffer view out of range said "has no POSITION attribute", and
/// `--train-fraction`, `--guiding-threshold`, `--exposure` were not checked. All are
/// refused before a device is opened, naming the flag or the accessor.
/// Mutation-checked: without the `--fov` check in `RenderSettings::validate`, `--fov 180`
/// renders and exits 0.
#[test]
fn wrong_values_are_refused() {
    let s = scene();
    let p = s.path();
    let out = s.arg("out.exr");
    let before = snapshot(s.dir.path());
    let flags: &[(&[&str], &str)] = &[
        (&["--fov", "180"], "--fov"),
        (&["--fov", "NaN"], "--fov"),
        (&["--fov", "0"], "--fov"),
        (&["--sample-offset", "4294967295", "--spp", "4"], "32-bit"),
        (&["--sample-offset", "4294967296", "--time", "1"], "32-bit"),
        (&["--exposure", "inf"], "--exposure"),
        (&["--exposure", "1e6"], "--exposure"),
        (
            &["--method", "guided", "--train-fraction", "2"],
            "--train-fraction",
        ),
        (
            &["--method", "guided", "--train-fraction", "NaN"],
            "--train-fraction",
        ),
        (
            &["--method", "guided", "--guide-history", "1.5"],
            "--guide-history",
        ),
        (
            &["--method", "guided", "--guiding-threshold", "0"],
            "--guiding-threshold",
        ),
        (
            &["--method", "guided", "--guiding-threshold", "NaN"],
            "--guiding-threshold",
        ),
        (
            &["--method", "guided", "--bsdf-fraction", "1.5"],
            "--bsdf-fraction",
        ),
        (&["--method", "guided", "--light-mix", "1"], "--light-mix"),
        (&["--ris-candidates", "0"], "--ris-candidates"),
    ];
    for (extra, flag) in flags {
        let mut args = vec!["render", p, "--width", "8", "-o", &out];
        args.extend_from_slice(extra);
        expect(&args, EXIT_ERROR, &[flag]);
    }
    assert_eq!(snapshot(s.dir.path()), before);

    let scenes: Vec<(Scene, &str)> = vec![
        (
            scene_with(|j| j["accessors"][0]["type"] = json!("VEC2")),
            "POSITION must be float VEC3",
        ),
        (
            scene_with(|j| j["accessors"][0]["componentType"] = json!(5121)),
            "POSITION must be float VEC3",
        ),
        (
            scene_with(|j| j["accessors"][1]["count"] = json!(1u64 << 31)),
            "buffer view 1 has 12",
        ),
        (
            scene_with(|j| j["accessors"][1]["componentType"] = json!(5126)),
            "indices must be SCALAR unsigned",
        ),
        (
            scene_with(|j| j["bufferViews"][0]["byteOffset"] = json!(1_000_000_000)),
            "buffer view 0 spans bytes",
        ),
        (
            scene_with(|j| j["cameras"][0]["perspective"]["yfov"] = json!(3.5)),
            "yfov",
        ),
        // KHR_mesh_quantization: byte normals are unit vectors only when normalised,
        // and without the extension they are not allowed at all.
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
                byte_normals(j);
            }),
            "byte but not normalized",
        ),
        (scene_with(byte_normals), "NORMAL must be float VEC3"),
        // KHR_materials_volume: values that would make the absorption negative, infinite
        // or NaN.
        (
            scene_with(|j| volume(j, json!({"thicknessFactor": 1, "attenuationDistance": 0}))),
            "attenuationDistance 0 must be positive",
        ),
        (
            scene_with(|j| volume(j, json!({"thicknessFactor": -1}))),
            "thicknessFactor -1 is negative",
        ),
        (
            scene_with(|j| {
                volume(
                    j,
                    json!({"thicknessFactor": 1, "attenuationColor": [2, 0, 0]}),
                )
            }),
            "attenuationColor must be three numbers in [0, 1]",
        ),
        (
            scene_with(|j| volume(j, json!({"thicknessFactor": 1, "attenuationColor": [1, 1]}))),
            "attenuationColor must be three numbers in [0, 1]",
        ),
        (
            scene_with(|j| volume(j, json!({"thicknessFactor": "thick"}))),
            "thicknessFactor is not a finite number",
        ),
        // KHR_materials_clearcoat: a factor that is not a number, texture references
        // that lead nowhere.
        (
            scene_with(|j| clearcoat(j, json!({"clearcoatFactor": "glossy"}))),
            "KHR_materials_clearcoat clearcoatFactor is not a finite number",
        ),
        (
            scene_with(|j| {
                clearcoat(
                    j,
                    json!({"clearcoatFactor": 1, "clearcoatNormalTexture": {"index": 7}}),
                )
            }),
            "clearcoatNormalTexture refers to texture 7, which does not exist",
        ),
        (
            scene_with(|j| {
                clearcoat(
                    j,
                    json!({"clearcoatFactor": 1, "clearcoatTexture": {"texCoord": 0}}),
                )
            }),
            "clearcoatTexture has no texture index",
        ),
        // KHR_materials_sheen: a colour that is not three numbers.
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_sheen"]);
                j["materials"][0]["extensions"] =
                    json!({"KHR_materials_sheen": {"sheenColorFactor": [1, "red", 0]}});
            }),
            "KHR_materials_sheen sheenColorFactor must be three finite numbers",
        ),
        // KHR_materials_diffuse_transmission: a colour that is not three numbers, a
        // texture that does not exist.
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_diffuse_transmission"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_diffuse_transmission":
                    {"diffuseTransmissionFactor": 0.5, "diffuseTransmissionColorFactor": [1, 0.5]}});
            }),
            "KHR_materials_diffuse_transmission diffuseTransmissionColorFactor must be three finite numbers",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_diffuse_transmission"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_diffuse_transmission":
                    {"diffuseTransmissionFactor": 0.5, "diffuseTransmissionTexture": {"index": 9}}});
            }),
            "KHR_materials_diffuse_transmission diffuseTransmissionTexture refers to texture 9, which does not exist",
        ),
        // KHR_materials_iridescence: a film index below 1, a negative thickness (the
        // extension's schema).
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_iridescence"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_iridescence":
                    {"iridescenceFactor": 1, "iridescenceIor": 0.5}});
            }),
            "KHR_materials_iridescence iridescenceIor 0.5 is below 1",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_iridescence"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_iridescence":
                    {"iridescenceFactor": 1, "iridescenceThicknessMinimum": -20}});
            }),
            "KHR_materials_iridescence iridescenceThicknessMinimum -20 is negative",
        ),
        // KHR_materials_dispersion: a negative spread, one beyond single precision, one
        // that is not a number (the extension's schema: a number from 0).
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_dispersion"]);
                j["materials"][0]["extensions"] =
                    json!({"KHR_materials_dispersion": {"dispersion": -0.5}});
            }),
            "KHR_materials_dispersion dispersion -0.5 is not a finite number of at least 0",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_dispersion"]);
                j["materials"][0]["extensions"] =
                    json!({"KHR_materials_dispersion": {"dispersion": 1e39}});
            }),
            "KHR_materials_dispersion dispersion inf is not a finite number of at least 0",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_dispersion"]);
                j["materials"][0]["extensions"] =
                    json!({"KHR_materials_dispersion": {"dispersion": "flint"}});
            }),
            "KHR_materials_dispersion dispersion is not a finite number",
        ),
        // EXT_meshopt_compression: a stream that is not one (the quad's float
        // positions), an unknown mode.
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
                j["bufferViews"][0]["extensions"] = json!({"EXT_meshopt_compression":
                    {"buffer": 0, "byteLength": 48, "byteStride": 12, "count": 4,
                     "mode": "ATTRIBUTES"}});
            }),
            "buffer view 0 (EXT_meshopt_compression): ATTRIBUTES stream starts with 0x00, not 0xa0",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
                j["bufferViews"][0]["extensions"] = json!({"EXT_meshopt_compression":
                    {"buffer": 0, "byteLength": 48, "byteStride": 12, "count": 4,
                     "mode": "SPIRAL"}});
            }),
            "buffer view 0 (EXT_meshopt_compression): unknown mode \"SPIRAL\"",
        ),
        // KHR_draco_mesh_compression: one byte of a stream changed so that the decoder
        // asks for 4 GB (its child process is refused it), or panics.
        (
            draco_with_byte("uvsets-level10.glb", 151, 0xff),
            "mesh 0 primitive 0 (KHR_draco_mesh_compression): its Draco stream (buffer view 0) \
             is damaged: the decoder aborted",
        ),
        (
            draco_with_byte("Box_Draco.glb", 125, 0xff),
            "its Draco stream (buffer view 0) is damaged: the decoder stopped on an internal error",
        ),
        // EXT_mesh_gpu_instancing: attributes of different counts, a rotation of
        // integers not normalised, a zero quaternion (normalised bytes over the zeros
        // of a float 0.0), an accessor that does not exist, a rotation of the wrong type.
        (
            instanced(
                json!({"TRANSLATION": 2, "SCALE": 3}),
                &[json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}),
                  json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"})],
            ),
            "EXT_mesh_gpu_instancing: TRANSLATION has 4 elements but SCALE has 3",
        ),
        (
            instanced(
                json!({"ROTATION": 2}),
                &[json!({"bufferView": 0, "componentType": 5120, "count": 4, "type": "VEC4"})],
            ),
            "EXT_mesh_gpu_instancing ROTATION: accessor 2 (ROTATION) is byte but not normalized",
        ),
        (
            instanced(
                json!({"ROTATION": 2}),
                &[json!({"bufferView": 0, "byteOffset": 8, "componentType": 5120,
                         "normalized": true, "count": 1, "type": "VEC4"})],
            ),
            "EXT_mesh_gpu_instancing ROTATION 0 is [0.0, 0.0, 0.0, 0.0], not a rotation",
        ),
        (
            instanced(json!({"TRANSLATION": 9}), &[]),
            "EXT_mesh_gpu_instancing TRANSLATION: accessor 9 (TRANSLATION) does not exist",
        ),
        (
            instanced(
                json!({"ROTATION": 2}),
                &[json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"})],
            ),
            "ROTATION must be VEC4 of float, normalized byte or normalized short",
        ),
        // KHR_materials_anisotropy: a rotation that is not a number, a texture that
        // does not exist.
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_anisotropy"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_anisotropy":
                    {"anisotropyStrength": 1, "anisotropyRotation": "sideways"}});
            }),
            "KHR_materials_anisotropy anisotropyRotation is not a finite number",
        ),
        (
            scene_with(|j| {
                j["extensionsUsed"] = json!(["KHR_materials_anisotropy"]);
                j["materials"][0]["extensions"] = json!({"KHR_materials_anisotropy":
                    {"anisotropyStrength": 1, "anisotropyTexture": {"index": 9}}});
            }),
            "anisotropyTexture refers to texture 9, which does not exist",
        ),
    ];
    for (s, says) in scenes {
        let before = snapshot(s.dir.path());
        let out = s.arg("out.exr");
        expect(
            &["render", s.path(), "--spp", "1", "--width", "8", "-o", &out],
            EXIT_ERROR,
            &[says],
        );
        expect(&["info", s.path()], EXIT_ERROR, &[says]);
        assert_eq!(snapshot(s.dir.path()), before);
    }
}

/// Guards the confusing messages: a raw `vkCreateBuffer failed` for a too-large image
/// (now: which limit, and what size fits). Mutation-checked: without
/// `limits::check_image_size`, the run fails with the allocation error instead.
#[test]
fn a_too_large_image_names_the_limit() {
    let s = scene();
    let out = s.arg("big.exr");
    expect(
        &[
            "render",
            s.path(),
            "--width",
            "16384",
            "--height",
            "16384",
            "--spp",
            "1",
            "-o",
            &out,
        ],
        EXIT_ERROR,
        &["16384×16384", "MiB", "--width"],
    );
    assert!(!s.file("big.exr").exists());
}

/// A running lanterna whose stderr is read line by line.
struct Running {
    child: std::process::Child,
    lines: std::sync::mpsc::Receiver<String>,
    seen: String,
}

fn spawn(args: &[&str]) -> Running {
    let mut c = command(args);
    c.arg("--log").arg("debug").stderr(Stdio::piped());
    let mut child = c.spawn().unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, lines) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
        {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    Running {
        child,
        lines,
        seen: String::new(),
    }
}

impl Running {
    /// Waits (at most 5 minutes) for a line of stderr containing `needle`.
    fn wait_for(&mut self, needle: &str) {
        let deadline = Instant::now() + Duration::from_secs(300);
        while Instant::now() < deadline {
            match self.lines.recv_timeout(Duration::from_secs(1)) {
                Ok(line) => {
                    self.seen.push_str(&line);
                    self.seen.push('\n');
                    if line.contains(needle) {
                        return;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(_) => break,
            }
        }
        panic!("no `{needle}` in the output:\n{}", self.seen);
    }

    fn signal(&self, name: &str) {
        let ok = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -{name} failed");
    }

    fn finish(mut self) -> Run {
        let status = self.child.wait().unwrap();
        for line in self.lines.iter() {
            self.seen.push_str(&line);
            self.seen.push('\n');
        }
        assert!(!self.seen.contains("panicked"), "panicked:\n{}", self.seen);
        let code = status
            .code()
            .unwrap_or_else(|| panic!("killed by a signal ({status:?}):\n{}", self.seen));
        Run {
            code,
            stderr: self.seen,
        }
    }
}

/// Guards "SIGTERM saves nothing; an interrupted render exits 0 and an interrupted
/// reference exits 1; Ctrl-C during guided training discards everything": SIGTERM and
/// SIGINT both stop at a chunk boundary, write what is consistent and exit 75; a second
/// signal exits 130 at once. Mutation-checked: without ctrlc's `termination` feature
/// SIGTERM kills the render (no exit status) and the test fails; before a training pass
/// kept at least one sample (and kept the previous pass when interrupted before its
/// start), the guided run exited 130 with nothing written in 2 of 8 runs.
#[test]
fn interruption_writes_the_partial_result_and_exits_75() {
    let s = scene();
    let p = s.path();
    let out = s.arg("pt.exr");
    let mut r = spawn(&[
        "render",
        p,
        "--spp",
        "100000000",
        "--width",
        "8",
        "-o",
        &out,
    ]);
    r.wait_for("first dispatch");
    std::thread::sleep(Duration::from_millis(500));
    r.signal("TERM");
    let run = r.finish();
    assert_eq!(run.code, EXIT_INTERRUPTED_SAVED, "{}", run.stderr);
    let image = lanterna::image_io::read_exr(&s.file("pt.exr")).unwrap();
    let spp = image.meta.spp.unwrap();
    assert!(spp > 0 && spp < 100_000_000, "spp {spp}");
    assert!(s.file("pt.png").exists());

    // Guided: interrupted while training, it keeps the last training pass and the tree.
    let out = s.arg("guided.exr");
    let tree = s.arg("guided.sdt");
    let mut r = spawn(&[
        "render",
        p,
        "--method",
        "guided-ris",
        "--spp",
        "100000000",
        "--train-fraction",
        "0.9",
        "--width",
        "8",
        "-o",
        &out,
        "--save-guiding",
        &tree,
    ]);
    r.wait_for("guiding iteration 2");
    r.signal("INT");
    let run = r.finish();
    assert_eq!(run.code, EXIT_INTERRUPTED_SAVED, "{}", run.stderr);
    let image = lanterna::image_io::read_exr(&s.file("guided.exr")).unwrap();
    assert!(image.meta.extra.contains_key("guiding.interrupted"));
    assert!(image.meta.spp.unwrap() > 0);
    lanterna::guiding::SdTree::load_unchecked(&s.file("guided.sdt")).unwrap();

    // A reference: the checkpoint is kept, the reference itself not written.
    let out = s.arg("ref.exr");
    let mut r = spawn(&[
        "reference",
        p,
        "--spp",
        "100000000",
        "--width",
        "8",
        "--chunk-spp",
        "1",
        "--checkpoint-every",
        "0",
        "-o",
        &out,
    ]);
    r.wait_for("checkpoint");
    r.signal("TERM");
    let run = r.finish();
    assert_eq!(run.code, EXIT_INTERRUPTED_SAVED, "{}", run.stderr);
    assert!(run.stderr.contains("--resume"), "{}", run.stderr);
    assert!(s.file("ref.checkpoint.exr").exists() && !s.file("ref.exr").exists());

    // Two signals in a row: out at once, nothing promised.
    let out = s.arg("twice.exr");
    let mut r = spawn(&[
        "render",
        p,
        "--spp",
        "100000000",
        "--width",
        "8",
        "-o",
        &out,
    ]);
    r.wait_for("first dispatch");
    r.signal("INT");
    r.signal("INT");
    let run = r.finish();
    assert!(
        [EXIT_INTERRUPTED_NOTHING, EXIT_INTERRUPTED_SAVED].contains(&run.code),
        "{}",
        run.stderr
    );
    // The render's own temporary files are gone (a write cut short by the second
    // signal leaves one, of the EXR or of its PNG companion, which the next write of
    // that file removes).
    tiny_exr(&s.file("twice.exr"));
    lanterna::files::write_atomically(&s.file("twice.png"), b"next run").unwrap();
    assert_eq!(temps(s.dir.path()), Vec::<PathBuf>::new());
}

/// Guards "`reference --resume` on a finished output without a checkpoint starts over
/// and overwrote a 4096-spp reference with 64 spp": through the CLI, a complete reference
/// is left byte-identical, one of another seed is refused untouched, and a larger --spp
/// continues it. (The library test `resume_continues_a_finished_reference_or_leaves_it_alone`
/// checks bit-exactness; mutation-checked there.)
#[test]
fn resume_never_starts_over_a_finished_reference() {
    let s = scene();
    let p = s.path();
    let out = s.arg("ref.exr");
    let base = ["reference", p, "--width", "8", "-o", &out];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        base.iter().copied().chain(extra.iter().copied()).collect()
    };
    expect(&with(&["--spp", "2"]), 0, &[]);
    let finished = std::fs::read(s.file("ref.exr")).unwrap();
    expect(&with(&["--spp", "2", "--resume"]), 0, &["nothing to do"]);
    assert_eq!(std::fs::read(s.file("ref.exr")).unwrap(), finished);
    expect(
        &with(&["--spp", "4", "--seed", "7", "--resume"]),
        EXIT_ERROR,
        &["seed"],
    );
    assert_eq!(std::fs::read(s.file("ref.exr")).unwrap(), finished);
    expect(&with(&["--spp", "3", "--resume"]), 0, &[]);
    let image = lanterna::image_io::read_exr(&s.file("ref.exr")).unwrap();
    assert_eq!(image.meta.spp, Some(3));
    assert_eq!(temps(s.dir.path()), Vec::<PathBuf>::new());
}
