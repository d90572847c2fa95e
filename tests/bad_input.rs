//! Bad input gives a clear error naming the file and the problem, a non-zero exit, no
//! panic, and no output file.

use std::path::Path;
use std::process::Command;

fn lanterna(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lanterna"))
        .args(args)
        .env("LANTERNA_VALIDATION", "1")
        .output()
        .expect("run lanterna");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "lanterna panicked:\n{stderr}");
    (out.status.success(), stderr)
}

/// A minimal valid scene: one emitting quad seen by a camera. Tests break one part of it.
fn scene_json(emissive: &str, camera: bool, buffer_uri: &str) -> String {
    let cameras = if camera {
        r#","cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}]"#
    } else {
        ""
    };
    let camera_node = if camera {
        r#",{"camera":0,"translation":[0,0,3]}"#
    } else {
        ""
    };
    let nodes = if camera { "[0,1]" } else { "[0]" };
    format!(
        r#"{{"asset":{{"version":"2.0"}},
        "buffers":[{{"uri":"{buffer_uri}","byteLength":60}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
        "materials":[{{"emissiveFactor":{emissive}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
        "nodes":[{{"mesh":0}}{camera_node}],
        "scenes":[{{"nodes":{nodes}}}],"scene":0{cameras}}}"#
    )
}

fn write_scene(dir: &Path, json: &str) -> String {
    let mut bin = Vec::new();
    for p in [
        [-1f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("quad.bin"), bin).unwrap();
    let path = dir.join("scene.gltf");
    std::fs::write(&path, json).unwrap();
    path.to_string_lossy().into_owned()
}

fn render_fails_with(scene: &str, dir: &Path, expected: &[&str]) {
    let out = dir.join("out.exr");
    let (ok, stderr) = lanterna(&[
        "render",
        scene,
        "--spp",
        "1",
        "--width",
        "8",
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!ok, "render succeeded on bad input {scene}");
    for e in expected {
        assert!(stderr.contains(e), "error message lacks `{e}`:\n{stderr}");
    }
    assert!(
        !out.exists() && !out.with_extension("png").exists(),
        "an output file was written"
    );
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

/// Renders `scene` (8 pixels wide, 1 spp, with `extra` arguments) into `dir`, which must
/// succeed and write the image; returns stderr.
fn renders(scene: &str, dir: &Path, extra: &[&str]) -> String {
    let out = dir.join("ok.exr");
    let out = out.to_str().unwrap();
    let mut args = vec!["render", scene, "--spp", "1", "--width", "8", "-o", out];
    args.extend_from_slice(extra);
    let (ok, stderr) = lanterna(&args);
    assert!(ok, "{stderr}");
    assert!(Path::new(out).exists());
    stderr
}

/// Writes `json` as a scene, renders it (see [`renders`]) and checks that stderr warns
/// with `warning`.
fn renders_with_warning(json: &str, warning: &str) {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), json);
    let stderr = renders(&scene, dir.path(), &[]);
    assert!(
        stderr.contains(warning),
        "no warning `{warning}`:\n{stderr}"
    );
}

#[test]
fn the_valid_scene_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", true, "quad.bin"));
    renders(&scene, dir.path(), &["--quiet"]);
}

#[test]
fn missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.gltf");
    render_fails_with(
        missing.to_str().unwrap(),
        dir.path(),
        &["nope.gltf", "cannot read"],
    );
}

#[test]
fn malformed_json() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.gltf");
    std::fs::write(&path, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [").unwrap();
    render_fails_with(
        path.to_str().unwrap(),
        dir.path(),
        &["broken.gltf", "not a valid glTF"],
    );
}

#[test]
fn truncated_glb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.glb");
    std::fs::write(&path, b"glTF\x02\x00\x00\x00\xff\x00\x00\x00").unwrap();
    render_fails_with(path.to_str().unwrap(), dir.path(), &["cut.glb"]);
}

#[test]
fn missing_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", true, "gone.bin"));
    render_fails_with(&scene, dir.path(), &["scene.gltf", "gone.bin"]);
}

#[test]
fn no_camera() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", false, "quad.bin"));
    render_fails_with(
        &scene,
        dir.path(),
        &["scene.gltf", "no camera", "--look-at"],
    );
}

#[test]
fn no_camera_but_look_at_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", false, "quad.bin"));
    renders(&scene, dir.path(), &["--look-at", "0,0,3,0,0,0", "--quiet"]);
}

#[test]
fn zero_lights() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[0,0,0]", true, "quad.bin"));
    render_fails_with(&scene, dir.path(), &["scene.gltf", "no lights"]);
}

/// `lanterna info` still describes a scene without lights (so a user can see why nothing
/// lights it), with a warning and zero light counts, while `render` refuses it above.
#[test]
fn info_describes_a_scene_without_lights() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[0,0,0]", true, "quad.bin"));
    let out = Command::new(env!("CARGO_BIN_EXE_lanterna"))
        .args(["info", &scene])
        .output()
        .expect("run lanterna");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("no lights"), "no warning:\n{stderr}");
    assert!(stdout.contains("triangles           2"), "{stdout}");
    assert!(stdout.contains("light models        0 "), "{stdout}");
}

/// An animation channel whose target has no `node`, which the gltf crate's types
/// require, is ignored with a warning, as the glTF specification says, unless it is a
/// `KHR_animation_pointer` channel (tests/animation_pointer.rs): such a file renders
/// instead of being refused as invalid glTF (Khronos's `AnimationPointer` samples were,
/// until 2026-11-29), and so do the file's other animations.
#[test]
fn animation_channels_without_a_node_do_not_stop_a_render() {
    let json = scene_json("[1,1,1]", true, "quad.bin").replacen(
        r#"{"asset":{"version":"2.0"},"#,
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_animation_pointer"],
        "animations":[{"samplers":[{"input":1,"output":0}],"channels":[{"sampler":0,
        "target":{"path":"translation"}},{"sampler":0,
        "target":{"path":"pointer","extensions":{"KHR_animation_pointer":
        {"pointer":"/materials/0/emissiveFactor"}}}}]}],"#,
        1,
    );
    assert!(json.contains("KHR_animation_pointer"));
    renders_with_warning(
        &json,
        "1 animation channel(s) whose target has no node and no pointer",
    );
    renders_with_warning(&json, "has 1 animation(s); without --animation-time");
}

/// A punctual light's `range` is a cutoff hint that lanterna does not apply; the user
/// hears so once per file.
#[test]
fn a_light_range_is_ignored_with_a_warning() {
    let json = scene_json("[1,1,1]", true, "quad.bin")
        .replacen(
            r#"{"asset":{"version":"2.0"},"#,
            r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_lights_punctual"],
            "extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","range":2},
            {"type":"point","range":3},{"type":"point"}]}},"#,
            1,
        )
        .replacen(
            r#""nodes":[{"mesh":0}"#,
            r#""nodes":[{"mesh":0,"children":[2,3,4]}"#,
            1,
        )
        .replacen(
            r#"{"camera":0,"translation":[0,0,3]}"#,
            r#"{"camera":0,"translation":[0,0,3]},
            {"extensions":{"KHR_lights_punctual":{"light":0}},"translation":[0,0,1]},
            {"extensions":{"KHR_lights_punctual":{"light":1}},"translation":[0,0,1]},
            {"extensions":{"KHR_lights_punctual":{"light":2}},"translation":[0,0,1]}"#,
            1,
        );
    renders_with_warning(&json, "2 punctual light(s) have a range, which is ignored");
}

/// glTF's zfar is a clip plane, which lanterna's camera rays honour: a far plane nearer
/// than part of the scene warns, saying how to see past it (the quad lies 3 units in
/// front of the camera), one beyond it does not. Clip planes the spec forbids (a far
/// plane in front of the near one, a negative near plane) are ignored with a warning
/// naming the camera. Seen to fail with the warnings left out.
#[test]
fn a_far_clip_plane_in_front_of_the_scene_warns() {
    let with_planes = |znear: &str, zfar: &str| {
        scene_json("[1,1,1]", true, "quad.bin").replacen(
            r#""znear":0.1}"#,
            &format!(r#""znear":{znear},"zfar":{zfar}}}"#),
            1,
        )
    };
    renders_with_warning(
        &with_planes("0.1", "2"),
        "camera 0 has zfar 2, nearer than parts of the scene",
    );
    renders_with_warning(&with_planes("0.1", "2"), "--no-clip-planes");
    renders_with_warning(
        &with_planes("0.1", "0.05"),
        "camera 0 has znear 0.1 and zfar 0.05: zfar must lie beyond znear; its clip planes are ignored",
    );
    renders_with_warning(
        &with_planes("-1", "5"),
        "camera 0 has znear -1 and zfar 5: znear must be a finite distance ≥ 0",
    );
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &with_planes("0.1", "5"));
    let stderr = renders(&scene, dir.path(), &[]);
    assert!(!stderr.contains("zfar"), "{stderr}");
}

/// A file with several scenes and no default renders the first, and says so: a user
/// whose objects are in another scene then knows why the image lacks them.
#[test]
fn several_scenes_without_a_default_warn() {
    let json = scene_json("[1,1,1]", true, "quad.bin").replacen(
        r#""scenes":[{"nodes":[0,1]}],"scene":0"#,
        r#""scenes":[{"nodes":[0,1]},{"nodes":[0]}]"#,
        1,
    );
    assert!(!json.contains(r#""scene":0"#));
    renders_with_warning(
        &json,
        "names no default scene; rendering the first of its 2 scenes",
    );
}

#[test]
fn non_finite_emission() {
    let dir = tempfile::tempdir().unwrap();
    // 1e39 overflows f32 to infinity.
    let scene = write_scene(dir.path(), &scene_json("[1e39,1,1]", true, "quad.bin"));
    render_fails_with(&scene, dir.path(), &["scene.gltf", "non-finite"]);
}

/// Finite emission far beyond any physical radiance (near f32's limit it overflowed in
/// the kernels to NaN samples, reported as a bug) is refused, naming the material; so
/// are vertex colours that take an unlit material's emission there, and a punctual light
/// with the same bound on intensity × colour. Seen to fail with each check removed:
/// without the first the file was refused only as "light powers are not finite",
/// naming nothing; without the second it rendered; without the third it rendered.
#[test]
fn emission_beyond_any_physical_radiance_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[3e38,1,1]", true, "quad.bin"));
    render_fails_with(
        &scene,
        dir.path(),
        &["scene.gltf", "material `#0` emits 3e38", "1e20"],
    );

    // An unlit material whose COLOR_0 reaches 1e30 in red.
    let mut json: serde_json::Value =
        serde_json::from_str(&scene_json("[0,0,0]", true, "quad.bin")).unwrap();
    let colours: Vec<u8> = [[1e30f32, 1.0, 1.0], [1.0; 3], [1.0; 3], [1.0; 3]]
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    std::fs::write(dir.path().join("colours.bin"), &colours).unwrap();
    json["buffers"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"uri": "colours.bin", "byteLength": 48}));
    json["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"buffer": 1, "byteLength": 48}));
    json["accessors"].as_array_mut().unwrap().push(
        serde_json::json!({"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"}),
    );
    json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2.into();
    json["materials"][0] = serde_json::json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0]},
        "extensions": {"KHR_materials_unlit": {}}
    });
    json["extensionsUsed"] = serde_json::json!(["KHR_materials_unlit"]);
    let scene = write_scene(dir.path(), &json.to_string());
    render_fails_with(
        &scene,
        dir.path(),
        &[
            "scene.gltf",
            "primitive 0: its vertex colours (COLOR_0) make its unlit material emit 5e29",
            "1e20",
        ],
    );

    // A point light of 2 × 10³⁰ cd in red (and the quad dark).
    let mut json: serde_json::Value =
        serde_json::from_str(&scene_json("[0,0,0]", true, "quad.bin")).unwrap();
    json["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
    json["extensions"] = serde_json::json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 1e30, "color": [2.0, 1.0, 1.0]}
    ]}});
    json["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "name": "lamp", "translation": [0.0, 0.0, 1.0],
            "extensions": {"KHR_lights_punctual": {"light": 0}}
        }));
    json["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(2.into());
    let scene = write_scene(dir.path(), &json.to_string());
    render_fails_with(
        &scene,
        dir.path(),
        &[
            "scene.gltf",
            "light on node `lamp` has intensity × colour 2e30",
            "1e20",
        ],
    );
}

#[test]
fn unknown_camera() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", true, "quad.bin"));
    let out = dir.path().join("x.exr");
    let (ok, stderr) = lanterna(&[
        "render",
        &scene,
        "--camera",
        "closeup",
        "--spp",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("closeup") && stderr.contains("0: `camera 0`"),
        "{stderr}"
    );
}

#[test]
fn bad_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", true, "quad.bin"));
    for args in [
        vec!["render", scene.as_str(), "--spp", "0"],
        vec!["render", scene.as_str(), "--max-depth", "0", "--spp", "1"],
        vec!["render", scene.as_str(), "--method", "magic"],
        vec!["render", scene.as_str(), "--time", "-3"],
        vec!["render", scene.as_str(), "--look-at", "1,2,3"],
    ] {
        let (ok, stderr) = lanterna(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(stderr.contains("error"), "{args:?}: {stderr}");
    }
}

/// Guided training records at most 16 path vertices: a longer --max-depth is refused with
/// the limit, rather than silently training on truncated paths (pt renders it).
#[test]
fn guided_methods_refuse_paths_longer_than_their_records() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), &scene_json("[1,1,1]", true, "quad.bin"));
    let out = dir.path().join("deep.exr");
    let args = |method: &'static str| {
        vec![
            "render".to_string(),
            scene.clone(),
            "--spp".into(),
            "1".into(),
            "--width".into(),
            "8".into(),
            "--max-depth".into(),
            "18".into(),
            "--method".into(),
            method.into(),
            "-o".into(),
            out.to_str().unwrap().into(),
            "--quiet".into(),
        ]
    };
    let run = |method| {
        let a = args(method);
        lanterna(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (ok, stderr) = run("guided");
    assert!(!ok, "guided at depth 18 rendered");
    assert!(
        stderr.contains("--max-depth 18") && stderr.contains("17"),
        "{stderr}"
    );
    assert!(!out.exists());
    let (ok, stderr) = run("pt");
    assert!(ok, "{stderr}");
}
