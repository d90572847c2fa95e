//! A seeded mutation fuzzer for the scene loader, run for a fixed number of cases: the
//! shipped `cornell-lights` scene, every small generated kind, and (less often, its
//! textures make it slow) the street are mutated — structurally in their glTF JSON
//! (numbers replaced by boundary values, keys dropped, types and URIs changed, array
//! elements duplicated), byte-wise in the JSON text and the `.bin`, and as GLB
//! containers with damaged headers — and loaded (no rendering). Every case must load or
//! fail with an error; a panic fails the test, which prints the seed and the case to
//! reproduce it. The input limit is lowered for the process (it is its own test binary)
//! so that a mutation cannot make a case allocate gigabytes.
//!
//! Mutation-checked: with `gltf_check::precheck` disabled, the loop finds the gltf
//! crate's panic on an out-of-range POSITION accessor (6 of the 3000 cases, the first at
//! case 91); with `gltf_check::check_accessor` disabled, its `unreachable!()` on index
//! accessors of a float type (2 cases), and 12 more cases load wrong geometry silently.

use lanterna::scene::generate::{generate, Kind, Options};
use lanterna::scene::{LoadOptions, Pose, Scene};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Cases per run (the whole loop takes a few seconds on two cores).
const CASES: usize = 3000;
const SEED: u64 = 0x5eed_1234;

/// SplitMix64.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
}

/// A scene to mutate: its JSON, its one `.bin` (named by the JSON), and any other files
/// it uses (textures), copied as they are.
struct Seed {
    name: String,
    json: Value,
    bin_name: String,
    bin: Vec<u8>,
    others: Vec<(String, Vec<u8>)>,
}

fn read_seed(gltf: &Path) -> Seed {
    let json: Value = serde_json::from_slice(&std::fs::read(gltf).unwrap()).unwrap();
    let dir = gltf.parent().unwrap();
    let bin_name = json["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = std::fs::read(dir.join(&bin_name)).unwrap();
    let others = json["images"]
        .as_array()
        .map(|imgs| {
            imgs.iter()
                .filter_map(|i| i["uri"].as_str())
                .map(|u| (u.to_string(), std::fs::read(dir.join(u)).unwrap()))
                .collect()
        })
        .unwrap_or_default();
    Seed {
        name: gltf.file_name().unwrap().to_string_lossy().into_owned(),
        json,
        bin_name,
        bin,
        others,
    }
}

fn seeds(scratch: &Path) -> Vec<Seed> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut seeds = vec![
        read_seed(&root.join("scenes/cornell-lights.gltf")),
        read_seed(&root.join("scenes/street.gltf")),
    ];
    seeds.push(animated(&seeds[0]));
    for kind in [
        Kind::Furnace,
        Kind::PlaneQuad,
        Kind::PlanePoint,
        Kind::Gap,
        Kind::AlphaTest,
    ] {
        let path = scratch.join(format!("{}.gltf", kind.name()));
        generate(kind, &Options::default(), &path).unwrap();
        seeds.push(read_seed(&path));
    }
    seeds
}

/// `cornell-lights` with an animation of its blockers and camera (translation LINEAR,
/// rotation CUBICSPLINE, scale STEP) in a second, data-URI buffer, for the cases that
/// pose the scene (`--animation-time`), with `KHR_animation_pointer` channels that
/// animate a material's emission, the camera's field of view, the IES light's multiplier
/// and a lamp's rotation, two material variants (`--variant`) and an IES light
/// (`EXT_lights_ies`) on the animated node.
fn animated(cornell: &Seed) -> Seed {
    use base64::Engine as _;
    let floats: Vec<f32> = [
        &[0.0, 0.5, 1.0][..],
        &[0., 0., 0., 0.1, 0.2, 0., 0., 0.3, 0.][..],
        &[0., 0., 0., 0., 0., 0., 0., 1., 0., 0.1, 0., 0.][..],
        &[0., 0., 0., 0., 0., 0.38, 0., 0.92, 0., 0., 0., 0.][..],
        &[0., 0., 0., 0., 0., 0., 0., 1., 0., 0.1, 0., 0.][..],
        &[1., 1., 1., 1.2, 0.8, 1., 1., 1., 1.][..],
        &[0.6, 0.8, 0.7][..],
    ]
    .concat();
    let bytes: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
    let mut json = cornell.json.clone();
    let buffer = json["buffers"].as_array().unwrap().len();
    json["buffers"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "byteLength": bytes.len(),
            "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&bytes)),
        }));
    let accessors = json["accessors"].as_array().unwrap().len();
    for (offset, length, count, ty) in [
        (0, 12, 3, "SCALAR"),
        (12, 36, 3, "VEC3"),
        (48, 144, 9, "VEC4"),
        (192, 36, 3, "VEC3"),
        (228, 12, 3, "SCALAR"),
    ] {
        let view = json["bufferViews"].as_array().unwrap().len();
        json["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!(
            {"buffer": buffer, "byteOffset": offset, "byteLength": length}));
        json["accessors"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!(
            {"bufferView": view, "componentType": 5126, "count": count, "type": ty,
             "min": if offset == 0 { serde_json::json!([0.0]) } else { Value::Null },
             "max": if offset == 0 { serde_json::json!([1.0]) } else { Value::Null }}));
    }
    for a in json["accessors"].as_array_mut().unwrap() {
        if let Some(o) = a.as_object_mut() {
            o.retain(|_, v| !v.is_null());
        }
    }
    let camera = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| n.get("camera").is_some())
        .unwrap();
    let input = accessors;
    json["animations"] = serde_json::json!([{
        "name": "move",
        "samplers": [
            {"input": input, "output": input + 1},
            {"input": input, "output": input + 2, "interpolation": "CUBICSPLINE"},
            {"input": input, "output": input + 3, "interpolation": "STEP"},
            {"input": input, "output": input + 4}
        ],
        "channels": [
            {"sampler": 0, "target": {"node": 1, "path": "translation"}},
            {"sampler": 1, "target": {"node": 1, "path": "rotation"}},
            {"sampler": 2, "target": {"node": 1, "path": "scale"}},
            {"sampler": 0, "target": {"node": camera, "path": "translation"}},
            {"sampler": 0, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/materials/0/emissiveFactor"}}}},
            {"sampler": 3, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/cameras/0/perspective/yfov"}}}},
            {"sampler": 3, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/nodes/1/extensions/EXT_lights_ies/multiplier"}}}},
            {"sampler": 1, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/nodes/2/rotation"}}}}
        ]
    }]);
    // Two material variants: the blockers red in the second. And an IES downlight on the
    // animated blocker (its profile in a data URI), which the animation carries.
    json["extensionsUsed"] = serde_json::json!([
        "KHR_materials_variants",
        "EXT_lights_ies",
        "KHR_animation_pointer"
    ]);
    let profile = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 2 1 2 0 0 0\n1 1 10\n0 45 90\n0 180\n\
                   5 3 0\n4 2 0\n";
    json["extensions"] = serde_json::json!({
        "KHR_materials_variants": {"variants": [{"name": "white"}, {"name": "red"}]},
        "EXT_lights_ies": {"lights": [{"uri": format!("data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(profile))}]}
    });
    json["nodes"][1]["extensions"] =
        serde_json::json!({"EXT_lights_ies": {"light": 0, "multiplier": 0.5}});
    json["meshes"][1]["primitives"][0]["extensions"] = serde_json::json!({"KHR_materials_variants":
        {"mappings": [{"material": 1, "variants": [1]}, {"material": 0, "variants": [0]}]}});
    Seed {
        name: "cornell-lights, animated, with material variants and an IES light".into(),
        json,
        bin_name: cornell.bin_name.clone(),
        bin: cornell.bin.clone(),
        others: Vec::new(),
    }
}

/// Values that have broken parsers before: boundaries of the integer types, huge and
/// tiny floats, wrong types.
fn interesting(rng: &mut Rng) -> Value {
    let choices: [Value; 22] = [
        Value::from(0),
        Value::from(1),
        Value::from(-1),
        Value::from(2),
        Value::from(3),
        Value::from(4),
        Value::from(255),
        Value::from(65535),
        Value::from(2147483647i64),
        Value::from(2147483648i64),
        Value::from(4294967295i64),
        Value::from(4294967296i64),
        Value::from(u64::MAX),
        Value::from(i64::MIN),
        Value::from(1e39),
        Value::from(-1e39),
        Value::from(1e-45),
        Value::from(0.5),
        Value::from(5126),
        Value::from(5121),
        Value::Null,
        Value::from("VEC2"),
    ];
    choices[rng.below(choices.len())].clone()
}

fn interesting_string(rng: &mut Rng, bin_name: &str) -> Value {
    let choices = [
        "SCALAR",
        "VEC2",
        "VEC3",
        "VEC4",
        "MAT4",
        "../outside.bin",
        "/etc/passwd",
        "file:///etc/passwd",
        "http://127.0.0.1:1/x.bin",
        "%FF%FE.bin",
        "data:application/octet-stream;base64,AAAA",
        "data:application/octet-stream;base64,@@@",
        "data:image/png;base64,iVBORw0KGgo=",
        "",
        "BLEND",
        "MASK",
        "image/jpeg",
        "TEXCOORD_7",
    ];
    match rng.below(choices.len() + 1) {
        i if i < choices.len() => Value::from(choices[i]),
        _ => Value::from(bin_name),
    }
}

/// Every path to a value in `v`, as a list of keys/indices.
fn paths(v: &Value, prefix: &mut Vec<PathPart>, out: &mut Vec<Vec<PathPart>>) {
    out.push(prefix.clone());
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                prefix.push(PathPart::Key(k.clone()));
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                prefix.push(PathPart::Index(i));
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum PathPart {
    Key(String),
    Index(usize),
}

fn at<'a>(v: &'a mut Value, path: &[PathPart]) -> &'a mut Value {
    path.iter().fold(v, |v, p| match p {
        PathPart::Key(k) => &mut v[k.as_str()],
        PathPart::Index(i) => &mut v[*i],
    })
}

/// One structural mutation of the JSON.
fn mutate_json(json: &mut Value, rng: &mut Rng, bin_name: &str) {
    let mut all = Vec::new();
    paths(json, &mut Vec::new(), &mut all);
    let path = all[rng.below(all.len())].clone();
    let parent_path = &path[..path.len().saturating_sub(1)];
    match rng.below(7) {
        0 | 1 => {
            let target = at(json, &path);
            *target = match target {
                Value::String(_) => interesting_string(rng, bin_name),
                _ => interesting(rng),
            };
        }
        2 => {
            // Drop a key or an array element.
            if let Some(last) = path.last() {
                match (at(json, parent_path), last) {
                    (Value::Object(m), PathPart::Key(k)) => {
                        m.remove(k);
                    }
                    (Value::Array(a), PathPart::Index(i)) => {
                        a.remove(*i);
                    }
                    _ => {}
                }
            }
        }
        3 => {
            // Duplicate an array element (more nodes, primitives, children…).
            if let (Value::Array(a), Some(PathPart::Index(i))) =
                (at(json, parent_path), path.last())
            {
                let copy = a[*i].clone();
                let n = 1 + rng.below(3);
                for _ in 0..n {
                    a.push(copy.clone());
                }
            }
        }
        4 => {
            // Change a value's type.
            let target = at(json, &path);
            *target = match target {
                Value::Array(_) => Value::Object(Default::default()),
                Value::Object(_) => Value::Array(vec![Value::from(0)]),
                Value::Number(n) => Value::from(n.to_string()),
                _ => Value::Array(vec![]),
            };
        }
        5 => {
            // An index field pointed elsewhere (the likeliest crash site).
            let target = at(json, &path);
            if target.is_u64() {
                *target = Value::from(target.as_u64().unwrap() + 1 + rng.below(100) as u64);
            } else {
                *target = interesting(rng);
            }
        }
        _ => {
            // A child pointing back up (cycles) or a node listed twice.
            let nodes = json.get_mut("nodes").and_then(Value::as_array_mut);
            if let Some(nodes) = nodes {
                let n = nodes.len();
                if n > 0 {
                    let target = rng.below(n + 1);
                    if let Some(node) = nodes[rng.below(n)].as_object_mut() {
                        node.insert("children".into(), Value::Array(vec![Value::from(target)]));
                    }
                }
            }
        }
    }
}

fn flip_bytes(data: &mut Vec<u8>, rng: &mut Rng) {
    if data.is_empty() {
        return;
    }
    match rng.below(4) {
        0 => {
            let n = 1 + rng.below(8);
            for _ in 0..n {
                let i = rng.below(data.len());
                data[i] ^= 1 << rng.below(8);
            }
        }
        1 => {
            let keep = rng.below(data.len());
            data.truncate(keep);
        }
        2 => {
            let i = rng.below(data.len());
            let b = [0x00, 0xff, 0x7f, 0x80][rng.below(4)];
            let n = 1 + rng.below(16);
            for j in i..(i + n).min(data.len()) {
                data[j] = b;
            }
        }
        _ => {
            let extra = rng.below(64);
            data.extend((0..extra).map(|_| rng.next() as u8));
        }
    }
}

thread_local! {
    /// Whether this thread is inside a load (whose panics the hook keeps quiet).
    static IN_LOAD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// What one case did.
enum Outcome {
    Loaded,
    Refused,
    Panicked(String),
}

fn load_case(
    path: &Path,
    allow_outside: bool,
    pose: Option<Pose>,
    variant: Option<String>,
) -> Outcome {
    let options = LoadOptions {
        allow_outside_uris: allow_outside,
        pose,
        variant,
    };
    IN_LOAD.with(|f| f.set(true));
    let result = std::panic::catch_unwind(|| Scene::load(path, &options));
    IN_LOAD.with(|f| f.set(false));
    match result {
        Ok(Ok(_)) => Outcome::Loaded,
        Ok(Err(_)) => Outcome::Refused,
        Err(payload) => Outcome::Panicked(
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "non-string panic".into()),
        ),
    }
}

#[test]
fn mutated_scenes_load_or_fail_without_panicking() {
    // SAFETY of set_var: this test binary runs this one test; nothing reads the
    // environment concurrently.
    std::env::set_var(lanterna::files::MAX_INPUT_ENV, "64");
    let scratch = tempfile::tempdir().unwrap();
    let seeds = seeds(scratch.path());
    let work = scratch.path().join("case");
    std::fs::create_dir(&work).unwrap();
    // A file outside the case folder, for URIs that escape it.
    std::fs::write(scratch.path().join("outside.bin"), vec![0u8; 4096]).unwrap();
    for seed in &seeds {
        for (name, bytes) in &seed.others {
            std::fs::write(work.join(name), bytes).unwrap();
        }
    }

    // Every seed loads as written, and posed: a broken seed would only test refusals.
    for seed in &seeds {
        std::fs::write(work.join(&seed.bin_name), &seed.bin).unwrap();
        let p = work.join("case.gltf");
        std::fs::write(&p, serde_json::to_vec(&seed.json).unwrap()).unwrap();
        assert!(
            matches!(load_case(&p, false, None, None), Outcome::Loaded),
            "seed {} does not load",
            seed.name
        );
        // Posed, too: the cases posed by the animated seed start from a file that loads.
        let pose = Pose {
            time: 0.25,
            animation: None,
        };
        assert!(
            matches!(load_case(&p, false, Some(pose), None), Outcome::Loaded),
            "seed {} does not load posed at 0.25 s",
            seed.name
        );
    }

    // Panics inside a load are counted below, not printed; any other is printed.
    let default_hook = std::sync::Arc::new(std::panic::take_hook());
    {
        let default_hook = default_hook.clone();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_LOAD.with(|f| f.get()) {
                default_hook(info);
            }
        }));
    }
    let mut rng = Rng(SEED);
    let (mut loaded, mut refused) = (0usize, 0usize);
    let mut panics = Vec::new();
    let started = std::time::Instant::now();
    for case in 0..CASES {
        // The street (five PNG textures, 30k triangles) in 1 case of 20.
        let seed = if rng.chance(0.05) {
            &seeds[1]
        } else {
            let i = rng.below(seeds.len() - 1);
            &seeds[if i >= 1 { i + 1 } else { i }]
        };
        let mut json = seed.json.clone();
        let mut bin = seed.bin.clone();
        for _ in 0..1 + rng.below(3) {
            mutate_json(&mut json, &mut rng, &seed.bin_name);
        }
        if rng.chance(0.2) {
            flip_bytes(&mut bin, &mut rng);
        }
        let mut text = serde_json::to_vec(&json).unwrap();
        if rng.chance(0.1) {
            flip_bytes(&mut text, &mut rng);
        }
        let as_glb = rng.chance(0.15);
        let path = if as_glb {
            let mut j = json.clone();
            let first = j.get_mut("buffers").and_then(|b| b.get_mut(0));
            if let Some(o) = first.and_then(Value::as_object_mut) {
                o.remove("uri");
            }
            let mut data = lanterna::testing::glb(&serde_json::to_vec(&j).unwrap(), Some(&bin));
            if rng.chance(0.3) {
                flip_bytes(&mut data, &mut rng);
            }
            let p = work.join("case.glb");
            std::fs::write(&p, data).unwrap();
            p
        } else {
            std::fs::write(work.join(&seed.bin_name), &bin).unwrap();
            let p = work.join("case.gltf");
            std::fs::write(&p, &text).unwrap();
            p
        };
        // Half the cases pose the file's animations, at a time inside or outside their
        // keys, all of them or one by index.
        let pose = rng.chance(0.5).then(|| Pose {
            time: [-1.0, 0.0, 0.25, 0.5, 0.99, 1.0, 1e30][rng.below(7)],
            animation: rng.chance(0.2).then(|| rng.below(2).to_string()),
        });
        let variant = rng
            .chance(0.3)
            .then(|| ["0", "1", "red", "2"][rng.below(4)].to_string());
        match load_case(&path, rng.chance(0.1), pose, variant) {
            Outcome::Loaded => loaded += 1,
            Outcome::Refused => refused += 1,
            Outcome::Panicked(message) => {
                let keep = scratch.path().join(format!(
                    "panic-{case}.{}",
                    if as_glb { "glb" } else { "gltf" }
                ));
                let _ = std::fs::copy(&path, &keep);
                panics.push(format!(
                    "case {case} (seed {SEED:#x}, from {}): {message}",
                    seed.name
                ));
            }
        }
    }
    println!(
        "scene fuzz: {CASES} cases in {:.1} s: {loaded} loaded, {refused} refused with an error, {} panics",
        started.elapsed().as_secs_f64(),
        panics.len()
    );
    assert!(
        panics.is_empty(),
        "{} of {CASES} mutated scenes panicked the loader:\n{}",
        panics.len(),
        panics.join("\n")
    );
    assert!(
        loaded > CASES / 20,
        "too few cases load: the mutations are too coarse"
    );
}
