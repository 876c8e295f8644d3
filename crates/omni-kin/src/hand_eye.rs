//! A sensor's mount on the base from motions alone (planar hand–eye calibration, as Censi, Franchi, Marchionni
//! and Oriolo do for odometry and an exteroceptive sensor, IEEE T-RO 2013): over each stretch of time the base
//! moves by `B` (dead reckoning through a design matrix) and the sensor, mounted at `X` (`base_from_sensor`),
//! moves by `A` in its own frame, with `X · A = B · X`. The rotations agree whatever the mount; the
//! translations give, linearly in `t_X` and `(cos φ, sin φ)` of the mount's yaw φ,
//!
//! `(I − R_B) t_X + R_φ t_A = t_B`,
//!
//! solved by least squares over every stretch: a first estimate for any yaw, which the fit then refines with
//! the wheels. A wheel scale off by `k` (the design's radii, a unit) scales `t_B`, hence the solution, by `k`:
//! the length of `(cos φ, sin φ)` as solved is `k`, and dividing by it gives the mount in the sensor's metres
//! and the design's distance per sensor distance besides. The rotations tell whether the sensor's frame is
//! mirrored (a lidar upside down read as upright turns against the base): [`RotationAgreement`].

use crate::ik::IkMatrix;
use crate::pose::{Pose2, wrap_angle};
use crate::run::Run;
use nalgebra::{Matrix4, Vector4};

/// One stretch of time: the base's motion by dead reckoning and the sensor's motion it measured, each in
/// its own frame at the stretch's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionPair {
    /// The base's motion (the design's dead reckoning). m, rad.
    pub body: Pose2,
    /// The sensor's motion (the reference's). m, rad.
    pub sensor: Pose2,
}

/// Stretches are cut between reference poses at least this far apart. s.
pub const STRETCH_S: f64 = 1.0;

/// The motion pairs of `runs` (their ground truth is the sensor's path): each run cut into stretches between
/// reference poses at least [`STRETCH_S`] apart, the base dead reckoned through `ik` over the same time (its
/// wheel speeds held over their intervals). Runs whose wheel count is not the matrix's are left out.
pub fn motion_pairs(runs: &[Run], ik: &IkMatrix) -> Vec<MotionPair> {
    let mut pairs = Vec::new();
    for run in runs.iter().filter(|r| r.n_wheels() == ik.n_wheels()) {
        let truth = run.truth();
        let mut a = 0;
        for b in 1..truth.len() {
            if truth[b].t_s - truth[a].t_s < STRETCH_S && b + 1 < truth.len() {
                continue;
            }
            let sensor = truth[a].pose.inverse().compose(&truth[b].pose);
            pairs.push(MotionPair { body: dead_reckoning(run, ik, truth[a].t_s, truth[b].t_s), sensor });
            a = b;
        }
    }
    pairs
}

/// The base's motion over `[a_s, b_s]` through `ik`, each wheel sample's speeds held over the interval that
/// ends at it (as the integrator holds them), in the frame at `a_s`.
fn dead_reckoning(run: &Run, ik: &IkMatrix, a_s: f64, b_s: f64) -> Pose2 {
    let ts = run.wheel_t_s();
    let (mut x, mut y, mut th) = (0.0, 0.0, 0.0_f64);
    let first = ts.partition_point(|&t| t <= a_s).max(1);
    for k in first..ts.len() {
        let dt = ts[k].min(b_s) - ts[k - 1].max(a_s);
        if dt > 0.0 {
            let v = ik.twist(run.wheel_sample(k));
            x += (v.vx_m_s * th.cos() - v.vy_m_s * th.sin()) * dt;
            y += (v.vx_m_s * th.sin() + v.vy_m_s * th.cos()) * dt;
            th += v.omega_rad_s * dt;
        }
        if ts[k] >= b_s {
            break;
        }
    }
    Pose2::new(x, y, th)
}

/// How the sensor's turning follows the base's: the slope of the sensor's turn on the base's over the
/// stretches (least squares through zero). About 1 for a sensor read in its true frame (the design's
/// turning a few per cent off), about −1 for a mirrored one (a lidar upside down read as upright).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationAgreement {
    /// Sensor turn per base turn.
    pub slope: f64,
    /// Share of the sensor's turning the slope explains (R² through zero).
    pub explained: f64,
    /// The base's turning summed over the stretches (|turn| each). rad.
    pub body_turn_rad: f64,
    /// Stretches.
    pub pairs: usize,
}

/// The base must have turned this much over the stretches for [`rotation_agreement`] to judge. rad.
pub const MIN_TURN_RAD: f64 = 1.0;

/// The [`RotationAgreement`] of `pairs`, when the base turned at least [`MIN_TURN_RAD`] over them.
pub fn rotation_agreement(pairs: &[MotionPair]) -> Option<RotationAgreement> {
    let (mut bb, mut ab, mut aa, mut turned) = (0.0, 0.0, 0.0, 0.0);
    for p in pairs {
        let (b, a) = (p.body.theta_rad, wrap_angle(p.sensor.theta_rad));
        bb += b * b;
        ab += a * b;
        aa += a * a;
        turned += b.abs();
    }
    if turned < MIN_TURN_RAD || aa.is_nan() || aa <= 0.0 {
        return None;
    }
    let slope = ab / bb;
    let explained = 1.0 - (aa - 2.0 * slope * ab + slope * slope * bb) / aa;
    Some(RotationAgreement { slope, explained, body_turn_rad: turned, pairs: pairs.len() })
}

/// The mount found from the motions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MountEstimate {
    /// The sensor's pose on the base, in the sensor's metres. m, rad.
    pub base_from_sensor: Pose2,
    /// The design's distance per sensor distance (1 when the design's wheels and the sensor agree).
    pub body_per_sensor: f64,
    /// Standard error of the yaw. rad.
    pub yaw_std_rad: f64,
    /// Standard error of the position (the larger axis's). m.
    pub position_std_m: f64,
    /// RMS of the translation residuals over the stretches kept. m.
    pub residual_rms_m: f64,
    /// Stretches kept (those whose residual is not an outlier).
    pub pairs: usize,
}

/// Residuals beyond this many times their median are outliers (a bad match, a wheel slip), dropped before
/// the second solve.
const OUTLIER_FACTOR: f64 = 5.0;

/// The mount that best explains `pairs` ([the module's equation](self)), solved twice (the second time
/// without the stretches whose residual is an outlier); `None` when the stretches do not determine it (too
/// few, or no translation).
pub fn estimate_mount(pairs: &[MotionPair]) -> Option<MountEstimate> {
    let first = solve(pairs, &vec![true; pairs.len()])?;
    let mut r: Vec<f64> = pairs.iter().map(|p| residual(&first.0, p)).collect();
    let keep: Vec<bool> = {
        let mut sorted = r.clone();
        sorted.sort_by(f64::total_cmp);
        let limit = OUTLIER_FACTOR * sorted[sorted.len() / 2];
        r.iter().map(|&e| e <= limit).collect()
    };
    let (x, cov) = solve(pairs, &keep)?;
    r = pairs.iter().zip(&keep).filter(|(_, k)| **k).map(|(p, _)| residual(&x, p)).collect();
    let n = r.len();
    let sigma2 = r.iter().map(|e| e * e).sum::<f64>() / (2 * n).saturating_sub(4).max(1) as f64;
    let k = x[2].hypot(x[3]);
    if !k.is_finite() || k <= 0.0 {
        return None;
    }
    // Var of the yaw: the component of (c, s)'s covariance across the direction, over k².
    let (c, s) = (x[2] / k, x[3] / k);
    let across = Vector4::new(0.0, 0.0, -s, c);
    let yaw_var = sigma2 * (across.transpose() * cov * across)[0] / (k * k);
    let position_var = sigma2 * cov[(0, 0)].max(cov[(1, 1)]) / (k * k);
    Some(MountEstimate {
        base_from_sensor: Pose2::new(x[0] / k, x[1] / k, x[3].atan2(x[2])),
        body_per_sensor: k,
        yaw_std_rad: yaw_var.sqrt(),
        position_std_m: position_var.sqrt(),
        residual_rms_m: (sigma2 * (2 * n).saturating_sub(4).max(1) as f64 / (2 * n) as f64).sqrt(),
        pairs: n,
    })
}

/// The two rows of one pair: `(I − R_B) t_X + [t_A, J t_A] (c, s)ᵀ = t_B` as `rows · (tx, ty, c, s) = rhs`.
fn rows(p: &MotionPair) -> ([Vector4<f64>; 2], [f64; 2]) {
    let (cb, sb) = (p.body.theta_rad.cos(), p.body.theta_rad.sin());
    let (ax, ay) = (p.sensor.x_m, p.sensor.y_m);
    ([Vector4::new(1.0 - cb, sb, ax, -ay), Vector4::new(-sb, 1.0 - cb, ay, ax)], [p.body.x_m, p.body.y_m])
}

/// The translation residual of one pair at `x` = (tx, ty, c, s). m.
fn residual(x: &Vector4<f64>, p: &MotionPair) -> f64 {
    let (r, rhs) = rows(p);
    (r[0].dot(x) - rhs[0]).hypot(r[1].dot(x) - rhs[1])
}

/// Least squares over the pairs kept: the solution and the inverse of the normal matrix; `None` when it is
/// singular (no rotation or no translation among them) or fewer than three pairs are kept.
fn solve(pairs: &[MotionPair], keep: &[bool]) -> Option<(Vector4<f64>, Matrix4<f64>)> {
    let (mut n, mut b, mut used) = (Matrix4::zeros(), Vector4::zeros(), 0);
    for (p, _) in pairs.iter().zip(keep).filter(|(_, k)| **k) {
        let (r, rhs) = rows(p);
        for (row, y) in r.iter().zip(rhs) {
            n += row * row.transpose();
            b += row * y;
        }
        used += 1;
    }
    if used < 3 {
        return None;
    }
    // Singular in practice: a direction of the normal matrix below 1e-9 of its largest.
    let eig = n.symmetric_eigenvalues();
    if eig.min().is_nan() || eig.min() <= 1e-9 * eig.max() {
        return None;
    }
    let cov = n.try_inverse()?;
    Some((cov * b, cov))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pairs of a base driving arcs and turning on the spot, seen by a sensor at `mount`, the base's
    /// dead reckoning `scale` times the sensor's distances, with a deterministic wobble of `noise_m`.
    fn pairs(mount: Pose2, scale: f64, noise_m: f64) -> Vec<MotionPair> {
        (0..40)
            .map(|i| {
                let t = i as f64;
                let body = Pose2::new(0.3 * (0.7 * t).cos(), 0.2 * (1.3 * t).sin(), 0.8 * (0.9 * t).sin());
                let sensor = mount.inverse().compose(&body).compose(&mount);
                let wobble = noise_m * (3.7 * t).sin();
                MotionPair {
                    body: Pose2::new(scale * body.x_m, scale * body.y_m, body.theta_rad),
                    sensor: Pose2::new(sensor.x_m + wobble, sensor.y_m - wobble, sensor.theta_rad),
                }
            })
            .collect()
    }

    #[test]
    fn any_yaw_comes_back_exactly_from_exact_motions_whatever_the_wheel_scale() {
        for yaw_deg in [0.0, 5.0, 90.0, -89.0, -107.0, 180.0] {
            let mount = Pose2::new(0.2, -0.05, f64::to_radians(yaw_deg));
            for scale in [1.0, 2.0, 0.5] {
                let e = estimate_mount(&pairs(mount, scale, 0.0)).unwrap();
                let m = e.base_from_sensor;
                assert!((m.x_m - 0.2).abs() < 1e-9 && (m.y_m + 0.05).abs() < 1e-9, "{yaw_deg}°, ×{scale}: {m:?}");
                assert!(wrap_angle(m.theta_rad - mount.theta_rad).abs() < 1e-9, "{yaw_deg}°: {m:?}");
                assert!((e.body_per_sensor - scale).abs() < 1e-9, "{e:?}");
            }
        }
    }

    #[test]
    fn noisy_motions_give_the_mount_within_its_standard_errors() {
        let mount = Pose2::new(0.2, 0.0, f64::to_radians(-107.0));
        let e = estimate_mount(&pairs(mount, 1.0, 0.003)).unwrap();
        let m = e.base_from_sensor;
        assert!(e.yaw_std_rad > 0.0 && e.yaw_std_rad < 0.02, "{e:?}");
        assert!(wrap_angle(m.theta_rad - mount.theta_rad).abs() < 4.0 * e.yaw_std_rad, "{e:?}");
        assert!((m.x_m - 0.2).abs() < 4.0 * e.position_std_m && m.y_m.abs() < 4.0 * e.position_std_m, "{e:?}");
    }

    #[test]
    fn straight_motion_alone_leaves_the_position_undetermined_and_a_mirrored_sensor_turns_against() {
        let straight: Vec<MotionPair> = (0..10)
            .map(|_| MotionPair { body: Pose2::new(0.5, 0.0, 0.0), sensor: Pose2::new(0.0, -0.5, 0.0) })
            .collect();
        assert_eq!(estimate_mount(&straight), None);
        let mirrored: Vec<MotionPair> = pairs(Pose2::IDENTITY, 1.0, 0.0)
            .into_iter()
            .map(|p| MotionPair { sensor: Pose2::new(p.sensor.x_m, -p.sensor.y_m, -p.sensor.theta_rad), ..p })
            .collect();
        let a = rotation_agreement(&mirrored).unwrap();
        assert!((a.slope + 1.0).abs() < 1e-9 && (a.explained - 1.0).abs() < 1e-9, "{a:?}");
        assert!((rotation_agreement(&pairs(Pose2::IDENTITY, 1.0, 0.0)).unwrap().slope - 1.0).abs() < 1e-9);
    }
}
