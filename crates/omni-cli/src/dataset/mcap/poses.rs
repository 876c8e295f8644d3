//! A stamped planar pose sequence gathered from pose messages (PoseStamped, PoseWithCovarianceStamped,
//! Odometry, or one parent → child pair of TFMessage), and how it becomes `StampedPose`s.
//!
//! Planar: x and y of the position, and the yaw of the orientation (z and roll/pitch are dropped). The yaw
//! sequence is unwrapped so the heading is continuous, then shifted by a whole number of turns so the first
//! pose of each run lies in (−π, π].

use super::common::{Quaternion, Stamp, Vector3, pose_problem, seconds_since};
use omni_kin::pose::{unwrap_headings, wrap_angle};
use omni_kin::{Pose2, StampedPose};
use std::f64::consts::PI;

/// Poses of one source, in message order.
#[derive(Debug, Default)]
pub(super) struct PoseSeries {
    /// Frame of the first pose (`header.frame_id`, without a leading `/`).
    pub frame: Option<String>,
    /// `child_frame_id` of the first pose, for Odometry and TF.
    pub child: Option<String>,
    /// Stamps. ns.
    pub t_ns: Vec<i64>,
    /// `[x_m, y_m, yaw_rad]` with yaw in (−π, π].
    pub xy_yaw: Vec<[f64; 3]>,
}

/// The names of the fields of one pose, for messages: `pose.position` and `pose.orientation`.
pub(super) struct Fields {
    pub stamp: &'static str,
    pub position: &'static str,
    pub orientation: &'static str,
}

impl PoseSeries {
    /// Takes one pose, or says what is wrong with it.
    pub fn push(&mut self, t_ns: i64, position: &Vector3, orientation: &Quaternion, f: &Fields) -> Result<(), String> {
        if let Some(problem) = pose_problem(f.position, position, f.orientation, orientation) {
            return Err(problem);
        }
        if let Some(&prev) = self.t_ns.last()
            && t_ns <= prev
        {
            return Err(format!(
                "{} {} is not after the previous pose's {} (stamps must increase)",
                f.stamp,
                Stamp(t_ns),
                Stamp(prev)
            ));
        }
        self.t_ns.push(t_ns);
        self.xy_yaw.push([position.x, position.y, orientation.yaw_rad()]);
        Ok(())
    }

    /// Checks that a later message keeps the frame of the first, and records the first's.
    pub fn check_frame(&mut self, frame: &str, child: Option<&str>) -> Result<(), String> {
        match &self.frame {
            None => {
                self.frame = Some(frame.to_string());
                self.child = child.map(str::to_string);
                Ok(())
            }
            Some(first) if first != frame => {
                Err(format!("header.frame_id {frame:?} differs from the first message's {first:?}"))
            }
            Some(_) => match (&self.child, child) {
                (Some(first), Some(c)) if first != c => {
                    Err(format!("child_frame_id {c:?} differs from the first message's {first:?}"))
                }
                _ => Ok(()),
            },
        }
    }

    /// The poses in seconds since `origin_s`, heading unwrapped.
    pub fn stamped(&self, origin_s: i64) -> Vec<StampedPose> {
        let mut poses: Vec<StampedPose> = self
            .t_ns
            .iter()
            .zip(&self.xy_yaw)
            .map(|(&t, &[x, y, yaw])| StampedPose { t_s: seconds_since(t, origin_s), pose: Pose2::new(x, y, yaw) })
            .collect();
        unwrap_headings(&mut poses);
        poses
    }
}

/// Shifts every heading by the same whole number of turns so the first lies in (−π, π].
pub(super) fn start_heading_in_half_turn(poses: &mut [StampedPose]) {
    if let Some(first) = poses.first() {
        let shift = first.pose.theta_rad - wrap_angle(first.pose.theta_rad);
        let turns = (shift / (2.0 * PI)).round();
        if turns != 0.0 {
            for p in poses.iter_mut() {
                p.pose.theta_rad -= turns * 2.0 * PI;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: Fields = Fields { stamp: "header.stamp", position: "pose.position", orientation: "pose.orientation" };

    #[test]
    fn unwraps_the_heading() {
        let mut s = PoseSeries::default();
        let yaws = [3.0, -3.0, -1.0, 1.0, 3.0, -3.1];
        for (k, yaw) in yaws.iter().enumerate() {
            s.push(k as i64 * 1_000_000_000, &Vector3::default(), &Quaternion::from_yaw(*yaw), &F).unwrap();
        }
        let th: Vec<f64> = s.stamped(0).iter().map(|p| p.pose.theta_rad).collect();
        let expected = [3.0, 2.0 * PI - 3.0, 2.0 * PI - 1.0, 2.0 * PI + 1.0, 2.0 * PI + 3.0, 4.0 * PI - 3.1];
        for (a, b) in th.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{th:?}");
        }
        let mut p = s.stamped(0)[3..].to_vec();
        start_heading_in_half_turn(&mut p);
        assert!((p[0].pose.theta_rad - 1.0).abs() < 1e-12 && (p[2].pose.theta_rad - (2.0 * PI - 3.1)).abs() < 1e-12);
    }

    #[test]
    fn rejects_nan_zero_rotation_and_backwards_stamps() {
        let mut s = PoseSeries::default();
        let nan = Vector3 { x: f64::NAN, ..Default::default() };
        let q = Quaternion::from_yaw(0.0);
        assert_eq!(s.push(0, &nan, &q, &F).unwrap_err(), "field pose.position.x is NaN");
        let zero = Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 0.0 };
        assert_eq!(
            s.push(0, &Vector3::default(), &zero, &F).unwrap_err(),
            "field pose.orientation is not a rotation (x = y = z = w = 0)"
        );
        s.push(2_000_000_000, &Vector3::default(), &q, &F).unwrap();
        assert_eq!(
            s.push(1_500_000_000, &Vector3::default(), &q, &F).unwrap_err(),
            "header.stamp 1.500000000 is not after the previous pose's 2.000000000 (stamps must increase)"
        );
    }
}
