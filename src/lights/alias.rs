//! Walker/Vose alias tables: O(1) sampling of a discrete distribution, built on the CPU
//! and read by the kernels (`AliasEntry`). Each entry also stores its own pmf so that a
//! sampler can report the probability of what it picked without a second lookup.

use crate::gpu::AliasEntry;

/// Build an alias table for `weights` (non-negative; at least one positive). Returns
/// `None` when every weight is zero or one is not finite.
pub fn build(weights: &[f64]) -> Option<Vec<AliasEntry>> {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    if n == 0
        || !total.is_finite()
        || total <= 0.0
        || weights.iter().any(|w| !w.is_finite() || *w < 0.0)
    {
        return None;
    }
    let mut scaled: Vec<f64> = weights.iter().map(|w| w / total * n as f64).collect();
    let mut table: Vec<AliasEntry> = weights
        .iter()
        .enumerate()
        .map(|(i, w)| AliasEntry {
            threshold: 1.0,
            alias: i as u32,
            pmf: (w / total) as f32,
        })
        .collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        table[s].threshold = scaled[s] as f32;
        table[s].alias = l as u32;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // Whatever remains has probability 1 of keeping itself (up to rounding).
    for i in small.into_iter().chain(large) {
        table[i].threshold = 1.0;
        table[i].alias = i as u32;
    }
    Some(table)
}

/// Sample an index with one uniform number in [0, 1) — the same arithmetic as
/// `alias_sample` in `shaders_glsl/inc/lights.glsl`.
pub fn sample(table: &[AliasEntry], u: f32) -> usize {
    let n = table.len();
    let scaled = u * n as f32;
    let i = (scaled as usize).min(n - 1);
    let frac = scaled - i as f32;
    if frac < table[i].threshold {
        i
    } else {
        table[i].alias as usize
    }
}

/// Probability of index `i`.
pub fn pmf(table: &[AliasEntry], i: usize) -> f32 {
    table[i].pmf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_probabilities() {
        // The probability of each index, summed over the table's two-way splits, must
        // equal its normalised weight.
        let w = [1.0, 0.0, 3.0, 0.5, 10.0, 2.5];
        let t = build(&w).unwrap();
        let total: f64 = w.iter().sum();
        let n = t.len() as f64;
        let mut p = vec![0.0f64; t.len()];
        for (i, e) in t.iter().enumerate() {
            p[i] += e.threshold as f64 / n;
            p[e.alias as usize] += (1.0 - e.threshold as f64) / n;
        }
        for i in 0..w.len() {
            assert!(
                (p[i] - w[i] / total).abs() < 1e-6,
                "index {i}: {} vs {}",
                p[i],
                w[i] / total
            );
            assert!((t[i].pmf as f64 - w[i] / total).abs() < 1e-6);
        }
    }

    #[test]
    fn rejects_degenerate() {
        assert!(build(&[]).is_none());
        assert!(build(&[0.0, 0.0]).is_none());
        assert!(build(&[1.0, f64::NAN]).is_none());
    }

    #[test]
    fn zero_weight_never_sampled() {
        let t = build(&[0.0, 1.0, 0.0, 2.0]).unwrap();
        for k in 0..10_000 {
            let i = sample(&t, k as f32 / 10_000.0);
            assert!(i == 1 || i == 3);
        }
    }
}
