//! World-space light reuse (`--light-reuse world`, shaders_glsl/inc/light_reuse.glsl)
//! keeps RIS unbiased: with reuse, `ris` and `guided-ris` converge to `pt`'s image
//! (per-block Welch tests, Šidák-corrected, and the whole image's mean per channel).
//! Each batch starts from an empty grid (`clear_film` clears it), so batches are
//! independent, while the samples inside a batch reuse each other's reservoirs. The
//! confidence cap is raised to 64 so that reused reservoirs dominate: a defect in their
//! weights then moves the image.

use lanterna::render::{LightReuse, Method, RenderSettings};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing;

fn reuse(s: &mut RenderSettings) {
    s.light_reuse = LightReuse {
        world: true,
        cell_pixels: 4.0,
        confidence_cap: 64.0,
    };
}

fn agree(t: &testing::TestScene, method: Method, w: u32, h: u32, spp: u64) {
    let mut with_reuse = testing::settings(method, w, h);
    with_reuse.seed = 22;
    reuse(&mut with_reuse);
    testing::assert_agrees_with_pt(t, with_reuse, 16, spp, "light reuse against pt");
}

#[test]
fn ris_with_light_reuse_agrees_with_pt_on_cornell_lights() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    agree(&t, Method::Ris, 16, 16, 64);
}

#[test]
fn ris_with_light_reuse_agrees_with_pt_on_a_small_street() {
    let t = testing::small_street();
    agree(&t, Method::Ris, 24, 16, 32);
}

/// Point and spot lights a few centimetres from surfaces: reused reservoirs hold
/// punctual lights (REUSE_PUNCTUAL) as well as points on emissive triangles.
#[test]
fn ris_with_light_reuse_agrees_with_pt_near_punctual_lights() {
    let t = testing::generated(Kind::PunctualNear, &Options::default());
    agree(&t, Method::Ris, 16, 16, 64);
}

#[test]
fn guided_ris_with_light_reuse_agrees_with_pt() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    agree(&t, Method::GuidedRis, 16, 16, 64);
}
