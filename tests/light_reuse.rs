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

/// One light candidate (M = 1) beside the direction candidate: where a direction sample
/// hits a lamp, RIS keeps it about half the time, and the reused reservoir often replaces
/// it. What was kept must go with it, both ways: a replaced direction candidate leaves
/// the reused point its own shadow ray, emission and distance, and a kept one is written
/// to the grid at the point its ray hit. Against 4× the batches of `pt`, on two scenes:
/// - the sconce room (lamps on, near and inside walls and ledges, closed emissive boxes)
///   at cap 64, 64 batches, with Welch's tests and the batches' image means by rank. Seen
///   (2026-11-29) to fail with the direction candidate's flag left set on replacement,
///   which makes nearly every batch brighter (median +7 %) and a few of them
///   1.5–3,000× (light from lamps shut inside boxes, and the direction hit's
///   1/distance² at the reused point), so that Welch's test alone passed it (t ≈ 1) and
///   the ranks did not (p = 10⁻⁹); twelve clean runs put every channel's rank test at
///   p ≥ 7·10⁻³.
/// - a plane 0.3 m under a 1 m quad at cap 4, 192 batches, Welch's tests alone: one large
///   emitter correlates each batch's pixels so much that batch means are skewed, and the rank
///   test rejected clean runs (p = 10⁻⁶ at cap 64, 10⁻⁵ at cap 4). Seen to fail with a
///   kept direction candidate written with its triangle's barycentrics (0, 0) instead of
///   its hit's (readers then take a corner of the quad: a block 12 % bright, p = 10⁻¹⁶;
///   at 64 batches one run of two caught it), which the sconce room passed.
#[test]
fn ris_with_light_reuse_agrees_with_pt_where_it_replaces_the_direction_candidate() {
    let plane_quad = Options {
        size: Some(1.0),
        height: Some(0.3),
        ..Options::default()
    };
    for (kind, options, cap, ranks, batches) in [
        (Kind::Sconces, Options::default(), 64.0, true, 64),
        (Kind::PlaneQuad, plane_quad, 4.0, false, 192),
    ] {
        let t = testing::generated(kind, &options);
        let mut with_reuse = testing::settings(Method::Ris, 24, 16);
        with_reuse.seed = 24;
        with_reuse.ris_candidates = 1;
        reuse(&mut with_reuse);
        with_reuse.light_reuse.confidence_cap = cap;
        let mean_alpha = testing::levels(&with_reuse).1;
        let what = format!("{kind:?}: light reuse with one light candidate against pt");
        let (a, b) = testing::assert_agrees_with_pt(&t, with_reuse, batches, 64, &what);
        if ranks {
            testing::assert_same_image_ranks(&a, &b, mean_alpha, &what);
        }
    }
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

/// Reuse lowers the noise it exists to lower: on a small street's direct light (120
/// lamps, depth 2, emitters seen directly hidden, cells of 4 pixels, cap 4) `ris` with
/// reuse has a per-pixel variance below 0.92 of `ris` alone (0.828 with any number of
/// lavapipe threads). Reuse that never finds a reservoir leaves RIS unbiased, so the
/// agreement tests above pass it; this one does not. Seen to fail (2026-11-29) with
/// readers looking in the wrong slot of the grid (1.000: no key matches) and with cells
/// keeping their last writer instead of the highest ticket's on one lavapipe thread
/// (`LP_NUM_THREADS=1`: 0.967, which chains each pixel's samples to one writer), and
/// with tickets that lack the generation (0.971: a high ticket of an early sample keeps
/// its cell's reservoir for good).
#[test]
fn light_reuse_lowers_the_noise_of_direct_light_on_a_small_street() {
    let t = testing::small_street();
    let ris = testing::direct_light_settings(Method::Ris, 24, 16);
    let mut with_reuse = ris.clone();
    with_reuse.light_reuse = LightReuse {
        world: true,
        cell_pixels: 4.0,
        confidence_cap: 4.0,
    };
    let what = "ris with light reuse against ris alone";
    testing::assert_lowers_variance(&t, ris, with_reuse, 16, 16, 0.92, what);
}
