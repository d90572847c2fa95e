//! The software traversal (`inc/bvh.glsl` over the CPU-built BVH) against the device's
//! ray queries, ray by ray, through the renderer's own `trace_closest` / `visible` (trace
//! kernels `tests/trace` and `tests/trace_sw`): camera rays, diffuse bounce rays from
//! their hits and shadow rays to points on lights, on the shipped scenes and on the
//! conformance scenes. The closest hit must be the same (instance, primitive, and t within
//! 10⁻⁵ relative) and visibility the same, for at least 99.99 % of the rays.
//!
//! Two allowances, both about what single precision can resolve, not about the traversal:
//! t may also differ by a few ulps of the ray origin's coordinates (a bounce ray leaving a
//! surface 10 m from the origin and hitting a ledge 2 cm away has t known only to about
//! 10⁻⁶ m whichever way it is computed: 5·10⁻⁵ relative), and a different triangle at the
//! same t is a tie, not a difference: the ray crosses an edge two triangles share, or two
//! coincident surfaces (the street has some), and which of them is "closest" is decided by
//! rounding. Ties are counted and printed, and may be at most 0.1 % of the rays.
//!
//! Seen to fail with defects injected into `inc/bvh.glsl` (LANTERNA_TEST_SHADER_DIR):
//! - the leaf loop skipping each leaf's last triangle (`i + 1u < end`): all three tests,
//!   19–30 % of the rays differ;
//! - the closest-hit test bounded by the ray's tmax instead of the closest t so far
//!   (`t < tmax`, so a farther hit can replace a nearer one): all three, 2–6 %;
//! - the alpha test skipped (every triangle opaque): alpha-lights 8.6 %, street 1.3 %
//!   (its foliage is alpha-masked); cornell-lights, which has none, passes.

use lanterna::gpu;
use lanterna::lights::LightTable;
use lanterna::render::trace::{camera_rays, secondary_rays, RaySets};
use lanterna::render::{Renderer, Traversal, TraversalKind};
use lanterna::scene::generate::{Kind, Options};
use lanterna::scene::{Camera, Scene};
use lanterna::testing;

const WIDTH: u32 = 128;
const HEIGHT: u32 = 96;
/// Largest share of rays allowed to differ.
const MAX_DIFFERENT: f64 = 1e-4;

fn renderer(scene: &Scene, camera: &Camera, traversal: Traversal) -> Renderer {
    let mut s = testing::settings(lanterna::render::Method::Pt, 8, 8);
    s.traversal = traversal;
    testing::test_renderer_on(testing::device(), scene, camera, &s)
}

/// Largest share of rays that may end in a tie.
const MAX_TIES: f64 = 1e-3;

#[derive(PartialEq)]
enum Agreement {
    Same,
    /// Another triangle at the same t.
    Tie,
    Different,
}

/// Is this the hit of a `TRACE_PROBED` ray whose probe is blocked?
fn probe_blocked(h: &gpu::TraceHit) -> bool {
    h.instance == gpu::INVALID_INDEX && h.primitive == gpu::TRACE_PROBE_BLOCKED
}

/// Do two hits of the same ray agree?
fn agree(ray: &gpu::TraceRay, a: &gpu::TraceHit, b: &gpu::TraceHit) -> Agreement {
    let verdict = |ok: bool| {
        if ok {
            Agreement::Same
        } else {
            Agreement::Different
        }
    };
    if ray.kind == gpu::TRACE_VISIBLE {
        return verdict(a.primitive == b.primitive);
    }
    if ray.kind == gpu::TRACE_PROBED && (probe_blocked(a) || probe_blocked(b)) {
        return verdict(probe_blocked(a) && probe_blocked(b));
    }
    if a.instance == gpu::INVALID_INDEX || b.instance == gpu::INVALID_INDEX {
        return verdict(a.instance == b.instance);
    }
    // 10⁻⁵ relative, plus 8 ulps of the origin's largest coordinate along the ray.
    let o = glam::Vec3::from(ray.origin).abs().max_element();
    let d = glam::Vec3::from(ray.dir).length();
    let tolerance = 1e-5 * a.t.abs().max(b.t.abs()) + 8.0 * f32::EPSILON * o / d;
    if (a.t - b.t).abs() > tolerance {
        return Agreement::Different;
    }
    if a.instance == b.instance && a.primitive == b.primitive {
        Agreement::Same
    } else {
        Agreement::Tie
    }
}

/// The ray sets of the camera's view (camera rays from seed `camera_seed`, traced with
/// `r`; the rest from `seed`).
fn view_rays(
    r: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    camera_seed: u64,
    seed: u64,
) -> RaySets {
    let lights = LightTable::build(scene).expect("light table");
    let cam = camera_rays(camera, WIDTH, HEIGHT, camera_seed);
    let cam_hits = r.trace(&cam).expect("trace").hits;
    secondary_rays(
        scene,
        &lights,
        &r.gpu_scene.instance_order,
        cam,
        &cam_hits,
        seed,
    )
}

fn compare(name: &str, scene: &Scene, camera: &Camera) {
    let mut rq = renderer(scene, camera, Traversal::RayQuery);
    let mut sw = renderer(scene, camera, Traversal::Software);
    assert_eq!(rq.traversal.kind, TraversalKind::RayQuery);
    assert_eq!(sw.traversal.kind, TraversalKind::Software);
    let sets = view_rays(&mut rq, scene, camera, 7, 11);
    let (mut total, mut different, mut tied) = (0usize, 0usize, 0usize);
    for (set, rays) in sets.sets() {
        let a = rq.trace(rays).expect("ray-query trace").hits;
        let b = sw.trace(rays).expect("software trace").hits;
        let hits = rays
            .iter()
            .zip(&a)
            .filter(|(r, h)| {
                if r.kind == gpu::TRACE_VISIBLE {
                    h.primitive == 1
                } else {
                    h.instance != gpu::INVALID_INDEX
                }
            })
            .count();
        let blocked = a.iter().filter(|h| probe_blocked(h)).count();
        let (mut diff, mut ties) = (0, 0);
        for (i, ((r, x), y)) in rays.iter().zip(&a).zip(&b).enumerate() {
            let verdict = agree(r, x, y);
            if verdict != Agreement::Same && diff + ties < 8 {
                println!(
                    "{name} {set} ray {i} ({}): ray query ({}, {}, t {}, bary {} {}) vs software ({}, {}, t {}, bary {} {})",
                    if verdict == Agreement::Tie { "tie" } else { "differs" },
                    x.instance, x.primitive, x.t, x.bary_u, x.bary_v,
                    y.instance, y.primitive, y.t, y.bary_u, y.bary_v
                );
            }
            match verdict {
                Agreement::Same => {}
                Agreement::Tie => ties += 1,
                Agreement::Different => diff += 1,
            }
        }
        println!(
            "{name} {set}: {} rays ({hits} hit / visible, {blocked} probes blocked), {ties} ties, {diff} differ",
            rays.len()
        );
        total += rays.len();
        different += diff;
        tied += ties;
    }
    assert!(total >= 10_000, "{name}: only {total} rays");
    let share = different as f64 / total as f64;
    assert!(
        share <= MAX_DIFFERENT,
        "{name}: {different} of {total} rays ({:.4} %) differ between ray-query and software traversal (at most {} % may)",
        100.0 * share,
        100.0 * MAX_DIFFERENT
    );
    assert!(
        tied as f64 <= MAX_TIES * total as f64,
        "{name}: {tied} of {total} rays end in ties (another triangle at the same t); at most {} % may",
        100.0 * MAX_TIES
    );
}

fn shipped(name: &str) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.gltf"));
    let scene = Scene::load(&path, &Default::default()).expect("load shipped scene");
    let camera = scene.cameras.first().cloned().expect("camera");
    compare(name, &scene, &camera);
}

fn generated(kind: Kind, offset: Option<[f32; 3]>) {
    let t = testing::generated(
        kind,
        &Options {
            offset,
            ..Options::default()
        },
    );
    compare(kind.name(), &t.scene, &t.camera);
}

/// The software traversal tests a bounce ray's probe in the ray's own walk of the tree
/// (inc/bvh.glsl). That walk must answer exactly what two walks answer: the probe's
/// segment traced alone (`visible`), and the ray alone (`trace_closest`) where the probe
/// is clear, with the same instance, primitive, t and barycentrics bit for bit. Returns
/// how many probes were blocked. Seen to fail (street: 133, 385 and 364 of 10,956 rays
/// answered differently) with the probe's flag not restored when a node is taken from
/// the stack, with a blocked probe not reported, and with children only the probe meets
/// left out of the walk.
fn probe_in_the_walk_is_exact(name: &str, scene: &Scene, camera: &Camera) -> usize {
    let mut sw = renderer(scene, camera, Traversal::Software);
    let sets = view_rays(&mut sw, scene, camera, 5, 13);
    let probes: Vec<gpu::TraceRay> = sets
        .probed
        .iter()
        .map(|r| gpu::TraceRay {
            origin: r.probe_origin,
            dir: r.probe_dir,
            tmax: 1.0,
            kind: gpu::TRACE_VISIBLE,
            ..*r
        })
        .collect();
    let alone: Vec<gpu::TraceRay> = sets
        .probed
        .iter()
        .map(|r| gpu::TraceRay {
            kind: gpu::TRACE_CLOSEST,
            ..*r
        })
        .collect();
    let merged = sw.trace(&sets.probed).expect("probed trace").hits;
    let probe_hits = sw.trace(&probes).expect("probe trace").hits;
    let ray_hits = sw.trace(&alone).expect("ray trace").hits;
    let bits = |h: &gpu::TraceHit| {
        (
            h.instance,
            h.primitive,
            h.t.to_bits(),
            h.bary_u.to_bits(),
            h.bary_v.to_bits(),
        )
    };
    let mut wrong = 0;
    let mut blocked = 0;
    for (i, ((m, p), r)) in merged.iter().zip(&probe_hits).zip(&ray_hits).enumerate() {
        let separate_blocked = p.primitive == 0;
        blocked += separate_blocked as usize;
        let same = if separate_blocked {
            probe_blocked(m)
        } else {
            bits(m) == bits(r)
        };
        if !same {
            if wrong < 8 {
                println!(
                    "{name} ray {i}: one walk ({}, {}, t {}) vs two (probe blocked {separate_blocked}; ray {}, {}, t {})",
                    m.instance, m.primitive, m.t, r.instance, r.primitive, r.t
                );
            }
            wrong += 1;
        }
    }
    println!(
        "{name}: {} probed rays, {blocked} probes blocked, {wrong} answered differently by one walk",
        merged.len()
    );
    assert_eq!(
        wrong, 0,
        "{name}: {wrong} probed rays answered differently by one walk of the tree than by two"
    );
    blocked
}

#[test]
fn probe_in_the_walk_answers_what_two_walks_answer() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/street.gltf");
    let street = Scene::load(&path, &Default::default()).expect("load street");
    let mut blocked = probe_in_the_walk_is_exact("street", &street, &street.cameras[0]);
    for kind in [Kind::Gap, Kind::Sconces, Kind::AlphaLights] {
        let t = testing::generated(kind, &Options::default());
        blocked += probe_in_the_walk_is_exact(kind.name(), &t.scene, &t.camera);
    }
    assert!(
        blocked >= 200,
        "only {blocked} probes blocked: too few to test the walk"
    );
    testing::assert_no_validation_errors();
}

#[test]
fn same_hits_street() {
    shipped("street");
    testing::assert_no_validation_errors();
}

#[test]
fn same_hits_cornell_lights() {
    shipped("cornell-lights");
    testing::assert_no_validation_errors();
}

#[test]
fn same_hits_conformance_scenes() {
    generated(Kind::Sconces, None);
    generated(Kind::Sconces, Some([1.0e4, 0.0, 1.0e4]));
    generated(Kind::PunctualNear, None);
    generated(Kind::AlphaLights, None);
    generated(Kind::AlphaTest, None);
    generated(Kind::Gap, None);
    testing::assert_no_validation_errors();
}
