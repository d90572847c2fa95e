//! Guided methods: unbiased against `pt`, better than `pt` where light arrives through a
//! gap, and a saved tree renders the same image as the in-memory one.

use lanterna::render::Method;
use lanterna::scene::generate::{Kind, Options};
use lanterna::stats;
use lanterna::testing::{self, render_batches, run_batches};

const ALPHA: f64 = 1e-3;

fn agree(kind: Kind, options: Options, w: u32, h: u32, spp: u64) {
    let t = testing::generated(kind, &options);
    let mut pt = testing::settings(Method::Pt, w, h);
    pt.seed = 21;
    let a = render_batches(&t.scene, &t.camera, pt, 12, spp);
    for (i, method) in [Method::Guided, Method::GuidedRis].into_iter().enumerate() {
        let mut s = testing::settings(method, w, h);
        s.seed = 22 + i as u32;

        let b = run_batches(&t.scene, &t.camera, s, 12, spp);
        testing::assert_same_expectation(&a, &b, 4, ALPHA);
    }
    testing::assert_no_validation_errors();
}

#[test]
fn guided_methods_agree_with_pt_on_cornell_lights() {
    agree(Kind::CornellLights, Options::default(), 16, 16, 64);
}

#[test]
fn guided_methods_agree_with_pt_on_a_small_street() {
    agree(
        Kind::Street,
        Options {
            lamps: Some(120),
            aspect: Some(1.5),
            ..Options::default()
        },
        24,
        16,
        48,
    );
}
