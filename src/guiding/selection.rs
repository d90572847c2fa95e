//! Learned probability of sampling the BSDF rather than the leaf's quadtree (Müller et
//! al. 2019, "Path guiding in production", §10; the reference implementation's
//! `bsdfSamplingFraction` optimisation). Each spatial leaf holds a logit θ, α = σ(θ) is
//! its BSDF selection probability, and Adam minimises the KL divergence between the
//! mixture p_α = α·p_bsdf + (1 − α)·p_guide and the integrand f·cos·L_in, estimated from
//! the training pass's direction samples (drawn from the mixture p_wo of that pass):
//!
//!   D_KL(α) = const − E_wo[ (f·cos·L / p_wo) · log p_α ] (normalised integrand),
//!   ∂D/∂α   = −E_wo[ f·cos·L / (p_wo · p_α) · (p_bsdf − p_guide) ],
//!   ∂D/∂θ   = ∂D/∂α · α(1 − α)  (+ 0.01·θ, the reference's L2 regularisation).
//!
//! The GPU appends one `GuideSelectionRecord` per guided direction sample that carried
//! light (shaders_glsl/inc/guiding_selection.glsl); between passes `SdTree::
//! learn_selection` runs the records through each leaf's optimiser in order, two
//! records per step, as the reference does with its per-sample updates. The GPU samples
//! with the learned α from the next pass on. θ is confined to [−θ_max, θ_max] so that
//! both techniques keep some probability: the BSDF must cover directions where the
//! quadtree's density is zero (unbiasedness), and the quadtree must keep being sampled
//! for its pdf to be learned against.

use crate::gpu::GuideSelectionRecord;

/// Adam's step size (the reference's 0.01).
pub const LEARNING_RATE: f32 = 0.01;
/// Weight of the L2 regularisation of θ (the reference's 0.01).
pub const L2_REGULARISATION: f32 = 0.01;
/// Records per Adam step (the reference steps once its accumulated weight exceeds 1).
pub const BATCH: f32 = 1.0;
/// Smallest and largest BSDF selection probability a leaf can learn.
pub const MIN_FRACTION: f32 = 0.05;
pub const MAX_FRACTION: f32 = 0.95;
/// Records a training pass may append (20 bytes each); passes that would make more
/// record a uniformly thinned share of them.
pub const RECORD_CAPACITY: u32 = 1 << 20;

const BETA1: f32 = 0.9;
const BETA2: f32 = 0.999;
const EPSILON: f32 = 1e-8;

fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

fn logit(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

/// θ's bounds: logit of the fraction bounds.
pub fn theta_max() -> f32 {
    *THETA_MAX
}

/// `theta_max`, computed once (every Adam step clamps to it).
static THETA_MAX: std::sync::LazyLock<f32> = std::sync::LazyLock::new(|| logit(MAX_FRACTION));

/// One leaf's optimiser: the logit and Adam's moments.
#[derive(Clone, Copy, Debug)]
pub struct SelectionState {
    pub theta: f32,
    first_moment: f32,
    second_moment: f32,
    steps: u32,
    /// β₁ and β₂ to the power `steps` (Adam's bias corrections), kept as running
    /// products rather than taken by `powi` at every step.
    beta1_power: f32,
    beta2_power: f32,
    batch_gradient: f32,
    batch_weight: f32,
    /// The fraction read from a saved tree, used as it is until the next step: σ(logit(α))
    /// is not α to the last bit in f32, and a loaded tree must render what it rendered.
    restored: Option<f32>,
}

/// Equal when they sample alike and learn alike: the fraction they sample with (restored
/// or σ(θ)) and the optimiser's state.
impl PartialEq for SelectionState {
    fn eq(&self, o: &Self) -> bool {
        self.fraction() == o.fraction()
            && self.theta == o.theta
            && self.first_moment == o.first_moment
            && self.second_moment == o.second_moment
            && self.steps == o.steps
            && self.batch_gradient == o.batch_gradient
            && self.batch_weight == o.batch_weight
    }
}

impl SelectionState {
    /// A fresh optimiser starting at BSDF selection probability `fraction` (clamped to
    /// the learnable range).
    pub fn new(fraction: f32) -> Self {
        let f = fraction.clamp(MIN_FRACTION, MAX_FRACTION);
        SelectionState {
            theta: logit(f),
            first_moment: 0.0,
            second_moment: 0.0,
            steps: 0,
            beta1_power: 1.0,
            beta2_power: 1.0,
            batch_gradient: 0.0,
            batch_weight: 0.0,
            restored: None,
        }
    }

    /// The optimiser of a leaf read from a saved tree whose BSDF selection probability
    /// was `fraction`: it samples with exactly that fraction until it learns again.
    pub fn restored(fraction: f32) -> Self {
        SelectionState {
            restored: Some(fraction.clamp(MIN_FRACTION, MAX_FRACTION)),
            ..SelectionState::new(fraction)
        }
    }

    /// α = σ(θ): the probability of sampling the BSDF.
    pub fn fraction(&self) -> f32 {
        if let Some(f) = self.restored {
            return f;
        }
        sigmoid(self.theta).clamp(MIN_FRACTION, MAX_FRACTION)
    }

    /// Adam steps taken.
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// ∂D_KL/∂θ of one record at the current θ, regularisation included; None for a
    /// record that carries no usable gradient.
    pub fn gradient(&self, r: &GuideSelectionRecord) -> Option<f32> {
        let ok = |x: f32| x.is_finite() && x >= 0.0;
        let usable = ok(r.bsdf_pdf)
            && ok(r.guide_pdf)
            && ok(r.product)
            && r.product > 0.0
            && r.wo_pdf.is_finite()
            && r.wo_pdf > 0.0;
        if !usable {
            return None;
        }
        let alpha = sigmoid(self.theta);
        let mix = alpha * r.bsdf_pdf + (1.0 - alpha) * r.guide_pdf;
        if mix.is_nan() || mix <= 0.0 {
            return None;
        }
        // In f64: product / (mix · wo) spans many decades.
        let d_alpha = -f64::from(r.product) / (f64::from(mix) * f64::from(r.wo_pdf))
            * f64::from(r.bsdf_pdf - r.guide_pdf);
        let d_theta = d_alpha * f64::from(alpha * (1.0 - alpha));
        let g = d_theta as f32 + L2_REGULARISATION * self.theta;
        g.is_finite().then_some(g)
    }

    /// Feed one record: its gradient joins the batch, and a full batch takes a step.
    /// False for a record without a usable gradient (it is skipped).
    pub fn append(&mut self, r: &GuideSelectionRecord) -> bool {
        let Some(g) = self.gradient(r) else {
            return false;
        };
        self.batch_gradient += g;
        self.batch_weight += 1.0;
        if self.batch_weight > BATCH {
            let g = self.batch_gradient / self.batch_weight;
            self.step(g);
            self.batch_gradient = 0.0;
            self.batch_weight = 0.0;
        }
        true
    }

    /// One Adam step (Kingma and Ba 2014) on gradient `g`, then θ is projected back into
    /// its bounds.
    pub fn step(&mut self, g: f32) {
        self.restored = None;
        self.steps += 1;
        self.beta1_power *= BETA1;
        self.beta2_power *= BETA2;
        self.first_moment = BETA1 * self.first_moment + (1.0 - BETA1) * g;
        self.second_moment = BETA2 * self.second_moment + (1.0 - BETA2) * g * g;
        let rate = LEARNING_RATE * (1.0 - self.beta2_power).sqrt() / (1.0 - self.beta1_power);
        self.theta -= rate * self.first_moment / (self.second_moment.sqrt() + EPSILON);
        let m = theta_max();
        self.theta = self.theta.clamp(-m, m);
    }
}

/// What one round of learning did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SelectionStats {
    /// Records used (with a gradient) and records dropped (bad leaf index or values).
    pub records: u64,
    pub dropped: u64,
    /// Mean learned BSDF probability over the leaves, each weighted by its records.
    pub mean_fraction: f32,
}

impl super::SdTree {
    /// Run the records of a training pass (leaf indices of the tree that rendered it,
    /// i.e. before `refit`) through their leaves' optimisers, in order.
    pub fn learn_selection(&mut self, records: &[GuideSelectionRecord]) -> SelectionStats {
        let mut stats = SelectionStats::default();
        // Each leaf's records in the order the GPU appended them (a counting sort), so
        // the leaves can learn on separate threads with the result of one.
        let leaves = self.leaves.len();
        let mut start = vec![0usize; leaves + 1];
        for r in records {
            match r.leaf as usize {
                l if l < leaves => start[l + 1] += 1,
                _ => stats.dropped += 1,
            }
        }
        for l in 0..leaves {
            start[l + 1] += start[l];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; start[leaves]];
        for (i, r) in records.iter().enumerate() {
            let l = r.leaf as usize;
            if l < leaves {
                order[fill[l]] = i as u32;
                fill[l] += 1;
            }
        }
        let cost: Vec<u64> = start.windows(2).map(|w| (w[1] - w[0]) as u64 + 1).collect();
        let learned = super::parallel::map_mut_by_cost(&mut self.leaves, &cost, |l, leaf| {
            let mut used = 0u64;
            for &i in &order[start[l]..start[l + 1]] {
                let r = &records[i as usize];
                // One gradient per record (it was computed twice, to count and to
                // learn: the selection is the largest part of guided-ris's refit).
                used += u64::from(leaf.selection.append(r));
            }
            (used, start[l + 1] - start[l])
        });
        let per_leaf: Vec<u64> = learned.iter().map(|&(used, _)| used).collect();
        for &(used, total) in &learned {
            stats.records += used;
            stats.dropped += total as u64 - used;
        }
        if stats.records > 0 {
            let sum: f64 = per_leaf
                .iter()
                .zip(&self.leaves)
                .map(|(&n, l)| n as f64 * f64::from(l.selection.fraction()))
                .sum();
            stats.mean_fraction = (sum / stats.records as f64) as f32;
        }
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(bsdf_pdf: f32, guide_pdf: f32, wo_pdf: f32, product: f32) -> GuideSelectionRecord {
        GuideSelectionRecord {
            leaf: 0,
            bsdf_pdf,
            guide_pdf,
            wo_pdf,
            product,
        }
    }

    #[test]
    fn starts_at_the_given_fraction_within_bounds() {
        assert!((SelectionState::new(0.5).fraction() - 0.5).abs() < 1e-6);
        assert!((SelectionState::new(0.3).fraction() - 0.3).abs() < 1e-6);
        assert_eq!(SelectionState::new(1.0).fraction(), MAX_FRACTION);
        assert_eq!(SelectionState::new(0.0).fraction(), MIN_FRACTION);
    }

    /// The analytic gradient matches a finite difference of the importance-sampled KL
    /// estimate −(product / wo) · log p_α(θ), regularisation included.
    #[test]
    fn gradient_is_the_derivative_of_the_kl_estimate() {
        let r = rec(0.3, 2.5, 1.1, 0.7);
        for theta in [-2.0f32, -0.3, 0.0, 0.8, 2.5] {
            let mut s = SelectionState::new(0.5);
            s.theta = theta;
            let loss = |t: f64| {
                let a = 1.0 / (1.0 + (-t).exp());
                let mix = a * 0.3 + (1.0 - a) * 2.5;
                -(0.7 / 1.1) * mix.ln() + 0.5 * f64::from(L2_REGULARISATION) * t * t
            };
            let h = 1e-4;
            let t = f64::from(theta);
            let numeric = (loss(t + h) - loss(t - h)) / (2.0 * h);
            let analytic = f64::from(s.gradient(&r).unwrap());
            assert!(
                (numeric - analytic).abs() < 1e-4 * (1.0 + numeric.abs()),
                "θ {theta}: numeric {numeric}, analytic {analytic}"
            );
        }
    }

    /// Samples where the quadtree's pdf is the larger push α down, where the BSDF's is,
    /// up; bad records are ignored.
    #[test]
    fn steps_go_toward_the_better_technique() {
        let mut s = SelectionState::new(0.5);
        for _ in 0..1000 {
            s.append(&rec(0.1, 3.0, 1.0, 1.0));
        }
        assert!(s.fraction() < 0.2, "{}", s.fraction());
        let mut s = SelectionState::new(0.5);
        for _ in 0..1000 {
            s.append(&rec(3.0, 0.1, 1.0, 1.0));
        }
        assert!(s.fraction() > 0.8, "{}", s.fraction());
        let before = s;
        s.append(&rec(f32::NAN, 0.1, 1.0, 1.0));
        s.append(&rec(1.0, 0.1, 0.0, 1.0));
        s.append(&rec(1.0, 0.1, 1.0, 0.0));
        assert_eq!(s, before);
        for _ in 0..10_000 {
            s.append(&rec(3.0, 0.0, 1.0, 1.0));
        }
        assert_eq!(s.fraction(), MAX_FRACTION);
    }

    /// On a stationary problem Adam reaches the α minimising the KL divergence: the
    /// integrand is a mixture of a BSDF-shaped and a guide-shaped part in proportion
    /// w : 1 − w over two disjoint direction sets, so the best mixture is α = w.
    #[test]
    fn converges_to_the_kl_optimum() {
        for w in [0.2f32, 0.5, 0.8] {
            let mut s = SelectionState::new(0.5);
            let mut x = 12345u64;
            for _ in 0..100_000 {
                x = super::super::sdtree::hash64(x);
                let u = (x >> 40) as f32 / (1u64 << 24) as f32;
                let a = s.fraction();
                // Disjoint supports: BSDF pdf 2 on half A, guide pdf 2 on half B; the
                // integrand puts w on A and 1 − w on B (density 2w and 2(1 − w)).
                let (b, g, product) = if u < a {
                    (2.0, 0.0, 2.0 * w)
                } else {
                    (0.0, 2.0, 2.0 * (1.0 - w))
                };
                let wo = a * b + (1.0 - a) * g;
                s.append(&rec(b, g, wo, product));
            }
            let f = s.fraction();
            assert!((f - w).abs() < 0.05, "w {w}: learned {f}");
        }
    }
}
