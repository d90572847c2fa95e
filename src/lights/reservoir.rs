//! CPU mirror of `shaders_glsl/inc/reservoir.glsl`: single-item streaming weighted
//! reservoir sampling, for tests and CPU-side tools.

/// Streaming reservoir over candidates of weight w ≥ 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct Reservoir {
    pub w_sum: f64,
    pub count: u32,
}

impl Reservoir {
    /// Stream a candidate; true when it replaces the kept one (u < w / w_sum).
    pub fn update(&mut self, w: f64, u: f64) -> bool {
        self.count += 1;
        // Zero, negative and NaN weights never win (as in the GLSL).
        if w.is_nan() || w <= 0.0 {
            return false;
        }
        self.w_sum += w;
        u * self.w_sum < w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats;

    /// A small PCG for the test (32-bit LCG with an output permutation).
    fn next(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f64) / (1u64 << 24) as f64
    }

    #[test]
    fn selection_frequencies_follow_weights() {
        let weights = [0.5, 0.0, 3.0, 1.0, 0.25, 7.0, 2.0];
        let total: f64 = weights.iter().sum();
        let trials = 200_000;
        let mut counts = vec![0.0; weights.len()];
        let mut s = 12345u64;
        for _ in 0..trials {
            let mut r = Reservoir::default();
            let mut kept = usize::MAX;
            for (i, &w) in weights.iter().enumerate() {
                if r.update(w, next(&mut s)) {
                    kept = i;
                }
            }
            counts[kept] += 1.0;
        }
        let expected: Vec<f64> = weights.iter().map(|w| w / total * trials as f64).collect();
        assert_eq!(counts[1], 0.0, "a zero weight was selected");
        let chi = stats::chi_square(&counts, &expected, 5.0);
        assert!(chi.p_value > 1e-4, "reservoir frequencies off: {chi:?}");
    }
}
