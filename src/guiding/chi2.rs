//! Statistical checks of guided direction sampling, shared by the CPU tests and the
//! GPU test (which runs `tests/guiding_sample` on the device and hands its output to
//! `check_guide_samples`): a χ² goodness-of-fit test of sampled directions against the
//! quadtree's exact cell probabilities on a grid over the (cosθ, φ) square, with bins of
//! small expected count pooled, and the exactness checks on the returned pdfs.

use super::quadtree::QuadTree;
use super::sphere::{dir_to_square, INV_4PI};
use glam::Vec3;
use std::collections::HashMap;

/// Result of a χ² test.
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2 {
    pub statistic: f64,
    pub dof: u32,
    /// Probability of a statistic at least this large if the samples follow the
    /// expected distribution.
    pub p_value: f64,
    /// Bins after pooling.
    pub bins: usize,
}

/// P(χ²_dof ≥ x) (the special functions live in `crate::stats`).
pub fn chi2_survival(x: f64, dof: u32) -> f64 {
    crate::stats::chi_square_sf(x, f64::from(dof))
}

/// χ² of observed counts against expected counts. Bins with expected counts below
/// `min_expected` are pooled (smallest first) until each pool reaches it. A sample in a
/// bin of zero expected count gives p = 0.
pub fn chi2_test(observed: &[u64], expected: &[f64], min_expected: f64) -> Chi2 {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut pools: Vec<(f64, f64)> = Vec::new();
    let (mut o, mut e) = (0.0, 0.0);
    for &i in &order {
        if expected[i] <= 0.0 {
            if observed[i] > 0 {
                return Chi2 {
                    statistic: f64::INFINITY,
                    dof: 0,
                    p_value: 0.0,
                    bins: 0,
                };
            }
            continue;
        }
        o += observed[i] as f64;
        e += expected[i];
        if e >= min_expected {
            pools.push((o, e));
            (o, e) = (0.0, 0.0);
        }
    }
    if e > 0.0 {
        match pools.last_mut() {
            Some(last) => {
                last.0 += o;
                last.1 += e;
            }
            None => pools.push((o, e)),
        }
    }
    let statistic: f64 = pools.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = pools.len().saturating_sub(1) as u32;
    let p_value = if dof == 0 {
        1.0
    } else {
        chi2_survival(statistic, dof)
    };
    Chi2 {
        statistic,
        dof,
        p_value,
        bins: pools.len(),
    }
}

/// Probability of each bin of a `res_u` × `res_v` grid over the square under `tree`'s
/// sampling, exact up to f64 rounding (cells are spread over the bins they overlap).
pub fn bin_probabilities(tree: &QuadTree, res_u: u32, res_v: u32) -> Vec<f64> {
    let mut out = vec![0.0; (res_u * res_v) as usize];
    let (ru, rv) = (f64::from(res_u), f64::from(res_v));
    for c in tree.cells() {
        let (ou, ov, s) = (
            f64::from(c.origin[0]),
            f64::from(c.origin[1]),
            f64::from(c.size),
        );
        let (i0, i1) = (
            (ou * ru).floor() as u32,
            (((ou + s) * ru).ceil() as u32).min(res_u),
        );
        let (j0, j1) = (
            (ov * rv).floor() as u32,
            (((ov + s) * rv).ceil() as u32).min(res_v),
        );
        for j in j0..j1 {
            let ly = ((f64::from(j + 1) / rv).min(ov + s) - (f64::from(j) / rv).max(ov)).max(0.0);
            for i in i0..i1 {
                let lx =
                    ((f64::from(i + 1) / ru).min(ou + s) - (f64::from(i) / ru).max(ou)).max(0.0);
                out[(j * res_u + i) as usize] += c.prob * lx * ly / (s * s);
            }
        }
    }
    out
}

/// Histogram of points of the square on the same grid.
pub fn square_histogram(
    points: impl IntoIterator<Item = [f32; 2]>,
    res_u: u32,
    res_v: u32,
) -> Vec<u64> {
    let mut out = vec![0u64; (res_u * res_v) as usize];
    for p in points {
        let i = ((p[0] * res_u as f32) as u32).min(res_u - 1);
        let j = ((p[1] * res_v as f32) as u32).min(res_v - 1);
        out[(j * res_u + i) as usize] += 1;
    }
    out
}

/// χ² of sampled points of the square against `tree` on a `res` × `res` grid, pooling
/// bins with expected counts below 5.
pub fn chi2_grid(tree: &QuadTree, points: &[[f32; 2]], res: u32) -> Chi2 {
    let n = points.len() as f64;
    let expected: Vec<f64> = bin_probabilities(tree, res, res)
        .iter()
        .map(|p| p * n)
        .collect();
    let observed = square_histogram(points.iter().copied(), res, res);
    chi2_test(&observed, &expected, 5.0)
}

/// `chi2_grid` of directions (mapped to the square on the CPU).
pub fn chi2_directions(tree: &QuadTree, dirs: &[Vec3], res: u32) -> Chi2 {
    let points: Vec<[f32; 2]> = dirs.iter().map(|&d| dir_to_square(d)).collect();
    chi2_grid(tree, &points, res)
}

/// χ² of sampled points of the square against the probabilities of `tree`'s leaf cells,
/// one bin per cell (pooling cells expecting fewer than 5): resolves the deep cells a
/// grid cannot.
pub fn chi2_leaf_cells(tree: &QuadTree, points: &[[f32; 2]]) -> Chi2 {
    let cells = tree.cells();
    let index: HashMap<(u32, u32, u32), usize> = cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            (
                (
                    c.origin[0].to_bits(),
                    c.origin[1].to_bits(),
                    c.size.to_bits(),
                ),
                i,
            )
        })
        .collect();
    let mut observed = vec![0u64; cells.len()];
    for &p in points {
        let (origin, size) = tree.cell_at(p);
        observed[index[&(origin[0].to_bits(), origin[1].to_bits(), size.to_bits())]] += 1;
    }
    let n = points.len() as f64;
    let expected: Vec<f64> = cells.iter().map(|c| c.prob * n).collect();
    chi2_test(&observed, &expected, 5.0)
}

/// One sample as the test kernel writes it: direction, pdf returned by `guide_sample`,
/// `guide_pdf` of the direction, and the direction's square coordinates as the sampler's
/// own `dir_to_square` computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideSample {
    pub dir: Vec3,
    pub pdf: f32,
    pub pdf_eval: f32,
    pub square: [f32; 2],
}

/// Everything the sampling tests assert, for samples drawn with uniform pairs from
/// `tree` (on the CPU or by the GPU kernel).
#[derive(Clone, Debug, PartialEq)]
pub struct SampleCheck {
    /// On a grid over the square.
    pub chi2: Chi2,
    /// One bin per leaf cell.
    pub chi2_cells: Chi2,
    /// Samples whose returned pdf is not bitwise `guide_pdf` of their direction.
    pub pdf_mismatches: usize,
    /// Samples whose pdf is not the CPU tree's pdf at the sample's square coordinates
    /// (1e-5 relative: Vulkan allows 2.5 ulp per division): the walks disagree.
    pub cpu_disagreements: usize,
    /// Directions that are not unit length (1e-5), have a non-positive pdf, or whose
    /// square coordinates are more than 1e-5 from the CPU's mapping of the direction.
    pub bad_samples: usize,
}

/// Significance of the sampling tests: a fixed-seed run fails if p < 1e-4.
pub const CHI2_SIGNIFICANCE: f64 = 1e-4;

impl SampleCheck {
    /// The sampling tests' verdict: χ² not rejected at `CHI2_SIGNIFICANCE` (neither on
    /// the grid nor per cell), every returned pdf exactly `guide_pdf` and equal to the
    /// CPU's, no invalid sample.
    pub fn verdict(&self) -> Result<(), String> {
        for c in [&self.chi2, &self.chi2_cells] {
            if c.p_value.is_nan() || c.p_value < CHI2_SIGNIFICANCE {
                return Err(format!("χ² rejects the samples: {c:?}"));
            }
        }
        if self.pdf_mismatches > 0 || self.bad_samples > 0 || self.cpu_disagreements > 0 {
            return Err(format!("{self:?}"));
        }
        Ok(())
    }
}

/// Check samples of `tree`, binned by their own square coordinates: χ² on a `res` ×
/// `res` grid and per leaf cell, pdf exactness, agreement with
/// the CPU pdf, validity.
pub fn check_guide_samples(tree: &QuadTree, samples: &[GuideSample], res: u32) -> SampleCheck {
    let points: Vec<[f32; 2]> = samples.iter().map(|s| s.square).collect();
    let mut check = SampleCheck {
        chi2: chi2_grid(tree, &points, res),
        chi2_cells: chi2_leaf_cells(tree, &points),
        pdf_mismatches: 0,
        cpu_disagreements: 0,
        bad_samples: 0,
    };
    for s in samples {
        if s.pdf.to_bits() != s.pdf_eval.to_bits() {
            check.pdf_mismatches += 1;
        }
        let cpu = if tree.is_empty() {
            INV_4PI
        } else {
            tree.density(s.square) * INV_4PI
        };
        if (cpu - s.pdf).abs() > 1e-5 * cpu.abs().max(s.pdf.abs()) {
            check.cpu_disagreements += 1;
        }
        let back = dir_to_square(s.dir);
        let mapped = (back[0] - s.square[0]).abs() < 1e-5 && (back[1] - s.square[1]).abs() < 1e-5;
        if !((s.dir.length() - 1.0).abs() < 1e-5 && s.pdf > 0.0 && mapped) {
            check.bad_samples += 1;
        }
    }
    check
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn survival_function_matches_tables() {
        // Reference values of the χ² upper tail.
        assert!((chi2_survival(3.841_458_820_694_124, 1) - 0.05).abs() < 1e-9);
        assert!((chi2_survival(18.307_038_053_275_146, 10) - 0.05).abs() < 1e-9);
        assert!((chi2_survival(100.0, 100) - 0.481_191_684_527_957).abs() < 1e-9); // mpmath
        assert!((chi2_survival(2.0, 2) - (-1.0f64).exp()).abs() < 1e-12);
        assert!(chi2_survival(1000.0, 10) < 1e-100);
    }

    #[test]
    fn pooling_and_zero_bins() {
        let c = chi2_test(&[10, 0, 1, 9], &[10.0, 0.5, 0.5, 9.0], 5.0);
        assert_eq!(c.bins, 2);
        let c = chi2_test(&[10, 1], &[10.0, 0.0], 5.0);
        assert_eq!(c.p_value, 0.0);
    }
}
