//! How far to trust the odometry (issue 46): a noise model of the calibrated odometry in the
//! parameterisation of AMCL's motion models, its covariance along a path, its fit on training runs and its
//! check on held-out runs.
//!
//! ## The model
//! Each step of the odometry, a body increment of length `d` (m) in the direction `β` and turn `φ = |Δθ|`
//! (rad), adds independent zero-mean errors along the motion, across it (strafe) and in heading, with
//! variances growing with the distance driven and the angle turned:
//!
//! - along: `trans_per_m · d + trans_per_rad · φ` (m²)
//! - across: `strafe_per_m · d + trans_per_rad · φ` (m², holonomic bases only; a differential drive
//!   cannot slip sideways in this model: its lateral error is its heading error driven on)
//! - heading: `rot_per_rad · φ + rot_per_m · d` (rad²)
//!
//! These are Nav2 AMCL's omni motion model (`OmniMotionModel`: `α1` rot from rot, `α2` rot from trans, `α3`
//! trans from trans, `α4` trans and strafe from rot, `α5` strafe from trans) and differential model
//! (`DifferentialMotionModel`, the same meaning of `α1`–`α4`) in continuous form: AMCL applies its variances
//! `α·δ²` per filter update, so over a path of updates of size `δ` they add up to `α δ` per unit of motion,
//! and [`Amcl::from_rates`] divides the rates by the update thresholds (`update_min_d`, `update_min_a`).
//!
//! The ground truth's own noise enters every comparison at both ends of a window as a **floor** (position
//! variance per axis, heading variance), fitted too and kept out of what is exported.
//!
//! ## Per-run biases
//! Real odometry is also wrong in the same way for a whole run, and differently from one run (or day) to
//! the next: a tyre a little softer, a floor a little more slippery. Such an error grows with the distance
//! itself (its variance with `d²`), not with its square root, and no random walk stands for it. The model
//! carries three, each a zero-mean constant per run with a fitted variance:
//!
//! - `run_scale_var`: the distance driven is off by a factor `1 + s` (`s²`, unitless);
//! - `run_drift_var`: the heading drifts by `κ` per metre driven (`κ²`, rad²/m²);
//! - `run_turn_scale_var`: the angle turned is off by a factor `1 + γ` (`γ²`, unitless).
//!
//! Their mean over the training runs is the systematic error ([`fit::Systematic`]), kept apart; what is
//! fitted is how much they vary around it. Beside them, `heading_wander_rad2`: a heading error that is
//! renewed as the robot turns (its correlation falls as `exp(−φ / HEADING_MEMORY_RAD)` over the angle `φ`
//! turned) instead of adding up, as the corners of real squares show. None of the four is AMCL's (whose
//! noise is drawn afresh every update), and none is exported there.
//!
//! ## Propagation
//! Over a window of the odometry from pose `i` to `j`, in the frame of pose `i`, the covariance of the
//! end pose grows as `Σ ← F Σ Fᵀ + G Q Gᵀ` per step (`F` moves the heading error into position by the
//! step's displacement, `G` turns the along/across errors by the motion's direction). It is linear in the
//! noise parameters, so each window's covariance is `Σ_w = Σ_m θ_m B_{w,m}` with basis matrices `B` taken
//! once ([`window_basis`]). A per-run bias `b` moves the end pose by `v b`, where `v ← F v + g` per step
//! (`g` the step's displacement for the scale, its distance in heading for the drift, its signed turn in
//! heading for the turn scale): its basis is `v vᵀ`.
//!
//! Plain data: no I/O. The odometry at the ground-truth stamps comes from the evaluator's errors
//! ([`crate::relative::estimate_at_truth`]).

mod check;
mod fit;

pub use check::{CHI2_2DOF_95, Coverage, HORIZONS_M, Horizon, HorizonCheck, Predictor, coverage, stock_defaults};
pub use fit::{FitNoiseOptions, NoiseFitError, Systematic, fit};

use crate::error::KinError;
use crate::evaluate::RunErrors;
use crate::pose::Pose2;
use crate::relative::estimates_at_truth;
use crate::run::Run;
use nalgebra::{Matrix3, Matrix4, Vector3};
use serde::{Deserialize, Serialize};

/// Number of noise parameters: five rates, two floor terms, three per-run bias variances and the wandering
/// heading.
pub const N_PARAMS: usize = 11;

/// The first per-run bias parameter's index: `run_scale_var`, `run_drift_var`, `run_turn_scale_var` follow.
const FIRST_BIAS: usize = 7;
/// The index of `heading_wander_rad2`.
const WANDER: usize = 10;
/// How much turning renews the wandering heading error: after `φ` turned, its correlation with what it
/// was is `exp(−φ / HEADING_MEMORY_RAD)`. rad.
pub const HEADING_MEMORY_RAD: f64 = 1.0;

/// The parameters' names in vector order (as in model files and JSON).
pub const PARAM_NAMES: [&str; N_PARAMS] = [
    "rot_per_rad",
    "rot_per_m",
    "trans_per_m",
    "trans_per_rad",
    "strafe_per_m",
    "floor_position_m2",
    "floor_heading_rad2",
    "run_scale_var",
    "run_drift_var",
    "run_turn_scale_var",
    "heading_wander_rad2",
];

/// The parameters' units in vector order.
pub const PARAM_UNITS: [&str; N_PARAMS] =
    ["rad²/rad", "rad²/m", "m²/m", "m²/rad", "m²/m", "m²", "rad²", "1", "rad²/m²", "1", "rad²"];

/// A noise model: the variance rates of the odometry and the ground truth's floor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseRates {
    /// Heading variance per radian turned. rad²/rad. (AMCL α1.)
    pub rot_per_rad: f64,
    /// Heading variance per metre driven. rad²/m. (AMCL α2.)
    pub rot_per_m: f64,
    /// Along-track variance per metre driven. m²/m. (AMCL α3.)
    pub trans_per_m: f64,
    /// Along-track (and, holonomic, across-track) variance per radian turned. m²/rad. (AMCL α4.)
    pub trans_per_rad: f64,
    /// Across-track variance per metre driven (holonomic bases; 0 for a differential drive). m²/m. (AMCL α5.)
    pub strafe_per_m: f64,
    /// Ground-truth position variance per axis at each end of a window. m².
    pub floor_position_m2: f64,
    /// Ground-truth heading variance at each end of a window. rad².
    pub floor_heading_rad2: f64,
    /// Variance over runs of a run's distance scale error `s` (the run drives `1 + s` times the
    /// odometry's distance). Unitless (1 % → 1e-4). 0 in model files written before it.
    #[serde(default)]
    pub run_scale_var: f64,
    /// Variance over runs of a run's heading drift per metre driven. rad²/m².
    #[serde(default)]
    pub run_drift_var: f64,
    /// Variance over runs of a run's turn scale error `γ` (it turns `1 + γ` times the odometry's angle).
    /// Unitless.
    #[serde(default)]
    pub run_turn_scale_var: f64,
    /// Variance of a heading error that comes and goes: a stationary error of the odometry's heading,
    /// renewed as the robot turns (forgotten over [`HEADING_MEMORY_RAD`] turned), which swings the position
    /// while it lasts but does not add up the way a random walk's does. rad².
    #[serde(default)]
    pub heading_wander_rad2: f64,
}

impl NoiseRates {
    /// No noise.
    pub const ZERO: NoiseRates = NoiseRates {
        rot_per_rad: 0.0,
        rot_per_m: 0.0,
        trans_per_m: 0.0,
        trans_per_rad: 0.0,
        strafe_per_m: 0.0,
        floor_position_m2: 0.0,
        floor_heading_rad2: 0.0,
        run_scale_var: 0.0,
        run_drift_var: 0.0,
        run_turn_scale_var: 0.0,
        heading_wander_rad2: 0.0,
    };

    /// The parameters in [`PARAM_NAMES`] order.
    pub fn to_vec(&self) -> [f64; N_PARAMS] {
        [
            self.rot_per_rad,
            self.rot_per_m,
            self.trans_per_m,
            self.trans_per_rad,
            self.strafe_per_m,
            self.floor_position_m2,
            self.floor_heading_rad2,
            self.run_scale_var,
            self.run_drift_var,
            self.run_turn_scale_var,
            self.heading_wander_rad2,
        ]
    }

    /// From parameters in [`PARAM_NAMES`] order.
    pub fn from_slice(p: &[f64; N_PARAMS]) -> Self {
        Self {
            rot_per_rad: p[0],
            rot_per_m: p[1],
            trans_per_m: p[2],
            trans_per_rad: p[3],
            strafe_per_m: p[4],
            floor_position_m2: p[5],
            floor_heading_rad2: p[6],
            run_scale_var: p[7],
            run_drift_var: p[8],
            run_turn_scale_var: p[9],
            heading_wander_rad2: p[10],
        }
    }

    /// The same rates without the floor (what the odometry itself does).
    pub fn without_floor(&self) -> Self {
        Self { floor_position_m2: 0.0, floor_heading_rad2: 0.0, ..*self }
    }

    /// The random walk alone: without the floor and the per-run biases (what AMCL's alphas and a
    /// controller's per-message covariance can carry).
    pub fn random_walk(&self) -> Self {
        Self {
            run_scale_var: 0.0,
            run_drift_var: 0.0,
            run_turn_scale_var: 0.0,
            heading_wander_rad2: 0.0,
            ..self.without_floor()
        }
    }
}

/// The fitted noise model of a calibrated odometry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryNoise {
    /// Whether the base moves sideways (omni, mecanum): `strafe_per_m` is fitted; else it is 0.
    pub holonomic: bool,
    /// The fitted rates and floor.
    pub rates: NoiseRates,
    /// Each parameter's standard error (bootstrap over runs), same units; `None` from a single run.
    pub std_errors: Option<NoiseRates>,
    /// The systematic error left after calibration, kept apart from the noise.
    pub systematic: Systematic,
    /// Training runs and windows the fit used.
    pub runs: usize,
    /// Windows of the fit.
    pub windows: usize,
}

/// A run's ground truth and the model's odometry at the same stamps (the odometry starts at the first).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunPoses {
    /// Ground truth.
    pub truth: Vec<Pose2>,
    /// Odometry.
    pub odometry: Vec<Pose2>,
}

/// Each run's ground truth and odometry at the same stamps, from its errors at every ground-truth pose
/// after the first (an evaluator at [`crate::odometry::Selection::Path`]`(1)`, in run order).
pub fn run_poses(runs: &[Run], errors: &RunErrors) -> Result<Vec<RunPoses>, KinError> {
    Ok(runs
        .iter()
        .zip(estimates_at_truth(runs, errors)?)
        .map(|(r, odometry)| RunPoses { truth: r.truth().iter().map(|s| s.pose).collect(), odometry })
        .collect())
}

/// `b` seen from `a`: `a⁻¹ b` (x, y in `a`'s frame; heading difference unwrapped).
pub fn between(a: &Pose2, b: &Pose2) -> Pose2 {
    let (s, c) = a.theta_rad.sin_cos();
    let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
    Pose2::new(c * dx + s * dy, -s * dx + c * dy, b.theta_rad - a.theta_rad)
}

/// The error of a window `i → j`: the odometry's relative pose minus the ground truth's, in the frame of
/// pose `i` (x m, y m, θ rad).
pub fn window_error(run: &RunPoses, i: usize, j: usize) -> [f64; 3] {
    let p = between(&run.odometry[i], &run.odometry[j]);
    let q = between(&run.truth[i], &run.truth[j]);
    [p.x_m - q.x_m, p.y_m - q.y_m, crate::pose::wrap_angle(p.theta_rad - q.theta_rad)]
}

/// Basis covariances of the window `i → j` of `run`'s odometry, one per parameter ([`PARAM_NAMES`]):
/// the window's covariance is `Σ_m θ_m B_m`. `holonomic` false leaves `strafe_per_m` (and the across part
/// of `trans_per_rad`) out.
pub fn window_basis(run: &RunPoses, i: usize, j: usize, holonomic: bool) -> [Matrix3<f64>; N_PARAMS] {
    let mut b = Basis::new();
    for k in i..j {
        b.propagate(run, i, k, holonomic);
    }
    b.at_end()
}

/// [`window_basis`] of every window from pose `i` to a later pose `j` (`out[j - i - 1]` is `i → j`), built
/// step by step: linear in the run's length where one window at a time is quadratic (the report's
/// ellipses and error band along a whole run).
pub fn path_bases(run: &RunPoses, i: usize, holonomic: bool) -> Vec<[Matrix3<f64>; N_PARAMS]> {
    let n = run.odometry.len().min(run.truth.len());
    let mut b = Basis::new();
    let mut out = Vec::with_capacity(n.saturating_sub(i + 1));
    for k in i..n.saturating_sub(1) {
        b.propagate(run, i, k, holonomic);
        out.push(b.at_end());
    }
    out
}

/// A window's bases while it grows: the random walk's and the floor's covariances, and how far each
/// per-run bias has moved the end pose (`v`; its basis is `v vᵀ`).
struct Basis {
    /// Covariance bases of the random walk and the floor (the bias entries stay zero here).
    walk: [Matrix3<f64>; N_PARAMS],
    /// The end pose's response to a unit scale error, heading drift per metre and turn scale error.
    bias: [Vector3<f64>; WANDER - FIRST_BIAS],
    /// Covariance of (x, y, the wandering heading error now, and at the window's start) per unit variance.
    wander: Matrix4<f64>,
}

impl Basis {
    /// A window at its start: the ground truth's floor there, no motion yet.
    fn new() -> Self {
        let mut walk = [Matrix3::zeros(); N_PARAMS];
        walk[5][(0, 0)] = 1.0;
        walk[5][(1, 1)] = 1.0;
        walk[6][(2, 2)] = 1.0;
        let mut wander = Matrix4::zeros();
        for (r, c) in [(2, 2), (2, 3), (3, 2), (3, 3)] {
            wander[(r, c)] = 1.0;
        }
        Self { walk, bias: [Vector3::zeros(); WANDER - FIRST_BIAS], wander }
    }

    /// The bases of the window as it ends here: the floor at its end added, the biases' `v vᵀ`.
    fn at_end(&self) -> [Matrix3<f64>; N_PARAMS] {
        let mut b = self.walk;
        b[5][(0, 0)] += 1.0;
        b[5][(1, 1)] += 1.0;
        b[6][(2, 2)] += 1.0;
        for (m, v) in self.bias.iter().enumerate() {
            b[FIRST_BIAS + m] = v * v.transpose();
        }
        // The window's heading error is the wandering error now less its value at the start.
        let pick = nalgebra::Matrix3x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0);
        b[WANDER] = pick * self.wander * pick.transpose();
        b
    }

    /// The window from pose `i` extended by the odometry's step `k → k + 1`: the covariance so far carried
    /// through the step (its heading error swings the position), and the step's own noise added.
    fn propagate(&mut self, run: &RunPoses, i: usize, k: usize, holonomic: bool) {
        let at = between(&run.odometry[i], &run.odometry[k]);
        let u = between(&run.odometry[k], &run.odometry[k + 1]);
        let (s, c) = at.theta_rad.sin_cos();
        let (dx, dy) = (c * u.x_m - s * u.y_m, s * u.x_m + c * u.y_m);
        let f = Matrix3::new(1.0, 0.0, -dy, 0.0, 1.0, dx, 0.0, 0.0, 1.0);
        let d = u.x_m.hypot(u.y_m);
        let phi = u.theta_rad.abs();
        // Direction of the motion in the window's frame (any, when the step does not translate).
        let bearing = at.theta_rad + if d > 0.0 { u.y_m.atan2(u.x_m) } else { 0.0 };
        let (sb, cb) = bearing.sin_cos();
        let along = Matrix3::new(cb * cb, cb * sb, 0.0, cb * sb, sb * sb, 0.0, 0.0, 0.0, 0.0);
        let across = Matrix3::new(sb * sb, -cb * sb, 0.0, -cb * sb, cb * cb, 0.0, 0.0, 0.0, 0.0);
        let mut heading = Matrix3::zeros();
        heading[(2, 2)] = 1.0;
        let b = &mut self.walk;
        for m in b.iter_mut() {
            *m = f * *m * f.transpose();
        }
        b[0] += heading * phi;
        b[1] += heading * d;
        b[2] += along * d;
        b[3] += along * phi;
        if holonomic {
            b[3] += across * phi;
            b[4] += across * d;
        }
        // The biases: the scale moves the step's displacement, the drift and the turn scale its heading.
        let moved = [Vector3::new(dx, dy, 0.0), Vector3::new(0.0, 0.0, d), Vector3::new(0.0, 0.0, u.theta_rad)];
        for (v, g) in self.bias.iter_mut().zip(moved) {
            *v = f * *v + g;
        }
        // The wandering heading error swings this step, then is partly renewed by its turn.
        let rho = (-phi / HEADING_MEMORY_RAD).exp();
        #[rustfmt::skip]
        let g = Matrix4::new(
            1.0, 0.0, -dy, dy,
            0.0, 1.0, dx, -dx,
            0.0, 0.0, rho, 0.0,
            0.0, 0.0, 0.0, 1.0,
        );
        self.wander = g * self.wander * g.transpose();
        self.wander[(2, 2)] += 1.0 - rho * rho;
    }
}

/// `Σ_m θ_m B_m`.
pub fn covariance(basis: &[Matrix3<f64>; N_PARAMS], rates: &NoiseRates) -> Matrix3<f64> {
    basis.iter().zip(rates.to_vec()).fold(Matrix3::zeros(), |acc, (b, t)| acc + b * t)
}

/// Nav2 AMCL's update thresholds by default (`update_min_d` m, `update_min_a` rad, Humble to Rolling).
pub const AMCL_UPDATE_MIN_D_M: f64 = 0.25;
/// See [`AMCL_UPDATE_MIN_D_M`].
pub const AMCL_UPDATE_MIN_A_RAD: f64 = 0.2;
/// Nav2 AMCL's default `alpha1`…`alpha5` (nav2_params.yaml, Humble to Rolling).
pub const AMCL_DEFAULT_ALPHA: f64 = 0.2;

/// AMCL's `alpha1`…`alpha5` for a noise model at given update thresholds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Amcl {
    /// `alpha1` … `alpha5`.
    pub alpha: [f64; 5],
    /// `update_min_d` the alphas are for. m.
    pub update_min_d_m: f64,
    /// `update_min_a` the alphas are for. rad.
    pub update_min_a_rad: f64,
}

impl Amcl {
    /// The alphas whose per-update variances, summed over updates of `update_min_d_m` and
    /// `update_min_a_rad`, grow as `rates` do. The differential model draws its rotation noise twice per
    /// update (before and after the translation), so its `alpha2` is halved; it has no `alpha5`.
    pub fn from_rates(rates: &NoiseRates, holonomic: bool, update_min_d_m: f64, update_min_a_rad: f64) -> Self {
        let (d, a) = (update_min_d_m, update_min_a_rad);
        let alpha2 = if holonomic { rates.rot_per_m / d } else { rates.rot_per_m / (2.0 * d) };
        let alpha5 = if holonomic { rates.strafe_per_m / d } else { 0.0 };
        Self {
            alpha: [rates.rot_per_rad / a, alpha2, rates.trans_per_m / d, rates.trans_per_rad / a, alpha5],
            update_min_d_m,
            update_min_a_rad,
        }
    }

    /// The rates (no floor, no per-run bias) AMCL's alphas stand for, the inverse of [`Self::from_rates`].
    pub fn to_rates(&self, holonomic: bool) -> NoiseRates {
        let (d, a) = (self.update_min_d_m, self.update_min_a_rad);
        NoiseRates {
            rot_per_rad: self.alpha[0] * a,
            rot_per_m: if holonomic { self.alpha[1] * d } else { 2.0 * self.alpha[1] * d },
            trans_per_m: self.alpha[2] * d,
            trans_per_rad: self.alpha[3] * a,
            strafe_per_m: if holonomic { self.alpha[4] * d } else { 0.0 },
            ..NoiseRates::ZERO
        }
    }
}

/// Body-frame twist covariance diagonal (vx m²/s², vy m²/s², ω rad²/s²) of one odometry message at
/// `speed_m_s` and `turn_rad_s`, published at `rate_hz`: the rates' variance over one message interval,
/// turned into a velocity variance (`var / dt²`).
pub fn twist_variances(rates: &NoiseRates, holonomic: bool, speed_m_s: f64, turn_rad_s: f64, rate_hz: f64) -> [f64; 3] {
    let dt = 1.0 / rate_hz;
    let (d, phi) = (speed_m_s.abs() * dt, turn_rad_s.abs() * dt);
    let along = rates.trans_per_m * d + rates.trans_per_rad * phi;
    let across = if holonomic { rates.strafe_per_m * d + rates.trans_per_rad * phi } else { 0.0 };
    let heading = rates.rot_per_rad * phi + rates.rot_per_m * d;
    [along / (dt * dt), across / (dt * dt), heading / (dt * dt)]
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn straight(n: usize, step_m: f64) -> RunPoses {
        let poses: Vec<Pose2> = (0..=n).map(|k| Pose2::new(k as f64 * step_m, 0.0, 0.0)).collect();
        RunPoses { truth: poses.clone(), odometry: poses }
    }

    #[test]
    fn a_straight_drive_grows_along_track_variance_by_the_distance_and_heading_into_lateral_cubically() {
        let run = straight(100, 0.01);
        let rates = NoiseRates { trans_per_m: 1e-3, rot_per_m: 2e-4, strafe_per_m: 5e-4, ..NoiseRates::ZERO };
        let s = covariance(&window_basis(&run, 0, 100, true), &rates);
        // 1 m: along 1e-3 m²; heading 2e-4 rad²; lateral strafe 5e-4 plus heading driven on, ∫ q (L − s)² ds
        // = q L³/3 in the limit (the sum over 100 steps of 1 cm: q Σ (L − s_k)² h).
        assert!((s[(0, 0)] - 1e-3).abs() < 1e-12, "{s}");
        assert!((s[(2, 2)] - 2e-4).abs() < 1e-12, "{s}");
        let driven: f64 = (1..=100).map(|k| 2e-4 * 0.01 * ((100 - k) as f64 * 0.01).powi(2)).sum();
        assert!((s[(1, 1)] - 5e-4 - driven).abs() < 1e-12, "{s} vs {driven}");
        assert!((driven - 2e-4 / 3.0).abs() < 2e-6);
        // A differential drive does not strafe.
        let diff = covariance(&window_basis(&run, 0, 100, false), &rates);
        assert!((diff[(1, 1)] - driven).abs() < 1e-12);
    }

    #[test]
    fn path_bases_are_every_window_from_the_start_built_step_by_step() {
        // An arc that turns while it drives, with odometry off the truth.
        let truth: Vec<Pose2> =
            (0..40).map(|k| Pose2::new((k as f64 * 0.05).sin(), 0.3 * k as f64 * 0.05, 0.05 * k as f64)).collect();
        let odometry: Vec<Pose2> = truth.iter().map(|p| Pose2::new(1.01 * p.x_m, p.y_m, 1.02 * p.theta_rad)).collect();
        let run = RunPoses { truth, odometry };
        for holonomic in [true, false] {
            for start in [0, 7] {
                let all = path_bases(&run, start, holonomic);
                assert_eq!(all.len(), 39 - start);
                for (n, b) in all.iter().enumerate() {
                    assert_eq!(
                        *b,
                        window_basis(&run, start, start + n + 1, holonomic),
                        "window {start} -> {}",
                        start + n + 1
                    );
                }
            }
        }
    }

    #[test]
    fn amcl_alphas_round_trip_and_sum_to_the_rates_over_updates() {
        let rates = NoiseRates {
            rot_per_rad: 0.01,
            rot_per_m: 0.002,
            trans_per_m: 0.004,
            trans_per_rad: 0.001,
            strafe_per_m: 0.003,
            ..NoiseRates::ZERO
        };
        for holonomic in [true, false] {
            let a = Amcl::from_rates(&rates, holonomic, 0.25, 0.2);
            let back = a.to_rates(holonomic);
            assert!((back.rot_per_m - rates.rot_per_m).abs() < 1e-15);
            // 4 updates of 0.25 m: α3 δ² each sums to trans_per_m · 1 m.
            assert!((4.0 * a.alpha[2] * 0.25f64.powi(2) - rates.trans_per_m).abs() < 1e-15);
        }
        assert_eq!(Amcl::from_rates(&rates, false, 0.25, 0.2).alpha[4], 0.0);
    }
}
