//! Costs on the CPU that decide between float atomics into GPU training trees and
//! appending records that the CPU accumulates: accumulating 1M records, and a refit.
//! Measurements, not assertions; run with
//! `cargo test --release --test guiding_bench -- --ignored --nocapture`.

use glam::Vec3;
use lanterna::gpu::GuideRecord;
use lanterna::guiding::{DirectionalFilter, GuidingConfig, SdTree, SpatialFilter};
use std::time::Instant;

/// Time this thread spent on a CPU (Linux; the machine is shared, so wall time lies).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(f64::NAN, |ns| ns as f64 * 1e-9)
}

struct Rng(u64);
impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Records like a room lit by a few small lights: positions on the walls and floor,
/// radiance mostly from the lights' directions.
fn records(n: usize, seed: u64) -> Vec<GuideRecord> {
    let lights = [
        Vec3::new(0.2, 2.9, 0.1),
        Vec3::new(-1.5, 2.0, 1.0),
        Vec3::new(1.8, 0.5, -1.9),
    ];
    let mut rng = Rng(seed);
    (0..n)
        .map(|i| {
            let mut p = Vec3::new(
                rng.f32() * 4.0 - 2.0,
                rng.f32() * 3.0,
                rng.f32() * 4.0 - 2.0,
            );
            match i % 3 {
                0 => p.y = 0.0,
                1 => p.x = -2.0,
                _ => p.z = -2.0,
            }
            let l = lights[i % lights.len()];
            let j = Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5;
            let dir = if rng.f32() < 0.7 {
                (l - p).normalize() + 0.02 * j
            } else {
                j
            }
            .normalize();
            GuideRecord {
                pos: p.to_array(),
                value: if rng.f32() < 0.7 { 5.0 } else { 0.3 },
                dir: dir.to_array(),
                weight: 1.0,
            }
        })
        .collect()
}

fn config(spatial: SpatialFilter, directional: DirectionalFilter, c: f32) -> GuidingConfig {
    GuidingConfig {
        spatial_filter: spatial,
        directional_filter: directional,
        spatial_threshold: c,
        ..GuidingConfig::default()
    }
}

#[test]
#[ignore]
fn bench_record_and_refit() {
    let n = 1_000_000;
    let recs = records(n, 1);
    // The default c, and a small c standing in for a large image (many more leaves).
    for (spatial, directional, c) in [
        (
            SpatialFilter::StochasticBox,
            DirectionalFilter::Box,
            12000.0,
        ),
        (SpatialFilter::Nearest, DirectionalFilter::Nearest, 12000.0),
        (SpatialFilter::StochasticBox, DirectionalFilter::Box, 400.0),
    ] {
        let cfg = config(spatial, directional, c);
        eprintln!("c = {c}");
        let mut tree =
            SdTree::new(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0), &cfg).unwrap();
        // Train a few iterations so the tree has the size of a real one: iteration k
        // gets 2^k × 128k records (a 128×128 image × ~8 records per pixel sample).
        for k in 0..6u32 {
            let batch = records(131_072 << k, 100 + u64::from(k));
            tree.record_batch(&batch, u64::from(k));
            // Refit clones many times: the CPU clock is coarse. The refit runs per leaf
            // on all cores, so wall time (this thread's CPU time misses the workers').
            let reps = 20;
            let clones: Vec<SdTree> = (0..reps).map(|_| tree.clone()).collect();
            let t = Instant::now();
            for mut t in clones {
                t.refit(2 << k);
            }
            let refit = t.elapsed().as_secs_f64() / f64::from(reps);
            let stats = tree.refit(2 << k);
            eprintln!(
                "{spatial:?}/{directional:?} refit {k}: {:.2} ms wall, {} leaves, {} spatial nodes, \
                 {} sampling + {} training nodes, max depth {}, {:.2} MiB, threshold {}",
                refit * 1e3,
                stats.leaves,
                stats.spatial_nodes,
                stats.sampling_nodes,
                stats.training_nodes,
                stats.max_quad_depth,
                stats.gpu_bytes as f64 / (1 << 20) as f64,
                stats.split_threshold
            );
        }
        let (t, c) = (Instant::now(), cpu_seconds());
        tree.record_batch(&recs, 7);
        let (rec_wall, rec) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
        // Flattening and the read-back's intake run on all cores too: wall time.
        let t = Instant::now();
        for _ in 0..99 {
            std::hint::black_box(tree.gpu_arrays());
        }
        let arrays = tree.gpu_arrays();
        let flat = t.elapsed().as_secs_f64() / 100.0;
        // What the upload does: write into memory kept between passes (the staging).
        let mut kept: Vec<Vec<u32>> = tree
            .gpu_buffer_lens()
            .iter()
            .map(|&l| vec![0u32; l / 4])
            .collect();
        let t = Instant::now();
        for _ in 0..100 {
            let [a, b, c, d, e, f] = &mut kept[..] else {
                unreachable!()
            };
            tree.write_gpu_buffers([a, b, c, d, e, f].map(|w| bytemuck::cast_slice_mut(w)));
        }
        let in_place = t.elapsed().as_secs_f64() / 100.0;
        eprintln!(
            "{spatial:?}/{directional:?}: 1M records accumulated in {:.1} ms CPU ({:.0} ns/record; \
             {:.1} ms wall); flatten {:.2} ms wall into new arrays, {:.2} ms into kept memory; \
             record struct {} bytes → {:.1} MiB per 1M records",
            rec * 1e3,
            rec * 1e9 / n as f64,
            rec_wall * 1e3,
            flat * 1e3,
            in_place * 1e3,
            std::mem::size_of::<GuideRecord>(),
            (n * std::mem::size_of::<GuideRecord>()) as f64 / (1 << 20) as f64
        );
        let mut gpu = tree.clone();
        let t = Instant::now();
        for _ in 0..100 {
            gpu.load_training_readback(&arrays.training).unwrap();
        }
        eprintln!(
            "readback ingest {:.3} ms wall",
            t.elapsed().as_secs_f64() * 10.0
        );
    }
}
