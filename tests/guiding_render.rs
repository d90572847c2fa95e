//! Guided methods: unbiased against `pt`, better than `pt` where light arrives through a
//! gap, and a saved tree renders the same image as the in-memory one.
//!
//! Seen to fail with defects injected through LANTERNA_TEST_SHADER_DIR (2026-11-28):
//! - the mixture pdf weighting its parts by the header's α while directions are drawn
//!   with the leaf's learned α (`direction_pdf_mix`): `cornell-lights` `guided` red
//!   0.831 against `pt`'s 0.855, p = 4e-8, and the kept-passes test; the block tests
//!   alone passed it, the whole image's mean (added for this) did not.
//! - the light tables' filter testing the neighbouring bit (`guide_light_filter_may_hold`:
//!   models in a leaf's table ruled out, their table share left out of the mixture pmf):
//!   the small street (120 lamps, so the filter is built), block p = 8·10⁻¹²;
//!   `cornell-lights` (16 models, no filter) passes, as it should.
//! - Not caught here, nor by tests/conformance.rs: `guide_sample` returning its density
//!   5 % high (about 0.5 % of these images). tests/guiding_kernel_checks.rs catches it,
//!   and a 0.1 % error, by comparing every sample's pdf with `guide_pdf`'s.

use lanterna::render::Method;
use lanterna::scene::generate::{Kind, Options};
use lanterna::stats;
use lanterna::testing::batch_mae;
use lanterna::testing::{self, render_batches, run_batches};

/// Training's float atomics make each guided run a fresh draw, so these comparisons take
/// the levels of fresh draws (`testing::FRESH_BLOCK_ALPHA`, `testing::FRESH_MEAN_ALPHA`)
/// and `pt`'s side, repeatable and cheap, `testing::PT_BATCHES_PER_BATCH` times the
/// batches.
const ALPHA: f64 = testing::FRESH_BLOCK_ALPHA;
/// Per channel, for the whole image's mean (`testing::assert_same_image_mean`).
const IMAGE_MEAN_ALPHA: f64 = testing::FRESH_MEAN_ALPHA;
const PT_BATCHES: u32 = testing::PT_BATCHES_PER_BATCH * 12;

fn agree(kind: Kind, options: Options, w: u32, h: u32, spp: u64) {
    let t = testing::generated(kind, &options);
    let mut pt = testing::settings(Method::Pt, w, h);
    pt.seed = 21;
    let a = render_batches(&t.scene, &t.camera, pt, PT_BATCHES, spp);
    for (i, method) in [Method::Guided, Method::GuidedRis].into_iter().enumerate() {
        let mut s = testing::settings(method, w, h);
        s.seed = 22 + i as u32;

        let b = run_batches(&t.scene, &t.camera, s, 12, spp);
        let what = format!("{method:?} against pt");
        testing::assert_agree(&a, &b, 4, ALPHA, IMAGE_MEAN_ALPHA, &what);
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

/// Where light reaches the visible room only through a doorway, the SD-tree learns to
/// send paths through it. `lanterna compare` on this scene at 64×48 measured guided at
/// 0.76× pt's MAE with 256 spp and 0.65× with 1024 (training included in the budget;
/// smaller images or budgets give the tree too little data to pay for its training
/// samples). The test asks for a margin of 10 %: guided's mean MAE over 8 independent
/// runs below 0.9× pt's, with Welch's test rejecting "not 10 % better" at p < 1e-3.
#[test]
fn guiding_learns_the_way_through_a_gap() {
    let t = testing::generated(Kind::Gap, &Options::default());
    let (w, h, spp) = (64, 48, 256);
    let mut s = testing::settings(Method::Pt, w, h);
    s.seed = 31;
    let reference = render_batches(&t.scene, &t.camera, s, 16, 256).mean();
    let mut pt = testing::settings(Method::Pt, w, h);
    pt.seed = 32;
    let pt_mae = batch_mae(&render_batches(&t.scene, &t.camera, pt, 8, spp), &reference);
    let mut g = testing::settings(Method::Guided, w, h);
    g.seed = 33;
    let g_mae = batch_mae(&run_batches(&t.scene, &t.camera, g, 8, spp), &reference);
    let target: Vec<f64> = pt_mae.iter().map(|m| 0.9 * m).collect();
    let (mg, _) = stats::mean_var(&g_mae);
    let (mp, _) = stats::mean_var(&pt_mae);
    let p = stats::welch(&g_mae, &target);
    assert!(
        mg < 0.9 * mp && p < 1e-3,
        "guided MAE {mg:.5} vs pt {mp:.5} (ratio {:.3}, p = {p:.2e})",
        mg / mp
    );
    eprintln!("gap scene: guided/pt MAE ratio {:.3} at {spp} spp", mg / mp);
    testing::assert_no_validation_errors();
}

#[test]
fn saved_tree_renders_the_same_image() {
    use lanterna::lights::LightTable;
    use lanterna::render::run::{run_method, Budget};
    use lanterna::render::Renderer;
    use std::sync::atomic::AtomicBool;
    let t = testing::generated(Kind::CornellLights, &Options::default());
    let lights = LightTable::build(&t.scene).unwrap();
    let cancel = AtomicBool::new(false);
    let mut s = testing::settings(Method::GuidedRis, 16, 16);
    // The film is the render phase alone, which the loaded tree renders again.
    s.guiding.output = lanterna::render::GuidedOutput::RenderPhase;
    let mut r = Renderer::new(
        testing::device(),
        &t.scene,
        &lights,
        t.camera.clone(),
        s.clone(),
        Default::default(),
    )
    .unwrap();
    let out = run_method(&mut r, Budget::Spp(32), 0, &cancel, &mut |_| {}).unwrap();
    let g = out.guiding.expect("guided run");
    let trained: u64 = g.iterations.iter().map(|i| i.spp).sum();
    let file = t.dir.0.join("tree.sdt");
    let hash = u64::from_str_radix(&t.scene.hash, 16).unwrap();
    g.tree
        .save(
            &file,
            hash,
            (t.scene.bounds_min.into(), t.scene.bounds_max.into()),
        )
        .unwrap();

    // A loaded tree skips training; render the same sample range as the render phase.
    let mut r2 = Renderer::new(
        testing::device(),
        &t.scene,
        &lights,
        t.camera.clone(),
        s,
        Default::default(),
    )
    .unwrap();
    r2.preloaded_tree = Some(lanterna::guiding::SdTree::load(&file, hash).unwrap());
    let again = run_method(
        &mut r2,
        Budget::Spp(out.film.spp),
        trained,
        &cancel,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(
        again.film, out.film,
        "a loaded tree rendered a different image"
    );
    // Another scene's hash is refused.
    assert!(lanterna::guiding::SdTree::load(&file, hash ^ 1).is_err());
    testing::assert_no_validation_errors();
}

/// The default output (`all-passes`) is every training pass and the render phase: its
/// film is the budget's whole range of sample indices, every sample counted once. It
/// and `late-passes` (the render phase and the last four training passes: a range
/// ending where the budget ends) agree with pt, as the render phase alone does.
#[test]
fn kept_passes_cover_their_sample_ranges_and_agree_with_pt() {
    use lanterna::render::run::{run_method, Budget};
    use lanterna::render::GuidedOutput;
    use std::sync::atomic::AtomicBool;
    let t = testing::generated(Kind::CornellLights, &Options::default());
    let mut s = testing::settings(Method::Guided, 16, 16);
    assert_eq!(s.guiding.output, GuidedOutput::AllPasses, "the default");
    let (first, spp) = (1000, 256);
    for output in [GuidedOutput::AllPasses, GuidedOutput::LatePasses] {
        s.guiding.output = output;
        let mut r = testing::test_renderer_on(testing::device(), &t.scene, &t.camera, &s);
        let out = run_method(
            &mut r,
            Budget::Spp(spp),
            first,
            &AtomicBool::new(false),
            &mut |_| {},
        )
        .unwrap();
        let its = out.guiding.as_ref().unwrap().iterations.clone();
        let trained: u64 = its.iter().map(|i| i.spp).sum();
        let late: u64 = its.iter().rev().take(4).map(|i| i.spp).sum();
        assert_eq!(its.len(), 6, "1 + 2 + … + 32 spp train 256");
        let kept = match output {
            GuidedOutput::AllPasses => spp,
            _ => late + (spp - trained),
        };
        assert_eq!(out.film.spp, kept, "{output:?}: passes kept");
        assert_eq!(out.film.sample_offset + out.film.spp, first + spp);
        assert!(
            out.combined.is_none(),
            "the film's exact sums are the image"
        );
    }

    let mut pt = testing::settings(Method::Pt, 16, 16);
    pt.seed = 61;
    let a = render_batches(&t.scene, &t.camera, pt, PT_BATCHES, 64);
    for (output, seed) in [
        (GuidedOutput::LatePasses, 62),
        (GuidedOutput::RenderPhase, 63),
        (GuidedOutput::AllPasses, 64),
    ] {
        let mut s = testing::settings(Method::Guided, 16, 16);
        s.seed = seed;
        s.guiding.output = output;
        let b = run_batches(&t.scene, &t.camera, s, 12, 64);
        // A weighting error scales the whole image: the image means are the sharpest test.
        testing::assert_agree(&a, &b, 4, ALPHA, IMAGE_MEAN_ALPHA, &format!("{output:?}"));
    }
    testing::assert_no_validation_errors();
}

/// Müller et al.'s inverse-variance combination of the passes is consistent: on
/// cornell-lights it agrees with pt at the same significance as the unbiased methods.
#[test]
fn inverse_variance_combination_agrees_with_pt() {
    let t = testing::generated(Kind::CornellLights, &Options::default());
    let mut pt = testing::settings(Method::Pt, 16, 16);
    pt.seed = 41;
    let a = render_batches(&t.scene, &t.camera, pt, PT_BATCHES, 64);
    let mut s = testing::settings(Method::GuidedRis, 16, 16);
    s.seed = 42;
    s.guiding.output = lanterna::render::GuidedOutput::InverseVariance;
    let b = run_batches(&t.scene, &t.camera, s, 12, 64);
    testing::assert_same_expectation(&a, &b, 4, ALPHA);
    testing::assert_no_validation_errors();
}

/// Learned light selection keeps NEE, RIS and MIS unbiased: guided methods with
/// --learn-lights agree with pt on the many-light scenes; `guided` with each leaf's
/// learned mix (its default), `guided-ris` with the largest fixed mix, 0.95, where a
/// mismatch between the mix that samples and the one in the pdfs weighs most. Seen to
/// fail (p = 4·10⁻⁹) with `sample_light` choosing from the table with probability 0.5
/// while the pdfs use the leaf's mix; pdfs alone using 0.5 (the table-chosen models'
/// own pmf right) went unnoticed here and in the conformance suite (+1.3 ± 0.4 %).
/// The street (with more than 64 light models) takes the RIS candidates' model filter
/// (`guide_light_filter`): a filter that ruled out models its table holds failed here
/// (p = 5·10⁻⁸; with the street's larger batches, a filter leaving out each table's
/// first entry: p = 2·10⁻⁶, and the table chosen at 0.5: p = 2·10⁻¹⁷ on cornell-lights).
#[test]
fn learned_light_selection_agrees_with_pt() {
    // Batch sizes: the guided methods' spp, pt's 4× that. Near the street's lamps rare,
    // bright samples make small batches' means skewed: a batch usually has none of
    // them, so its mean is low and the batches' spread understates the error, which
    // the t-test reads as a difference. In block (8, 8) (red; 0.211 ± 0.002 from 24 ×
    // 768 spp of pt) guided-ris's batch spread is 0.014 at 48 spp but 0.033 at 192,
    // where the rare samples show up. With 48-spp guided batches against pt's 192,
    // twelve runs of guided-ris put that block at p = 1.8·10⁻⁵ once (the Šidák bound
    // is 1.4·10⁻⁵) and below 10⁻⁴ twice; with 192 against 768, eight runs had no block
    // below 10⁻² (576 tests).
    for (kind, options, w, h, spp) in [
        (Kind::CornellLights, Options::default(), 16, 16, 48),
        (
            Kind::Street,
            Options {
                lamps: Some(120),
                aspect: Some(1.5),
                ..Options::default()
            },
            24,
            16,
            192,
        ),
    ] {
        let t = testing::generated(kind, &options);
        let mut pt = testing::settings(Method::Pt, w, h);
        pt.seed = 51;
        let a = render_batches(&t.scene, &t.camera, pt, 12, 4 * spp);
        for (i, method) in [Method::Guided, Method::GuidedRis].into_iter().enumerate() {
            let mut s = testing::settings(method, w, h);
            s.seed = 52 + i as u32;
            s.guiding.learn_lights = true;
            if method == Method::GuidedRis {
                s.guiding.learn_light_mix = Some(false);
                s.guiding.light_mix = lanterna::guiding::MAX_LIGHT_MIX;
            }
            let b = run_batches(&t.scene, &t.camera, s, 12, spp);
            let p = testing::assert_same_expectation(&a, &b, 4, ALPHA);
            eprintln!("{kind:?} {method:?}: worst block p = {p:.2e}");
        }
    }
    testing::assert_no_validation_errors();
}

/// Relative L1 distance Σ|a − b| / Σ|a| of two lists of sums.
fn relative_l1(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
    d / a
        .iter()
        .map(|x| x.abs())
        .sum::<f64>()
        .max(f64::MIN_POSITIVE)
}

/// The SD-tree's arrays read through their device addresses (push constants; the
/// default on CPU devices) and through the bound storage buffers: with the same tree
/// (trained through the bound buffers, 32×32 at 128 spp: about 40 leaves), the render
/// phase is the same bit for bit, and a training pass leaves the same training
/// quadtrees (children equal, sums within 1e-5 relative L1: the float atomics' order
/// moves them by about 1e-8) and the same learned light tables (summed per leaf and
/// model, within 1e-2: which of two models claims a slot first, and so which record a
/// full neighbourhood drops, depends on the lanes' order; measured 1e-4 and below).
/// `guided` and `guided-ris`, with learned selection and light tables, on
/// cornell-lights (a street of 120 lamps agreed as well, and is left out for the time
/// its textured layout's kernels take). Seen to fail with the training and sampling
/// addresses swapped (the render phase differs), with the training address at the
/// sampling trees (nothing recorded), and with the light training table's address at
/// the light tables (no entries); with the leaves' address at the spatial tree lavapipe
/// read out of bounds and the test process crashed.
#[test]
fn sd_tree_arrays_through_addresses_and_bound_buffers_agree() {
    use lanterna::render::run::{run_method, Budget};
    use lanterna::render::{GuideBuffers, GuidedOutput, RenderStats};
    use std::collections::HashMap;
    use std::sync::atomic::AtomicBool;
    let cancel = AtomicBool::new(false);
    let kind = Kind::CornellLights;
    let t = testing::generated(kind, &Options::default());
    for method in [Method::Guided, Method::GuidedRis] {
        let mut s = testing::settings(method, 32, 32);
        s.guiding.learn_lights = true;
        s.guiding.output = GuidedOutput::RenderPhase;
        let renderer = |addresses: bool| {
            let mut s = s.clone();
            s.scene_addresses = Some(addresses);
            testing::test_renderer_on(testing::device(), &t.scene, &t.camera, &s)
        };
        // The tree is trained through the bound buffers, so that a defect of the
        // addresses cannot spoil it.
        let mut r = renderer(false);
        let out = run_method(&mut r, Budget::Spp(128), 0, &cancel, &mut |_| {}).unwrap();
        let g = out.guiding.expect("a guided run");
        let trained: u64 = g.iterations.iter().map(|i| i.spp).sum();
        let mut results = Vec::new();
        for addresses in [true, false] {
            let mut r = renderer(addresses);
            r.preloaded_tree = Some(g.tree.clone());
            let film = run_method(
                &mut r,
                Budget::Spp(out.film.spp),
                trained,
                &cancel,
                &mut |_| {},
            )
            .unwrap()
            .film;
            // One training pass from the trained tree.
            r.set_guide_buffers(GuideBuffers::upload(&r.device, &g.tree).unwrap());
            r.clear_film().unwrap();
            r.render_samples(
                1 << 20,
                8,
                true,
                &cancel,
                &mut |_| {},
                &mut RenderStats::default(),
            )
            .unwrap();
            let (children, sums, table) = r
                .guide_buffers()
                .read_pass(&r.device, true, |pass| {
                    let children: Vec<[u32; 4]> = pass.training.iter().map(|n| n.child).collect();
                    let sums: Vec<f64> = pass
                        .training
                        .iter()
                        .flat_map(|n| n.sum.map(f64::from))
                        .collect();
                    let mut table: HashMap<(usize, u32), [f64; 2]> = HashMap::new();
                    for (i, slot) in pass.lights.iter().enumerate() {
                        if slot.model != lanterna::gpu::GUIDE_LIGHT_EMPTY {
                            let e = table
                                .entry((i / lanterna::gpu::GUIDE_LIGHT_SLOTS as usize, slot.model))
                                .or_default();
                            e[0] += slot.value as f64;
                            e[1] += slot.second as f64;
                        }
                    }
                    (children, sums, table)
                })
                .unwrap();
            results.push((film, children, sums, table));
        }
        let what = format!("{kind:?} {method}");
        let (a, b) = (&results[0], &results[1]);
        assert!(a.0.sums.iter().any(|&v| v > 0), "{what}: black film");
        assert_eq!(a.0, b.0, "{what}: the render phase differs");
        assert_eq!(a.1, b.1, "{what}: the training trees' children differ");
        let sums = relative_l1(&a.2, &b.2);
        let keys: Vec<(usize, u32)> = a.3.keys().chain(b.3.keys()).copied().collect();
        let table = |t: &HashMap<(usize, u32), [f64; 2]>, k: usize| -> Vec<f64> {
            keys.iter()
                .map(|key| t.get(key).map_or(0.0, |e| e[k]))
                .collect()
        };
        let values = relative_l1(&table(&a.3, 0), &table(&b.3, 0));
        let seconds = relative_l1(&table(&a.3, 1), &table(&b.3, 1));
        eprintln!(
            "{what}: training sums {sums:.2e}, light values {values:.2e}, squares {seconds:.2e} (relative L1), {} table entries",
            a.3.len()
        );
        assert!(a.2.iter().any(|&v| v > 0.0), "{what}: nothing recorded");
        assert!(!a.3.is_empty(), "{what}: no light table entries");
        assert!(sums < 1e-5, "{what}: training sums differ by {sums:.2e}");
        assert!(
            values < 1e-2 && seconds < 1e-2,
            "{what}: light tables differ by {values:.2e} / {seconds:.2e}"
        );
    }
    testing::assert_no_validation_errors();
}

/// Learned light selection learns punctual lights too: on the conformance room of point
/// and spot lights a few centimetres from surfaces (no emissive geometry), every leaf's
/// table is made of the punctual lights' models, every light that reaches the camera's
/// surfaces appears in some table, and the leaves at the block top 1 cm under a point
/// light and at the wall 2 cm behind another hold that light as their largest entry
/// (their irradiance there is 10⁴ times any other light's). Until 2026-11-27 the NEE
/// record named a light model only for points on emissive triangles, so punctual
/// lights never entered a table, and in scenes mixing them with area lights the tables
/// starved them (random scene 20: `guided` at 1.46× `pt`'s MAE, 0.56× once fixed). Seen
/// to fail with the punctual model of the light sample left unset (no table entries).
#[test]
fn learned_light_tables_hold_punctual_lights() {
    use lanterna::lights::LightTable;
    let t = testing::generated(Kind::PunctualNear, &Options::default());
    let table = LightTable::build(&t.scene).unwrap();
    let model_of = |punctual: u32| {
        table
            .models
            .iter()
            .position(|m| m.punctual == punctual)
            .expect("a model per punctual light") as u32
    };
    let mut s = testing::settings(Method::Guided, 32, 24);
    s.guiding.learn_lights = true;
    let tree = testing::trained_tree(&t.scene, &t.camera, &s, 128);
    let mut seen = std::collections::BTreeSet::new();
    for leaf in tree.leaves() {
        for &(model, _) in leaf.lights.iter() {
            seen.insert(model);
        }
    }
    let punctual: Vec<u32> = (0..t.scene.punctual.len() as u32).map(model_of).collect();
    eprintln!("models in tables: {seen:?}; punctual models {punctual:?}");
    assert!(
        seen.iter().all(|m| punctual.contains(m)),
        "a table holds a model that is no light of the scene"
    );
    assert!(
        seen.len() >= punctual.len() - 1,
        "only {} of {} punctual lights in any table",
        seen.len(),
        punctual.len()
    );
    // Surface points next to a light: the block top 1 cm under one point light, the
    // back wall 2 cm behind another; each leaf's strongest entry must be the nearest light.
    for p in [
        glam::Vec3::new(0.55, 0.4, -0.75),
        glam::Vec3::new(-0.7, 1.2, -1.5),
    ] {
        let nearest = (0..t.scene.punctual.len() as u32)
            .min_by(|&a, &b| {
                let d =
                    |i: u32| glam::Vec3::from(t.scene.punctual[i as usize].position).distance(p);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let leaf = tree.leaf(tree.find_leaf(p));
        let top = leaf
            .lights
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .copied();
        eprintln!(
            "at {p}: nearest light model {}, leaf table {:?}",
            model_of(nearest),
            leaf.lights
        );
        assert_eq!(
            top.map(|e| e.0),
            Some(model_of(nearest)),
            "the leaf at {p} does not hold its nearest light first"
        );
    }
    testing::assert_no_validation_errors();
}
