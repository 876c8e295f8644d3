//! Relative pose error (RPE) as evo's `evo_rpe` computes it (Sturm et al. 2012, the TUM RGB-D
//! benchmark), in SE(2): how wrong the model's odometry is over a window of travel, whatever error it
//! accumulated before the window.
//!
//! For a pair of ground-truth samples `(i, j)`, with `Q` the ground truth (reference) and `P` the model's
//! odometry at the same stamps (estimate), the error is the relative motion of the estimate seen from the
//! reference's:
//!
//! $$ E_{ij} = (Q_i^{-1} Q_j)^{-1} \\, (P_i^{-1} P_j) $$
//!
//! Its translation error is `|t(E)|` (m), its rotation error `|θ(E)|` wrapped to [0, π] (rad), and its
//! drift `100 |t(E)| / d_ij` (% of distance), `d_ij` the ground truth's path length from `i` to `j` (the
//! KITTI odometry benchmark's ratio, averaged over pairs).
//!
//! Pairs: evo's consecutive pairs (`all_pairs` off), taken on the ground truth (`evo_rpe
//! --pairs_from_reference`; evo's default takes them on the estimate, so a scale error would move them).
//! Starting at sample 0, the window is accumulated sample by sample: for a distance window the length of
//! each step `sqrt(dx² + dy²)`, for a time window the time since the pair's first sample; the first sample
//! where it reaches `Δ` (`≥ Δ`) ends the pair and starts the next one (the overshoot is dropped, as evo's).
//! So the pairs chain `(0, k1), (k1, k2), …`, each spanning at least `Δ`; a run shorter than `Δ` has none.
//! evo has no time unit: the time window is this rule with elapsed time in place of distance.
//!
//! Plain data: no I/O. The model's odometry at the ground-truth stamps is read off the evaluator's errors
//! at every pose ([`crate::odometry::Selection::Path`]`(1)`), the numbers `eval` already reports.

use crate::error::KinError;
use crate::evaluate::RunErrors;
use crate::pose::{Pose2, PoseError, StampedPose, wrap_angle};
use crate::run::Run;
use crate::stats::Stats;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Pairs of a time window shorter than this path length (m) are left out of the drift: standing still,
/// the ratio is the ground truth's noise over nothing. A distance window's pairs all count.
pub const DRIFT_MIN_DISTANCE_M: f64 = 0.1;

/// The window between the two poses of a pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RpeDelta {
    /// A distance travelled by the ground truth (evo's `--delta D --delta_unit m`). m, > 0.
    DistanceM(f64),
    /// A time. s, > 0.
    TimeS(f64),
}

impl RpeDelta {
    /// The default window: 1 m of travel (evo's `--delta 1 --delta_unit m`).
    pub const DEFAULT: RpeDelta = RpeDelta::DistanceM(1.0);

    /// The window's size in its unit (m or s).
    pub fn value(&self) -> f64 {
        match *self {
            RpeDelta::DistanceM(v) | RpeDelta::TimeS(v) => v,
        }
    }

    /// The unit's symbol: `m` or `s`.
    pub fn unit(&self) -> &'static str {
        match self {
            RpeDelta::DistanceM(_) => "m",
            RpeDelta::TimeS(_) => "s",
        }
    }

    /// The shortest path (m) of a pair that counts in the drift.
    pub fn drift_min_distance_m(&self) -> f64 {
        match self {
            RpeDelta::DistanceM(_) => 0.0,
            RpeDelta::TimeS(_) => DRIFT_MIN_DISTANCE_M,
        }
    }
}

impl Default for RpeDelta {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl fmt::Display for RpeDelta {
    /// `1m`, `2.5s`: the spelling [`FromStr`] reads.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.value(), self.unit())
    }
}

/// Why a window's spelling is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RpeDeltaError {
    /// No unit, or one other than `m` and `s`.
    #[error("expected a distance in metres or a time in seconds, as 1m or 2s")]
    Unit,
    /// The number before the unit does not parse, or is not finite.
    #[error("`{0}` is not a finite number (expected a distance in metres or a time in seconds, as 1m or 2s)")]
    Number(String),
    /// Zero or negative.
    #[error("the window must be longer than 0 (got {0}{1})")]
    NotPositive(f64, &'static str),
}

impl FromStr for RpeDelta {
    type Err = RpeDeltaError;

    /// `1m`, `0.5 m`, `2s`: a positive, finite number and its unit, `m` (distance travelled) or `s` (time).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        let (number, make, unit): (&str, fn(f64) -> RpeDelta, &'static str) = if let Some(n) = s.strip_suffix('m') {
            (n, RpeDelta::DistanceM, "m")
        } else if let Some(n) = s.strip_suffix('s') {
            (n, RpeDelta::TimeS, "s")
        } else {
            return Err(RpeDeltaError::Unit);
        };
        let number = number.trim();
        let v: f64 = match number.parse() {
            Ok(v) => v,
            // `1km`, `m`: another unit, or none.
            Err(_) if number.is_empty() || number.ends_with(|c: char| c.is_alphabetic()) => {
                return Err(RpeDeltaError::Unit);
            }
            Err(_) => return Err(RpeDeltaError::Number(number.into())),
        };
        if !v.is_finite() {
            return Err(RpeDeltaError::Number(number.into()));
        }
        if v <= 0.0 {
            return Err(RpeDeltaError::NotPositive(v, unit));
        }
        Ok(make(v))
    }
}

/// The error of one pair of ground-truth samples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairError {
    /// Index of the pair's first ground-truth sample in its run.
    pub from: usize,
    /// Index of its last.
    pub to: usize,
    /// `|t(E)|`: the relative motion's position error. m.
    pub translation_m: f64,
    /// `|θ(E)|`: the relative motion's heading error, in [0, π]. rad.
    pub rotation_rad: f64,
    /// The ground truth's path length from `from` to `to`. m.
    pub distance_m: f64,
    /// The time from `from` to `to`. s.
    pub duration_s: f64,
}

impl PairError {
    /// The translation error in % of the distance travelled (infinite for a pair that did not move).
    pub fn drift_pct(&self) -> f64 {
        100.0 * self.translation_m / self.distance_m
    }
}

/// evo's consecutive pairs of `reference`'s samples for window `delta` (the module's rule).
pub fn pairs(reference: &[StampedPose], delta: RpeDelta) -> Vec<(usize, usize)> {
    let Some(first) = reference.first() else { return Vec::new() };
    let mut ids = vec![0];
    let mut travelled = 0.0;
    let mut start_s = first.t_s;
    for (k, w) in reference.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let reached = match delta {
            RpeDelta::DistanceM(d) => {
                let (dx, dy) = (b.pose.x_m - a.pose.x_m, b.pose.y_m - a.pose.y_m);
                travelled += (dx * dx + dy * dy).sqrt();
                travelled >= d
            }
            RpeDelta::TimeS(t) => b.t_s - start_s >= t,
        };
        if reached {
            ids.push(k + 1);
            travelled = 0.0;
            start_s = b.t_s;
        }
    }
    ids.windows(2).map(|w| (w[0], w[1])).collect()
}

/// `E = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j)`: the estimate's relative motion `p_i → p_j` seen from the reference's
/// `q_i → q_j`.
pub fn relative_pose_error(q_i: &Pose2, q_j: &Pose2, p_i: &Pose2, p_j: &Pose2) -> Pose2 {
    let reference = q_i.inverse().compose(q_j);
    let estimate = p_i.inverse().compose(p_j);
    reference.inverse().compose(&estimate)
}

/// The error of each of evo's pairs ([`pairs`] on `reference`) of an estimate given at `reference`'s
/// stamps (one pose each, in order).
pub fn pair_errors(reference: &[StampedPose], estimate: &[Pose2], delta: RpeDelta) -> Result<Vec<PairError>, KinError> {
    if estimate.len() != reference.len() {
        return Err(KinError::Shape {
            what: "estimated poses (one per reference pose)".into(),
            got: estimate.len(),
            expected: reference.len(),
        });
    }
    let mut along = Vec::with_capacity(reference.len());
    let mut d = 0.0;
    for (k, q) in reference.iter().enumerate() {
        if k > 0 {
            let p = reference[k - 1].pose;
            d += (q.pose.x_m - p.x_m).hypot(q.pose.y_m - p.y_m);
        }
        along.push(d);
    }
    Ok(pairs(reference, delta)
        .into_iter()
        .map(|(i, j)| {
            let e = relative_pose_error(&reference[i].pose, &reference[j].pose, &estimate[i], &estimate[j]);
            PairError {
                from: i,
                to: j,
                translation_m: e.x_m.hypot(e.y_m),
                rotation_rad: wrap_angle(e.theta_rad).abs(),
                distance_m: along[j] - along[i],
                duration_s: reference[j].t_s - reference[i].t_s,
            }
        })
        .collect())
}

/// The model's odometry at every ground-truth sample of a run: the first sample itself (odometry starts
/// there), then each sample plus its error (`errors_after_first`: one per later sample, as the evaluator
/// gives them at [`crate::odometry::Selection::Path`]`(1)`).
pub fn estimate_at_truth(truth: &[StampedPose], errors_after_first: &[PoseError]) -> Vec<Pose2> {
    let first = truth.first().map(|s| s.pose);
    let later = truth
        .iter()
        .skip(1)
        .zip(errors_after_first)
        .map(|(q, e)| Pose2::new(q.pose.x_m + e.dx_m, q.pose.y_m + e.dy_m, q.pose.theta_rad + e.dtheta_rad));
    first.into_iter().chain(later).collect()
}

/// Every run's odometry at its ground-truth samples ([`estimate_at_truth`]) from its errors at every
/// ground-truth pose after the first (`errors` from an evaluator at
/// [`crate::odometry::Selection::Path`]`(1)`, in run order); errors at other poses are refused, naming the
/// run.
pub fn estimates_at_truth(runs: &[Run], errors: &RunErrors) -> Result<Vec<Vec<Pose2>>, KinError> {
    if errors.n_runs() != runs.len() {
        return Err(KinError::Shape { what: "runs' errors".into(), got: errors.n_runs(), expected: runs.len() });
    }
    runs.iter()
        .enumerate()
        .map(|(i, r)| {
            let (truth, e) = (r.truth(), errors.run(i));
            if e.len() + 1 != truth.len() {
                return Err(KinError::Shape {
                    what: format!("run {}: errors at the ground-truth poses after the first", r.name()),
                    got: e.len(),
                    expected: truth.len() - 1,
                });
            }
            Ok(estimate_at_truth(truth, e))
        })
        .collect()
}

/// Statistics of the pair errors of one run or of all.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RpeSummary {
    /// Number of pairs.
    pub pairs: usize,
    /// Translation error `|t(E)|`. m.
    pub translation_m: Stats,
    /// Rotation error `|θ(E)|`. rad.
    pub rotation_rad: Stats,
    /// Pairs counted in the drift (all of a distance window's; a time window's that travelled at least
    /// [`DRIFT_MIN_DISTANCE_M`]).
    pub drift_pairs: usize,
    /// Drift: translation error over distance travelled, per pair. % (of distance).
    pub drift_pct: Stats,
}

impl RpeSummary {
    /// The statistics of `pairs` (each pair counting once) for window `delta`.
    pub fn of(pairs: &[PairError], delta: RpeDelta) -> Self {
        let min = delta.drift_min_distance_m();
        let drift: Vec<f64> =
            pairs.iter().filter(|p| p.distance_m >= min && p.distance_m > 0.0).map(PairError::drift_pct).collect();
        Self {
            pairs: pairs.len(),
            translation_m: Stats::of(pairs.iter().map(|p| p.translation_m)),
            rotation_rad: Stats::of(pairs.iter().map(|p| p.rotation_rad)),
            drift_pairs: drift.len(),
            drift_pct: Stats::of(drift),
        }
    }
}

/// The pair errors of every run, in run order.
#[derive(Clone, Debug, PartialEq)]
pub struct RelativeErrors {
    delta: RpeDelta,
    runs: Vec<Vec<PairError>>,
}

impl RelativeErrors {
    /// The pair errors of `runs` from their errors at every ground-truth pose after the first (`errors`
    /// from an evaluator at [`crate::odometry::Selection::Path`]`(1)`, in run order); errors at other
    /// poses are refused, naming the run.
    pub fn new(runs: &[Run], errors: &RunErrors, delta: RpeDelta) -> Result<Self, KinError> {
        let each = runs
            .iter()
            .zip(estimates_at_truth(runs, errors)?)
            .map(|(r, estimate)| pair_errors(r.truth(), &estimate, delta))
            .collect::<Result<_, _>>()?;
        Ok(Self { delta, runs: each })
    }

    /// The window.
    pub fn delta(&self) -> RpeDelta {
        self.delta
    }

    /// Run `i`'s pairs.
    pub fn run(&self, i: usize) -> &[PairError] {
        &self.runs[i]
    }

    /// Run `i`'s statistics.
    pub fn run_summary(&self, i: usize) -> RpeSummary {
        RpeSummary::of(&self.runs[i], self.delta)
    }

    /// The statistics of every pair of every run (each pair counting once, so a long run counts more).
    pub fn summary(&self) -> RpeSummary {
        let all: Vec<PairError> = self.runs.iter().flatten().copied().collect();
        RpeSummary::of(&all, self.delta)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
