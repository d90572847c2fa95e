//! RIS NEE converges to the same image as `pt` (per-block Welch tests, Šidák-corrected).

use lanterna::render::{LightSource, Method};
use lanterna::scene::generate::{Kind, Options};
use lanterna::testing::{self, render_batches};

const ALPHA: f64 = 1e-3;

fn agree(
    kind: Kind,
    options: Options,
    w: u32,
    h: u32,
    spp: u64,
    tweak: impl Fn(&mut lanterna::render::RenderSettings),
) {
    let t = testing::generated(kind, &options);
    let mut pt = testing::settings(Method::Pt, w, h);
    pt.seed = 11;
    let mut ris = testing::settings(Method::Ris, w, h);
    ris.seed = 12;
    tweak(&mut ris);
    let a = render_batches(&t.scene, &t.camera, pt, 12, spp);
    let b = render_batches(&t.scene, &t.camera, ris, 12, spp);
    testing::assert_same_expectation(&a, &b, 4, ALPHA);
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
