//! Summaries of repeated measurements: every timing the bench reports is the minimum,
//! median and maximum over its repetitions, so one noisy run cannot hide or fake a trend.

/// Minimum, median and maximum of a set of measurements.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (non-finite values are dropped; all zero when none is left).
    pub fn of(values: &[f64]) -> Spread {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return Spread {
                min: 0.0,
                median: 0.0,
                max: 0.0,
            };
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        Spread {
            min: v[0],
            median,
            max: v[n - 1],
        }
    }

    /// The spread of `f` over `items`.
    pub fn over<T>(items: &[T], f: impl Fn(&T) -> f64) -> Spread {
        Spread::of(&items.iter().map(f).collect::<Vec<_>>())
    }

    /// Every statistic multiplied by `k` (k ≥ 0).
    pub fn scaled(self, k: f64) -> Spread {
        Spread {
            min: self.min * k,
            median: self.median * k,
            max: self.max * k,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_even_and_empty() {
        let s = Spread::of(&[3.0, 1.0, 2.0]);
        assert_eq!((s.min, s.median, s.max), (1.0, 2.0, 3.0));
        let s = Spread::of(&[4.0, 1.0, 2.0, 3.0]);
        assert_eq!((s.min, s.median, s.max), (1.0, 2.5, 4.0));
        let s = Spread::of(&[f64::NAN]);
        assert_eq!((s.min, s.median, s.max), (0.0, 0.0, 0.0));
        assert_eq!(Spread::of(&[2.0]).scaled(3.0).median, 6.0);
    }
}
