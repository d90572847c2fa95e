use glam::Vec3;
use lanterna::guiding::{GuidingConfig, SdTree};
fn main() {
    let cfg = GuidingConfig::default();
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE, &cfg).unwrap();
    let d0 = Vec3::new(-0.8, 0.5, 0.3).normalize();
    for it in 0..4 {
        for i in 0..20000u32 {
            let u = [
                (i % 97) as f32 / 97.0,
                (i % 89) as f32 / 89.0,
                (i % 83) as f32 / 83.0,
            ];
            // 90% of energy from d0 (with a little spread), 10% elsewhere.
            let j = Vec3::new(u[0] - 0.5, u[1] - 0.5, u[2] - 0.5) * 0.1;
            let dir = if i % 10 != 0 {
                (d0 + j).normalize()
            } else {
                Vec3::new(u[1] - 0.5, u[2] - 0.5, u[0] - 0.5).normalize()
            };
            tree.record(
                &lanterna::gpu::GuideRecord::new(Vec3::splat(0.5), dir, 1.0, 1.0),
                u,
            );
        }
        tree.refit(1 << (it + 1));
    }
    let mut mean = Vec3::ZERO;
    let n = 10000;
    for i in 0..n {
        let u = [
            (i as f32 + 0.5) / n as f32,
            ((i * 7919) % n) as f32 / n as f32,
        ];
        let leaf = tree.find_leaf(Vec3::splat(0.5));
        let (d, pdf) = tree.sample(leaf, u);
        mean += d;
        let _ = pdf;
    }
    println!(
        "d0 = {d0:?}; mean sampled direction = {:?}",
        (mean / n as f32).normalize()
    );
    let leaf = tree.find_leaf(Vec3::splat(0.5));
    println!(
        "pdf at d0 = {}, at -d0 = {}",
        tree.pdf(leaf, d0),
        tree.pdf(leaf, -d0)
    );
}
