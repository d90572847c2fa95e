//! The training schedule: iteration k renders 2^k samples per pixel (Müller et al. 2017,
//! §5.1: doubling keeps each tree trained on as many samples as all earlier ones
//! together), refitting the SD-tree after each; a fraction of the budget (default 0.3)
//! goes to training, the rest renders with the final tree. Budgets are in samples per
//! pixel or in seconds; for seconds the caller reports each iteration's duration and the
//! schedule predicts the next one (twice as many samples: twice the time), the last
//! iteration filling the training time that is left.

/// Default share of the budget spent training.
pub const DEFAULT_TRAIN_FRACTION: f64 = 0.3;

/// A budget in samples per pixel, split into training iterations and the final render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SppSchedule {
    /// Samples per pixel of each training iteration: 1, 2, 4, …
    pub training: Vec<u32>,
    /// Samples per pixel rendered with the final tree.
    pub final_spp: u32,
}

impl SppSchedule {
    /// As many doubling iterations as fit in `train_fraction` of `total_spp` (never
    /// all of it: at least one sample is rendered with the final tree).
    pub fn new(total_spp: u32, train_fraction: f64) -> Self {
        let budget = (f64::from(total_spp) * train_fraction.clamp(0.0, 1.0)).floor() as u64;
        let budget = budget.min(u64::from(total_spp.saturating_sub(1)));
        let mut training = Vec::new();
        let mut used = 0u64;
        while let Some(next) = 1u64.checked_shl(training.len() as u32) {
            if used + next > budget {
                break;
            }
            used += next;
            training.push(next as u32);
        }
        Self {
            training,
            final_spp: total_spp - used as u32,
        }
    }

    /// Training alone: the doubling iterations whose total fits in `total_spp`; the
    /// last refit prepares the tree for twice the last iteration's samples (what another
    /// iteration would render), since the renders that follow are not known yet.
    pub fn training_only(total_spp: u32) -> Self {
        let mut s = Self::new(total_spp.saturating_add(1), 1.0);
        s.final_spp = s.training.last().map_or(1, |&last| last.saturating_mul(2));
        s
    }

    pub fn training_spp(&self) -> u32 {
        self.training.iter().sum()
    }

    /// Samples per pixel of the iteration after training iteration `k` (what
    /// `SdTree::refit` wants): the next training iteration's, or the final render's.
    pub fn spp_after(&self, k: usize) -> u32 {
        self.training.get(k + 1).copied().unwrap_or(self.final_spp)
    }
}

/// A budget in seconds: decides after each training iteration how many samples per
/// pixel the next one renders. Iterations double while the one after the next would
/// still fit; otherwise the next iteration is the last and takes all of the training
/// time that is left, at the speed the finished iteration measured (the reference
/// implementation's rule for sample budgets, "the last iteration uses at least half of
/// what is left", carried over to seconds). Stopping before a doubled iteration that does
/// not fit, as this schedule did until 2026-11-27, used between half and all of the
/// training time, 16–18 % of the total instead of 30 % in most runs on the H200.
#[derive(Clone, Debug)]
pub struct TimeSchedule {
    train_budget_s: f64,
    elapsed_s: f64,
    iteration: u32,
    last: bool,
}

impl TimeSchedule {
    pub fn new(total_seconds: f64, train_fraction: f64) -> Self {
        Self {
            train_budget_s: total_seconds.max(0.0) * train_fraction.clamp(0.0, 1.0),
            elapsed_s: 0.0,
            iteration: 0,
            last: false,
        }
    }

    /// Samples per pixel of the first training iteration, or None if the training
    /// budget is zero.
    pub fn first(&self) -> Option<u32> {
        (self.train_budget_s > 0.0).then_some(1)
    }

    /// After an iteration of `spp` samples per pixel that took `seconds` (its render and
    /// the refit), the samples per pixel of the next training iteration, or None when
    /// training is over. The next iteration's time is predicted from this one's time per
    /// sample, so a doubled iteration takes twice as long.
    pub fn next(&mut self, seconds: f64, spp: u32) -> Option<u32> {
        self.elapsed_s += seconds.max(0.0);
        self.iteration += 1;
        if self.last {
            return None;
        }
        let doubled = 1u32.checked_shl(self.iteration)?;
        let per_spp = seconds.max(0.0) / f64::from(spp.max(1));
        let left = self.train_budget_s - self.elapsed_s;
        let t = f64::from(doubled) * per_spp;
        if t + 2.0 * t <= left {
            return Some(doubled);
        }
        // The iteration after the next would not fit: the next one is the last and
        // takes what is left, if that is at least this iteration's count (a tree learned
        // from fewer samples than the current one would be no better; passes slower than
        // predicted get here with less than a doubled iteration left).
        self.last = true;
        if per_spp <= 0.0 {
            return Some(doubled);
        }
        let fill = (left / per_spp).floor().min(f64::from(u32::MAX)).max(0.0) as u32;
        (fill >= spp.max(1)).then_some(fill)
    }

    /// Training seconds spent so far.
    pub fn elapsed(&self) -> f64 {
        self.elapsed_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spp_schedules() {
        let s = SppSchedule::new(64, 0.3);
        assert_eq!(s.training, vec![1, 2, 4, 8]);
        assert_eq!(s.final_spp, 49);
        assert_eq!(s.spp_after(0), 2);
        assert_eq!(s.spp_after(3), 49);
        let s = SppSchedule::new(1024, 0.3);
        assert_eq!(s.training_spp(), 255);
        assert_eq!(s.final_spp, 769);
        assert_eq!(SppSchedule::new(2, 0.3).training, Vec::<u32>::new());
        assert_eq!(SppSchedule::new(4, 0.3).training, vec![1]);
        // Everything for training still leaves one sample for the final tree.
        let s = SppSchedule::new(4, 1.0);
        assert_eq!((s.training, s.final_spp), (vec![1, 2], 1));
        assert_eq!(SppSchedule::new(0, 0.3).final_spp, 0);
    }

    #[test]
    fn training_only_schedules() {
        let s = SppSchedule::training_only(15);
        assert_eq!((s.training.clone(), s.final_spp), (vec![1, 2, 4, 8], 16));
        assert_eq!(s.spp_after(2), 8);
        assert_eq!(SppSchedule::training_only(14).training, vec![1, 2, 4]);
        assert_eq!(SppSchedule::training_only(1).training, vec![1]);
        assert!(SppSchedule::training_only(0).training.is_empty());
    }

    #[test]
    fn time_schedule() {
        // Doubling while the iteration after the next fits, then one iteration that
        // fills the training time: 1 + 2 + 4 + 23 = 30 s of the 30 s (15 s before).
        let mut s = TimeSchedule::new(100.0, 0.3);
        assert_eq!(s.first(), Some(1));
        assert_eq!(s.next(1.0, 1), Some(2)); // 2 + 4 ≤ 29 left
        assert_eq!(s.next(2.0, 2), Some(4)); // 4 + 8 ≤ 27
        assert_eq!(s.next(4.0, 4), Some(23)); // 8 + 16 > 23: the last takes the 23 s left
        assert_eq!(s.next(23.0, 23), None);
        assert_eq!(s.elapsed(), 30.0);
        assert_eq!(TimeSchedule::new(100.0, 0.0).first(), None);

        // The time per sample comes from the finished iteration, whatever its count.
        let mut s = TimeSchedule::new(100.0, 0.5);
        assert_eq!(s.next(0.5, 1), Some(2)); // 0.5 s per spp: 1 + 2 s ≤ 49.5
        assert_eq!(s.next(1.0, 2), Some(4));
        assert_eq!(s.next(2.0, 4), Some(8));
        assert_eq!(s.next(4.0, 8), Some(16)); // 8 + 16 ≤ 42.5
        assert_eq!(s.next(8.0, 16), Some(69)); // 16 + 32 > 34.5: floor(34.5 / 0.5)
        assert_eq!(s.next(34.5, 69), None);

        // Less time left than this iteration's count takes ends training (a slow first
        // pass: a kernel compile).
        let mut s = TimeSchedule::new(10.0, 0.3);
        assert_eq!(s.next(2.5, 1), None); // 0.5 s left: not even 1 spp at 2.5 s each

        // A pass slower than predicted leaves less than a doubled iteration: the last
        // one takes what is left when that is at least the slow pass's count.
        let mut s = TimeSchedule::new(100.0, 0.3);
        assert_eq!(s.next(1.0, 1), Some(2));
        assert_eq!(s.next(2.0, 2), Some(4));
        assert_eq!(s.next(12.0, 4), Some(5)); // 15 s left at 3 s per spp: 8 do not fit
        assert_eq!(s.next(15.0, 5), None);
        let mut s = TimeSchedule::new(100.0, 0.3);
        assert_eq!(s.next(1.0, 1), Some(2));
        assert_eq!(s.next(2.0, 2), Some(4));
        assert_eq!(s.next(16.0, 4), None); // 11 s left at 4 s per spp: 2 < 4

        // A doubled iteration fits but the one after it does not: the last takes it all.
        let mut s = TimeSchedule::new(10.0, 1.0);
        assert_eq!(s.next(1.0, 1), Some(2));
        assert_eq!(s.next(2.0, 2), Some(7)); // 4 + 8 > 7 left: floor(7 / 1)
    }
}
