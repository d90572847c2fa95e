//! Sampling the SD-tree's quadtrees: χ² of sampled directions against the exact cell
//! probabilities (fixed seeds, rejected at p < 1e-4, small bins pooled), the pdf
//! returned by sampling bitwise equal to the pdf, and the pdf integrating to 1 over the
//! sphere. These run the CPU mirror of shaders_glsl/inc/guiding.glsl; the GPU test feeds
//! the output of the `tests/guiding_sample` kernel to the same `check_guide_samples`.

use glam::Vec3;
use lanterna::gpu::GuideRecord;
use lanterna::guiding::{
    check_guide_samples, chi2_directions, GuideSample, GuidingConfig, QuadTree, SdTree,
    SpatialFilter, INV_4PI,
};

/// SplitMix64 → floats in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn pair(&mut self) -> [f32; 2] {
        [self.f32(), self.f32()]
    }
}

/// A direction within roughly `spread` radians of `axis`.
fn around(axis: Vec3, spread: f32, rng: &mut Rng) -> Vec3 {
    let jitter = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * (2.0 * spread);
    (axis.normalize() + jitter).normalize()
}

/// A one-leaf SD-tree trained for `iterations` on a tight lobe (`spread` radians; 0 is
/// a single direction, which refines down to the depth cap), a wide lobe and a uniform
/// floor, with a cap (z < -0.5) that never receives energy (though the box filter
/// spreads some into it).
fn trained(iterations: u32, max_quad_depth: u32, spread: f32, seed: u64) -> SdTree {
    let config = GuidingConfig {
        spatial_filter: SpatialFilter::Nearest,
        spatial_threshold: 1e9, // one leaf
        max_quad_depth,
        ..GuidingConfig::default()
    };
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE, &config).unwrap();
    let mut rng = Rng(seed);
    for _ in 0..iterations {
        for _ in 0..20000 {
            let r = rng.f32();
            let dir = if r < 0.5 {
                around(Vec3::new(0.3, -0.8, 0.2), spread, &mut rng)
            } else if r < 0.8 {
                around(Vec3::new(-0.5, 0.1, 0.6), 0.3, &mut rng)
            } else {
                let d = lanterna::guiding::square_to_dir(rng.pair());
                Vec3::new(d.x, d.y, d.z.abs() * 1.5 - 0.5).normalize()
            };
            if dir.z < -0.5 {
                continue;
            }
            let u = [rng.f32(), rng.f32(), rng.f32()];
            tree.record(
                &GuideRecord::new(Vec3::splat(0.5), dir, 1.0 + rng.f32(), 1.0),
                u,
            );
        }
        tree.refit(1);
    }
    tree
}

fn cpu_samples(tree: &QuadTree, n: usize, seed: u64) -> Vec<GuideSample> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let (dir, pdf) = tree.sample(rng.pair());
            GuideSample {
                dir,
                pdf,
                pdf_eval: tree.pdf(dir),
                square: lanterna::guiding::dir_to_square(dir),
            }
        })
        .collect()
}

#[test]
fn trained_tree_passes_chi2_and_exactness() {
    let tree = trained(5, 20, 0.01, 1);
    let q = &tree.leaf(0).sampling;
    assert!(q.depth() >= 10, "depth {}", q.depth());
    let n = 1_000_000;
    let samples = cpu_samples(q, n, 2);
    let check = check_guide_samples(q, &samples, 64);
    check.verdict().unwrap();
    assert_eq!(check.cpu_disagreements, 0);
}

#[test]
fn depth_capped_and_empty_trees_pass_chi2() {
    let tree = trained(7, 20, 0.0, 3);
    let q = &tree.leaf(0).sampling;
    assert_eq!(q.depth(), 20);
    let n = 300_000;
    check_guide_samples(q, &cpu_samples(q, n, 4), 64)
        .verdict()
        .unwrap();
    // Nothing learned: uniform over the sphere, pdf 1/4π.
    let empty = QuadTree::empty();
    let samples = cpu_samples(&empty, n, 5);
    check_guide_samples(&empty, &samples, 32).verdict().unwrap();
    assert!(samples.iter().all(|s| s.pdf == INV_4PI));
}

#[test]
fn chi2_rejects_a_wrong_distribution() {
    // Samples of one tree tested against a tree trained on other data: the test must
    // have the power to notice.
    let a = trained(3, 20, 0.01, 6);
    let b = trained(3, 20, 0.02, 7);
    let (qa, qb) = (&a.leaf(0).sampling, &b.leaf(0).sampling);
    let dirs: Vec<Vec3> = cpu_samples(qa, 1_000_000, 8)
        .iter()
        .map(|s| s.dir)
        .collect();
    assert!(chi2_directions(qa, &dirs, 64).p_value >= 1e-4);
    // The tight lobe twice as wide: close, yet distinguishable at 1M samples.
    assert!(chi2_directions(qb, &dirs, 64).p_value < 1e-4);
    // A uniform sampler against the trained tree fails overwhelmingly.
    let uniform: Vec<Vec3> = cpu_samples(&QuadTree::empty(), 100_000, 9)
        .iter()
        .map(|s| s.dir)
        .collect();
    assert!(chi2_directions(qa, &uniform, 64).p_value < 1e-30);
}

#[test]
fn pdf_integrates_to_one_over_the_sphere() {
    // Quadtree depth ≤ 10 puts every cell border on the 2048² grid's cell borders, so
    // the midpoint rule is exact up to float rounding.
    let tree = trained(5, 10, 0.01, 10);
    let q = &tree.leaf(0).sampling;
    assert_eq!(q.depth(), 10);
    let n = 2048u32;
    let mut sum = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let p = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
            let dir = lanterna::guiding::square_to_dir(p);
            sum += f64::from(q.pdf(dir));
        }
    }
    let integral = sum * 4.0 * std::f64::consts::PI / f64::from(n * n);
    assert!((integral - 1.0).abs() < 1e-4, "∫pdf = {integral}");
}
