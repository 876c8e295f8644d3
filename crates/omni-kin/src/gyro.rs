//! A gyro as a rotation reference. An IMU's yaw rate senses the base's turning and nothing of its
//! translation: it reaches the rotation row of the wheel matrix (ω = m₃ · w) and no other. The row is linear
//! in the data, so it is fitted by least squares, with the gyro's bias, over windows: each window's turn as
//! the gyro integrates it against the wheels' angles over the same window,
//!
//! `∫ω_gyro dt = m₃ · ∫w dt + b · Δt`,
//!
//! which holds at any sample rate of either (the gyro's rate integrated by the trapezoid rule, the wheel
//! speeds held over their intervals as the integrator holds them). A gyro's scale error multiplies the row
//! and cannot be told from it with the gyro alone.

use crate::error::KinError;
use crate::pose::StampedPose;
use crate::run::Run;
use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};
use serde::Serialize;

/// How an IMU sits on the base: the rotation of the IMU's frame in the base frame (`base_from_imu`, as a
/// URDF joint or `/tf_static` states it). The base's yaw rate is the base-z component of the IMU's angular
/// velocity turned into the base frame, so an IMU upside down (roll π) or on its side reads the same yaw rate
/// as an upright one once its mount is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuMount {
    /// The IMU frame's rotation in the base frame.
    pub base_from_imu: UnitQuaternion<f64>,
}

impl ImuMount {
    /// Upright, the IMU's axes the base's.
    pub const UPRIGHT: Self =
        Self { base_from_imu: UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(1.0, 0.0, 0.0, 0.0)) };

    /// The mount of URDF's `rpy` (radians): roll about x, then pitch about y, then yaw about z, all about the
    /// base's fixed axes (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`).
    pub fn from_rpy_rad(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> Self {
        Self { base_from_imu: UnitQuaternion::from_euler_angles(roll_rad, pitch_rad, yaw_rad) }
    }

    /// Roll, pitch and yaw (URDF's `rpy`, [`Self::from_rpy_rad`]). rad.
    pub fn rpy_rad(&self) -> [f64; 3] {
        let (r, p, y) = self.base_from_imu.euler_angles();
        [r, p, y]
    }

    /// The base's yaw rate (rad/s) from the IMU's angular velocity `imu_rad_s` (x, y, z in the IMU's frame):
    /// the base-z component of the vector turned into the base frame.
    pub fn yaw_rate(&self, imu_rad_s: [f64; 3]) -> f64 {
        (self.base_from_imu * Vector3::from(imu_rad_s)).z
    }

    /// The angular velocity in the IMU's frame (x, y, z, rad/s) of a base turning at `yaw_rad_s` about its z.
    pub fn imu_rates(&self, yaw_rad_s: f64) -> [f64; 3] {
        let v = self.base_from_imu.inverse() * Vector3::new(0.0, 0.0, yaw_rad_s);
        [v.x, v.y, v.z]
    }

    /// How far the IMU's z axis points along the base's: 1 upright, −1 upside down, 0 on its side.
    pub fn z_up(&self) -> f64 {
        (self.base_from_imu * Vector3::z()).z
    }
}

/// One gyro sample: the yaw rate about the base's z axis. rad/s, at `t_s` on the run's clock (s).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GyroSample {
    /// s.
    pub t_s: f64,
    /// rad/s.
    pub z_rad_s: f64,
}

/// The rotation row fitted from a gyro.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RotationFit {
    /// ω per wheel speed, one entry per wheel (the wheel matrix's rotation row). rad/s per rad/s.
    pub row: Vec<f64>,
    /// Standard errors of `row` (iid windows).
    pub row_std: Vec<f64>,
    /// The gyro's bias. rad/s.
    pub bias_rad_s: f64,
    /// Standard error of the bias. rad/s.
    pub bias_std_rad_s: f64,
    /// Windows fitted.
    pub windows: usize,
    /// RMS of the windows' turn residuals. rad.
    pub residual_rms_rad: f64,
    /// Total turn the gyro saw (sum of |turn| per window). rad.
    pub turned_rad: f64,
}

/// The least turn the windows must add up to for a fit (rad): below it, the row is noise.
pub const MIN_TURN_RAD: f64 = 1.0;

/// Integral of the gyro rate over `[a, b]` (trapezoid rule on the samples, linear between them; `a`, `b`
/// within the samples' span).
fn gyro_turn(g: &[GyroSample], a: f64, b: f64) -> f64 {
    let at = |t: f64| {
        let i = g.partition_point(|s| s.t_s <= t).clamp(1, g.len() - 1);
        let (p, q) = (g[i - 1], g[i]);
        let f = ((t - p.t_s) / (q.t_s - p.t_s)).clamp(0.0, 1.0);
        (i, p.z_rad_s + f * (q.z_rad_s - p.z_rad_s))
    };
    let (ia, za) = at(a);
    let (ib, zb) = at(b);
    if ia == ib {
        return 0.5 * (za + zb) * (b - a);
    }
    let mut sum = 0.5 * (za + g[ia].z_rad_s) * (g[ia].t_s - a);
    for k in ia..ib - 1 {
        sum += 0.5 * (g[k].z_rad_s + g[k + 1].z_rad_s) * (g[k + 1].t_s - g[k].t_s);
    }
    sum + 0.5 * (g[ib - 1].z_rad_s + zb) * (b - g[ib - 1].t_s)
}

/// Each wheel's angle turned over `[a, b]`: the speeds held over their intervals (rad).
fn wheel_turns(run: &Run, a: f64, b: f64) -> Vec<f64> {
    let t = run.wheel_t_s();
    let mut out = vec![0.0; run.n_wheels()];
    for k in 0..t.len() - 1 {
        let (lo, hi) = (t[k].max(a), t[k + 1].min(b));
        if hi > lo {
            for (o, w) in out.iter_mut().zip(run.wheel_sample(k)) {
                *o += w * (hi - lo);
            }
        }
    }
    out
}

/// The windows of `runs` and their gyro samples (`gyro[i]` for `runs[i]`, in time order, on the run's
/// clock): per window, each wheel's angle turned, the window's length (s), and the gyro's turn (rad).
struct Windows {
    wheel_turns: Vec<Vec<f64>>,
    duration_s: Vec<f64>,
    gyro_turn_rad: Vec<f64>,
}

impl Windows {
    /// Cuts the runs' overlaps with their gyro streams into windows of `window_s`. Errors when the runs
    /// and streams do not pair up, the window is not positive, or the windows number fewer than `at_least`
    /// or turn less than [`MIN_TURN_RAD`] in all.
    fn of(runs: &[Run], gyro: &[Vec<GyroSample>], window_s: f64, at_least: usize) -> Result<Self, KinError> {
        if runs.len() != gyro.len() || runs.is_empty() {
            return Err(invalid(format!("{} runs but {} gyro streams", runs.len(), gyro.len())));
        }
        if !(window_s.is_finite() && window_s > 0.0) {
            return Err(invalid(format!("window {window_s} s: it must be longer than 0")));
        }
        let mut w = Windows { wheel_turns: Vec::new(), duration_s: Vec::new(), gyro_turn_rad: Vec::new() };
        for (run, g) in runs.iter().zip(gyro) {
            if g.len() < 2 {
                continue;
            }
            let t = run.wheel_t_s();
            let (start, end) = (t[0].max(g[0].t_s), t[t.len() - 1].min(g[g.len() - 1].t_s));
            let count = ((end - start) / window_s).floor();
            for k in 0..count.max(0.0) as usize {
                let (a, b) = (start + k as f64 * window_s, start + (k + 1) as f64 * window_s);
                w.wheel_turns.push(wheel_turns(run, a, b));
                w.duration_s.push(b - a);
                w.gyro_turn_rad.push(gyro_turn(g, a, b));
            }
        }
        let turned_rad = w.turned_rad();
        if w.duration_s.len() < at_least || turned_rad < MIN_TURN_RAD {
            return Err(invalid(format!(
                "{} windows of {window_s} s where the wheels and the gyro overlap, turning {turned_rad:.2} rad in \
                 all: at least {at_least} windows and {MIN_TURN_RAD} rad are needed (drive turns while both are \
                 recorded)",
                w.duration_s.len(),
            )));
        }
        Ok(w)
    }

    /// Sum of |turn| over the windows, as the gyro saw it. rad.
    fn turned_rad(&self) -> f64 {
        self.gyro_turn_rad.iter().map(|y| y.abs()).sum()
    }
}

/// The error of the gyro reference.
fn invalid(why: String) -> KinError {
    KinError::Invalid { what: "the gyro reference".into(), why }
}

/// Least squares `y ≈ x β` with iid errors: β, its covariance, and the residual RMS. Errors (with `why`)
/// when the columns of `x` do not determine β.
fn least_squares(x: &DMatrix<f64>, y: &DVector<f64>, why: &str) -> Result<(DVector<f64>, DMatrix<f64>, f64), KinError> {
    let beta = x.clone().svd(true, true).solve(y, 1e-12).map_err(|e| invalid(e.to_string()))?;
    let resid = y - x * &beta;
    let dof = (x.nrows() - x.ncols()).max(1) as f64;
    let sigma2 = resid.norm_squared() / dof;
    let cov = (x.transpose() * x).try_inverse().ok_or_else(|| invalid(why.into()))? * sigma2;
    Ok((beta, cov, (resid.norm_squared() / x.nrows() as f64).sqrt()))
}

/// Fits the rotation row and the gyro's bias from `runs` and their gyro samples (`gyro[i]` for `runs[i]`,
/// in time order, on the run's clock) over windows of `window_s`. Errors when the runs and gyro streams do
/// not pair up, overlap too little, or turn less than [`MIN_TURN_RAD`] in all.
pub fn fit_rotation_row(runs: &[Run], gyro: &[Vec<GyroSample>], window_s: f64) -> Result<RotationFit, KinError> {
    let n = runs.first().map_or(0, Run::n_wheels);
    let w = Windows::of(runs, gyro, window_s, n + 2)?;
    let m = w.duration_s.len();
    let x = DMatrix::from_fn(m, n + 1, |r, c| if c < n { w.wheel_turns[r][c] } else { w.duration_s[r] });
    let y = DVector::from_vec(w.gyro_turn_rad.clone());
    let why = "the wheels' turns do not determine the row (one wheel pattern only, or none turning)";
    let (beta, cov, residual_rms_rad) = least_squares(&x, &y, why)?;
    Ok(RotationFit {
        row: beta.iter().take(n).copied().collect(),
        row_std: (0..n).map(|i| cov[(i, i)].sqrt()).collect(),
        bias_rad_s: beta[n],
        bias_std_rad_s: cov[(n, n)].sqrt(),
        windows: m,
        residual_rms_rad,
        turned_rad: w.turned_rad(),
    })
}

/// The gyro calibrated against a known rotation row (a model fitted on a reference that senses the
/// turning: motion capture, a lidar, a localization): `gyro = scale · ω + bias`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GyroScaleFit {
    /// The gyro's scale: its rate per rad/s of the row's. 1.
    pub scale: f64,
    /// Standard error of `scale` (iid windows).
    pub scale_std: f64,
    /// The gyro's bias. rad/s.
    pub bias_rad_s: f64,
    /// Standard error of the bias. rad/s.
    pub bias_std_rad_s: f64,
    /// Windows fitted.
    pub windows: usize,
    /// RMS of the windows' turn residuals. rad.
    pub residual_rms_rad: f64,
}

/// Fits the gyro's scale and bias against the rotation row `row` (ω per wheel speed, one entry per wheel)
/// over the windows of [`fit_rotation_row`]: each window's gyro turn against `scale · row · wheel turns +
/// bias · Δt`. Errors as [`fit_rotation_row`], and when `row` has not one entry per wheel.
pub fn fit_gyro_scale(
    runs: &[Run],
    gyro: &[Vec<GyroSample>],
    window_s: f64,
    row: &[f64],
) -> Result<GyroScaleFit, KinError> {
    let n = runs.first().map_or(0, Run::n_wheels);
    if row.len() != n {
        return Err(invalid(format!("a rotation row of {} entries for {n} wheels", row.len())));
    }
    let w = Windows::of(runs, gyro, window_s, 4)?;
    let m = w.duration_s.len();
    let turn = |r: usize| w.wheel_turns[r].iter().zip(row).map(|(a, b)| a * b).sum::<f64>();
    let x = DMatrix::from_fn(m, 2, |r, c| if c == 0 { turn(r) } else { w.duration_s[r] });
    let y = DVector::from_vec(w.gyro_turn_rad.clone());
    let (beta, cov, residual_rms_rad) = least_squares(&x, &y, "the row gives the windows no turn")?;
    Ok(GyroScaleFit {
        scale: beta[0],
        scale_std: cov[(0, 0)].sqrt(),
        bias_rad_s: beta[1],
        bias_std_rad_s: cov[(1, 1)].sqrt(),
        windows: m,
        residual_rms_rad,
    })
}

/// Salt of the gyro's random stream, so that its noise draws none of the simulator's other numbers.
const GYRO_SEED_SALT: u64 = 0x1a2b_3c4d_5e6f_7081;

/// A simulated upright gyro on the base: the yaw rate of the true base poses `base` (central differences of
/// the heading at each pose's stamp), plus `bias_rad_s` and Gaussian noise of `noise_rad_s`, drawn from
/// stream `stream` of `seed` (one per run: the same seed gives the same samples whatever the threads).
pub fn simulate_gyro(
    base: &[StampedPose],
    bias_rad_s: f64,
    noise_rad_s: f64,
    seed: u64,
    stream: u64,
) -> Vec<GyroSample> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ GYRO_SEED_SALT);
    rng.set_stream(stream);
    (0..base.len())
        .map(|k| {
            let (a, b) = (base[k.saturating_sub(1)], base[(k + 1).min(base.len() - 1)]);
            let rate = if b.t_s > a.t_s { (b.pose.theta_rad - a.pose.theta_rad) / (b.t_s - a.t_s) } else { 0.0 };
            let z: f64 = StandardNormal.sample(&mut rng);
            GyroSample { t_s: base[k].t_s, z_rad_s: rate + bias_rad_s + noise_rad_s * z }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Pose2;
    use crate::run::RunData;

    /// A run of two wheels whose speeds vary, and its gyro at `rate_hz`: ω = 0.1·w₁ − 0.12·w₂ + 0.01.
    fn run_and_gyro(rate_hz: f64) -> (Run, Vec<GyroSample>) {
        let n = 2001;
        let wheel_t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let speeds = |t: f64| [3.0 * (0.7 * t).sin() + 1.0, 2.0 * (0.3 * t).cos()];
        let wheel_rad_s = wheel_t_s.iter().flat_map(|&t| speeds(t)).collect();
        let truth =
            vec![StampedPose { t_s: 0.0, pose: Pose2::IDENTITY }, StampedPose { t_s: 20.0, pose: Pose2::IDENTITY }];
        let run =
            Run::new(RunData { name: "r".into(), wheel_t_s, wheel_rad_s, n_wheels: 2, truth, ..Default::default() })
                .unwrap();
        // The gyro samples the turn rate the held wheel speeds give (the speed of the interval it falls in).
        let gyro = (0..(20.0 * rate_hz) as usize)
            .map(|k| {
                let t = k as f64 / rate_hz;
                let held = (t / 0.01).floor() * 0.01;
                let w = speeds(held);
                GyroSample { t_s: t, z_rad_s: 0.1 * w[0] - 0.12 * w[1] + 0.01 }
            })
            .collect();
        (run, gyro)
    }

    #[test]
    fn the_row_and_the_bias_come_back_at_any_gyro_rate() {
        for rate in [100.0, 1000.0] {
            let (run, gyro) = run_and_gyro(rate);
            let fit = fit_rotation_row(&[run], &[gyro], 1.0).unwrap();
            let tol = if rate < 500.0 { 2e-3 } else { 2e-4 };
            assert!((fit.row[0] - 0.1).abs() < tol && (fit.row[1] + 0.12).abs() < tol, "{rate} Hz: {fit:?}");
            assert!((fit.bias_rad_s - 0.01).abs() < tol, "{rate} Hz: {fit:?}");
        }
    }

    #[test]
    fn a_mounted_imu_reads_the_base_yaw_rate() {
        use std::f64::consts::{FRAC_PI_2, PI};
        let w = 0.7;
        for (rpy, z_up) in
            [([0.0, 0.0, 0.3], 1.0), ([PI, 0.0, 0.0], -1.0), ([FRAC_PI_2, 0.0, 0.0], 0.0), ([0.0, -PI / 3.0, 1.0], 0.5)]
        {
            let m = ImuMount::from_rpy_rad(rpy[0], rpy[1], rpy[2]);
            let imu = m.imu_rates(w);
            assert!((m.yaw_rate(imu) - w).abs() < 1e-12, "{rpy:?}: {imu:?}");
            assert!((m.z_up() - z_up).abs() < 1e-12, "{rpy:?}");
            let back = m.rpy_rad();
            let again = ImuMount::from_rpy_rad(back[0], back[1], back[2]);
            assert!(again.base_from_imu.angle_to(&m.base_from_imu) < 1e-12, "{rpy:?} → {back:?}");
        }
        // Upside down (roll π): the IMU's own z reads −ω. On its side (roll 90°): its y axis points up and reads ω.
        assert!((ImuMount::from_rpy_rad(PI, 0.0, 0.0).imu_rates(w)[2] + w).abs() < 1e-12);
        let side = ImuMount::from_rpy_rad(FRAC_PI_2, 0.0, 0.0).imu_rates(w);
        assert!(side[0].abs() < 1e-12 && (side[1] - w).abs() < 1e-12 && side[2].abs() < 1e-12, "{side:?}");
        assert_eq!(ImuMount::UPRIGHT.yaw_rate([0.1, 0.2, w]), w);
    }

    #[test]
    fn a_known_row_gives_the_gyros_scale_and_bias() {
        // The gyro reads 1.5 % high with its bias: gyro = 1.015 · (0.1·w₁ − 0.12·w₂) + 1.015 · 0.01.
        let (run, gyro) = run_and_gyro(100.0);
        let scaled: Vec<GyroSample> = gyro.iter().map(|g| GyroSample { z_rad_s: 1.015 * g.z_rad_s, ..*g }).collect();
        let fit =
            fit_gyro_scale(std::slice::from_ref(&run), std::slice::from_ref(&scaled), 1.0, &[0.1, -0.12]).unwrap();
        assert!((fit.scale - 1.015).abs() < 2e-3 && (fit.bias_rad_s - 0.01015).abs() < 2e-3, "{fit:?}");
        // The free row cannot tell the scale from the row: it comes back 1.5 % large.
        let free = fit_rotation_row(std::slice::from_ref(&run), &[scaled], 1.0).unwrap();
        assert!((free.row[0] - 0.1015).abs() < 2e-3 && (free.row[1] + 0.1218).abs() < 2e-3, "{free:?}");
        let err = fit_gyro_scale(&[run], &[gyro], 1.0, &[0.1]).unwrap_err().to_string();
        assert_eq!(err, "the gyro reference: a rotation row of 1 entries for 2 wheels");
    }

    #[test]
    fn too_little_turning_is_refused() {
        let (run, gyro) = run_and_gyro(100.0);
        let err = fit_rotation_row(&[run], &[gyro[..150].to_vec()], 1.0).unwrap_err().to_string();
        assert!(
            err.starts_with(
                "the gyro reference: 1 windows of 1 s where the wheels and the gyro overlap, turning 0.03 rad in all"
            ),
            "{err}"
        );
    }
}
