//! What a guided run makes of its passes: the training iterations (each rendered with
//! the previous iteration's tree) and the render phase (the frozen tree) are all
//! unbiased images of the same pixels, from disjoint sample indices. Which of them the
//! output uses is `GuidedOutput`:
//!
//! * `AllPasses` (the default): every training pass and the render phase, every sample
//!   weighted equally. The film is then the whole budget's range of sample indices
//!   [first, first + spp), exactly as an unguided render's: unbiased, exact fixed-point
//!   sums, and renders of disjoint ranges merge exactly. The pixel samples are
//!   stratified (Owen-scrambled Sobol' indices), and a whole power-of-two range of
//!   indices is stratified far better than the same range missing a few: on
//!   `cornell-lights` at 256 spp, `ris` over indices [3, 256) has 1.07× the MAE of
//!   [0, 256). That outweighs the first passes' higher variance (their trees learned from
//!   little data): against `LatePasses`, 0.94–0.98× the MAE on `cornell-lights` and the
//!   street, level on gap and `bistro-night` (README, Path guiding).
//! * `LatePasses`: the render phase and the last `LATE_TRAINING_PASSES` training
//!   passes, every sample weighted equally (the default before stratified sampling).
//!   Which passes count depends only on the schedule, never on the samples, so the image
//!   is unbiased and its film exact. The earlier passes are left out: with independent
//!   numbers, measured on the gap scene, their samples have 2–4× the render phase's
//!   variance, above the 2× beyond which an equally weighted sample adds error.
//! * `RenderPhase`: the render phase alone (the training images are discarded).
//! * `InverseVariance`: Müller et al.'s weighting of every pass by the inverse of its
//!   estimated mean pixel variance. Each pass is rendered as two halves whose difference
//!   estimates that variance; the weights are estimates made from the images they weigh,
//!   so the combination is consistent rather than unbiased.

use super::{Film, GuidedOutput};
use std::collections::VecDeque;

/// Training passes that `GuidedOutput::LatePasses` keeps (the last ones).
pub const LATE_TRAINING_PASSES: usize = 4;

/// The training passes kept for the output, as they are rendered.
#[derive(Debug)]
pub struct KeptPasses {
    output: GuidedOutput,
    /// `LatePasses`: the films of the last passes, oldest first (`AllPasses` keeps its
    /// passes in the device's film: `in_device_film`).
    films: VecDeque<Film>,
    /// `InverseVariance`: each pass's mean image and estimated mean pixel variance.
    estimates: Vec<(Vec<f32>, f64)>,
}

impl KeptPasses {
    /// What a run with `output` keeps; None when it keeps nothing (`RenderPhase`).
    pub fn for_output(output: GuidedOutput) -> Option<KeptPasses> {
        (output != GuidedOutput::RenderPhase).then(|| KeptPasses {
            output,
            films: VecDeque::new(),
            estimates: Vec::new(),
        })
    }

    /// Whether the kept passes stay in the device's film rather than being read back
    /// after each pass: `AllPasses` is the sum of every pass and the render phase, one
    /// contiguous range of sample indices, which the film accumulates by itself when it
    /// is not cleared between them (exact fixed-point sums: the same film as merging
    /// the passes' read-backs on the host, without a read-back and merge per pass).
    pub fn in_device_film(&self) -> bool {
        self.output == GuidedOutput::AllPasses
    }

    /// Whether passes are to be rendered as two halves (for a variance estimate).
    pub fn wants_halves(&self) -> bool {
        self.output == GuidedOutput::InverseVariance
    }

    /// Keep a finished pass: its film, and the film after its first half when it was
    /// rendered in halves.
    pub fn add(&mut self, film: Film, half: Option<&Film>) {
        match self.output {
            GuidedOutput::RenderPhase => {}
            GuidedOutput::AllPasses => match self.films.back_mut() {
                Some(sum) => sum.merge(&film),
                None => self.films.push_back(film),
            },
            GuidedOutput::LatePasses => {
                self.films.push_back(film);
                if self.films.len() > LATE_TRAINING_PASSES {
                    self.films.pop_front();
                }
            }
            GuidedOutput::InverseVariance => {
                let var = half
                    .and_then(|h| split_variance(h, &film))
                    .unwrap_or(f64::INFINITY);
                self.estimates.push((film.mean(), var));
            }
        }
    }

    /// `AllPasses` and `LatePasses`: the kept training films merged with `last` (the
    /// render phase), which follows them in sample order; `last` alone for the other
    /// outputs, and for `AllPasses` kept in the device's film (`in_device_film`: none
    /// were added).
    pub fn merged_film(&self, last: Film) -> Film {
        if !matches!(
            self.output,
            GuidedOutput::AllPasses | GuidedOutput::LatePasses
        ) {
            return last;
        }
        // The kept passes and `last` are contiguous: one range of sample indices.
        self.films.iter().fold(last, |mut out, f| {
            out.merge(f);
            out
        })
    }

    /// `AllPasses` and `LatePasses`: the kept training films merged (after an
    /// interruption in training, when there is no render phase); None for the other
    /// outputs or before any pass.
    pub fn merged_so_far(&self) -> Option<Film> {
        let mut films = self.films.iter().rev();
        let last = films.next()?.clone();
        Some(films.fold(last, |mut out, f| {
            out.merge(f);
            out
        }))
    }

    /// `InverseVariance`: the combination with the render phase `last` (rendered with
    /// `half` its first half); None for the other outputs.
    pub fn combined(&self, last: &Film, half: Option<&Film>) -> Option<Vec<f32>> {
        if self.output != GuidedOutput::InverseVariance {
            return None;
        }
        let var = half
            .and_then(|h| split_variance(h, last))
            .unwrap_or(f64::INFINITY);
        let mean = last.mean();
        let mut passes = self.estimate_refs();
        passes.push((&mean, var));
        Some(combine_inverse_variance(&passes))
    }

    /// `InverseVariance` after an interruption in training: the passes so far.
    pub fn combined_so_far(&self) -> Option<Vec<f32>> {
        if self.output != GuidedOutput::InverseVariance || self.estimates.is_empty() {
            return None;
        }
        Some(combine_inverse_variance(&self.estimate_refs()))
    }

    /// The training passes' (image, variance) estimates, borrowed.
    fn estimate_refs(&self) -> Vec<(&[f32], f64)> {
        self.estimates
            .iter()
            .map(|(img, v)| (img.as_slice(), *v))
            .collect()
    }
}

/// Mean pixel variance of the image of `total`, estimated from its first part `first`:
/// with a and b the means of the two parts over n_a and n_b samples, E[(a − b)²] =
/// σ²·(1/n_a + 1/n_b) for the per-sample variance σ², and the image's variance is σ²/n.
pub fn split_variance(first: &Film, total: &Film) -> Option<f64> {
    let (na, n) = (first.spp as f64, total.spp as f64);
    let nb = n - na;
    if na < 1.0 || nb < 1.0 {
        return None;
    }
    let scale = crate::gpu::FILM_FIXED_SCALE as f64;
    let sum_sq: f64 = first
        .sums
        .iter()
        .zip(&total.sums)
        .map(|(&a, &t)| {
            let ma = a as f64 / scale / na;
            let mb = (t - a) as f64 / scale / nb;
            (ma - mb) * (ma - mb)
        })
        .sum();
    let sigma2 = sum_sq / first.sums.len() as f64 / (1.0 / na + 1.0 / nb);
    Some(sigma2 / n)
}

/// Average the passes' images with weights ∝ 1/variance (passes without an estimate get
/// no weight; when none has one, the last pass alone).
pub fn combine_inverse_variance(passes: &[(&[f32], f64)]) -> Vec<f32> {
    let weights: Vec<f64> = passes
        .iter()
        .map(|(_, v)| {
            if v.is_finite() {
                1.0 / v.max(1e-30)
            } else {
                0.0
            }
        })
        .collect();
    let total: f64 = weights.iter().sum();
    if total <= 0.0 {
        return passes.last().map(|p| p.0.to_vec()).unwrap_or_default();
    }
    let mut out = vec![0.0f64; passes[0].0.len()];
    for ((img, _), w) in passes.iter().zip(&weights) {
        for (o, &x) in out.iter_mut().zip(img.iter()) {
            *o += w / total * x as f64;
        }
    }
    log::debug!(
        "inverse-variance weights of the passes: {:?}",
        weights
            .iter()
            .map(|w| (w / total * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>()
    );
    out.into_iter().map(|x| x as f32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::FILM_FIXED_SCALE;

    fn film(offset: u64, spp: u64, value: f64) -> Film {
        let s = (value * FILM_FIXED_SCALE as f64 * spp as f64) as u64;
        Film {
            width: 1,
            height: 1,
            spp,
            sample_offset: offset,
            sums: vec![s; 3],
        }
    }

    #[test]
    fn late_passes_keep_the_last_training_passes_and_merge_exactly() {
        let mut kept = KeptPasses::for_output(GuidedOutput::LatePasses).unwrap();
        let mut offset = 0;
        for k in 0..6u64 {
            let spp = 1 << k;
            kept.add(film(offset, spp, k as f64), None);
            offset += spp;
        }
        let out = kept.merged_film(film(offset, 100, 10.0));
        // Passes 2..=5 (4 + 8 + 16 + 32 spp) and the render phase.
        assert_eq!(out.spp, 60 + 100);
        assert_eq!(out.sample_offset, 3);
        let expected = (4.0 * 2.0 + 8.0 * 3.0 + 16.0 * 4.0 + 32.0 * 5.0 + 1000.0) / 160.0;
        assert!((out.mean()[0] as f64 - expected).abs() < 1e-6);
    }

    #[test]
    fn all_passes_keep_every_sample_and_merge_exactly() {
        let mut kept = KeptPasses::for_output(GuidedOutput::AllPasses).unwrap();
        let mut offset = 7;
        for k in 0..6u64 {
            let spp = 1 << k;
            kept.add(film(offset, spp, k as f64), None);
            offset += spp;
        }
        assert_eq!(kept.films.len(), 1, "one running sum, not a film per pass");
        let so_far = kept.merged_so_far().unwrap();
        assert_eq!((so_far.sample_offset, so_far.spp), (7, 63));
        let out = kept.merged_film(film(offset, 193, 10.0));
        assert_eq!((out.sample_offset, out.spp), (7, 256));
        let passes: f64 = (0..6).map(|k| f64::from(1 << k) * f64::from(k)).sum();
        let expected = (passes + 1930.0) / 256.0;
        assert!((out.mean()[0] as f64 - expected).abs() < 1e-6);
    }

    #[test]
    fn render_phase_output_keeps_nothing() {
        assert!(KeptPasses::for_output(GuidedOutput::RenderPhase).is_none());
    }
}
