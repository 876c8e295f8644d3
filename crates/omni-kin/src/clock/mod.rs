//! The clock offset between wheel data and a ground truth recorded on another clock (a motion-capture PC,
//! a TUM file from evo), estimated from the data alone.
//!
//! Convention: **`t_wheel = t_truth + offset_s`**; adding [`ClockAlignment::offset_s`] to the ground truth's
//! stamps puts them on the wheel clock.
//!
//! # Method
//! Both sides are compared over the same time intervals as averages, which is omnical's wheel convention
//! (sample `k` is the mean speed over `(t_{k−1}, t_k]`):
//! - the wheels give the mean wheel speeds `u ∈ ℝⁿ` over an interval (differences of the integrated wheel
//!   angle), rad/s;
//! - the ground truth gives the mean body-frame velocity `y = (v_x, v_y, ω)` over the interval shifted by
//!   `−offset` (pose differences of the linearly interpolated truth, rotated into the body frame at the
//!   interval's middle heading), m/s and rad/s.
//!
//! For a rigid robot `y ≈ A u` with an unknown 3×n matrix `A` (the inverse kinematics, a lever arm of the
//! tracked marker, a rotated marker frame: all linear). So no model is needed: for a candidate offset each
//! channel of `y` is regressed on `u` (least squares without intercept) and the offset scores the mean
//! share of the channels' sums of squares the fit explains (R²).
//!
//! 1. **Coarse**: on a uniform grid of step `h` (10 ms, coarser for long recordings so that a side has at
//!    most [`COARSE_INTERVALS`] intervals), every offset `(w₀ − g₀) + k h` whose overlap covers at least half
//!    of the shorter side and [`MIN_OVERLAP_S`] is scored: a cross-correlation of the profiles over the whole
//!    recording. The best lag is kept.
//! 2. **Fine**: around it (±1.5 h) the offset is refined as a continuous parameter by golden-section
//!    search of the normalised residual `Σ_c RSS_c / TSS_c`. Here the truth keeps its own sample times
//!    (blocks of [`FINE_BLOCK_S`]) and the offset moves the wheel side, whose angle is exactly piecewise
//!    linear: interpolating the noisy truth at moving times would make its noise's share of the residual
//!    depend on the offset (more where the interval ends fall on samples), which biases the minimum by
//!    milliseconds.
//! 3. **Standard error** from the Gauss–Newton curvature of that least-squares problem (the offset's
//!    derivative of the targets, projected off the regressors' span), with the residual variance. Residuals of
//!    neighbouring intervals are correlated (they share poses), so it is a lower bound of the true
//!    uncertainty rather than an exact one.
//!
//! **Gaps.** Where the ground truth has none for more than [`GAP_MEDIAN_INTERVALS`] times its median interval
//! (a marker lost, a take spanning several recordings with nothing between them), nothing is compared: its
//! linear interpolation there is no measurement, and a constant velocity across a long gap would match wheel
//! speeds by chance. Both stages leave such intervals out.
//!
//! A ground truth that matches the wheels at no offset (explained share below [`MIN_R_SQUARED`]) is an
//! error, as is one too short to overlap, or a robot that does not move.

mod coarse;
mod fine;
#[cfg(test)]
mod tests;

use crate::StampedPose;
use coarse::coarse;
use fine::Fine;
use thiserror::Error;

/// The coarse grid has at most this many intervals on the longer side.
pub const COARSE_INTERVALS: usize = 4000;
/// The finest coarse grid step. s.
pub const MIN_COARSE_STEP_S: f64 = 0.010;
/// A body velocity channel (v_x or v_y) whose sum of squares is below this share of the other's is a
/// direction the base does not move in, left out of the fit's score.
pub const STILL_CHANNEL_SHARE: f64 = 0.01;
/// Wheel data and ground truth must overlap at least this long. s.
pub const MIN_OVERLAP_S: f64 = 2.0;
/// The fine stage compares truth intervals of about this length (whole truth sample intervals). s.
pub const FINE_BLOCK_S: f64 = 0.05;
/// The fine stage's blocks hold at least this many truth intervals, when that leaves enough blocks to fit:
/// a reference sampled slower than [`FINE_BLOCK_S`] (a lidar's scans at 10 Hz) would otherwise difference
/// each sample's noise alone.
pub const MIN_BLOCK_SAMPLES: usize = 2;
/// The best offset must explain at least this share of the ground truth's motion.
pub const MIN_R_SQUARED: f64 = 0.5;
/// Consecutive ground-truth poses farther apart than this many median intervals bound a gap.
pub const GAP_MEDIAN_INTERVALS: f64 = 4.0;
/// A clear estimate's standard error is at most this (the one test of a clear estimate, for every
/// reference: [`ClockAlignment::is_clear`]). s.
pub const CLEAR_MAX_STD_ERROR_S: f64 = 0.02;
/// A clear estimate explains at least this share of the reference's motion ([`ClockAlignment::is_clear`]).
pub const CLEAR_MIN_R_SQUARED: f64 = 0.9;
/// Largest offset between wheel data and a reference recorded with it (a topic of the same recording, a
/// lidar's scans) that is a lag rather than another clock: the range of the `time_offset` effect, which
/// models it and diagnose names. s.
pub const SAME_CLOCK_MAX_OFFSET_S: f64 = 0.5;

/// An estimated clock offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockAlignment {
    /// `t_wheel = t_truth + offset_s`. s.
    pub offset_s: f64,
    /// Its standard error (Gauss–Newton, see the module docs). s.
    pub std_error_s: f64,
    /// The coarse estimate (grid lag). s.
    pub coarse_offset_s: f64,
    /// The coarse grid step. s.
    pub step_s: f64,
    /// The mean share of the ground truth's body velocity the wheel speeds explain at `offset_s` (0–1).
    pub r_squared: f64,
    /// How long wheel data and ground truth overlap at `offset_s`. s.
    pub overlap_s: f64,
}

impl ClockAlignment {
    /// The one test of a clear estimate, the same for every reference (a ground-truth topic or file, a
    /// lidar's path, a relative reference, an IMU): a standard error of at most [`CLEAR_MAX_STD_ERROR_S`]
    /// and at least [`CLEAR_MIN_R_SQUARED`] of the reference's motion explained. An estimate that fails it
    /// is never applied silently.
    pub fn is_clear(&self) -> bool {
        self.std_error_s <= CLEAR_MAX_STD_ERROR_S && self.r_squared >= CLEAR_MIN_R_SQUARED
    }

    /// The offset differs from `other_s` by more than three standard errors.
    pub fn differs_from(&self, other_s: f64) -> bool {
        (self.offset_s - other_s).abs() > 3.0 * self.std_error_s
    }
}

/// The smallest lag between wheels and a sensor recorded with them that is worth naming. s.
pub const MIN_NAMED_LAG_S: f64 = 0.02;

/// What an estimate means for a reference recorded with the wheels (a topic of the same recording, a
/// lidar's scans): the rules every such reference follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SameRecording {
    /// The clocks agree: within the same-clock band and not a lag worth naming.
    Agree,
    /// A lag within the band, beyond three standard errors and [`MIN_NAMED_LAG_S`], that is not clear: a
    /// note may say it is suggested; never applied.
    UnclearLag,
    /// A clear lag within the band ([`SAME_CLOCK_MAX_OFFSET_S`]), beyond three standard errors and
    /// [`MIN_NAMED_LAG_S`]: a clock offset between wheels and sensor the `time_offset` effect fits; named,
    /// not applied.
    Lag,
    /// A clear offset beyond the band and no longer than the recording: the reference runs on another clock;
    /// its stamps are moved by it.
    Move,
    /// Beyond the band but not clear: never applied; the stamps stay as recorded, with a note.
    Unclear,
    /// Clear but longer than the recording itself: implausible for stamps that overlap as recorded; never
    /// applied.
    Implausible,
}

impl ClockAlignment {
    /// The rules for a reference recorded with the wheels ([`SameRecording`]); `recording_s`: how long the
    /// wheel data lasts. s.
    pub fn same_recording(&self, recording_s: f64) -> SameRecording {
        let beyond_noise = self.differs_from(0.0);
        if self.offset_s.abs() <= SAME_CLOCK_MAX_OFFSET_S || !beyond_noise {
            return match (beyond_noise && self.offset_s.abs() >= MIN_NAMED_LAG_S, self.is_clear()) {
                (true, true) => SameRecording::Lag,
                (true, false) => SameRecording::UnclearLag,
                (false, _) => SameRecording::Agree,
            };
        }
        if !self.is_clear() {
            SameRecording::Unclear
        } else if self.offset_s.abs() > recording_s {
            SameRecording::Implausible
        } else {
            SameRecording::Move
        }
    }
}

/// Why no offset could be estimated.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ClockError {
    /// Too little data on one side.
    #[error("{what} has {count} samples; at least 2 are needed to estimate a clock offset")]
    TooFew {
        /// `wheel data` or `ground truth`.
        what: &'static str,
        /// Samples given.
        count: usize,
    },
    /// No offset gives enough overlap.
    #[error(
        "the wheel data spans {wheel_s:.3} s and the ground truth {truth_s:.3} s: no clock offset overlaps them \
         for at least {MIN_OVERLAP_S} s and half the shorter one"
    )]
    NoOverlap {
        /// Wheel data's span. s.
        wheel_s: f64,
        /// The ground truth's span. s.
        truth_s: f64,
    },
    /// The robot (or the truth) does not move, so the profiles say nothing about the offset.
    #[error("the ground truth does not move: its velocity profile cannot be matched to the wheels")]
    NoMotion,
    /// The best offset explains too little.
    #[error(
        "the ground truth matches the wheel data at no clock offset: the best, {offset_s:+.3} s, explains only \
         {:.0} % of its motion (at least {:.0} % expected); is it the same robot and the same time?",
        r_squared * 100.0, MIN_R_SQUARED * 100.0
    )]
    NoMatch {
        /// The best offset. s.
        offset_s: f64,
        /// Its explained share.
        r_squared: f64,
    },
}

/// The share of the ground truth's motion the wheels explain when the clocks differ by `offset_s` (the R²
/// of [`align_clocks`]'s fine step at that one offset, without searching): a cheap check that a ground
/// truth is on the wheels' clock. `None` when the truth does not move or hardly overlaps the wheel data.
/// Inputs as for [`align_clocks`].
pub fn explained_at(
    wheel_t_s: &[f64],
    wheel_rad_s: &[f64],
    n_wheels: usize,
    truth: &[StampedPose],
    offset_s: f64,
) -> Option<f64> {
    if wheel_t_s.len() < 2 || truth.len() < 2 {
        return None;
    }
    let wheels = WheelAngles::new(wheel_t_s, wheel_rad_s, n_wheels);
    let fine = Fine::new(&wheels, &Poses::new(truth), offset_s, offset_s)?;
    let fit = fine.fit(offset_s)?;
    Some(1.0 - fit.normalised_rss / fit.channels as f64)
}

/// A sensor's clock from its whole motion or from its rotation alone, whichever is clearer: a scan matcher's
/// heading is far less noisy than its translation over one scan interval, so the rotation may give a clear
/// estimate ([`ClockAlignment::is_clear`]) where the whole motion does not. The whole motion's estimate is
/// kept when it is clear, or when the rotation's is neither clear nor sharper. Returns the estimate, the
/// poses it compared (`truth`, or its headings alone at the origin) and whether they are the rotation alone.
pub fn align_clocks_clearest(
    wheel_t_s: &[f64],
    wheel_rad_s: &[f64],
    n_wheels: usize,
    truth: &[StampedPose],
) -> Option<(ClockAlignment, Vec<StampedPose>, bool)> {
    let rotation: Vec<StampedPose> =
        truth.iter().map(|p| StampedPose { t_s: p.t_s, pose: crate::Pose2::new(0.0, 0.0, p.pose.theta_rad) }).collect();
    let whole = align_clocks(wheel_t_s, wheel_rad_s, n_wheels, truth).ok();
    let turning = align_clocks(wheel_t_s, wheel_rad_s, n_wheels, &rotation).ok();
    match (whole, turning) {
        (Some(w), Some(r)) if !w.is_clear() && (r.is_clear() || r.std_error_s < w.std_error_s) => {
            Some((r, rotation, true))
        }
        (Some(w), _) => Some((w, truth.to_vec(), false)),
        (None, Some(r)) => Some((r, rotation, true)),
        (None, None) => None,
    }
}

/// Estimates the clock offset `t_wheel = t_truth + offset_s` (see the module docs). Wheel times and speeds as
/// in [`crate::RunData`] (`rad_s` row-major, `n_wheels` per sample, increasing times); truth poses with
/// increasing times on their own clock and an unwrapped heading. Times on both sides should be small
/// numbers (seconds since a nearby origin) for float accuracy.
pub fn align_clocks(
    wheel_t_s: &[f64],
    wheel_rad_s: &[f64],
    n_wheels: usize,
    truth: &[StampedPose],
) -> Result<ClockAlignment, ClockError> {
    if wheel_t_s.len() < 2 {
        return Err(ClockError::TooFew { what: "wheel data", count: wheel_t_s.len() });
    }
    if truth.len() < 2 {
        return Err(ClockError::TooFew { what: "ground truth", count: truth.len() });
    }
    let wheels = WheelAngles::new(wheel_t_s, wheel_rad_s, n_wheels);
    let poses = Poses::new(truth);
    let coarse = coarse(&wheels, &poses)?;
    let h = coarse.step_s;
    let fine =
        Fine::new(&wheels, &poses, coarse.offset_s - 1.5 * h, coarse.offset_s + 1.5 * h).ok_or(ClockError::NoMotion)?;
    let offset_s = fine.minimise(coarse.offset_s - 1.5 * h, coarse.offset_s + 1.5 * h);
    let fit = fine.fit(offset_s).ok_or(ClockError::NoMotion)?;
    let r_squared = 1.0 - fit.normalised_rss / fit.channels as f64;
    if r_squared < MIN_R_SQUARED {
        return Err(ClockError::NoMatch { offset_s, r_squared });
    }
    Ok(ClockAlignment {
        offset_s,
        std_error_s: fine.std_error(offset_s, &fit),
        coarse_offset_s: coarse.offset_s,
        step_s: h,
        r_squared,
        overlap_s: fine.overlap_s(),
    })
}

/// The wheel angles integrated from the speeds: piecewise linear in time, 0 at the first sample.
struct WheelAngles<'a> {
    t_s: &'a [f64],
    /// `angle[k * n + w]`. rad.
    angle: Vec<f64>,
    n: usize,
}

impl<'a> WheelAngles<'a> {
    fn new(t_s: &'a [f64], rad_s: &[f64], n: usize) -> Self {
        let mut angle = vec![0.0; t_s.len() * n];
        for k in 1..t_s.len() {
            let dt = t_s[k] - t_s[k - 1];
            for w in 0..n {
                angle[k * n + w] = angle[(k - 1) * n + w] + rad_s[k * n + w] * dt;
            }
        }
        Self { t_s, angle, n }
    }

    /// Mean wheel speeds over `[a, b]` (inside the data's span). rad/s.
    fn mean_rates(&self, a: f64, b: f64, out: &mut [f64]) {
        let (ia, fa) = locate(self.t_s, a);
        let (ib, fb) = locate(self.t_s, b);
        for (w, o) in out.iter_mut().enumerate() {
            let at = |i: usize, f: f64| {
                let a0 = self.angle[i * self.n + w];
                let a1 = self.angle[(i + 1).min(self.t_s.len() - 1) * self.n + w];
                a0 + (a1 - a0) * f
            };
            *o = (at(ib, fb) - at(ia, fa)) / (b - a);
        }
    }
}

/// The ground truth, interpolated linearly (heading unwrapped), with its gaps.
struct Poses<'a> {
    poses: &'a [StampedPose],
    /// `(start, end)` of every gap, in time order (see the module docs). s.
    gaps: Vec<(f64, f64)>,
    /// The median interval between poses. s.
    median_dt_s: f64,
}

impl<'a> Poses<'a> {
    /// At least two poses with increasing times.
    fn new(poses: &'a [StampedPose]) -> Self {
        let mut dt: Vec<f64> = poses.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
        dt.sort_by(f64::total_cmp);
        let median_dt_s = dt[dt.len() / 2];
        let gaps = poses
            .windows(2)
            .filter(|w| w[1].t_s - w[0].t_s > GAP_MEDIAN_INTERVALS * median_dt_s)
            .map(|w| (w[0].t_s, w[1].t_s))
            .collect();
        Self { poses, gaps, median_dt_s }
    }

    /// Whether `[a, b]` lies clear of every gap (touching one's ends is fine).
    fn measured(&self, a: f64, b: f64) -> bool {
        let first_ending_after_a = self.gaps.partition_point(|g| g.1 <= a);
        self.gaps.get(first_ending_after_a).is_none_or(|g| g.0 >= b)
    }

    fn span(&self) -> (f64, f64) {
        (self.poses[0].t_s, self.poses[self.poses.len() - 1].t_s)
    }

    /// `(x, y, θ)` at `t` (inside the span).
    fn at(&self, t: f64) -> [f64; 3] {
        let p = self.poses;
        let i = p.partition_point(|q| q.t_s <= t).clamp(1, p.len() - 1) - 1;
        let (a, b) = (&p[i], &p[i + 1]);
        let f = ((t - a.t_s) / (b.t_s - a.t_s)).clamp(0.0, 1.0);
        let lerp = |u: f64, v: f64| u + (v - u) * f;
        [lerp(a.pose.x_m, b.pose.x_m), lerp(a.pose.y_m, b.pose.y_m), lerp(a.pose.theta_rad, b.pose.theta_rad)]
    }

    /// Mean body-frame velocity `(v_x, v_y, ω)` over `[a, b]` (inside the span). m/s, rad/s.
    fn mean_twist(&self, a: f64, b: f64) -> [f64; 3] {
        let (p, q) = (self.at(a), self.at(b));
        let mid = 0.5 * (p[2] + q[2]);
        let (s, c) = mid.sin_cos();
        let (dx, dy, dt) = (q[0] - p[0], q[1] - p[1], b - a);
        [(c * dx + s * dy) / dt, (-s * dx + c * dy) / dt, (q[2] - p[2]) / dt]
    }
}

/// Index `i` and fraction `f` with `t = t_s[i] + f (t_s[i+1] − t_s[i])`, clamped to the span.
fn locate(t_s: &[f64], t: f64) -> (usize, f64) {
    let i = t_s.partition_point(|&u| u <= t).clamp(1, t_s.len() - 1) - 1;
    let f = if i + 1 < t_s.len() { ((t - t_s[i]) / (t_s[i + 1] - t_s[i])).clamp(0.0, 1.0) } else { 0.0 };
    (i, f)
}
