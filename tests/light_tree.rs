//! The light tree (`--source tree`, src/lights/tree.rs, shaders_glsl/inc/light_tree.glsl)
//! keeps every method unbiased: with it, each method converges to `pt`'s image with the
//! paper's uniform source (per-block Welch tests, Šidák-corrected, and the whole image's
//! mean per channel; `testing::assert_agrees_with_pt`).
//!
//! The tree's probabilities depend on the shading point, and the kernels find them twice:
//! while sampling (the product of the choices on the way down) and for MIS, RIS's
//! direction candidate and light reuse (walking the model's stored path). A mismatch, a
//! wrong path, or bounds that rule out a light that shines on the point would bias these
//! images. The scenes cover emissive meshes near surfaces (`cornell-lights`, lamps
//! behind a blocker), hundreds of lamps (a small street), point and spot lights
//! centimetres from surfaces (`punctual-near`), and a directional light beside point
//! and spot lights (tests/data/mitsuba/punctual.gltf), which sits under the tree's fixed
//! split at the root.

use lanterna::render::{LightReuse, LightSource, Method, RenderSettings};
use lanterna::scene::generate::{Kind, Options};
use lanterna::scene::Scene;
use lanterna::testing;

fn with_tree(method: Method, w: u32, h: u32) -> RenderSettings {
    let mut s = testing::settings(method, w, h);
    s.seed = 33;
    s.source = LightSource::Tree;
    s
}

const WHAT: &str = "the light tree's source against pt's uniform one";

#[test]
fn pt_with_the_light_tree_agrees_with_pt_on_cornell_lights() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    testing::assert_agrees_with_pt(&t, with_tree(Method::Pt, 16, 16), 16, 64, WHAT);
}

#[test]
fn pt_and_ris_with_the_light_tree_agree_with_pt_on_a_small_street() {
    let t = testing::small_street();
    for method in [Method::Pt, Method::Ris] {
        testing::assert_agrees_with_pt(&t, with_tree(method, 24, 16), 16, 32, WHAT);
    }
}

#[test]
fn ris_with_the_light_tree_agrees_with_pt_near_punctual_lights() {
    let t = testing::generated(Kind::PunctualNear, &Options::default());
    testing::assert_agrees_with_pt(&t, with_tree(Method::Ris, 16, 16), 16, 64, WHAT);
}

/// The guided methods mix the tree with their learned light tables; `guided-ris` also
/// weighs its direction candidate and the reused reservoirs of `--light-reuse world`
/// with the tree's pmf at other points.
#[test]
fn guided_methods_with_the_light_tree_agree_with_pt() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    testing::assert_agrees_with_pt(&t, with_tree(Method::Guided, 16, 16), 16, 64, WHAT);
    let mut s = with_tree(Method::GuidedRis, 16, 16);
    s.light_reuse = LightReuse {
        world: true,
        ..LightReuse::default()
    };
    testing::assert_agrees_with_pt(&t, s, 16, 64, WHAT);
}

/// A directional light with point and spot lights: the fixed split at the tree's root.
#[test]
fn pt_and_ris_with_the_light_tree_agree_with_pt_under_a_directional_light() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/punctual.gltf");
    let scene = Scene::load(&path, &Default::default()).expect("load punctual.gltf");
    let camera = scene.cameras.first().cloned().expect("a camera");
    let mut pt = testing::settings(Method::Pt, 16, 12);
    pt.seed = 21;
    let a = testing::render_batches(&scene, &camera, pt, 16, 64);
    for method in [Method::Pt, Method::Ris] {
        let b = testing::render_batches(&scene, &camera, with_tree(method, 16, 12), 16, 64);
        let alpha = testing::REPEATABLE_ALPHA;
        testing::assert_agree(&a, &b, 4, alpha, alpha, WHAT);
    }
    testing::assert_no_validation_errors();
}

/// The tree lowers the noise it exists to lower: on a small street's direct light (120
/// lamps, depth 2, emitters seen directly hidden), `pt` drawing from the tree has a
/// per-pixel variance below 0.045 of its uniform self's (measured 0.030; `pt` is
/// repeatable, so the ratio moves only when the code changes what it draws, and its own
/// sampling error, 16 batches over 384 pixels, is a few per cent). Unbiasedness does not
/// need the kernels' bounds to be right (the sampling and the pmf walk agree, and a
/// uniform share keeps every model samplable), so the agreement tests above pass a tree
/// that favours the wrong lights; this one does not. Seen to fail (2026-11-29) with
/// the receiver's normal turned over (ratio 1.35), the emission cone's test reversed
/// (0.28), the nodes' power left out (0.067), the distance unsquared (0.054) and the
/// normals' spread left out of the orientation bound (0.056).
#[test]
fn the_light_tree_lowers_the_noise_of_direct_light_on_a_small_street() {
    let t = testing::small_street();
    let uniform = testing::direct_light_settings(Method::Pt, 24, 16);
    let mut tree = uniform.clone();
    tree.source = LightSource::Tree;
    let what = "pt with the light tree against the uniform source";
    testing::assert_lowers_variance(&t, uniform, tree, 16, 16, 0.045, what);
}
