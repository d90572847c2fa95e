//! RIS and reservoir sampling in the real GLSL (test kernels on lavapipe), checked
//! against exact distributions computed on the CPU.
//!
//! Seen to fail with defects injected through LANTERNA_TEST_SHADER_DIR (2026-11-28):
//! - the reservoir's comparison reversed, as printed in the paper's Algorithm 1
//!   (`inc/reservoir.glsl` keeping x_i when u ≥ w_i/w_sum): every reservoir and RIS
//!   test but the pixel sampler's two;
//! - the resampling weights' denominator counting one slot too many (M + 1 instead of
//!   M, so W is low by M/(M + 1)): `ris_contribution_weight_is_unbiased` alone (the
//!   selection probabilities do not change);
//! - the candidates' strata switched off (`ris_resample` drawing every u.x independently):
//!   `stratified_candidates_lower_the_variance` (10.61 against 10.58);
//! - the pixel sampler's second coordinate taken from the first's sequence (van der
//!   Corput, scrambled with another seed, instead of Sobol's second dimension):
//!   `pixel_positions_are_stratified`.

use lanterna::{stats, testing};

const TRIALS: u32 = 1 << 18;

fn run_reservoir(weights: &[f32], seed: u32) -> Vec<u32> {
    let push: Vec<u8> = [weights.len() as u32, TRIALS, seed]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let out = testing::run_kernel(
        "tests/reservoir",
        bytemuck::cast_slice(weights),
        &[],
        TRIALS as usize * 4,
        &push,
        TRIALS,
    )
    .expect("reservoir kernel");
    bytemuck::pod_collect_to_vec(&out)
}

#[test]
fn reservoir_selects_in_proportion_to_weights() {
    let weights = [0.5f32, 0.0, 3.0, 1.0, 0.25, 7.0, 2.0, 1e-3];
    let kept = run_reservoir(&weights, 7);
    let mut counts = vec![0.0; weights.len()];
    for k in kept {
        assert!((k as usize) < weights.len(), "nothing kept");
        counts[k as usize] += 1.0;
    }
    assert_eq!(counts[1], 0.0, "a zero-weight candidate was kept");
    let total: f32 = weights.iter().sum();
    let expected: Vec<f64> = weights
        .iter()
        .map(|&w| (w / total) as f64 * TRIALS as f64)
        .collect();
    let chi = stats::chi_square(&counts, &expected, 5.0);
    assert!(
        chi.p_value > 1e-4,
        "selection frequencies differ from w/Σw: {chi:?}"
    );
    testing::assert_no_validation_errors();
}

/// Exact probability that RIS with `m` candidates from `q` selects each light, for
/// targets `p`: sum over all multisets of candidates (multinomial counts n) of
/// P(n) · n_j w_j / Σ n_i w_i with w_i = p_i / q_i.
fn exact_selection(p: &[f64], q: &[f64], m: u32) -> Vec<f64> {
    /// Walks all multinomial counts n of m candidates over the lights.
    struct Walk<'a> {
        q: &'a [f64],
        w: Vec<f64>,
        ln_fact: Vec<f64>,
        m: u32,
        out: Vec<f64>,
    }
    impl Walk<'_> {
        fn rec(&mut self, i: usize, left: u32, n: &mut [u32]) {
            if i + 1 == n.len() {
                n[i] = left;
                let mut ln_p = self.ln_fact[self.m as usize];
                for (k, &c) in n.iter().enumerate() {
                    if c > 0 {
                        if self.q[k] == 0.0 {
                            return;
                        }
                        ln_p += c as f64 * self.q[k].ln() - self.ln_fact[c as usize];
                    }
                }
                let total: f64 = n.iter().zip(&self.w).map(|(&c, w)| c as f64 * w).sum();
                if total > 0.0 {
                    for ((o, &c), w) in self.out.iter_mut().zip(n.iter()).zip(&self.w) {
                        *o += ln_p.exp() * c as f64 * w / total;
                    }
                }
                return;
            }
            for c in 0..=left {
                n[i] = c;
                self.rec(i + 1, left - c, n);
            }
        }
    }
    let mut walk = Walk {
        q,
        w: p.iter()
            .zip(q)
            .map(|(p, q)| if *q > 0.0 { p / q } else { 0.0 })
            .collect(),
        ln_fact: (0..=m).map(|k| stats::ln_gamma(k as f64 + 1.0)).collect(),
        m,
        out: vec![0.0; p.len()],
    };
    walk.rec(0, m, &mut vec![0u32; p.len()]);
    walk.out
}

fn run_ris(p: &[f32], q: &[f32], m: u32, seed: u32, stratified: bool) -> Vec<(u32, f32)> {
    let push: Vec<u8> = [p.len() as u32, TRIALS, seed, m, stratified as u32]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let out = testing::run_kernel(
        "tests/ris",
        bytemuck::cast_slice(p),
        bytemuck::cast_slice(q),
        TRIALS as usize * 8,
        &push,
        TRIALS,
    )
    .expect("ris kernel");
    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&out);
    words
        .chunks_exact(2)
        .map(|c| (c[0], f32::from_bits(c[1])))
        .collect()
}

// Five lights whose target and source disagree strongly (as a uniform source does for
// lights of very different power).
const TARGET: [f32; 5] = [0.2, 5.0, 1.0, 0.05, 2.5];
const SOURCE: [f32; 5] = [0.2, 0.2, 0.2, 0.2, 0.2];

#[test]
fn ris_selection_matches_exact_distribution_for_each_m() {
    let p: Vec<f64> = TARGET.iter().map(|&v| v as f64).collect();
    let q: Vec<f64> = SOURCE.iter().map(|&v| v as f64).collect();
    let p_norm: Vec<f64> = p.iter().map(|v| v / p.iter().sum::<f64>()).collect();
    let mut last_tv = f64::INFINITY;
    for (i, m) in [1u32, 4, 32].into_iter().enumerate() {
        let exact = exact_selection(&p, &q, m);
        let picks = run_ris(&TARGET, &SOURCE, m, 100 + i as u32, false);
        let mut counts = vec![0.0; p.len()];
        for (index, _) in &picks {
            counts[*index as usize] += 1.0;
        }
        let expected: Vec<f64> = exact.iter().map(|e| e * TRIALS as f64).collect();
        let chi = stats::chi_square(&counts, &expected, 5.0);
        assert!(
            chi.p_value > 1e-4,
            "M = {m}: selections differ from the exact RIS distribution: {chi:?}"
        );
        // As M grows the selection approaches p̂ / Σp̂.
        let tv: f64 = 0.5
            * exact
                .iter()
                .zip(&p_norm)
                .map(|(a, b)| (a - b).abs())
                .sum::<f64>();
        assert!(
            tv < last_tv,
            "M = {m}: total variation to p̂/Σp̂ did not shrink ({tv} ≥ {last_tv})"
        );
        last_tv = tv;
    }
    assert!(
        last_tv < 0.02,
        "M = 32 is still far from p̂/Σp̂ (TV {last_tv})"
    );
    testing::assert_no_validation_errors();
}

#[test]
fn ris_contribution_weight_is_unbiased() {
    // E[f(Y)·W] = Σ f over the source's support, for any f that is zero where p̂ is.
    let f = [1.0f64, 2.0, 0.5, 4.0, 1.0];
    for (m, stratified) in [(1u32, false), (8, false), (1, true), (8, true), (32, true)] {
        let picks = run_ris(&TARGET, &SOURCE, m, 200 + m, stratified);
        // Batch means make the t-test's normal approximation sound.
        let batch = 1024;
        let estimates: Vec<f64> = picks
            .chunks(batch)
            .map(|c| {
                c.iter()
                    .map(|&(i, w)| f[i as usize] * w as f64)
                    .sum::<f64>()
                    / c.len() as f64
            })
            .collect();
        let p = stats::t_test_against(&estimates, f.iter().sum());
        assert!(
            p > 1e-4,
            "M = {m}, stratified {stratified}: RIS estimate biased (p = {p})"
        );
    }
    testing::assert_no_validation_errors();
}

/// Stratified candidates (the kernel's default) lower the variance of the RIS estimate
/// where the target fits the integrand: with f = p̂ the estimate f(Y)·W is Σw/M, and with
/// 8 candidates over 5 lights each light is drawn about as often as its share of the
/// source, so Σw varies far less than with independent candidates.
#[test]
fn stratified_candidates_lower_the_variance() {
    let f: Vec<f64> = TARGET.iter().map(|&t| t as f64).collect();
    let variance = |stratified: bool| {
        let picks = run_ris(&TARGET, &SOURCE, 8, 300, stratified);
        let values: Vec<f64> = picks
            .iter()
            .map(|&(i, w)| f[i as usize] * w as f64)
            .collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (values.len() - 1) as f64
    };
    let (independent, stratified) = (variance(false), variance(true));
    // 2^18 trials: each variance is known to about 1 %.
    assert!(
        stratified < 0.8 * independent,
        "stratified candidates: variance {stratified} against {independent} independent"
    );
    testing::assert_no_validation_errors();
}

/// The pixel positions of the first 2^m samples of a pixel form a (0, m, 2)-net: every
/// elementary interval [a/2^i, (a+1)/2^i) × [b/2^j, (b+1)/2^j) with i + j = m holds
/// exactly one of them (Owen scrambling keeps Sobol's net property).
#[test]
fn pixel_positions_are_stratified() {
    let (pixels, m) = (16u32, 6u32);
    let count = 1u32 << m;
    let push: Vec<u8> = [pixels, count, 7]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let out = testing::run_kernel(
        "tests/pixel_sampler",
        &[],
        &[],
        (pixels * count) as usize * 8,
        &push,
        pixels * count,
    )
    .unwrap();
    let p: Vec<[f32; 2]> = bytemuck::pod_collect_to_vec(&out);
    for px in 0..pixels as usize {
        let points = &p[px * count as usize..(px + 1) * count as usize];
        for i in 0..=m {
            let j = m - i;
            let mut hits = vec![0u32; 1 << m];
            for q in points {
                assert!((0.0..1.0).contains(&q[0]) && (0.0..1.0).contains(&q[1]));
                let a = (q[0] * (1u32 << i) as f32) as usize;
                let b = (q[1] * (1u32 << j) as f32) as usize;
                hits[(a << j) + b] += 1;
            }
            assert!(
                hits.iter().all(|&h| h == 1),
                "pixel {px}: {i}×{j} intervals not stratified"
            );
        }
    }
    testing::assert_no_validation_errors();
}

/// The kernels' integer floor (`floor_to_uint`, which RIS and light sampling use to pick a
/// light model and a triangle) equals the CPU's floor over 0 ≤ x < 2³²: integers and their
/// neighbouring floats, powers of two, denormals, and random values at every magnitude.
#[test]
fn kernel_integer_floor_is_exact() {
    let mut xs: Vec<f32> = vec![0.0, f32::from_bits(1), f32::MIN_POSITIVE, 0.5, 0.999_999_94];
    for k in 1..2048u32 {
        let f = k as f32;
        xs.extend([
            f,
            f32::from_bits(f.to_bits() - 1),
            f32::from_bits(f.to_bits() + 1),
        ]);
    }
    for e in 0..32 {
        let f = (1u64 << e) as f32;
        xs.extend([
            f,
            f32::from_bits(f.to_bits() - 1),
            f32::from_bits(f.to_bits() + 1),
        ]);
    }
    xs.retain(|&x| (x as f64) < 4_294_967_296.0);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..20_000 {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        let bits = (state >> 33) as u32;
        // Every exponent from denormal to just under 2^32.
        let x = f32::from_bits(bits % 0x4F80_0000);
        xs.push(x);
    }
    let push: Vec<u8> = (xs.len() as u32).to_le_bytes().to_vec();
    let out = testing::run_kernel(
        "tests/floor_to_uint",
        bytemuck::cast_slice(&xs),
        &[],
        xs.len() * 4,
        &push,
        xs.len() as u32,
    )
    .unwrap();
    let got: Vec<u32> = bytemuck::pod_collect_to_vec(&out);
    for (x, g) in xs.iter().zip(&got) {
        assert_eq!(*g as f64, (*x as f64).floor(), "floor_to_uint({x:e}) = {g}");
    }
    testing::assert_no_validation_errors();
}
