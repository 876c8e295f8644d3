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

use crate::StampedPose;
use nalgebra::{DMatrix, DVector};
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
/// The best offset must explain at least this share of the ground truth's motion.
pub const MIN_R_SQUARED: f64 = 0.5;
/// Consecutive ground-truth poses farther apart than this many median intervals bound a gap.
pub const GAP_MEDIAN_INTERVALS: f64 = 4.0;

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

struct Coarse {
    offset_s: f64,
    step_s: f64,
}

/// The best lag on the coarse grid (step 1 of the module docs).
fn coarse(wheels: &WheelAngles<'_>, poses: &Poses<'_>) -> Result<Coarse, ClockError> {
    let (w0, w1) = (wheels.t_s[0], wheels.t_s[wheels.t_s.len() - 1]);
    let (g0, g1) = poses.span();
    let h = MIN_COARSE_STEP_S.max((w1 - w0).max(g1 - g0) / COARSE_INTERVALS as f64);
    let nw = ((w1 - w0) / h).floor() as usize;
    let ng = ((g1 - g0) / h).floor() as usize;
    let n = wheels.n;
    let mut u = vec![0.0; nw * n];
    for i in 0..nw {
        let a = w0 + i as f64 * h;
        wheels.mean_rates(a, a + h, &mut u[i * n..(i + 1) * n]);
    }
    // Truth intervals inside a gap are no measurement: `None`, left out of every lag's sums.
    let y: Vec<Option<[f64; 3]>> = (0..ng)
        .map(|j| {
            let (a, b) = (g0 + j as f64 * h, g0 + (j + 1) as f64 * h);
            poses.measured(a, b).then(|| poses.mean_twist(a, b))
        })
        .collect();
    let measured = y.iter().filter(|v| v.is_some()).count();
    let min_pairs = ((nw.min(measured)) / 2).max((MIN_OVERLAP_S / h).ceil() as usize).max(n + 1);
    if nw.min(measured) < min_pairs {
        return Err(ClockError::NoOverlap { wheel_s: w1 - w0, truth_s: g1 - g0 });
    }
    let mut best: Option<(f64, i64)> = None;
    let (mut b, mut gram) = (vec![[0.0; 3]; n], DMatrix::zeros(n, n));
    // Lag L pairs wheel interval i with truth interval j = i − L.
    for lag in -(ng as i64 - 1)..(nw as i64) {
        let i0 = lag.max(0) as usize;
        let i1 = nw.min((ng as i64 + lag) as usize);
        if i1 < i0 + min_pairs {
            continue;
        }
        b.iter_mut().for_each(|v| *v = [0.0; 3]);
        gram.fill(0.0);
        let (mut tss, mut pairs) = ([0.0; 3], 0usize);
        for i in i0..i1 {
            let Some(yj) = &y[(i as i64 - lag) as usize] else { continue };
            pairs += 1;
            let ui = &u[i * n..(i + 1) * n];
            for (r, br) in b.iter_mut().enumerate() {
                for c in 0..3 {
                    br[c] += ui[r] * yj[c];
                }
                for c in 0..n {
                    gram[(r, c)] += ui[r] * ui[c];
                }
            }
            for c in 0..3 {
                tss[c] += yj[c] * yj[c];
            }
        }
        if pairs < min_pairs {
            continue;
        }
        let Some(chol) = gram.clone().cholesky() else { continue };
        let mut score = 0.0;
        for (c, &tss) in tss.iter().enumerate() {
            if tss > 0.0 {
                let bc = DVector::from_fn(n, |r, _| b[r][c]);
                score += bc.dot(&chol.solve(&bc)) / tss;
            }
        }
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, lag));
        }
    }
    let Some((score, lag)) = best else {
        return Err(ClockError::NoOverlap { wheel_s: w1 - w0, truth_s: g1 - g0 });
    };
    if score <= 0.0 {
        return Err(ClockError::NoMotion);
    }
    Ok(Coarse { offset_s: (w0 - g0) + lag as f64 * h, step_s: h })
}

/// The fine objective over the ground truth's own sample intervals whose shifted copies stay inside the wheel
/// data for every offset in the search bracket (so the set is the same for all of them). The targets (the
/// truth's body velocities, with its noise) stay fixed; the offset moves the wheel side, whose angle is
/// piecewise linear between samples *exactly* (speeds are interval means), so the truth's noise adds the
/// same amount to the residual at every offset instead of one that varies with where the interpolation
/// falls between its samples.
struct Fine<'a> {
    wheels: &'a WheelAngles<'a>,
    /// Truth intervals `[start, end]` on the truth's clock. s.
    intervals: Vec<(f64, f64)>,
    /// Targets, one row per interval: mean body velocity `(v_x, v_y, ω)`.
    y: DMatrix<f64>,
    /// `1 / TSS_c` per channel (0 for a channel without motion).
    weights: [f64; 3],
}

/// One least-squares fit at an offset.
struct Fit {
    /// `Σ_c RSS_c / TSS_c`.
    normalised_rss: f64,
    /// The fitted map, n × 3 (wheel speeds → body velocity, one column per channel).
    beta: DMatrix<f64>,
    /// Channels with motion.
    channels: usize,
}

impl<'a> Fine<'a> {
    fn new(wheels: &'a WheelAngles<'a>, poses: &Poses<'_>, lo: f64, hi: f64) -> Option<Self> {
        let t = wheels.t_s;
        let (w0, w1) = (t[0], t[t.len() - 1]);
        let p = poses.poses;
        // Blocks of consecutive truth samples spanning about FINE_BLOCK_S: the truth's noise, differenced,
        // shrinks with the block's length while the motion stays resolved. None across a gap.
        let m = ((FINE_BLOCK_S / poses.median_dt_s).round() as usize).max(1);
        let intervals: Vec<(f64, f64)> = (0..(p.len() - 1) / m)
            .map(|j| (p[j * m].t_s, p[(j + 1) * m].t_s))
            .filter(|&(a, b)| a + lo >= w0 && b + hi <= w1 && poses.measured(a, b))
            .collect();
        if intervals.len() <= 3 * wheels.n {
            return None;
        }
        let mut y = DMatrix::zeros(intervals.len(), 3);
        for (r, &(a, b)) in intervals.iter().enumerate() {
            let v = poses.mean_twist(a, b);
            for c in 0..3 {
                y[(r, c)] = v[c];
            }
        }
        let tss: [f64; 3] = std::array::from_fn(|c| y.column(c).norm_squared());
        let mut weights = [0.0; 3];
        for (c, w) in weights.iter_mut().enumerate() {
            // A direction the base does not move in (a differential drive's v_y: the truth's noise, or
            // far less than its motion the other way) has nothing an offset could explain; scoring it
            // would cap the explained share of a diff robot at two thirds.
            let still = c < 2 && tss[c] < STILL_CHANNEL_SHARE * tss[1 - c];
            if tss[c] > 0.0 && !still {
                *w = 1.0 / tss[c];
            }
        }
        weights.iter().any(|&w| w > 0.0).then_some(Self { wheels, intervals, y, weights })
    }

    fn overlap_s(&self) -> f64 {
        match (self.intervals.first(), self.intervals.last()) {
            (Some(a), Some(b)) => b.1 - a.0,
            _ => 0.0,
        }
    }

    /// The regressors at `offset`: the mean wheel speeds over each truth interval moved onto the wheel clock.
    fn regressors(&self, offset: f64) -> DMatrix<f64> {
        let n = self.wheels.n;
        let mut u = DMatrix::zeros(self.intervals.len(), n);
        let mut row = vec![0.0; n];
        for (r, &(a, b)) in self.intervals.iter().enumerate() {
            self.wheels.mean_rates(a + offset, b + offset, &mut row);
            for (w, v) in row.iter().enumerate() {
                u[(r, w)] = *v;
            }
        }
        u
    }

    fn fit(&self, offset: f64) -> Option<Fit> {
        let u = self.regressors(offset);
        // Normal equations: n is a handful of wheels and the speeds are well scaled.
        let beta = (u.transpose() * &u).cholesky()?.solve(&(u.transpose() * &self.y));
        let res = &self.y - &u * &beta;
        let mut normalised_rss = 0.0;
        for c in 0..3 {
            normalised_rss += self.weights[c] * res.column(c).norm_squared();
        }
        let channels = self.weights.iter().filter(|&&w| w > 0.0).count();
        Some(Fit { normalised_rss, beta, channels })
    }

    /// Golden-section search of the normalised residual on `[lo, hi]`.
    fn minimise(&self, mut lo: f64, mut hi: f64) -> f64 {
        const INV_PHI: f64 = 0.618_033_988_749_895;
        let f = |x: f64| self.fit(x).map_or(f64::INFINITY, |fit| fit.normalised_rss);
        let (mut a, mut b) = (hi - INV_PHI * (hi - lo), lo + INV_PHI * (hi - lo));
        let (mut fa, mut fb) = (f(a), f(b));
        while hi - lo > 1e-6 {
            if fa < fb {
                hi = b;
                (b, fb) = (a, fa);
                a = hi - INV_PHI * (hi - lo);
                fa = f(a);
            } else {
                lo = a;
                (a, fa) = (b, fb);
                b = lo + INV_PHI * (hi - lo);
                fb = f(b);
            }
        }
        0.5 * (lo + hi)
    }

    /// Gauss–Newton standard error of the offset at `offset`: the prediction's derivative `(∂U/∂offset) β`,
    /// projected off the regressors' span, against the residual variance.
    fn std_error(&self, offset: f64, fit: &Fit) -> f64 {
        const DELTA_S: f64 = 1e-4;
        let u = self.regressors(offset);
        let du = (self.regressors(offset + DELTA_S) - self.regressors(offset - DELTA_S)) / (2.0 * DELTA_S);
        let d = &du * &fit.beta;
        let q = u.qr().q();
        let d_perp = &d - &q * (q.transpose() * &d);
        let curvature: f64 = (0..3).map(|c| self.weights[c] * d_perp.column(c).norm_squared()).sum();
        let dof = (3 * self.intervals.len()).saturating_sub(3 * self.wheels.n + 1).max(1) as f64;
        (fit.normalised_rss / dof / curvature).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pose2;

    /// A three-wheel omni base driving a smooth twist: wheel samples as interval means at 100 Hz, truth at
    /// 125 Hz on a clock `offset` behind.
    fn recording(offset: f64) -> (Vec<f64>, Vec<f64>, Vec<StampedPose>) {
        let twist = |t: f64| [0.25 * (0.7 * t).sin(), 0.18 * (1.1 * t + 1.0).sin(), 0.9 * (0.45 * t + 0.3).sin()];
        let angles = [90f64, 210.0, 330.0].map(f64::to_radians);
        let dt = 1e-4;
        let (mut t, mut pose, mut wheel) = (-0.1, [0.0f64, 0.0, 0.3], [0.0f64; 3]);
        let (mut wheel_t, mut rates, mut truth) = (Vec::new(), Vec::new(), Vec::new());
        let mut last_wheel = [0.0; 3];
        let mut step = 0usize;
        while t < 30.0 {
            let [vx, vy, wz] = twist(t + 0.5 * dt);
            let (s, c) = pose[2].sin_cos();
            pose = [pose[0] + (c * vx - s * vy) * dt, pose[1] + (s * vx + c * vy) * dt, pose[2] + wz * dt];
            for (w, b) in angles.iter().enumerate() {
                wheel[w] += (-b.sin() * vx + b.cos() * vy + 0.2 * wz) / 0.05 * dt;
            }
            t += dt;
            step += 1;
            if step.is_multiple_of(100) && t > 0.0 {
                wheel_t.push(t);
                rates.extend((0..3).map(|w| (wheel[w] - last_wheel[w]) / 0.01));
            }
            if step.is_multiple_of(100) {
                last_wheel = wheel;
            }
            if step.is_multiple_of(80) {
                truth.push(StampedPose {
                    t_s: t - offset,
                    pose: Pose2 { x_m: pose[0], y_m: pose[1], theta_rad: pose[2] },
                });
            }
        }
        (wheel_t, rates, truth)
    }

    #[test]
    fn recovers_offsets_of_seconds_and_of_milliseconds() {
        for offset in [3.217, 0.05, -1.3] {
            let (t, rates, truth) = recording(offset);
            let a = align_clocks(&t, &rates, 3, &truth).unwrap();
            assert!((a.offset_s - offset).abs() < 2e-4, "{offset}: {a:?}");
            assert!(a.std_error_s > 0.0 && a.std_error_s < 1e-3, "{a:?}");
            assert!(a.r_squared > 0.999, "{a:?}");
        }
    }

    #[test]
    fn gaps_in_the_truth_are_left_out() {
        // The marker lost for 1.5 s of every 5 s, and a stretch 100 s later that no wheel data covers (a
        // take spanning several recordings): before gaps were left out, the interpolation across the long
        // one matched the wheels better than the motion did, and the estimate failed.
        let offset = 0.8;
        let (t, rates, truth) = recording(offset);
        let mut gappy: Vec<StampedPose> = truth.iter().copied().filter(|p| (p.t_s + offset) % 5.0 < 3.5).collect();
        // Later, the robot parked where it stopped (the next recording not yet started).
        let last = truth[truth.len() - 1];
        let later = (0..3000).map(|k| StampedPose { t_s: last.t_s + 100.0 + k as f64 * 0.008, pose: last.pose });
        gappy.extend(later);
        let a = align_clocks(&t, &rates, 3, &gappy).unwrap();
        assert!((a.offset_s - offset).abs() < 2e-4, "{a:?}");
        assert!(a.r_squared > 0.999, "{a:?}");
        let poses = Poses::new(&gappy);
        assert!(poses.gaps.len() >= 6, "{:?}", poses.gaps);
        assert!(!poses.measured(40.0, 40.1) && poses.measured(0.5, 0.6));
    }

    #[test]
    fn refuses_a_truth_of_another_motion() {
        let (t, rates, _) = recording(0.0);
        let still: Vec<StampedPose> = (0..3000)
            .map(|k| StampedPose {
                t_s: k as f64 * 0.01,
                pose: Pose2 { x_m: (k as f64 * 0.37).sin(), y_m: 0.0, theta_rad: 0.0 },
            })
            .collect();
        assert!(matches!(align_clocks(&t, &rates, 3, &still), Err(ClockError::NoMatch { .. })));
        let short = &still[..100];
        assert!(matches!(align_clocks(&t, &rates, 3, short), Err(ClockError::NoOverlap { .. })));
    }
}
