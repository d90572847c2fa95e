//! Each leaf's mixing probability of learned light selection. NEE at a shading point in
//! a leaf with a learned light table T chooses light models from the defensive mixture
//!
//!   p_m(i) = (1 − m)·s(i) + m·T(i)       (s: the source distribution, m: the mix).
//!
//! One m for the whole scene is too bold where a table was learned from few or
//! misleading estimates (the street at small budgets: every lamp contributes a little,
//! and a table of 16 models concentrates on the first ones it met) and too timid where
//! the table knows which few lights are visible. So each leaf picks its own m between
//! passes: the one that minimises the predicted second moment of its NEE estimates.
//!
//! An NEE estimate v (luminance) that chose model i under p_m, the mixture the pass
//! sampled with, predicts by importance reweighting the second moment of one-sample NEE
//! under any other mix m' (c the visible integrand; only the model's pmf differs):
//!
//!   E_m'[v²] = Σ_i E[c²|i] / p_m'(i) = E_m[ v² · p_m(i) / p_m'(i) ],
//!   p_m(i)/p_m'(i) = ((1 − m) + m·r_i) / ((1 − m') + m'·r_i),   r_i = T(i)/s(i).
//!
//! So the per-model sums of v² the GPU records (`GuideLightTrainingSlot.second`) and the
//! leaf's total (for the models outside T, r = 0) predict every m' at once. The table judged is
//! the one the pass sampled with, learned from earlier passes and so independent of the
//! estimates that judge it (a table judged by the estimates it was learned from would
//! look better than it is); the chosen m' then goes with the new table, learned from
//! twice the samples.
//!
//! This is exact for one-sample NEE (`guided`), the default there. For RIS NEE
//! (`guided-ris`) it is a proxy, and so is the first-order analysis of RIS (its second
//! moment is ∫p̂·∫f + (∫f²/q − ∫p̂·∫f)/M to first order in 1/M, so q only decides ∫f²/q,
//! which the RIS estimate times the kept point's f/q estimates without bias): at 80×45,
//! 1,024 spp both chose mixes near 0 on `bistro-night` and lost to the fixed 0.5
//! (`guided-ris`/`ris` 0.93 and 0.98 against 0.87), where 32 candidates among 600 light
//! models are far from the large-M limit. `guided-ris` keeps the fixed mix by default.
//!
//! Only which m a leaf uses depends on the estimates; every m keeps every light
//! samplable (m ≤ `MAX_LEARNED_MIX` < 1), and the kernels use the mixture's pdf, so
//! rendering stays unbiased.

/// Largest mix a leaf learns: the source keeps at least a tenth of every light's
/// probability. It was 0.5 for a few hours on 2026-11-27, after random scenes of point,
/// spot and box lights (scripts/random_scene.py seeds 16, 19, 20) rendered `guided` at
/// 1.7-3.5x `pt`'s MAE with 0.9; the cause was that punctual lights never reached the
/// tables (NEE named no model for them), so the prediction never saw their estimates.
/// With that fixed, 0.9 beats 0.5 on all six random scenes (`guided`/`pt` 0.39-0.58
/// against 0.48-0.69, three seeds) and on `cornell-lights` (0.45 against 0.53), level on
/// the street and `bistro-night` (README, "The learned mix").
pub const MAX_LEARNED_MIX: f32 = 0.9;
/// Candidate mixes are 0, 1/STEPS·MAX_LEARNED_MIX, …, MAX_LEARNED_MIX.
const STEPS: u32 = 18;

/// What the GPU recorded for one light model in one leaf during a pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSums {
    pub model: u32,
    /// Σ v: the model's contribution (becomes its table probability, normalised).
    pub value: f32,
    /// Σ v².
    pub second: f32,
}

/// The mix for a leaf's next table: the candidate with the least predicted second
/// moment of NEE, judged with `table` (the one the pass sampled with, mixed with `mix`).
/// `recorded`: the pass's per-model sums; `second_total`: Σ v² over all of the leaf's NEE
/// estimates; `source_pmf`: s(i). None when there is nothing to judge by (no table, or
/// no light recorded).
pub fn choose_mix(
    table: &[(u32, f32)],
    mix: f32,
    recorded: &[LightSums],
    second_total: f32,
    source_pmf: impl Fn(u32) -> f32,
) -> Option<f32> {
    if table.is_empty() || !(second_total.is_finite() && second_total > 0.0) {
        return None;
    }
    let m = f64::from(mix);
    // (Σ v², r) of each recorded model in the table; everything else has r = 0.
    let mut in_table = Vec::with_capacity(table.len());
    let mut table_second = 0.0;
    for s in recorded {
        let Some(&(_, t)) = table.iter().find(|(model, _)| *model == s.model) else {
            continue;
        };
        let src = source_pmf(s.model);
        if src > 0.0 && s.second.is_finite() && s.second > 0.0 {
            in_table.push((f64::from(s.second), f64::from(t) / f64::from(src)));
            table_second += f64::from(s.second);
        }
    }
    let rest = (f64::from(second_total) - table_second).max(0.0);
    let predicted = |mp: f64| {
        rest * (1.0 - m) / (1.0 - mp)
            + in_table
                .iter()
                .map(|&(second, r)| second * ((1.0 - m) + m * r) / ((1.0 - mp) + mp * r))
                .sum::<f64>()
    };
    let mut best = (f64::INFINITY, 0.0f32);
    for k in 0..=STEPS {
        let candidate = MAX_LEARNED_MIX * (k as f32 / STEPS as f32);
        let cost = predicted(f64::from(candidate));
        // Strictly less: ties keep the smaller, more defensive mix.
        if cost < best.0 {
            best = (cost, candidate);
        }
    }
    best.0.is_finite().then_some(best.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums(model: u32, second: f32) -> LightSums {
        LightSums {
            model,
            value: second.sqrt(),
            second,
        }
    }

    #[test]
    fn a_table_holding_the_light_that_arrives_is_trusted() {
        // 100 models, uniform source; the table puts 0.9 on model 7, and every estimate
        // came from model 7: sampling it more can only help, so the largest mix wins.
        let table = [(7, 0.9), (3, 0.1)];
        let m = choose_mix(&table, 0.5, &[sums(7, 10.0)], 10.0, |_| 0.01).unwrap();
        assert_eq!(m, MAX_LEARNED_MIX);
    }

    #[test]
    fn a_table_that_misses_the_light_is_not_used() {
        // Every estimate came from models outside the table: the table only takes
        // samples away from them.
        let table = [(7, 1.0)];
        let m = choose_mix(&table, 0.5, &[sums(40, 5.0), sums(41, 5.0)], 10.0, |_| 0.01).unwrap();
        assert_eq!(m, 0.0);
    }

    #[test]
    fn the_optimum_of_a_split_between_table_and_source_is_interior() {
        // A tenth of the second moment through a model the table holds with r = 100, the
        // rest through models outside it: the predicted cost
        // S/10·(a/(1−m'+100m')) + 9S/10·(1−m)/(1−m') has its minimum (m' ≈ 0.24) where
        // the derivative vanishes; brute force on a fine grid.
        let table = [(1, 1.0)];
        let rec = [sums(1, 1.0)];
        let m = choose_mix(&table, 0.5, &rec, 10.0, |_| 0.01).unwrap();
        let cost = |mp: f64| 1.0 * 50.5 / (1.0 - mp + 100.0 * mp) + 9.0 * 0.5 / (1.0 - mp);
        let top = f64::from(MAX_LEARNED_MIX);
        let fine = (0..=10000)
            .map(|k| top * k as f64 / 10000.0)
            .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))
            .unwrap();
        assert!(m > 0.0 && m < MAX_LEARNED_MIX, "{m}");
        assert!(
            (f64::from(m) - fine).abs() <= top / f64::from(STEPS) / 2.0 + 1e-6,
            "{m} vs {fine}"
        );
    }

    #[test]
    fn nothing_to_judge_by_keeps_the_caller_s_mix() {
        assert_eq!(choose_mix(&[], 0.5, &[sums(1, 1.0)], 1.0, |_| 0.1), None);
        assert_eq!(choose_mix(&[(1, 1.0)], 0.5, &[], 0.0, |_| 0.1), None);
        assert_eq!(
            choose_mix(&[(1, 1.0)], 0.5, &[], f32::INFINITY, |_| 0.1),
            None
        );
    }
}
