//! RIS NEE converges to the same image as `pt` (per-block Welch tests, Šidák-corrected,
//! and Welch tests of the whole image's mean per channel).
//!
//! Seen to fail with defects injected through LANTERNA_TEST_SHADER_DIR (2026-11-28):
//! - the resampling weights' denominator counting M + 1 slots (W low by M/(M + 1), 3 %
//!   of the direct light at M = 32): with the block tests alone only the textured
//!   emitter and M = 1 tests failed; with the image-mean tests (added for this) every
//!   test but the small street's: `cornell-lights` red 0.833 against 0.822, p = 1e-7;
//! - the direction candidate's density left out of every candidate's denominator (the
//!   emission a direction sample finds counted by both strategies): the textured
//!   emitter's block test and the M = 1 image mean (+2.5 %, p = 2e-5); at M = 32 on
//!   `cornell-lights` the excess is below these tests' power, and the conformance suite
//!   (tests/conformance.rs) is what catches it there (three of its six tests fail).

use lanterna::render::{LightSource, Method};
use lanterna::scene::generate::{Kind, Options};
use lanterna::scene::TextureData;
use lanterna::testing::{self, render_batches};
use lanterna::vk::{SamplerDesc, Texels, TextureFormat, WrapMode};

const ALPHA: f64 = 1e-3;

fn agree(
    kind: Kind,
    options: Options,
    w: u32,
    h: u32,
    spp: u64,
    tweak: impl Fn(&mut lanterna::render::RenderSettings),
) {
    agree_on(&testing::generated(kind, &options), w, h, spp, tweak);
}

fn agree_on(
    t: &testing::TestScene,
    w: u32,
    h: u32,
    spp: u64,
    tweak: impl Fn(&mut lanterna::render::RenderSettings),
) {
    let mut pt = testing::settings(Method::Pt, w, h);
    pt.seed = 11;
    let mut ris = testing::settings(Method::Ris, w, h);
    ris.seed = 12;
    tweak(&mut ris);
    let a = render_batches(&t.scene, &t.camera, pt, 12, spp);
    let b = render_batches(&t.scene, &t.camera, ris, 12, spp);
    testing::assert_agree(&a, &b, 4, ALPHA, ALPHA, "ris against pt");
    testing::assert_no_validation_errors();
}

#[test]
fn ris_agrees_with_pt_on_cornell_lights() {
    agree(Kind::CornellLights, Options::default(), 16, 16, 64, |_| {});
}

#[test]
fn ris_agrees_with_pt_on_a_small_street() {
    agree(
        Kind::Street,
        Options {
            lamps: Some(120),
            aspect: Some(1.5),
            ..Options::default()
        },
        24,
        16,
        32,
        |_| {},
    );
}

#[test]
fn ris_with_power_source_agrees_with_pt() {
    agree(Kind::CornellLights, Options::default(), 16, 16, 64, |s| {
        s.source = LightSource::Power
    });
}

#[test]
fn ris_with_one_candidate_equals_pt_in_expectation() {
    agree(Kind::CornellLights, Options::default(), 16, 16, 64, |s| {
        s.ris_candidates = 1
    });
}

/// RIS's target takes a textured emitter's emission as the material's times the texture's
/// mean luminance over the triangle (no texture lookups for the 32 candidates); the kept
/// candidate's contribution must still carry the texture's colour. The plane-quad emitter
/// gets a checkerboard of saturated red, blue and black cells, whose mean is a grey that
/// is far from every cell. Seen to fail with the target's emission left in the
/// contribution (light_sample_complete and the direction candidate's true emission
/// skipped in nee_ris).
#[test]
fn ris_agrees_with_pt_under_a_textured_emitter() {
    let mut t = testing::generated(
        Kind::PlaneQuad,
        &Options {
            size: Some(1.0),
            height: Some(0.6),
            ..Options::default()
        },
    );
    let cells: [[u8; 4]; 4] = [
        [255, 0, 0, 255],
        [0, 0, 255, 255],
        [0, 0, 0, 255],
        [255, 0, 0, 255],
    ];
    let n = 4u32;
    let mut rgba = Vec::new();
    for y in 0..n {
        for x in 0..n {
            rgba.extend_from_slice(&cells[((x + y) % 4) as usize]);
        }
    }
    let index = t.scene.textures.len() as i32;
    t.scene.textures.push(TextureData {
        name: "checker".into(),
        width: n,
        height: n,
        texels: Texels::Rgba8(rgba),
        format: TextureFormat::Srgb,
        sampler: SamplerDesc {
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            nearest: true,
        },
    });
    let mut textured = 0;
    for m in &mut t.scene.materials {
        if m.emission.iter().any(|&c| c > 0.0) {
            m.emissive_tex.index = index;
            m.emissive_tex.uv_set = 0;
            textured += 1;
        }
    }
    assert_eq!(textured, 1, "plane-quad has one emissive material");
    agree_on(&t, 16, 16, 64, |_| {});
}

/// RIS lowers the noise it exists to lower: on `cornell-lights`' direct light (depth 2,
/// emitters seen directly hidden) `ris`'s per-pixel variance is below 0.15 of `pt`'s
/// (measured 0.116; both repeatable, so the ratio moves only when the code changes what
/// they draw, and its own sampling error, 16 batches over 384 pixels, is a few per cent).
/// A target p̂ other than the paper's Le·f·G keeps RIS unbiased, so the agreement tests
/// pass it; this one does not. Seen to fail (2026-11-29) with the BSDF left out of p̂
/// (0.198), the geometry term left out (0.630) and p̂ from the red channel alone
/// instead of the luminance (0.213).
#[test]
fn ris_lowers_the_noise_of_direct_light_on_cornell_lights() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    let pt = testing::direct_light_settings(Method::Pt, 24, 16);
    let mut ris = pt.clone();
    ris.method = Method::Ris;
    testing::assert_lowers_variance(&t, pt, ris, 16, 16, 0.15, "ris against pt");
}
