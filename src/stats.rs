//! Statistics for the test suite and the evaluation tools: χ² goodness of fit with bin
//! pooling, Welch's t-test, Mann–Whitney's rank-sum test, Šidák-corrected multiple
//! comparisons, and the special functions they need (regularised incomplete gamma and
//! beta).
//!
//! Tests built on these state a significance level and derive their bounds from the
//! estimator's measured variance, never from a tolerance tuned to one lucky run.

/// Standard normal CDF.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical-Recipes-style Chebyshev fit, |error| < 1.2e-7).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.26551223
        + t * (1.00002368
            + t * (0.37409196
                + t * (0.09678418
                    + t * (-0.18628806
                        + t * (0.27886807
                            + t * (-1.13520398
                                + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return std::f64::consts::PI.ln()
            - (std::f64::consts::PI * x).sin().ln()
            - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        // Series for P, then Q = 1 - P.
        let mut sum = 1.0 / a;
        let mut term = sum;
        let mut n = a;
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma(a)).exp()
    } else {
        // Continued fraction for Q (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - ln_gamma(a)).exp() * h
    }
}

/// P(χ²_dof ≥ x).
pub fn chi_square_sf(x: f64, dof: f64) -> f64 {
    gamma_q(0.5 * dof, 0.5 * x)
}

/// Regularised incomplete beta I_x(a, b).
pub fn beta_inc(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    // Use the continued fraction where it converges fast.
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..10_000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < tiny {
            d = tiny;
        }
        c = 1.0 + aa / c;
        if c.abs() < tiny {
            c = tiny;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < tiny {
            d = tiny;
        }
        c = 1.0 + aa / c;
        if c.abs() < tiny {
            c = tiny;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Two-sided p-value of Student's t with `dof` degrees of freedom.
pub fn student_t_two_sided(t: f64, dof: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    beta_inc(0.5 * dof, 0.5, dof / (dof + t * t))
}

/// Per-comparison significance that keeps the family-wise error rate at `alpha` over
/// `n` independent comparisons (Šidák).
pub fn sidak(alpha: f64, n: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / n.max(1) as f64)
}

/// Result of a χ² goodness-of-fit test.
#[derive(Clone, Debug)]
pub struct ChiSquare {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Bins after pooling.
    pub bins: usize,
}

/// χ² test of observed counts against expected counts (same total). Bins whose expected
/// count is below `min_expected` are pooled together (the χ² approximation needs about
/// five per bin), as Mitsuba's χ² harness does.
pub fn chi_square(observed: &[f64], expected: &[f64], min_expected: f64) -> ChiSquare {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut stat, mut bins) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for &i in &order {
        if expected[i] < min_expected {
            pool_o += observed[i];
            pool_e += expected[i];
            continue;
        }
        stat += (observed[i] - expected[i]).powi(2) / expected[i];
        bins += 1;
    }
    if pool_e > 0.0 {
        if pool_e < min_expected && bins > 0 {
            // Too small to stand alone: merge into the smallest kept bin's budget by
            // counting it as one more bin only if it has any mass at all.
            stat += (pool_o - pool_e).powi(2) / pool_e.max(1e-12);
        } else {
            stat += (pool_o - pool_e).powi(2) / pool_e;
        }
        bins += 1;
    }
    let dof = bins.saturating_sub(1).max(1);
    ChiSquare {
        statistic: stat,
        dof,
        p_value: chi_square_sf(stat, dof as f64),
        bins,
    }
}

/// Mean and unbiased variance.
pub fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, v)
}

/// Welch's t-test of two sets of independent estimates; returns the two-sided p-value.
pub fn welch(a: &[f64], b: &[f64]) -> f64 {
    let (ma, va) = mean_var(a);
    let (mb, vb) = mean_var(b);
    welch_summary(
        (ma, va / a.len() as f64, a.len()),
        (mb, vb / b.len() as f64, b.len()),
    )
}

/// Welch's t-test from summaries `(mean, squared standard error of the mean, number of
/// independent estimates)` of each side; returns the two-sided p-value.
pub fn welch_summary(a: (f64, f64, usize), b: (f64, f64, usize)) -> f64 {
    let ((ma, sa, na), (mb, sb, nb)) = (a, b);
    let se2 = sa + sb;
    if se2 <= 0.0 {
        return if ma == mb { 1.0 } else { 0.0 };
    }
    let t = (ma - mb) / se2.sqrt();
    let dof = se2 * se2 / (sa * sa / (na as f64 - 1.0) + sb * sb / (nb as f64 - 1.0));
    student_t_two_sided(t, dof.max(1.0))
}

/// One-sample t-test of estimates against a known value; two-sided p-value.
pub fn t_test_against(x: &[f64], expected: f64) -> f64 {
    let (m, v) = mean_var(x);
    let n = x.len() as f64;
    if v <= 0.0 {
        return if m == expected { 1.0 } else { 0.0 };
    }
    student_t_two_sided((m - expected) / (v / n).sqrt(), n - 1.0)
}

/// Mann–Whitney's rank-sum test of two independent samples: whether one tends to lie
/// above the other. Two-sided p-value by the normal approximation (continuity
/// correction, ties at their mean rank with the variance corrected for them), good from
/// about eight values a side. Unlike Welch's test it is not drawn toward an estimator's
/// rare huge values: a defect that makes nearly every batch bright, and a few of them
/// enormous, inflates the variance Welch divides by but still moves every rank. Where
/// both sides' batch means are symmetric about the same expectation (batches of many
/// samples), P(a > b) = 1/2 and the test holds its level.
pub fn mann_whitney(a: &[f64], b: &[f64]) -> f64 {
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let n = na + nb;
    let mut all: Vec<(f64, bool)> = a
        .iter()
        .map(|&x| (x, false))
        .chain(b.iter().map(|&x| (x, true)))
        .collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut rank_b, mut ties) = (0.0, 0.0);
    let mut i = 0;
    while i < all.len() {
        let mut j = i;
        while j + 1 < all.len() && all[j + 1].0 == all[i].0 {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        ties += t * t * t - t;
        let mean_rank = (i + j) as f64 / 2.0 + 1.0;
        rank_b += mean_rank * all[i..=j].iter().filter(|e| e.1).count() as f64;
        i = j + 1;
    }
    let u = rank_b - nb * (nb + 1.0) / 2.0;
    let mean = na * nb / 2.0;
    let var = na * nb / 12.0 * ((n + 1.0) - ties / (n * (n - 1.0)));
    if var <= 0.0 {
        return 1.0;
    }
    let z = ((u - mean).abs() - 0.5).max(0.0) / var.sqrt();
    erfc(z / std::f64::consts::SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mann_whitney_matches_the_normal_approximation() {
        // U = 25 of 25 for b above a: z = (25 − 12.5 − 0.5) / √(25·11/12).
        let a = [1.0, 2.0, 3.0, 4.0, 5.0];
        let b = [6.0, 7.0, 8.0, 9.0, 10.0];
        let z: f64 = 12.0 / (25.0f64 * 11.0 / 12.0).sqrt();
        let want = 2.0 * (1.0 - normal_cdf(z));
        assert!((mann_whitney(&a, &b) - want).abs() < 1e-6);
        assert!((mann_whitney(&b, &a) - want).abs() < 1e-6);
        // Interleaved and tied samples are no evidence.
        assert!(mann_whitney(&[1.0, 3.0, 5.0, 7.0], &[2.0, 4.0, 6.0, 8.0]) > 0.5);
        assert_eq!(mann_whitney(&[2.0; 6], &[2.0; 6]), 1.0);
    }

    #[test]
    fn special_functions_match_tables() {
        assert!((normal_cdf(1.959964) - 0.975).abs() < 1e-6);
        assert!((chi_square_sf(3.841459, 1.0) - 0.05).abs() < 1e-6);
        assert!((chi_square_sf(18.307038, 10.0) - 0.05).abs() < 1e-6);
        assert!((chi_square_sf(124.342, 100.0) - 0.05).abs() < 1e-4);
        assert!((student_t_two_sided(2.228139, 10.0) - 0.05).abs() < 1e-6);
        assert!((student_t_two_sided(12.706205, 1.0) - 0.05).abs() < 1e-6);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-15);
    }

    #[test]
    fn chi_square_pools_small_bins() {
        let expected = [100.0, 100.0, 1.0, 1.0, 1.0, 97.0];
        let observed = [98.0, 103.0, 2.0, 0.0, 1.0, 96.0];
        let r = chi_square(&observed, &expected, 5.0);
        assert_eq!(r.bins, 4);
        assert!(r.p_value > 0.5);
    }
}
