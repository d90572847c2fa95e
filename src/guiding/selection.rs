//! Learned probability of sampling the BSDF rather than the leaf's quadtree (Müller et
//! al. 2019, "Path guiding in production", §10; the reference implementation's
//! `bsdfSamplingFraction` optimisation). Each spatial leaf holds a logit θ, and α = σ(θ)
//! is its BSDF selection probability for the mixture p_α = α·p_bsdf + (1 − α)·p_guide.
//!
//! The GPU appends one `GuideSelectionRecord` per guided direction sample that carried
//! light (shaders_glsl/inc/guiding_selection.glsl): the two pdfs, the pdf p_wo of the
//! mixture that drew it, and F = f·cos·L_in. Between passes `SdTree::learn_selection`
//! takes each leaf's records and learns in one of two ways (`SelectionLearner`):
//!
//! - `Variance` (the default): the α that minimises the pass's estimate of the
//!   direction estimator's second moment,
//!   V(α) = Σ F² / (p_wo · p_α), with V′(α) = −Σ F² (p_bsdf − p_guide) / (p_wo · p_α²),
//!   convex in α (1/p_α is), so its minimiser over [α_min, α_max] is found by bisection
//!   on V′. That α is averaged with the leaf's current one, weighted by the effective
//!   number of records behind each (Kish's (Σw)²/Σw² of the weights F/p_wo; the start
//!   value counts as `PRIOR_RECORDS`), so that a leaf with a few noisy records moves
//!   little.
//! - `KlAdam` (the reference's): Adam minimises the KL divergence between p_α and the
//!   normalised integrand, one step per two records in the order the GPU appended them,
//!   on D_KL(α) = const − E_wo[ (F / p_wo) · log p_α ], whose derivatives are
//!   ∂D/∂α = −E_wo[ F / (p_wo · p_α) · (p_bsdf − p_guide) ] and
//!   ∂D/∂θ = ∂D/∂α · α(1 − α) (+ 0.01·θ, the reference's L2 regularisation).
//!
//! The GPU samples with the learned α from the next pass on. α is confined to
//! [0.05, 0.95] so that both techniques keep some probability: the BSDF must cover
//! directions where the quadtree's density is zero (unbiasedness), and the quadtree must
//! keep being sampled for its pdf to be learned against.

use super::SelectionLearner;
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

/// Weight of a leaf's starting α in the variance learner, in effective records.
pub const PRIOR_RECORDS: f32 = 64.0;

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
    /// Effective records behind θ (the variance learner's running weight; the start
    /// value counts as `PRIOR_RECORDS`).
    confidence: f32,
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
            && self.confidence == o.confidence
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
            confidence: PRIOR_RECORDS,
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

    /// Learning steps taken: Adam steps, or passes learned from by the variance learner.
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// ∂D_KL/∂θ of one record at the current θ, regularisation included; None for a
    /// record that carries no usable gradient.
    pub fn gradient(&self, r: &GuideSelectionRecord) -> Option<f32> {
        if !usable(r) {
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

    /// The variance learner: move α to the pass's second-moment minimiser, weighted by
    /// the records' effective number against the weight already behind α. Returns the
    /// records used (the others carry no usable value).
    pub fn learn_variance<'a>(
        &mut self,
        records: impl IntoIterator<Item = &'a GuideSelectionRecord>,
    ) -> u64 {
        let used: Vec<Term> = records.into_iter().filter_map(Term::of).collect();
        if used.is_empty() {
            return 0;
        }
        let sum: f64 = used.iter().map(|t| t.weight).sum();
        let sum_sq: f64 = used.iter().map(|t| t.weight * t.weight).sum();
        let effective = (sum * sum / sum_sq) as f32;
        if !(effective.is_finite() && effective > 0.0) {
            return 0;
        }
        let best = second_moment_minimiser(&used);
        let alpha =
            (self.confidence * self.fraction() + effective * best) / (self.confidence + effective);
        self.theta = logit(alpha.clamp(MIN_FRACTION, MAX_FRACTION));
        self.confidence += effective;
        self.restored = None;
        self.steps += 1;
        used.len() as u64
    }
}

/// Whether a record carries a usable value (finite, non-negative pdfs, light, a
/// positive pdf of the technique that drew it).
fn usable(r: &GuideSelectionRecord) -> bool {
    let ok = |x: f32| x.is_finite() && x >= 0.0;
    ok(r.bsdf_pdf)
        && ok(r.guide_pdf)
        && ok(r.product)
        && r.product > 0.0
        && r.wo_pdf.is_finite()
        && r.wo_pdf > 0.0
}

/// What the variance learner keeps of one usable record, in f64 (the ratios span many
/// decades).
struct Term {
    /// F / p_wo: the record's importance weight (for the effective record count).
    weight: f64,
    /// F² / p_wo: its share of the second moment, up to the 1/p_α that α changes.
    second: f64,
    /// p_bsdf − p_guide and p_guide: p_α = p_guide + α·(p_bsdf − p_guide).
    difference: f64,
    guide: f64,
}

impl Term {
    fn of(r: &GuideSelectionRecord) -> Option<Term> {
        if !usable(r) {
            return None;
        }
        let (wo, f) = (f64::from(r.wo_pdf), f64::from(r.product));
        let guide = f64::from(r.guide_pdf);
        Some(Term {
            weight: f / wo,
            second: f * f / wo,
            difference: f64::from(r.bsdf_pdf) - guide,
            guide,
        })
    }
}

/// argmin over α in [MIN_FRACTION, MAX_FRACTION] of V(α) = Σ F²/(p_wo·p_α): V is
/// convex, so bisection on V′.
fn second_moment_minimiser(terms: &[Term]) -> f32 {
    let slope = |a: f64| -> f64 {
        terms
            .iter()
            .map(|t| {
                let p = t.guide + a * t.difference;
                if p > 0.0 {
                    -t.second * t.difference / (p * p)
                } else {
                    0.0
                }
            })
            .sum()
    };
    let (mut lo, mut hi) = (f64::from(MIN_FRACTION), f64::from(MAX_FRACTION));
    if slope(lo) >= 0.0 {
        return MIN_FRACTION;
    }
    if slope(hi) <= 0.0 {
        return MAX_FRACTION;
    }
    // 2⁻²⁴ of the interval: below f32's resolution of α.
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)) as f32
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
        let learner = self.config.selection_learner;
        let learned = super::parallel::map_mut_by_cost(&mut self.leaves, &cost, |l, leaf| {
            let mine = &order[start[l]..start[l + 1]];
            if learner == SelectionLearner::Variance {
                let used = leaf
                    .selection
                    .learn_variance(mine.iter().map(|&i| &records[i as usize]));
                return (used, mine.len());
            }
            let mut used = 0u64;
            for &i in mine {
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

    /// A stationary problem on [0, 1) where the second moment and the KL divergence
    /// have different minimisers: BSDF pdf 1 everywhere, quadtree pdf 2 on [0, ½);
    /// integrand 4 on [0, ¼), 0 on [¼, ½), 1 on [½, 1). Then
    ///   V(α) = ∫F²/p_α = 4/(2 − α) + ½/α,  minimised at α = √2/(2 + 1/√2) ≈ 0.5224,
    ///   KL:  −∫F log p_α = −log(2 − α) − ½ log α, minimised at α = ⅔.
    /// Records are drawn from the current mixture in passes of doubling size, as the
    /// kernel makes them.
    fn stationary_records(alpha: f32, n: usize, seed: &mut u64) -> Vec<GuideSelectionRecord> {
        let mut out = Vec::new();
        let mut uniform = || {
            *seed = super::super::sdtree::hash64(*seed);
            (*seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..n {
            let x = if uniform() < alpha {
                uniform()
            } else {
                0.5 * uniform()
            };
            let g = if x < 0.5 { 2.0 } else { 0.0 };
            let f = if x < 0.25 {
                4.0
            } else if x < 0.5 {
                0.0
            } else {
                1.0
            };
            if f > 0.0 {
                out.push(rec(1.0, g, alpha + (1.0 - alpha) * g, f));
            }
        }
        out
    }

    const SECOND_MOMENT_OPTIMUM: f32 = 0.522_407;

    #[test]
    fn the_optimum_is_what_the_docs_say() {
        let v = |a: f64| 4.0 / (2.0 - a) + 0.5 / a;
        let best = (1..10_000)
            .map(|i| f64::from(i) / 10_000.0)
            .min_by(|a, b| v(*a).total_cmp(&v(*b)))
            .unwrap();
        assert!((best as f32 - SECOND_MOMENT_OPTIMUM).abs() < 2e-4, "{best}");
    }

    /// The bisection returns the minimiser of the records' own second-moment estimate
    /// Σ F²/(p_wo·p_α), found again by brute force over α, for record sets drawn from
    /// mixtures with different α (so p_wo varies between records).
    #[test]
    fn minimiser_of_the_estimate() {
        let mut seed = 7u64;
        for drawn_with in [0.2f32, 0.5, 0.9] {
            let records = stationary_records(drawn_with, 300, &mut seed);
            let estimate = |a: f64| -> f64 {
                records
                    .iter()
                    .map(|r| {
                        let p = a * f64::from(r.bsdf_pdf) + (1.0 - a) * f64::from(r.guide_pdf);
                        f64::from(r.product).powi(2) / (f64::from(r.wo_pdf) * p)
                    })
                    .sum()
            };
            let brute = (0..=9000)
                .map(|i| 0.05 + 0.9 * f64::from(i) / 9000.0)
                .min_by(|a, b| estimate(*a).total_cmp(&estimate(*b)))
                .unwrap() as f32;
            let terms: Vec<Term> = records.iter().filter_map(Term::of).collect();
            let found = second_moment_minimiser(&terms);
            assert!(
                (found - brute).abs() < 2e-4,
                "drawn with α {drawn_with}: bisection {found}, brute force {brute}"
            );
        }
    }

    /// Pass after pass of records drawn with the learned α, the variance learner ends
    /// at the second moment's minimiser (0.522), not the KL divergence's (0.667).
    #[test]
    fn variance_learner_reaches_the_second_moment_optimum() {
        let mut s = SelectionState::new(0.5);
        let mut seed = 99u64;
        for pass in 0..16 {
            let records = stationary_records(s.fraction(), 2 << pass, &mut seed);
            s.learn_variance(&records);
        }
        let f = s.fraction();
        assert!(
            (f - SECOND_MOMENT_OPTIMUM).abs() < 0.02,
            "learned {f}, optimum {SECOND_MOMENT_OPTIMUM}"
        );
    }

    /// A leaf moves by the weight of its records: a handful that all favour the BSDF
    /// move α a little, many move it to the bound; records without light change nothing.
    #[test]
    fn variance_learner_moves_by_the_records_behind_it() {
        let favour_bsdf = |n| vec![rec(3.0, 0.1, 1.55, 1.0); n];
        let mut s = SelectionState::new(0.5);
        assert_eq!(s.learn_variance(&favour_bsdf(4)), 4);
        // (64·0.5 + 4·0.95) / 68
        assert!((s.fraction() - 0.5265).abs() < 1e-3, "{}", s.fraction());
        let mut s = SelectionState::new(0.5);
        s.learn_variance(&favour_bsdf(100_000));
        assert!(s.fraction() > 0.94, "{}", s.fraction());
        let before = s;
        let bad = [
            rec(f32::NAN, 0.1, 1.0, 1.0),
            rec(1.0, 0.1, 0.0, 1.0),
            rec(1.0, 0.1, 1.0, 0.0),
        ];
        assert_eq!(s.learn_variance(&bad), 0);
        assert_eq!(s, before);
    }
}
