//! The training schedule: iteration k renders 2^k samples per pixel (Müller et al. 2017,
//! §5.1: doubling keeps each tree trained on as many samples as all earlier ones
//! together), refitting the SD-tree after each; a fraction of the budget (default 0.3)
//! goes to training, the rest renders with the final tree. Budgets are in samples per
//! pixel or in seconds; for seconds the caller reports each iteration's duration and the
//! schedule predicts the next one (twice as many samples: twice the time).

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

/// A budget in seconds: decides after each training iteration whether another fits.
#[derive(Clone, Debug)]
pub struct TimeSchedule {
    train_budget_s: f64,
    elapsed_s: f64,
    iteration: u32,
}

impl TimeSchedule {
    pub fn new(total_seconds: f64, train_fraction: f64) -> Self {
        Self {
            train_budget_s: total_seconds.max(0.0) * train_fraction.clamp(0.0, 1.0),
            elapsed_s: 0.0,
            iteration: 0,
        }
    }

    /// Samples per pixel of the first training iteration, or None if the training
    /// budget is zero.
    pub fn first(&self) -> Option<u32> {
        (self.train_budget_s > 0.0).then_some(1)
    }

    /// After an iteration that took `seconds` (its render and the refit), the samples
    /// per pixel of the next training iteration, or None when it would not fit (the
    /// next iteration, with twice the samples, is predicted to take twice as long).
    pub fn next(&mut self, seconds: f64) -> Option<u32> {
        self.elapsed_s += seconds.max(0.0);
        self.iteration += 1;
        let spp = 1u32.checked_shl(self.iteration)?;
        (self.elapsed_s + 2.0 * seconds <= self.train_budget_s).then_some(spp)
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
        let mut s = TimeSchedule::new(100.0, 0.3);
        assert_eq!(s.first(), Some(1));
        assert_eq!(s.next(1.0), Some(2)); // 1 + 2 ≤ 30
        assert_eq!(s.next(2.0), Some(4)); // 3 + 4
        assert_eq!(s.next(4.0), Some(8)); // 7 + 8
        assert_eq!(s.next(8.0), None); // 15 + 16 > 30
        assert_eq!(s.elapsed(), 15.0);
        assert_eq!(TimeSchedule::new(100.0, 0.0).first(), None);
    }
}
