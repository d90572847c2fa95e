//! The guiding test-kernel checks (`lanterna::guiding::kernel_checks`) run against the
//! CPU mirror. The GPU test runs the same checks with runners that dispatch
//! `tests/guiding_sample` and `tests/guiding_record` on the device.

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
