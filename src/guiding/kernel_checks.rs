//! The checks of the guiding test kernels (`tests/guiding_sample`, `tests/guiding_record`),
//! independent of how a kernel is run: each check builds its inputs with fixed seeds,
//! hands them with the tree's GPU arrays to a runner, and judges the runner's output.
//! The CPU mirror provides runners (`cpu_sample_runner`, `cpu_record_runner`) so the
//! checks are tested without a device; the GPU test passes runners that dispatch the
//! kernels (buffers: TEST_BINDING_IN inputs, TEST_BINDING_OUT results, the four guiding
//! buffers at BINDING_GUIDE_*; the device needs scalarBlockLayout and
//! shaderBufferFloat32AtomicAdd).

use super::chi2::{check_guide_samples, GuideSample, SampleCheck};
use super::flat::GuideArrays;
use super::sdtree::{hash64, SdTree};
use super::sphere::dir_to_square;
use super::{DirectionalFilter, GuidingConfig, SpatialFilter};
use crate::gpu::{
    GuideQuadNode, GuideRecord, GuideTestRecord, GuideTestResult, GuideTestSample, GUIDE_TEST_EVAL,
    GUIDE_TEST_SAMPLE,
};
use glam::Vec3;

/// Runs `tests/guiding_sample`: (arrays, inputs) → one result per input.
pub type SampleRunner<'a> =
    dyn FnMut(&GuideArrays, &[GuideTestSample]) -> Vec<GuideTestResult> + 'a;
/// Runs `tests/guiding_record` on the uploaded arrays: → the training buffer afterwards.
pub type RecordRunner<'a> = dyn FnMut(&GuideArrays, &[GuideTestRecord]) -> Vec<GuideQuadNode> + 'a;

fn unit(bits: u64) -> f32 {
    (bits >> 40) as f32 / (1u64 << 24) as f32
}

/// Deterministic uniform numbers: the `i`-th of stream `seed`.
fn uniform(seed: u64, i: u64) -> f32 {
    unit(hash64(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ i))
}

/// Records of a room lit by three small lights: positions on the floor and two walls of
/// [-2,2]×[0,3]×[-2,2], radiance mostly from the lights' directions.
pub fn scene_records(n: usize, seed: u64) -> Vec<GuideTestRecord> {
    let lights = [
        Vec3::new(0.2, 2.9, 0.1),
        Vec3::new(-1.5, 2.0, 1.0),
        Vec3::new(1.8, 0.5, -1.9),
    ];
    (0..n)
        .map(|i| {
            let r = |k: u64| uniform(seed, i as u64 * 16 + k);
            let mut p = Vec3::new(r(0) * 4.0 - 2.0, r(1) * 3.0, r(2) * 4.0 - 2.0);
            match i % 3 {
                0 => p.y = 0.0,
                1 => p.x = -2.0,
                _ => p.z = -2.0,
            }
            let l = lights[i % lights.len()];
            let j = Vec3::new(r(3), r(4), r(5)) - 0.5;
            let dir = if r(6) < 0.7 {
                (l - p).normalize() + 0.02 * j
            } else {
                j
            }
            .normalize_or(Vec3::Z);
            GuideTestRecord {
                record: GuideRecord {
                    pos: p.to_array(),
                    value: if r(7) < 0.7 { 5.0 } else { 0.3 },
                    dir: dir.to_array(),
                    weight: 1.0,
                },
                u: [r(8), r(9), r(10)],
                pad: 0,
            }
        })
        .collect()
}

/// A tree trained on `scene_records` for five iterations (≈160 leaves, quadtrees to
/// depth ≈ 9), its training trees empty.
pub fn scene_tree(config: &GuidingConfig) -> SdTree {
    let mut tree = SdTree::new(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0), config)
        .expect("valid fixture bounds");
    for k in 0..5u32 {
        for r in scene_records(65_536 << k, 100 + u64::from(k)) {
            let rec = r.record;
            tree.record(&rec, r.u);
        }
        tree.refit(2 << k);
    }
    tree
}

/// A one-leaf tree refined down to the depth cap around a single direction.
pub fn deep_tree() -> SdTree {
    let config = GuidingConfig {
        spatial_threshold: 1e9,
        ..GuidingConfig::default()
    };
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE, &config).expect("valid fixture bounds");
    let peak = Vec3::new(0.3, -0.8, 0.2).normalize();
    for k in 0..7u64 {
        for i in 0..20_000u64 {
            let r = |j: u64| uniform(k, i * 8 + j);
            let d = if i % 2 == 0 {
                peak
            } else {
                Vec3::new(r(0), r(1), r(2)) - 0.5
            };
            tree.record(
                &GuideRecord::new(Vec3::splat(0.5), d.normalize_or(Vec3::Z), 1.0, 1.0),
                [r(3), r(4), r(5)],
            );
        }
        tree.refit(1);
    }
    tree
}

/// The leaves the sampling check uses: the deepest sampling tree, a median one, and an
/// empty one if there is any.
fn check_leaves(tree: &SdTree) -> Vec<u32> {
    let mut by_depth: Vec<u32> = (0..tree.leaves().len() as u32).collect();
    by_depth.sort_by_key(|&l| (tree.leaf(l).sampling.depth(), l));
    let mut leaves = vec![by_depth[by_depth.len() - 1], by_depth[by_depth.len() / 2]];
    if let Some(&e) = by_depth.iter().find(|&&l| tree.leaf(l).sampling.is_empty()) {
        leaves.push(e);
    }
    leaves.dedup();
    leaves
}

/// What the sampling check found, per leaf.
#[derive(Clone, Debug)]
pub struct SamplingReport {
    pub leaf: u32,
    pub depth: u32,
    pub check: SampleCheck,
    /// ∫ guide_pdf dω on a grid of the square as fine as the tree's cells (None when
    /// the tree is deeper than 11 levels and the grid would not resolve it).
    pub integral: Option<f64>,
}

/// Check `tests/guiding_sample` on `tree`: for a few leaves, `n` samples must pass
/// `SampleCheck::verdict`, and the pdf must integrate to 1 within 1e-4.
pub fn check_sampling_kernel(
    tree: &SdTree,
    n: usize,
    run: &mut SampleRunner,
) -> Result<Vec<SamplingReport>, String> {
    let arrays = tree.gpu_arrays();
    let mut reports = Vec::new();
    for leaf in check_leaves(tree) {
        let inputs: Vec<GuideTestSample> = (0..n as u64)
            .map(|i| GuideTestSample {
                u: [
                    uniform(u64::from(leaf), 2 * i),
                    uniform(u64::from(leaf), 2 * i + 1),
                ],
                leaf,
                mode: GUIDE_TEST_SAMPLE,
            })
            .collect();
        let results = run(&arrays, &inputs);
        if results.len() != n {
            return Err(format!(
                "leaf {leaf}: {} results for {n} inputs",
                results.len()
            ));
        }
        let samples: Vec<GuideSample> = results
            .iter()
            .map(|r| GuideSample {
                dir: Vec3::from_array(r.dir),
                pdf: r.pdf,
                pdf_eval: r.pdf_eval,
                square: r.square,
            })
            .collect();
        let q = &tree.leaf(leaf).sampling;
        let check = check_guide_samples(q, &samples, 64);
        check.verdict().map_err(|e| format!("leaf {leaf}: {e}"))?;
        let depth = q.depth();
        let integral = if depth <= 11 {
            let g = 1u32 << depth.max(6);
            let inputs: Vec<GuideTestSample> = (0..g * g)
                .map(|k| GuideTestSample {
                    u: [
                        ((k % g) as f32 + 0.5) / g as f32,
                        ((k / g) as f32 + 0.5) / g as f32,
                    ],
                    leaf,
                    mode: GUIDE_TEST_EVAL,
                })
                .collect();
            let results = run(&arrays, &inputs);
            let sum: f64 = results.iter().map(|r| f64::from(r.pdf_eval)).sum();
            let integral = sum * 4.0 * std::f64::consts::PI / f64::from(g * g);
            if (integral - 1.0).abs() > 1e-4 {
                return Err(format!("leaf {leaf}: ∫pdf dω = {integral}"));
            }
            Some(integral)
        } else {
            None
        };
        reports.push(SamplingReport {
            leaf,
            depth,
            check,
            integral,
        });
    }
    Ok(reports)
}

/// What the record check found.
#[derive(Clone, Debug)]
pub struct RecordReport {
    pub records: usize,
    /// Σ|kernel − CPU| / Σ CPU over all training sums (directions near a cell border
    /// may land on the other side under the device's atan).
    pub relative_l1: f64,
}

/// Check `tests/guiding_record` on `tree` (training trees empty): `n` records must give
/// exactly the CPU mirror's statistical weights per leaf and the same energy up to
/// 2e-3 relative L1 (border crossings), and refit to the same spatial tree.
pub fn check_record_kernel(
    tree: &SdTree,
    n: usize,
    run: &mut RecordRunner,
) -> Result<RecordReport, String> {
    let arrays = tree.gpu_arrays();
    let records = scene_records(n, 77);
    let readback = run(&arrays, &records);
    let mut device = tree.clone();
    device
        .load_training_readback(&readback)
        .map_err(|e| e.to_string())?;
    let mut cpu = tree.clone();
    for r in &records {
        let rec = r.record;
        cpu.record(&rec, r.u);
    }
    let (mut l1, mut total) = (0.0f64, 0.0f64);
    for (i, (a, b)) in device.leaves().iter().zip(cpu.leaves()).enumerate() {
        if a.training_weight != b.training_weight {
            return Err(format!(
                "leaf {i}: weight {} on the device, {} on the CPU",
                a.training_weight, b.training_weight
            ));
        }
        for (na, nb) in a.training.nodes().iter().zip(b.training.nodes()) {
            for q in 0..4 {
                l1 += f64::from((na.sum[q] - nb.sum[q]).abs());
                total += f64::from(nb.sum[q]);
            }
        }
    }
    let relative_l1 = l1 / total.max(f64::MIN_POSITIVE);
    if relative_l1 > 2e-3 {
        return Err(format!(
            "training energy differs by {relative_l1:e} (relative L1)"
        ));
    }
    let (sa, sb) = (device.refit(64), cpu.refit(64));
    if sa.leaves != sb.leaves {
        return Err(format!(
            "refit gives {} leaves from the device, {} from the CPU",
            sa.leaves, sb.leaves
        ));
    }
    Ok(RecordReport {
        records: n,
        relative_l1,
    })
}

/// The configurations the record check runs with: the default filters, both nearest,
/// and the stochastic spatial box (no longer the default, so named here; its second
/// descent must not reuse the leaf a caller passes for the record's own position).
pub fn record_configs() -> [GuidingConfig; 3] {
    [
        GuidingConfig::default(),
        GuidingConfig {
            spatial_filter: SpatialFilter::Nearest,
            directional_filter: DirectionalFilter::Nearest,
            ..GuidingConfig::default()
        },
        GuidingConfig {
            spatial_filter: SpatialFilter::StochasticBox,
            ..GuidingConfig::default()
        },
    ]
}

/// The CPU mirror as a sample runner (rebuilds the tree from the arrays).
pub fn cpu_sample_runner(arrays: &GuideArrays, inputs: &[GuideTestSample]) -> Vec<GuideTestResult> {
    let tree = SdTree::from_gpu_arrays(arrays, &GuidingConfig::default()).expect("valid arrays");
    inputs
        .iter()
        .map(|s| {
            let q = &tree.leaf(s.leaf).sampling;
            let (dir, pdf) = if s.mode == GUIDE_TEST_EVAL {
                (super::sphere::square_to_dir(s.u), 0.0)
            } else {
                q.sample(s.u)
            };
            GuideTestResult {
                dir: dir.to_array(),
                pdf,
                pdf_eval: q.pdf(dir),
                square: dir_to_square(dir),
            }
        })
        .collect()
}

/// The CPU mirror as a record runner; `config` supplies the filters (the kernel reads
/// them from the header flags).
pub fn cpu_record_runner(
    config: &GuidingConfig,
) -> impl FnMut(&GuideArrays, &[GuideTestRecord]) -> Vec<GuideQuadNode> + '_ {
    move |arrays, records| {
        let mut tree = SdTree::from_gpu_arrays(arrays, config).expect("valid arrays");
        for r in records {
            let rec = r.record;
            tree.record(&rec, r.u);
        }
        tree.gpu_arrays().training
    }
}
