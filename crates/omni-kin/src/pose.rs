//! Planar poses and twists (SE(2)), REP-103 conventions: x forward, y left, yaw counter-clockwise, metres
//! and radians.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Wrap an angle to (−π, π]. Radians.
pub fn wrap_angle(a_rad: f64) -> f64 {
    let mut w = a_rad % (2.0 * PI);
    if w <= -PI {
        w += 2.0 * PI;
    } else if w > PI {
        w -= 2.0 * PI;
    }
    w
}

/// Make a heading sequence continuous: each heading moves by whole turns to lie within π of the previous
/// one. Already-continuous sequences are left bit-identical; a jump of one turn is one subtraction of 2π.
/// Constant time per pose whatever the jump (a huge or infinite heading is left for `Run::new` to reject).
pub fn unwrap_headings(poses: &mut [StampedPose]) {
    const TURN: f64 = 2.0 * PI;
    for i in 1..poses.len() {
        let prev = poses[i - 1].pose.theta_rad;
        let mut th = poses[i].pose.theta_rad;
        let jump = th - prev;
        if !jump.is_finite() || jump.abs() <= PI {
            continue;
        }
        if jump.abs() > 3.0 * PI {
            th -= (jump / TURN).round() * TURN;
        }
        if th - prev > PI {
            th -= TURN;
        } else if th - prev < -PI {
            th += TURN;
        }
        poses[i].pose.theta_rad = th;
    }
}

/// A planar pose: position in metres and heading in radians. Used as `world_from_body`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// Position x. m.
    pub x_m: f64,
    /// Position y. m.
    pub y_m: f64,
    /// Heading (yaw), counter-clockwise. rad. Not wrapped: odometry keeps it continuous.
    pub theta_rad: f64,
}

impl Pose2 {
    /// A pose from its components (m, m, rad).
    pub const fn new(x_m: f64, y_m: f64, theta_rad: f64) -> Self {
        Self { x_m, y_m, theta_rad }
    }

    /// The identity pose.
    pub const IDENTITY: Pose2 = Pose2::new(0.0, 0.0, 0.0);

    /// `self ∘ other`: if `self` is `a_from_b` and `other` is `b_from_c`, the result is `a_from_c`.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let (s, c) = self.theta_rad.sin_cos();
        Pose2 {
            x_m: self.x_m + c * other.x_m - s * other.y_m,
            y_m: self.y_m + s * other.x_m + c * other.y_m,
            theta_rad: self.theta_rad + other.theta_rad,
        }
    }

    /// The inverse transform: `b_from_a` for `a_from_b`.
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = self.theta_rad.sin_cos();
        Pose2 { x_m: -(c * self.x_m + s * self.y_m), y_m: -(-s * self.x_m + c * self.y_m), theta_rad: -self.theta_rad }
    }

    /// Error of `self` against a reference: world-frame (dx, dy) in m and the heading difference wrapped to
    /// (−π, π] in rad — the terms of the paper's Eq. 6.
    pub fn error_to(&self, reference: &Pose2) -> PoseError {
        PoseError {
            dx_m: self.x_m - reference.x_m,
            dy_m: self.y_m - reference.y_m,
            dtheta_rad: wrap_angle(self.theta_rad - reference.theta_rad),
        }
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.x_m.is_finite() && self.y_m.is_finite() && self.theta_rad.is_finite()
    }
}

/// A pose with its time stamp. s, m, rad.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StampedPose {
    /// Time. s.
    pub t_s: f64,
    /// The pose at `t_s`.
    pub pose: Pose2,
}

/// A body-frame twist: the vector the IK matrix produces from wheel speeds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist2 {
    /// Forward velocity. m/s.
    pub vx_m_s: f64,
    /// Leftward velocity. m/s.
    pub vy_m_s: f64,
    /// Yaw rate, counter-clockwise. rad/s.
    pub omega_rad_s: f64,
}

/// A pose difference in the world frame (model minus reference): the terms of Eq. 6.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseError {
    /// x difference. m.
    pub dx_m: f64,
    /// y difference. m.
    pub dy_m: f64,
    /// Heading difference wrapped to (−π, π]. rad.
    pub dtheta_rad: f64,
}

impl PoseError {
    /// The paper's Eq. 6 term: sqrt(dx² + dy² + dθ²), mixing m and rad with weight 1.
    pub fn norm(&self) -> f64 {
        (self.dx_m * self.dx_m + self.dy_m * self.dy_m + self.dtheta_rad * self.dtheta_rad).sqrt()
    }

    /// Position error only. m.
    pub fn position_m(&self) -> f64 {
        self.dx_m.hypot(self.dy_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn unwrap_takes_constant_time_and_keeps_small_jumps_bit_identical() {
        let at = |th: &[f64]| -> Vec<StampedPose> {
            th.iter().map(|&t| StampedPose { t_s: 0.0, pose: Pose2::new(0.0, 0.0, t) }).collect()
        };
        let got = |mut p: Vec<StampedPose>| -> Vec<f64> {
            unwrap_headings(&mut p);
            p.iter().map(|q| q.pose.theta_rad).collect()
        };
        // One turn: one subtraction, as before.
        assert_eq!(got(at(&[3.1, -3.1])), [3.1, -3.1 + 2.0 * PI]);
        // A thousand turns and more: whole turns removed at once, within π of the previous heading.
        let far = got(at(&[0.5, 0.5 + 2000.0 * PI + 0.25]));
        assert!((far[1] - 0.75).abs() < 1e-9, "{far:?}");
        // Huge and infinite headings end (they are left for Run::new to reject), NaN is left alone.
        let huge = got(at(&[0.0, 1e30, f64::INFINITY, f64::NAN, 1.0]));
        assert!(huge[1].abs() < 1e30 * 2.0 && huge[2].is_infinite() && huge[3].is_nan() && huge[4] == 1.0);
    }

    #[test]
    fn wrap_is_half_open() {
        assert_relative_eq!(wrap_angle(PI), PI);
        assert_relative_eq!(wrap_angle(-PI), PI);
        assert_relative_eq!(wrap_angle(3.0 * PI / 2.0), -PI / 2.0, epsilon = 1e-12);
        assert_relative_eq!(wrap_angle(0.1 + 4.0 * PI), 0.1, epsilon = 1e-12);
    }

    #[test]
    fn compose_inverse_is_identity() {
        let a = Pose2::new(1.0, -2.0, 0.7);
        let i = a.compose(&a.inverse());
        assert_relative_eq!(i.x_m, 0.0, epsilon = 1e-12);
        assert_relative_eq!(i.y_m, 0.0, epsilon = 1e-12);
        assert_relative_eq!(i.theta_rad, 0.0, epsilon = 1e-12);
        let b = Pose2::new(0.0, 0.0, PI / 2.0).compose(&Pose2::new(1.0, 0.0, 0.0));
        assert_relative_eq!(b.x_m, 0.0, epsilon = 1e-12);
        assert_relative_eq!(b.y_m, 1.0, epsilon = 1e-12);
    }
}
