//! NEE contributions train the SD-tree (the paper's proposal), observed on the tree.
//!
//! A floor lit by one 2 mm square lamp 1 m above it (`plane-quad --size 0.002`): a BSDF
//! sample hits the lamp about once in 10⁶, so during training (≈ 10⁵ paths) direction
//! sampling all but never finds it and what the tree learns of the lamp's direction
//! comes from NEE records alone. After `guided-ris` trains at max depth 2, the sampling
//! quadtree of the leaf under the lamp must send most of its samples within 30° of
//! straight up (a uniform tree sends 6.7 %), and with `--no-record-nee` it must not.
//!
//! Defects it was seen to catch: NEE records splatted as value × statistical weight with
//! weight 0 (the code before GuideRecord), and NEE records dropped in `record_path`:
//! both leave the leaf as uniform as `--no-record-nee` does.

use glam::Vec3;
use lanterna::render::{Method, RenderSettings};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing;

/// Fraction of directions sampled from the leaf's quadtree within `degrees` of +Y.
fn fraction_toward_lamp(record_nee: bool) -> f64 {
    let ts = testing::generated(
        Kind::PlaneQuad,
        &Options {
            size: Some(0.002),
            emission: Some(2000.0),
            ..Options::default()
        },
    );
    let base = testing::settings(Method::GuidedRis, 48, 48);
    let settings = RenderSettings {
        max_depth: 2,
        guiding: lanterna::render::GuidingSettings {
            record_nee,
            // NEE records are part of the paper's target (the default is `indirect`).
            target: lanterna::guiding::GuideTarget::All,
            ..base.guiding.clone()
        },
        ..base
    };
    let tree = testing::trained_tree(&ts.scene, &ts.camera, &settings, 128);
    let leaf = tree.leaf(tree.find_leaf(Vec3::new(0.0, 0.0, 0.0)));
    let cos_cone = 30f32.to_radians().cos();
    let n = 20_000;
    let mut inside = 0;
    for i in 0..n {
        // A 2-D Fibonacci lattice: evenly spread numbers, no RNG needed.
        let u = [(i as f32 + 0.5) / n as f32, (i as f32 * 0.618_034) % 1.0];
        let (dir, _) = leaf.sampling.sample(u);
        if dir.y >= cos_cone {
            inside += 1;
        }
    }
    testing::assert_no_validation_errors();
    inside as f64 / n as f64
}

#[test]
fn nee_records_teach_the_tree_where_the_lamp_is() {
    let with = fraction_toward_lamp(true);
    let without = fraction_toward_lamp(false);
    println!("within 30° of the lamp: {with:.3} with NEE records, {without:.3} without");
    assert!(
        with > 0.5,
        "with NEE records only {with:.3} of the leaf's samples go toward the lamp"
    );
    assert!(
        without < 0.25,
        "without NEE records {without:.3} of the samples go toward the lamp: the test \
         no longer isolates what NEE records teach"
    );
}
