//! The SD-tree's arrays and files: flatten → unflatten round trip, the training
//! readback path (a CPU stand-in for the GPU recording into the uploaded training
//! buffer), save → load bit-exact, and the errors for wrong files, versions, corrupt
//! data and another scene.

use glam::Vec3;
use lanterna::gpu::GuideRecord;
use lanterna::guiding::{GuidingConfig, GuidingError, SceneHasher, SdTree};

/// SplitMix64 → floats in [0, 1).
struct Rng(u64);
impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

const BBOX: ([f32; 3], [f32; 3]) = ([-2.0, 0.0, -1.0], [2.0, 3.0, 1.5]);

/// Records spread over the box, radiance from a direction depending on position.
fn record_some(tree: &mut SdTree, n: u32, rng: &mut Rng) {
    let (lo, hi) = (Vec3::from_array(BBOX.0), Vec3::from_array(BBOX.1));
    for _ in 0..n {
        let p = lo + (hi - lo) * Vec3::new(rng.f32(), rng.f32(), rng.f32());
        let to_light = (Vec3::new(0.0, 2.9, 0.0) - p).normalize_or(Vec3::Y);
        let dir = (to_light + 0.05 * Vec3::new(rng.f32(), rng.f32(), rng.f32())).normalize();
        let u = [rng.f32(), rng.f32(), rng.f32()];
        tree.record(&GuideRecord::new(p, dir, 2.0 * rng.f32(), 1.0), u);
    }
}

/// A tree after a few iterations: many leaves, shared and distinct sampling trees, and
/// a training tree holding records.
fn grown_tree() -> SdTree {
    let config = GuidingConfig {
        spatial_threshold: 200.0,
        ..GuidingConfig::default()
    };
    let mut tree =
        SdTree::new(Vec3::from_array(BBOX.0), Vec3::from_array(BBOX.1), &config).unwrap();
    let mut rng = Rng(1);
    for k in 0..4 {
        record_some(&mut tree, 4000 << k, &mut rng);
        tree.refit(2 << k);
    }
    record_some(&mut tree, 3000, &mut rng);
    assert!(tree.leaves().len() > 20);
    tree
}

#[test]
fn flatten_round_trip() {
    let tree = grown_tree();
    let arrays = tree.gpu_arrays();
    assert_eq!(arrays.byte_size(), tree.gpu_bytes());
    // Split halves share sampling trees: the sampling array is smaller than the sum.
    let separate: usize = tree.leaves().iter().map(|l| l.sampling.node_count()).sum();
    assert!(arrays.sampling.len() < separate);
    let back = SdTree::from_gpu_arrays(&arrays, tree.config()).unwrap();
    assert_eq!(back.gpu_arrays(), arrays);
    // Equal as trees, apart from the refit counter, which the arrays do not hold.
    assert_eq!(back.leaves(), tree.leaves());
    // Lookups agree.
    let mut rng = Rng(2);
    for _ in 0..1000 {
        let p = Vec3::new(
            rng.f32() * 4.0 - 2.0,
            rng.f32() * 3.0,
            rng.f32() * 2.5 - 1.0,
        );
        assert_eq!(back.find_leaf(p), tree.find_leaf(p));
    }
}

#[test]
fn arrays_are_validated() {
    let tree = grown_tree();
    let config = tree.config().clone();
    let good = tree.gpu_arrays();
    let mut a = good.clone();
    a.spatial[0].child = 1_000_000;
    assert!(SdTree::from_gpu_arrays(&a, &config).is_err());
    let mut a = good.clone();
    a.sampling[a.leaves[3].sampling_root as usize].child[2] = a.leaves[3].sampling_root;
    assert!(SdTree::from_gpu_arrays(&a, &config).is_err());
    let mut a = good.clone();
    a.leaves[1].training_root = a.leaves[0].training_root;
    assert!(SdTree::from_gpu_arrays(&a, &config).is_err());
    let mut a = good.clone();
    a.header.leaf_count += 1;
    assert!(SdTree::from_gpu_arrays(&a, &config).is_err());
}

#[test]
fn training_readback_replaces_cpu_training() {
    // The GPU starts from the uploaded training buffer and adds records; here the CPU
    // mirror plays the GPU on a copy, and its training arrays are "read back".
    let mut tree = grown_tree();
    let mut gpu = tree.clone();
    record_some(&mut gpu, 5000, &mut Rng(3));
    let readback = gpu.gpu_arrays().training;
    tree.load_training_readback(&readback).unwrap();
    assert_eq!(tree.leaves(), gpu.leaves());
    // The refits then agree.
    let (a, b) = (tree.refit(32), gpu.refit(32));
    assert_eq!(a, b);
    assert_eq!(tree.gpu_arrays(), gpu.gpu_arrays());
    // A buffer of another topology is refused.
    let stale = readback;
    let err = tree.load_training_readback(&stale).unwrap_err();
    assert!(matches!(err, GuidingError::TrainingMismatch(_)), "{err}");
}

fn scene_hash() -> u64 {
    SceneHasher::default()
        .update(b"some scene geometry")
        .finish()
}

#[test]
fn save_load_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let tree = grown_tree();
    let path = dir.path().join("tree.sdt");
    tree.save(&path, scene_hash(), BBOX).unwrap();
    let loaded = SdTree::load(&path, scene_hash()).unwrap();
    assert_eq!(loaded, tree);
    let again = dir.path().join("again.sdt");
    loaded.save(&again, scene_hash(), BBOX).unwrap();
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read(&again).unwrap()
    );
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    let (_, info) = SdTree::load_unchecked(&path).unwrap();
    assert_eq!(
        (info.bbox_min, info.bbox_max, info.iterations),
        (BBOX.0, BBOX.1, 4)
    );
}

#[test]
fn load_refuses_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    let tree = grown_tree();
    let path = dir.path().join("tree.sdt");
    tree.save(&path, scene_hash(), BBOX).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let write = |name: &str, data: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, data).unwrap();
        p
    };

    let err = SdTree::load(&path, scene_hash() ^ 1).unwrap_err();
    assert!(matches!(err, GuidingError::SceneMismatch { .. }), "{err}");
    assert!(err.to_string().contains("tree.sdt") && err.to_string().contains("another scene"));

    let err = SdTree::load(
        &write("png.sdt", b"\x89PNG\r\n\x1a\n0000000000000000"),
        scene_hash(),
    )
    .unwrap_err();
    assert!(matches!(err, GuidingError::NotAnSdTree { .. }), "{err}");

    let mut v3 = bytes.clone();
    v3[16] = 3;
    let err = SdTree::load(&write("v3.sdt", &v3), scene_hash()).unwrap_err();
    assert!(
        matches!(
            err,
            GuidingError::Version {
                found: 3,
                supported: 4,
                ..
            }
        ),
        "{err}"
    );

    let err =
        SdTree::load(&write("short.sdt", &bytes[..bytes.len() / 2]), scene_hash()).unwrap_err();
    assert!(matches!(err, GuidingError::Corrupt { .. }), "{err}");

    let mut flipped = bytes.clone();
    let mid = bytes.len() / 2;
    flipped[mid] ^= 0x40;
    let err = SdTree::load(&write("flipped.sdt", &flipped), scene_hash()).unwrap_err();
    assert!(matches!(err, GuidingError::Corrupt { .. }), "{err}");

    let err = SdTree::load(&dir.path().join("missing.sdt"), scene_hash()).unwrap_err();
    assert!(matches!(err, GuidingError::File(_)), "{err}");
}

#[test]
fn leaf_view_shows_the_leaf() {
    let tree = grown_tree();
    let p = Vec3::new(0.5, 1.0, 0.2);
    let view = tree.leaf_view(p, 128);
    assert_eq!(view.rgb.len(), 128 * 128 * 3);
    let leaf = tree.leaf(tree.find_leaf(p));
    assert_eq!(view.info.box_min, leaf.box_min);
    assert_eq!(view.info.sampling_weight, leaf.sampling_weight);
    assert!(view.info.max_density > 1.0 && !view.info.uniform);
    let text = view.info.to_string();
    assert!(
        text.contains("bounds") && text.contains("sample weight"),
        "{text}"
    );
    assert!(view.rgb.iter().all(|v| (0.0..=1.0).contains(v)));
}

/// The upload flattens the tree straight into staging memory kept between passes
/// (`SdTree::write_gpu_buffers`): every byte must be written, whatever the memory held
/// (the last pass's arrays), and the bytes must be those of `gpu_arrays`, which the
/// saved file and the other tests use. The tree has light tables (a recorded pass of
/// light sums, refit), so the packed, hash and alias parts are not all empty.
#[test]
fn gpu_buffers_written_in_place_are_the_arrays() {
    use lanterna::gpu::{GuideLightTrainingSlot, GUIDE_LIGHT_EMPTY, GUIDE_LIGHT_SLOTS};
    let mut tree = grown_tree();
    let slots = GUIDE_LIGHT_SLOTS as usize;
    let mut sums = vec![
        GuideLightTrainingSlot {
            model: GUIDE_LIGHT_EMPTY,
            value: 0.0,
            second: 0.0,
        };
        tree.leaves().len() * slots
    ];
    for (leaf, table) in sums.chunks_exact_mut(slots).enumerate() {
        for (k, slot) in table.iter_mut().take(leaf % 4).enumerate() {
            *slot = GuideLightTrainingSlot {
                model: (leaf * 7 + k * 3) as u32 % 40,
                value: 1.0 + k as f32,
                second: 2.0,
            };
        }
    }
    tree.load_light_readback(&sums, &[1.0 / 40.0; 40]).unwrap();
    tree.refit(64);
    let arrays = tree.gpu_arrays();
    assert!(arrays.lights.iter().any(|s| s.model != GUIDE_LIGHT_EMPTY));
    let expected: [Vec<u8>; 6] = [
        arrays.spatial_buffer(),
        bytemuck::cast_slice(&arrays.leaves).to_vec(),
        bytemuck::cast_slice(&arrays.sampling).to_vec(),
        bytemuck::cast_slice(&arrays.training).to_vec(),
        bytemuck::cast_slice(&arrays.light_buffer()).to_vec(),
        bytemuck::cast_slice(&arrays.light_training).to_vec(),
    ];
    let lens = tree.gpu_buffer_lens();
    for (e, &len) in expected.iter().zip(&lens) {
        assert_eq!(e.len(), len);
    }
    for stale in [0x00u32, 0xabab_abab, u32::MAX] {
        // 4-byte aligned, as the staging memory is.
        let mut words: Vec<Vec<u32>> = lens.iter().map(|&l| vec![stale; l / 4]).collect();
        let [a, b, c, d, e, f] = &mut words[..] else {
            unreachable!()
        };
        tree.write_gpu_buffers([a, b, c, d, e, f].map(|w| bytemuck::cast_slice_mut(w)));
        for (k, (w, e)) in words.iter().zip(&expected).enumerate() {
            assert!(
                bytemuck::cast_slice::<u32, u8>(w) == e.as_slice(),
                "buffer {k} differs from gpu_arrays' over stale {stale:#x}"
            );
        }
    }
}

/// The kernel looks a model's probability up in the hash copy of its leaf's table
/// (`guide_light_pmf`) and draws models from its alias copy (`guide_light_sample`):
/// every entry of every table must be found with its value, models a table lacks must
/// get 0, draws must follow the table, and the tables must keep their packed form in
/// front (the saved file and the alias draws read that). Full tables of models that share
/// first slots make the probing wrap around.
#[test]
fn light_hash_and_alias_copies_match_the_table() {
    use lanterna::gpu::{
        GuideLightSlot, GUIDE_LIGHT_EMPTY, GUIDE_LIGHT_HASH_BITS, GUIDE_LIGHT_HASH_SLOTS,
        GUIDE_LIGHT_SLOTS,
    };
    use lanterna::guiding::{light_alias_sample, light_hash_lookup};
    let mut arrays = grown_tree().gpu_arrays();
    let leaves = arrays.leaves.len();
    assert!(leaves >= 3);
    let slots = GUIDE_LIGHT_SLOTS as usize;
    let empty = GuideLightSlot {
        model: GUIDE_LIGHT_EMPTY,
        value: 0.0,
    };
    arrays.lights = vec![empty; leaves * slots];
    // Leaf 0: a full table of models that all start probing at slot 30 of 32 (the
    // kernel's hash: top bits of model · 2654435761), so probes collide and wrap; leaf 1:
    // one entry; leaf 2 and beyond: empty.
    let first_slot = |m: u32| m.wrapping_mul(2_654_435_761) >> (32 - GUIDE_LIGHT_HASH_BITS);
    let full: Vec<u32> = (0u32..)
        .filter(|&m| first_slot(m) == GUIDE_LIGHT_HASH_SLOTS - 2)
        .take(slots)
        .collect();
    for (k, &model) in full.iter().enumerate() {
        arrays.lights[k] = GuideLightSlot {
            model,
            value: (k + 1) as f32 / 136.0,
        };
    }
    arrays.lights[slots] = GuideLightSlot {
        model: 5,
        value: 1.0,
    };
    let buffer = arrays.light_buffer();
    assert_eq!(buffer.len(), arrays.light_buffer_len());
    assert_eq!(&buffer[..arrays.lights.len()], arrays.lights.as_slice());
    for (k, &model) in full.iter().enumerate() {
        assert_eq!(
            light_hash_lookup(&buffer, leaves, 0, model),
            (k + 1) as f32 / 136.0,
            "model {model} of the full table"
        );
        assert_eq!(light_hash_lookup(&buffer, leaves, 1, model), 0.0);
    }
    assert_eq!(light_hash_lookup(&buffer, leaves, 1, 5), 1.0);
    for model in [full[0] + 1, full[3] + 1, 9_999, GUIDE_LIGHT_EMPTY - 1] {
        assert_eq!(light_hash_lookup(&buffer, leaves, 0, model), 0.0);
        assert_eq!(light_hash_lookup(&buffer, leaves, 2, model), 0.0);
    }
    // The alias copy (`guide_light_sample`) draws each model with its probability:
    // over a fine grid of u each model's share is its probability to the grid's
    // resolution, and the reported probability is the table's.
    let grid = 1 << 16;
    let mut drawn = vec![0usize; slots];
    for j in 0..grid {
        let u = (j as f32 + 0.5) / grid as f32;
        let (model, p) = light_alias_sample(&buffer, leaves, 0, u);
        let k = full
            .iter()
            .position(|&m| m == model)
            .expect("a model of the table");
        assert_eq!(p, (k + 1) as f32 / 136.0);
        drawn[k] += 1;
        assert_eq!(light_alias_sample(&buffer, leaves, 1, u), (5, 1.0));
        assert_eq!(
            light_alias_sample(&buffer, leaves, 2, u).0,
            GUIDE_LIGHT_EMPTY
        );
    }
    for (k, &n) in drawn.iter().enumerate() {
        let share = n as f64 / grid as f64;
        let p = (k + 1) as f64 / 136.0;
        assert!(
            (share - p).abs() < 1e-3,
            "model {k}: drawn {share}, probability {p}"
        );
    }
}

#[test]
fn light_tables_normalise_and_follow_splits() {
    use lanterna::gpu::{GUIDE_LIGHT_EMPTY, GUIDE_LIGHT_SLOTS};
    let config = GuidingConfig {
        learn_lights: true,
        spatial_threshold: 1.0,
        ..GuidingConfig::default()
    };
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE, &config).unwrap();
    // Leaf 0 delivered light from models 7 (3 units) and 2 (1 unit), and one bad slot.
    let mut slots = light_slots(&[]);
    slots[3] = light_slot(7, 3.0, 9.0);
    slots[9] = light_slot(2, 1.0, 1.0);
    slots[5] = light_slot(4, f32::NAN, f32::NAN);
    let source = [0.1; 10];
    tree.load_light_readback(&slots, &source).unwrap();
    for _ in 0..100 {
        tree.record(
            &GuideRecord::new(Vec3::splat(0.25), Vec3::Z, 1.0, 1.0),
            [0.5; 3],
        );
    }
    tree.refit(4);
    assert!(tree.leaves().len() > 1, "the leaf should have split");
    for leaf in tree.leaves() {
        assert_eq!(
            leaf.lights.as_slice(),
            &[(7, 0.75), (2, 0.25)],
            "children inherit the parent's table"
        );
    }
    let arrays = tree.gpu_arrays();
    assert_eq!(
        arrays.lights.len(),
        tree.leaves().len() * GUIDE_LIGHT_SLOTS as usize
    );
    assert_eq!(
        arrays.lights[0].model, 7,
        "entries come first, most probable first"
    );
    assert!(arrays
        .light_training
        .iter()
        .all(|s| s.model == GUIDE_LIGHT_EMPTY));
    assert!(
        tree.load_light_readback(&slots, &source).is_err(),
        "wrong slot count is refused"
    );
    let mut bad = light_slots(&[]);
    bad.resize(tree.leaves().len() * GUIDE_LIGHT_SLOTS as usize, bad[0]);
    bad[0] = light_slot(10, 1.0, 1.0);
    assert!(
        tree.load_light_readback(&bad, &source).is_err(),
        "a light model the scene does not have is refused"
    );
}

fn light_slot(model: u32, value: f32, second: f32) -> lanterna::gpu::GuideLightTrainingSlot {
    lanterna::gpu::GuideLightTrainingSlot {
        model,
        value,
        second,
    }
}

/// One leaf's light training slots with the given (model, Σv, Σv²), hashed anywhere.
fn light_slots(entries: &[(u32, f32, f32)]) -> Vec<lanterna::gpu::GuideLightTrainingSlot> {
    use lanterna::gpu::{GUIDE_LIGHT_EMPTY, GUIDE_LIGHT_SLOTS};
    let mut slots = vec![light_slot(GUIDE_LIGHT_EMPTY, 0.0, 0.0); GUIDE_LIGHT_SLOTS as usize];
    for (slot, &(model, value, second)) in slots.iter_mut().zip(entries) {
        *slot = light_slot(model, value, second);
    }
    slots
}

/// One pass of learned light selection on a one-leaf tree, as the renderer runs it:
/// training read-back (the leaf's Σv² in its header node), light read-back, refit.
/// Returns the light mix the leaf's next pass samples with.
fn light_pass(tree: &mut SdTree, entries: &[(u32, f32, f32)], source: &[f32]) -> f32 {
    let mut arrays = tree.gpu_arrays();
    let header = arrays.leaves[0].training_root as usize - 1;
    arrays.training[header].sum[1] = entries.iter().map(|e| e.2).sum();
    tree.load_training_readback(&arrays.training).unwrap();
    tree.load_light_readback(&light_slots(entries), source)
        .unwrap();
    tree.refit(4);
    assert_eq!(tree.leaves().len(), 1);
    tree.gpu_arrays().leaves[0].light_mix
}

/// Each leaf chooses its light mix from the pass's NEE estimates, judged with the table
/// the pass sampled with (src/guiding/light_mix.rs): all the light through the table's
/// model → the largest mix; all of it through a model the table lacks → 0; and back
/// once the table follows. Injected once: with each table judged by the estimates it
/// was learned from instead, the first table got 0.9 at once and this failed.
#[test]
fn each_leaf_learns_its_light_mix_from_its_estimates() {
    let config = GuidingConfig {
        learn_lights: true,
        learn_light_mix: true,
        ..GuidingConfig::default()
    };
    let source = vec![0.01; 100];
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE, &config).unwrap();
    assert_eq!(
        tree.gpu_arrays().leaves[0].light_mix,
        0.0,
        "no table: source only"
    );
    // First table: nothing judged it yet, it starts at the configured mix.
    assert_eq!(light_pass(&mut tree, &[(7, 3.0, 9.0)], &source), 0.5);
    // All the light came through model 7, which the table holds.
    assert_eq!(
        light_pass(&mut tree, &[(7, 3.0, 9.0)], &source),
        lanterna::guiding::MAX_LEARNED_MIX
    );
    // The light now comes from model 40, which the table lacks: the table only takes
    // samples from it.
    assert_eq!(light_pass(&mut tree, &[(40, 2.0, 4.0)], &source), 0.0);
    // With mix 0 the table (now model 40) still learns and is judged again.
    assert_eq!(
        light_pass(&mut tree, &[(40, 2.0, 4.0)], &source),
        lanterna::guiding::MAX_LEARNED_MIX
    );
    // Fixed mix (--light-mix 0.3): every leaf with a table samples with it.
    let fixed = GuidingConfig {
        learn_light_mix: false,
        light_mix: 0.3,
        ..config
    };
    tree.set_config(&fixed).unwrap();
    assert_eq!(tree.gpu_arrays().leaves[0].light_mix, 0.3);
    assert_eq!(light_pass(&mut tree, &[(40, 2.0, 4.0)], &source), 0.3);
}

/// A crafted tree file whose checksum is recomputed after the edit: the checksum cannot
/// catch it, so the loader must check the sums themselves. Guards issue 14's "overflowing
/// sums lose all indirect light" (injected once each: without the overflow check in
/// `QuadTree::from_nodes` the first load succeeds and the test fails; without
/// `check_sums_consistent` the second does).
#[test]
fn load_refuses_crafted_sums_behind_a_valid_checksum() {
    use lanterna::gpu::{GuideHeader, GuideLeaf, GuideQuadNode, GuideSpatialNode};
    use std::mem::size_of;
    let dir = tempfile::tempdir().unwrap();
    let tree = grown_tree();
    let path = dir.path().join("tree.sdt");
    tree.save(&path, scene_hash(), BBOX).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    // The fixed part of the format (io.rs): magic, version, hash, iterations, box, the
    // options, then the five counts; then the header, spatial nodes, leaves, sampling.
    // The options are 13 words (the learned light mix made them 13 in format 4; with 12
    // the edits below landed in the wrong arrays and passed by luck until the default
    // spatial filter changed), so the counts are checked against the arrays.
    let counts_at = 16 + 4 + 8 + 4 + 24 + 52;
    let count = |i: usize| {
        let at = counts_at + 4 * i;
        u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize
    };
    let arrays = tree.gpu_arrays();
    assert_eq!(
        [count(0), count(1), count(2), count(3), count(4)],
        [
            arrays.spatial.len(),
            arrays.leaves.len(),
            arrays.sampling.len(),
            arrays.training.len(),
            arrays.lights.len()
        ],
        "the test's idea of the file layout is stale"
    );
    let sampling_at = counts_at
        + 20
        + size_of::<GuideHeader>()
        + count(0) * size_of::<GuideSpatialNode>()
        + count(1) * size_of::<GuideLeaf>();
    let node = size_of::<GuideQuadNode>();
    let with_checksum = |mut body: Vec<u8>| {
        body.truncate(body.len() - 8);
        let sum = SceneHasher::default().update(&body).finish();
        body.extend_from_slice(&sum.to_le_bytes());
        body
    };
    let training_at = sampling_at + count(2) * node;
    let edit = |name: &str, array_at: usize, f: &dyn Fn(&mut [u8])| {
        let mut b = bytes.clone();
        f(&mut b[array_at..]);
        let p = dir.path().join(name);
        std::fs::write(&p, with_checksum(b)).unwrap();
        match SdTree::load(&p, scene_hash()) {
            Ok(_) => panic!("{name} loaded"),
            Err(e) => e,
        }
    };

    // Every sum of the root of leaf 0's training tree (node 1: node 0 is its header),
    // whose sums are not otherwise related, near f32::MAX: each finite, the total not.
    let err = edit("huge.sdt", training_at + node, &|s| {
        for q in 0..4 {
            s[4 * q..4 * q + 4].copy_from_slice(&3.0e38f32.to_le_bytes());
        }
    });
    assert!(matches!(err, GuidingError::Corrupt { .. }), "{err}");
    assert!(err.to_string().contains("sums overflow"), "{err}");

    // One interior quadrant's sum no longer its subtree's total.
    let err = edit("inconsistent.sdt", sampling_at, &|s| {
        let nodes: Vec<GuideQuadNode> = bytemuck::pod_collect_to_vec(&s[..count(2) * node]);
        let (n, q) = nodes
            .iter()
            .enumerate()
            .find_map(|(n, g)| g.child.iter().position(|&c| c != 0).map(|q| (n, q)))
            .expect("an interior quadrant");
        let at = n * node + 4 * q;
        let v = f32::from_le_bytes(s[at..at + 4].try_into().unwrap());
        s[at..at + 4].copy_from_slice(&(v * 3.0 + 1.0).to_le_bytes());
    });
    assert!(err.to_string().contains("sums to"), "{err}");
}
