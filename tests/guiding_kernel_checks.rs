//! The guiding test-kernel checks (`lanterna::guiding::kernel_checks`) run against the
//! CPU mirror. The GPU test runs the same checks with runners that dispatch
//! `tests/guiding_sample` and `tests/guiding_record` on the device.
//!
//! Seen to fail with defects injected into `inc/guiding.glsl` through
//! LANTERNA_TEST_SHADER_DIR (2026-11-28):
//! - `guide_sample` returning its density 0.1 % high: the device's sampling check
//!   (every sample's pdf differs from `guide_pdf`'s and from the CPU mirror's, while
//!   the χ² tests, blind to 0.1 %, pass);
//! - the directional box filter clamping its cells at φ's seam instead of wrapping
//!   around it: the device's record check (training energy 0.7 % off in relative L1).

use lanterna::guiding::kernel_checks::{
    check_record_kernel, check_sampling_kernel, cpu_record_runner, cpu_sample_runner, deep_tree,
    record_configs, scene_tree,
};
use lanterna::guiding::GuidingConfig;

#[test]
fn sampling_checks_pass_on_the_cpu_mirror() {
    for tree in [scene_tree(&GuidingConfig::default()), deep_tree()] {
        let reports = check_sampling_kernel(&tree, 200_000, &mut cpu_sample_runner).unwrap();
        assert!(!reports.is_empty());
        for r in &reports {
            assert!(r.integral.is_some() || r.depth > 11);
        }
    }
}

#[test]
fn record_checks_pass_on_the_cpu_mirror() {
    for config in record_configs() {
        let tree = scene_tree(&config);
        let report = check_record_kernel(&tree, 200_000, &mut cpu_record_runner(&config)).unwrap();
        assert_eq!(report.relative_l1, 0.0);
    }
}

#[test]
fn record_check_notices_a_wrong_kernel() {
    // A "kernel" that drops every tenth record fails on the weights.
    let config = GuidingConfig::default();
    let tree = scene_tree(&config);
    let mut cpu = cpu_record_runner(&config);
    let mut lossy = |arrays: &_, records: &[_]| {
        let kept: Vec<_> = records
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 10 != 0)
            .map(|(_, r)| *r)
            .collect();
        cpu(arrays, &kept)
    };
    assert!(check_record_kernel(&tree, 10_000, &mut lossy).is_err());
}

// ---- the same checks on the device, with the real GLSL -------------------------------

use lanterna::gpu::{self, GuideQuadNode, GuideTestRecord, GuideTestResult, GuideTestSample};
use lanterna::guiding::GuideArrays;
use lanterna::testing;

fn guide_buffers(arrays: &GuideArrays) -> [Vec<u8>; 4] {
    [
        arrays.spatial_buffer(),
        bytemuck::cast_slice(&arrays.leaves).to_vec(),
        bytemuck::cast_slice(&arrays.sampling).to_vec(),
        bytemuck::cast_slice(&arrays.training).to_vec(),
    ]
}

fn gpu_sample_runner(arrays: &GuideArrays, inputs: &[GuideTestSample]) -> Vec<GuideTestResult> {
    let [spatial, leaves, sampling, training] = guide_buffers(arrays);
    let out = vec![0u8; inputs.len() * std::mem::size_of::<GuideTestResult>()];
    let buffers = testing::dispatch(
        "tests/guiding_sample",
        &[
            (gpu::TEST_BINDING_IN, bytemuck::cast_slice(inputs)),
            (gpu::TEST_BINDING_OUT, &out),
            (gpu::BINDING_GUIDE_SPATIAL, &spatial),
            (gpu::BINDING_GUIDE_LEAVES, &leaves),
            (gpu::BINDING_GUIDE_SAMPLING, &sampling),
            (gpu::BINDING_GUIDE_TRAINING, &training),
        ],
        &[],
        inputs.len() as u32,
    )
    .expect("guiding_sample kernel");
    bytemuck::pod_collect_to_vec(&buffers[1])
}

fn gpu_record_runner(arrays: &GuideArrays, records: &[GuideTestRecord]) -> Vec<GuideQuadNode> {
    let [spatial, leaves, sampling, training] = guide_buffers(arrays);
    let buffers = testing::dispatch(
        "tests/guiding_record",
        &[
            (gpu::TEST_BINDING_IN, bytemuck::cast_slice(records)),
            (gpu::BINDING_GUIDE_SPATIAL, &spatial),
            (gpu::BINDING_GUIDE_LEAVES, &leaves),
            (gpu::BINDING_GUIDE_SAMPLING, &sampling),
            (gpu::BINDING_GUIDE_TRAINING, &training),
        ],
        &[],
        records.len() as u32,
    )
    .expect("guiding_record kernel");
    bytemuck::pod_collect_to_vec(&buffers[4])
}

#[test]
fn sampling_checks_pass_on_the_device() {
    // χ² of sampled directions against the pdf, sample() pdf == pdf(), ∫pdf = 1.
    for tree in [scene_tree(&GuidingConfig::default()), deep_tree()] {
        let reports = check_sampling_kernel(&tree, 200_000, &mut gpu_sample_runner).unwrap();
        assert!(!reports.is_empty());
    }
    testing::assert_no_validation_errors();
}

#[test]
fn record_checks_pass_on_the_device() {
    for config in record_configs() {
        let tree = scene_tree(&config);
        check_record_kernel(&tree, 200_000, &mut gpu_record_runner).unwrap();
    }
    testing::assert_no_validation_errors();
}
