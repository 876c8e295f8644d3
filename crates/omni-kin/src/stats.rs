//! Summary statistics of an error over runs or pose pairs, as evo prints them (`evo_ape`, `evo_rpe`):
//! mean, median, root mean square and largest, of the values' absolute values, in the values' unit.

use serde::{Deserialize, Serialize};

/// Summary statistics of one error (of its absolute values), in the error's unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Median (the mean of the two middle values for an even count, as numpy's).
    pub median: f64,
    /// Root mean square.
    pub rmse: f64,
    /// Largest.
    pub max: f64,
}

impl Stats {
    /// The statistics of no value: NaN each (`null` in JSON).
    pub const NONE: Stats = Stats { mean: f64::NAN, median: f64::NAN, rmse: f64::NAN, max: f64::NAN };

    /// The statistics of `values`' absolute values ([`Self::NONE`] for none). Sums in the given order.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values.into_iter().map(f64::abs).collect();
        if v.is_empty() {
            return Self::NONE;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Self {
            mean: v.iter().sum::<f64>() / n as f64,
            median,
            rmse: (v.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt(),
            max: v[n - 1],
        }
    }

    /// Every statistic times `k` (a change of unit, `k` ≥ 0).
    pub fn scaled(self, k: f64) -> Self {
        Self { mean: k * self.mean, median: k * self.median, rmse: k * self.rmse, max: k * self.max }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_of_absolute_values() {
        let s = Stats::of([3.0, -4.0, 1.0, 0.0]);
        assert_eq!((s.mean, s.median, s.max), (2.0, 2.0, 4.0));
        assert!((s.rmse - (26.0f64 / 4.0).sqrt()).abs() < 1e-15);
        assert_eq!(Stats::of([-2.0, 5.0, 1.0]).median, 2.0);
        assert!(Stats::of([]).mean.is_nan());
        assert_eq!(Stats::of([1.0, 3.0]).scaled(10.0).max, 30.0);
    }
}
