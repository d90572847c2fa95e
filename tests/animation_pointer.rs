//! `KHR_animation_pointer`: channels that animate materials, lights, cameras, texture
//! transforms, visibility and morph weights by JSON pointer. The file is built here, so
//! every keyframe is known, and each posed value is worked out by hand from the glTF
//! specification's interpolation rules: the posed file must load as the same scene as a
//! file that states those values outright.

use glam::{Quat, Vec3};
use lanterna::scene::{LoadOptions, Pose, Scene};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The time the tests pose the file at: s = 0.3 into every [0, 2] key interval.
const TIME: f32 = 0.6;
const S: f64 = 0.3;

/// Accessors appended to one buffer.
#[derive(Default)]
struct Buffer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffer {
    /// One accessor over `bytes`: `count` elements of `ty` in `component`; returns its index.
    fn add(
        &mut self,
        bytes: &[u8],
        component: u32,
        count: usize,
        ty: &str,
        normalized: bool,
    ) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views
            .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        let mut accessor = json!({"bufferView": self.views.len() - 1, "componentType": component,
            "count": count, "type": ty});
        if normalized {
            accessor["normalized"] = json!(true);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let width = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let index = self.add(&bytes, 5126, data.len() / width, ty, false);
        if ty == "SCALAR" {
            let lo = data.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = data.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            self.accessors[index]["min"] = json!([lo]);
            self.accessors[index]["max"] = json!([hi]);
        }
        index
    }

    fn uri(&self) -> String {
        use base64::Engine as _;
        format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        )
    }
}

/// A pointer channel.
fn channel(sampler: usize, pointer: &str) -> Value {
    json!({"sampler": sampler, "target": {"path": "pointer",
        "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}})
}

/// The file with its animations, and the same file without them but with every animated
/// property set to its value at `TIME`, worked out here.
fn scenes() -> (Value, Value) {
    let mut b = Buffer::default();
    // A unit quad in z = 0 with two morph targets (raising vertex 2, and vertex 3).
    let quad = b.floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.], "VEC3");
    b.accessors[quad]["min"] = json!([0, 0, 0]);
    b.accessors[quad]["max"] = json!([1, 1, 0]);
    let raise2 = b.floats(&[0., 0., 0., 0., 0., 0., 0., 0., 1., 0., 0., 0.], "VEC3");
    let raise3 = b.floats(&[0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 1.], "VEC3");
    let uv = b.floats(&[0., 0., 1., 0., 1., 1., 0., 1.], "VEC2");
    let indices: Vec<u8> = [0u16, 1, 2, 0, 2, 3]
        .iter()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let index = b.add(&indices, 5123, 6, "SCALAR", false);
    let mut png = Vec::new();
    image::RgbaImage::from_fn(2, 2, |x, y| {
        image::Rgba([60 + 100 * x as u8, 40 * y as u8, 90, 255])
    })
    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
    .unwrap();
    use base64::Engine as _;
    let png_uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png)
    );

    let t02 = b.floats(&[0., 2.], "SCALAR");
    let t0h = b.floats(&[0., 0.5], "SCALAR");
    let t0 = b.floats(&[0.], "SCALAR");
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let mut samplers = Vec::new();
    let mut sampler = |input: usize, output: usize, interpolation: &str| {
        samplers.push(json!({"input": input, "output": output, "interpolation": interpolation}));
        samplers.len() - 1
    };
    let move_ = b.floats(&[0., 0., 0., 2., 0., -1.], "VEC3");
    let move_ = sampler(t02, move_, "LINEAR");
    let turn = b.floats(&[0., 0., 0., 1., 0., s, 0., s], "VEC4");
    let turn = sampler(t02, turn, "LINEAR");
    // Normalised unsigned bytes: (1, 0, 0, 1) to (0, 1, 0.2, 1).
    let base = b.add(&[255, 0, 0, 255, 0, 255, 51, 255], 5121, 2, "VEC4", true);
    let base = sampler(t02, base, "LINEAR");
    // CUBICSPLINE: values 0.2 and 0.8, out-tangent 0.5 of the first key and in-tangent
    // 0.1 of the second (per second); the outer tangents (9) must not matter.
    let rough = b.floats(&[9., 0.2, 0.5, 0.1, 0.8, 9.], "SCALAR");
    let rough = sampler(t02, rough, "CUBICSPLINE");
    let offset = b.floats(&[0., 0., 1., 0.5], "VEC2");
    let offset = sampler(t02, offset, "LINEAR");
    // Unsigned bytes that are not normalised: 1 is 1.0.
    let glow = b.add(&[0, 0, 0, 1, 1, 0], 5121, 2, "VEC3", false);
    let glow = sampler(t0h, glow, "STEP");
    let strength = b.floats(&[1., 11.], "SCALAR");
    let strength = sampler(t02, strength, "LINEAR");
    let colour = b.floats(&[1., 1., 1., 1., 0., 0.], "VEC3");
    let colour = sampler(t02, colour, "LINEAR");
    let intensity = b.floats(&[5., 20.], "SCALAR");
    let intensity = sampler(t0h, intensity, "STEP");
    let cone = b.floats(&[0.5, 1.0], "SCALAR");
    let cone = sampler(t02, cone, "LINEAR");
    let fov = b.floats(&[0.5, 1.5], "SCALAR");
    let fov = sampler(t02, fov, "LINEAR");
    let visible = b.add(&[1, 0], 5121, 2, "SCALAR", false);
    let visible = sampler(t0h, visible, "STEP");
    let one_weight = b.floats(&[0., 1.], "SCALAR");
    let one_weight = sampler(t02, one_weight, "LINEAR");
    let two_weights = b.floats(&[0., 0., 1., 0.5], "SCALAR");
    let two_weights = sampler(t02, two_weights, "LINEAR");
    // Not used by the file as written: a negative value.
    let negative = b.floats(&[-2., -2.], "SCALAR");
    sampler(t02, negative, "LINEAR");
    let late = b.floats(&[0.9], "SCALAR");
    let samplers_0 = samplers.clone();
    let samplers_1 = vec![json!({"input": t0, "output": late, "interpolation": "STEP"})];

    let file = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_animation_pointer", "KHR_lights_punctual", "KHR_node_visibility",
                           "KHR_texture_transform", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "intensity": 5, "spot": {}}]}},
        "buffers": [{"uri": b.uri(), "byteLength": b.bin.len()}],
        "bufferViews": b.views,
        "accessors": b.accessors,
        "images": [{"uri": png_uri}],
        "textures": [{"source": 0}],
        "materials": [
            {"name": "lamp", "emissiveFactor": [1, 0.8, 0.5],
             "extensions": {"KHR_materials_emissive_strength": {}}},
            {"name": "floor", "pbrMetallicRoughness": {
                "baseColorFactor": [1, 0, 0, 1], "roughnessFactor": 0.2,
                "baseColorTexture": {"index": 0,
                    "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}}}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": quad}, "indices": index, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": quad, "TEXCOORD_0": uv}, "indices": index,
                             "material": 1}]},
            {"primitives": [{"attributes": {"POSITION": quad}, "indices": index, "material": 1,
                             "targets": [{"POSITION": raise2}, {"POSITION": raise3}]}]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "nodes": [
            {"name": "lamp", "mesh": 0, "translation": [0, 0, 3], "rotation": [1, 0, 0, 0]},
            {"name": "floor", "mesh": 1, "scale": [4, 4, 1]},
            {"name": "spot", "translation": [0, 0, 2], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "eye", "camera": 0, "translation": [0.5, 0.5, 6]},
            {"name": "blinker", "mesh": 0, "translation": [2, 0, 3], "rotation": [1, 0, 0, 0],
             "extensions": {"KHR_node_visibility": {}}},
            {"name": "morph one", "mesh": 2, "translation": [-2, 0, 0]},
            {"name": "morph both", "mesh": 2, "translation": [-2, 2, 0]}
        ],
        "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6]}],
        "scene": 0,
        "animations": [
            {"name": "everything", "samplers": samplers_0, "channels": [
                channel(move_, "/nodes/1/translation"),
                channel(turn, "/nodes/1/rotation"),
                channel(base, "/materials/1/pbrMetallicRoughness/baseColorFactor"),
                channel(rough, "/materials/1/pbrMetallicRoughness/roughnessFactor"),
                channel(offset, "/materials/1/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset"),
                channel(glow, "/materials/1/emissiveFactor"),
                channel(strength, "/materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength"),
                channel(colour, "/extensions/KHR_lights_punctual/lights/0/color"),
                channel(intensity, "/extensions/KHR_lights_punctual/lights/0/intensity"),
                channel(cone, "/extensions/KHR_lights_punctual/lights/0/spot/outerConeAngle"),
                channel(fov, "/cameras/0/perspective/yfov"),
                channel(visible, "/nodes/4/extensions/KHR_node_visibility/visible"),
                channel(one_weight, "/meshes/2/weights/1"),
                channel(two_weights, "/nodes/6/weights"),
                channel(one_weight, "/nodes/0/extras/blink")
            ]},
            {"name": "late", "samplers": samplers_1, "channels": [
                channel(0, "/materials/1/pbrMetallicRoughness/roughnessFactor")
            ]}
        ]
    });

    // The values at TIME, from the specification's rules.
    let lerp = |a: f64, b: f64| a + S * (b - a);
    let hermite = |v0: f64, b0: f64, a1: f64, v1: f64, dt: f64| {
        let (s2, s3) = (S * S, S * S * S);
        (2.0 * s3 - 3.0 * s2 + 1.0) * v0
            + (s3 - 2.0 * s2 + S) * dt * b0
            + (-2.0 * s3 + 3.0 * s2) * v1
            + (s3 - s2) * dt * a1
    };
    let turned = Quat::from_rotation_y(S as f32 * std::f32::consts::FRAC_PI_2);
    let mut stated = file.clone();
    stated.as_object_mut().unwrap().remove("animations");
    stated["nodes"][1]["translation"] = json!([lerp(0., 2.), 0, lerp(0., -1.)]);
    stated["nodes"][1]["rotation"] = json!(turned.to_array());
    stated["materials"][1]["pbrMetallicRoughness"]["baseColorFactor"] =
        json!([lerp(1., 0.), lerp(0., 1.), lerp(0., 0.2), 1]);
    stated["materials"][1]["pbrMetallicRoughness"]["roughnessFactor"] =
        json!(hermite(0.2, 0.5, 0.1, 0.8, 2.0));
    stated["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
        ["KHR_texture_transform"]["offset"] = json!([lerp(0., 1.), lerp(0., 0.5)]);
    stated["materials"][1]["emissiveFactor"] = json!([1, 1, 0]);
    stated["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] =
        json!(lerp(1., 11.));
    stated["extensions"]["KHR_lights_punctual"]["lights"][0]["color"] =
        json!([1, lerp(1., 0.), lerp(1., 0.)]);
    stated["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(20);
    stated["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"]["outerConeAngle"] =
        json!(lerp(0.5, 1.0));
    stated["cameras"][0]["perspective"]["yfov"] = json!(lerp(0.5, 1.5));
    stated["nodes"][4]["extensions"]["KHR_node_visibility"]["visible"] = json!(false);
    stated["meshes"][2]["weights"] = json!([0, lerp(0., 1.)]);
    stated["nodes"][6]["weights"] = json!([lerp(0., 1.), lerp(0., 0.5)]);
    (file, stated)
}

fn write(dir: &Path, name: &str, json: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    path
}

fn posed(path: &Path, time: f32, animation: Option<&str>) -> Result<Scene, String> {
    let options = LoadOptions {
        pose: Some(Pose {
            time,
            animation: animation.map(str::to_string),
        }),
        ..Default::default()
    };
    Scene::load(path, &options).map_err(|e| e.to_string())
}

/// Two words of the kernels' tables agree: the same bits, or floats (not index-like
/// denormals) within a relative 10⁻⁵.
fn same_words(a: &[u32], b: &[u32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
        let (fx, fy) = (f32::from_bits(x), f32::from_bits(y));
        let big = fx.abs().max(fy.abs());
        let close = fx.is_finite()
            && fy.is_finite()
            && big > 1e-30
            && (fx - fy).abs() <= 1e-5 * big.max(1e-3);
        assert!(
            x == y || close,
            "{what}: word {i} is {fx} ({x:#x}) instead of {fy} ({y:#x})"
        );
    }
}

/// Every property the channels animate, posed at `TIME`, loads as in the file that states
/// the values: materials (a normalised byte colour lerped, a CUBICSPLINE roughness, a
/// texture transform's offset, an emission given in plain bytes, an emissive strength
/// from its default), a spot light's colour, intensity (STEP) and cone, a camera's field
/// of view, a node's translation and rotation (slerped), a node hidden by a boolean, a
/// mesh's morph weight from its default and a node's weights. An `extras` pointer is
/// ignored with a warning, and a second animation's channel for the roughness is not
/// used. Seen to fail with the rotation lerped instead of slerped, with normalised bytes
/// read as plain ones, with booleans read as true, and with the first animation's
/// roughness lost to the second's.
#[test]
fn pointer_animations_pose_what_a_file_states() {
    let dir = tempfile::tempdir().unwrap();
    let (file, stated) = scenes();
    let animated = write(dir.path(), "animated.gltf", &file);
    let expected = Scene::load(
        &write(dir.path(), "stated.gltf", &stated),
        &Default::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let got = posed(&animated, TIME, None).unwrap_or_else(|e| panic!("{e}"));

    let words = |m: &[lanterna::gpu::Material]| bytemuck::cast_slice::<_, u32>(m).to_vec();
    same_words(
        &words(&got.materials),
        &words(&expected.materials),
        "materials",
    );
    let lights = |l: &[lanterna::gpu::PunctualLight]| bytemuck::cast_slice::<_, u32>(l).to_vec();
    same_words(
        &lights(&got.punctual),
        &lights(&expected.punctual),
        "punctual lights",
    );
    assert_eq!(
        got.instances.len(),
        expected.instances.len(),
        "instances (the blinker hidden)"
    );
    assert_eq!(got.instances.len(), 4);
    let world = |s: &Scene| -> Vec<Vec3> {
        s.instances
            .iter()
            .flat_map(|i| {
                (0..s.primitives[i.primitive as usize].triangle_count)
                    .flat_map(|t| s.world_triangle(i, t))
            })
            .map(|p| p + s.origin)
            .collect()
    };
    let (a, b) = (world(&got), world(&expected));
    assert_eq!(a.len(), b.len());
    for (k, (p, q)) in a.iter().zip(&b).enumerate() {
        assert!((*p - *q).length() < 1e-5, "vertex {k}: {p} instead of {q}");
    }
    let yfov = |s: &Scene| match s.cameras[0].projection {
        lanterna::scene::Projection::Perspective { yfov, .. } => yfov,
        _ => panic!("a perspective camera"),
    };
    assert!((yfov(&got) - 0.8).abs() < 1e-6, "yfov {}", yfov(&got));
    assert!((yfov(&got) - yfov(&expected)).abs() < 1e-6);
    // Unposed, the file is its static self: the floor red and rough 0.2, the blinker shown.
    let unposed = Scene::load(&animated, &Default::default()).unwrap();
    assert_eq!(unposed.instances.len(), 5);
    assert_ne!(unposed.hash, got.hash);
    // Before the first key every value holds the first key's.
    let early = posed(&animated, -1.0, None).unwrap();
    assert_eq!(early.instances.len(), 5);
    assert_eq!(early.punctual[0].intensity, unposed.punctual[0].intensity);

    // `lanterna info` counts pointer channels and names the ignored and the lost ones.
    let out = Command::new(env!("CARGO_BIN_EXE_lanterna"))
        .args([
            "info",
            animated.to_str().unwrap(),
            "--animation-time",
            "0.6",
        ])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("0 (`everything`): 0–2 s, 15 channels"),
        "{stdout}"
    );
    assert!(
        stderr.contains("animates `/nodes/0/extras/blink`, a property lanterna does not animate"),
        "{stderr}"
    );
    assert!(
        stderr.contains("animation 1 (`late`) channel 0 animates `/materials/1/pbrMetallicRoughness/roughnessFactor`, which animation 0 animates too"),
        "{stderr}"
    );
}

/// Pointer channels the specification does not allow, or that point at nothing, are
/// refused, naming the animation, the channel and what is wrong.
#[test]
fn pointer_channels_that_cannot_be_posed_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = scenes();
    let refused = |edit: &dyn Fn(&mut Value), expected: &str| {
        let mut bad = file.clone();
        edit(&mut bad);
        let path = write(dir.path(), "bad.gltf", &bad);
        match posed(&path, TIME, None) {
            Ok(_) => panic!("loaded, though it should be refused with «{expected}»"),
            Err(e) => e,
        }
    };
    let pointer = |j: &mut Value, c: usize, p: &str| {
        j["animations"][0]["channels"][c]["target"]["extensions"]["KHR_animation_pointer"]
            ["pointer"] = json!(p)
    };
    type Edit<'a> = Box<dyn Fn(&mut Value) + 'a>;
    let cases: Vec<(Edit<'_>, &str)> = vec![
        (
            Box::new(|j| pointer(j, 10, "/cameras/0/perspective/zfar")),
            "animation 0 (`everything`) channel 10 animates `/cameras/0/perspective/zfar`, \
             which the file does not define",
        ),
        (
            Box::new(|j| pointer(j, 6, "/materials/0/extensions/KHR_materials_ior/ior")),
            "which the file does not define",
        ),
        (
            Box::new(|j| pointer(j, 6, "/materials/5/alphaCutoff")),
            "which the file does not define",
        ),
        (
            Box::new(|j| j["animations"][0]["samplers"][11]["interpolation"] = json!("LINEAR")),
            "channel 11 animates the boolean `/nodes/4/extensions/KHR_node_visibility/visible`, \
             which must use STEP interpolation",
        ),
        (
            Box::new(|j| pointer(j, 5, "/materials/1/pbrMetallicRoughness/baseColorFactor")),
            "channel 5: a second channel for `/materials/1/pbrMetallicRoughness/baseColorFactor`",
        ),
        (
            Box::new(|j| pointer(j, 4, "/nodes/2/rotation")),
            "is float VEC2, but pointer keyframes must be VEC4",
        ),
        (
            Box::new(|j| pointer(j, 2, "/nodes/1/weights/0")),
            "animates the morph weights of node `floor`, whose mesh has no morph targets",
        ),
        (
            Box::new(|j| pointer(j, 12, "/nodes/5/weights/2")),
            "animates morph weight 2 of node `morph one`, whose mesh has 2 morph target(s)",
        ),
        (
            Box::new(|j| pointer(j, 12, "/meshes/0/weights/0")),
            "but that mesh has no morph targets",
        ),
        (
            Box::new(|j| pointer(j, 12, "meshes/2/weights/0")),
            "channel 12: the pointer `meshes/2/weights/0` does not start with `/`",
        ),
        (
            Box::new(|j| j["animations"][0]["channels"][3]["target"]["extensions"] = json!({})),
            "channel 3: its target's path is `pointer` but it has no KHR_animation_pointer pointer",
        ),
        (
            Box::new(|j| j["animations"][0]["channels"][3]["sampler"] = json!(40)),
            "channel 3: its sampler is not one of the animation's",
        ),
        (
            // A core channel and a pointer for one property in one animation.
            Box::new(|j| {
                let channels = j["animations"][0]["channels"].as_array_mut().unwrap();
                channels.push(json!({"sampler": 0, "target": {"node": 1, "path": "translation"}}));
            }),
            "channel 15: a second channel for the translation of node `floor`",
        ),
        (
            // A value the property cannot take, named as posed.
            Box::new(|j| j["animations"][0]["channels"][8]["sampler"] = json!(14)),
            "light on node `spot` has a non-finite or negative intensity/colour (as its \
             animations pose it at time 0.6 s)",
        ),
    ];
    for (edit, expected) in cases {
        let err = refused(&*edit, expected);
        assert!(err.contains(expected), "expected «{expected}» in: {err}");
    }
}
