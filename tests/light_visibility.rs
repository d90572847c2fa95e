//! Learned light visibility (`--light-visibility learned`,
//! shaders_glsl/inc/light_visibility.glsl) keeps RIS unbiased and learns.
//!
//! - Unbiased: with it, `ris` and `guided-ris` converge to `pt`'s image (per-block Welch
//!   tests, Šidák-corrected, and the whole image's mean per channel). The floor is
//!   lowered to 0.02 and the cells to 2 pixels, so that learned factors move the target
//!   as far as the option allows: a light that looks occluded from a cell but is visible
//!   from part of it then weighs 50 times less there, which a defect in how the factor
//!   enters the weights would turn into a visible bias.
//! - Learns: at max depth 2, where each path has one RIS vertex, the share of RIS's
//!   shadow rays that reach their light (the `light-count` AOV) is higher with learned
//!   visibility than without, by far more than its sampling error.
//!
//! Each batch starts from an empty table (`run_method` and the test helpers clear it), so
//! batches are independent, while the dispatches inside a batch learn from each other.

use lanterna::render::{LightReuse, LightVisibility, Method, RenderSettings};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing::{self, render_once};

fn learned(s: &mut RenderSettings) {
    s.light_visibility = LightVisibility {
        learned: true,
        cell_pixels: 2.0,
        floor: 0.02,
    };
}

fn agree(t: &testing::TestScene, method: Method, w: u32, h: u32, spp: u64, reuse: bool) {
    let mut with = testing::settings(method, w, h);
    with.seed = 32;
    learned(&mut with);
    if reuse {
        with.light_reuse = LightReuse {
            world: true,
            ..LightReuse::default()
        };
    }
    let what = "learned light visibility against pt";
    testing::assert_agrees_with_pt(t, with, 16, spp, what);
}

#[test]
fn ris_with_learned_visibility_agrees_with_pt_on_cornell_lights() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    agree(&t, Method::Ris, 16, 16, 64, false);
}

#[test]
fn ris_with_learned_visibility_agrees_with_pt_on_a_small_street() {
    agree(&testing::small_street(), Method::Ris, 24, 16, 32, false);
}

/// Point and spot lights a few centimetres from surfaces: punctual lights have their own
/// entries (by light model), as emissive meshes do.
#[test]
fn ris_with_learned_visibility_agrees_with_pt_near_punctual_lights() {
    let t = testing::generated(Kind::PunctualNear, &Options::default());
    agree(&t, Method::Ris, 16, 16, 64, false);
}

/// The guided method's passes share one table; and world-space light reuse, whose
/// combination evaluates both vertices' targets, factors included.
#[test]
fn guided_ris_with_learned_visibility_and_light_reuse_agrees_with_pt() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    agree(&t, Method::GuidedRis, 16, 16, 64, true);
}

/// Mean over pixels of the `light-count` AOV: unoccluded RIS connections per path.
fn connected_per_path(t: &testing::TestScene, visibility: bool) -> f64 {
    let (w, h) = (24, 16);
    let mut s = testing::settings(Method::Ris, w, h);
    s.seed = 33;
    s.max_depth = 2;
    s.aovs = true;
    if visibility {
        learned(&mut s);
        s.light_visibility.floor = lanterna::render::DEFAULT_VISIBILITY_FLOOR;
        s.light_visibility.cell_pixels = lanterna::render::DEFAULT_VISIBILITY_CELL_PIXELS;
    }
    let (r, _) = render_once(&t.scene, &t.camera, &s, 128);
    let aovs = r.aovs().unwrap();
    let n = lanterna::gpu::AOV_CHANNELS as usize;
    let sum: f64 = aovs
        .chunks_exact(n)
        .map(|px| px[lanterna::gpu::AOV_LIGHT_COUNT as usize] as f64)
        .sum();
    sum / (w * h) as f64
}

/// On the street, where about half of RIS's shadow rays are occluded, learned visibility
/// sends more of them to lights they reach. Each path's count is 0 or 1, so over the
/// 24 × 16 × 128 paths the mean's standard error is at most 0.5 / √49,152 = 0.0023 per
/// render; the test asks for a rise of 0.03, over nine times the difference's error
/// (both renders at the defaults; measured: 0.44 → 0.51).
#[test]
fn learned_visibility_sends_more_shadow_rays_to_visible_lights() {
    let t = testing::small_street();
    let off = connected_per_path(&t, false);
    let on = connected_per_path(&t, true);
    eprintln!("unoccluded connections per path: {off:.4} without, {on:.4} with");
    assert!(
        on > off + 0.03,
        "learned visibility did not raise the share of visible light samples: {off:.4} → {on:.4}"
    );
}
