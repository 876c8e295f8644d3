//! The wheels of a description (`[[wheels]]`, `[diff]`): their schema, checks, and conversion into geometry
//! [`Wheel`]s (positions in either form, drive directions, roller angles, plausible sizes).

use super::BaseKind;
use super::error::{RobotError, RobotProblem, err, finite, plausible, positive};
use crate::geometry::{RobotGeometry, Wheel};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Largest roller angle of an omni wheel. deg. (At 90° the rollers run along the drive: no traction.)
pub(super) const MAX_ROLLER_DEG: f64 = 80.0;
/// Mecanum rollers sit at ±45° within this tolerance. deg.
const MECANUM_ROLLER_TOL_DEG: f64 = 1e-9;

/// One wheel of an `omni` or `mecanum` base. Give the position either as `x_m`, `y_m` or as
/// `distance_m`, `angle_deg`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelSpec {
    /// The wheel's joint name (ROS `sensor_msgs/JointState`).
    pub joint: String,
    /// Contact point, forward of the rotation centre. m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x_m: Option<f64>,
    /// Contact point, left of the rotation centre. m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y_m: Option<f64>,
    /// Distance of the contact point from the rotation centre. m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distance_m: Option<f64>,
    /// Angle of the contact point, from x (forward) towards y (left). deg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<f64>,
    /// Direction the rim pushes the robot at positive wheel speed, from x towards y. deg. Default: omni
    /// `angle + 90` (counter-clockwise tangent), mecanum and skid `0` (forward).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drive_deg: Option<f64>,
    /// Wheel radius. m.
    pub radius_m: f64,
    /// Roller angle: the wheel transmits force along `drive_deg + roller_angle_deg`. deg. Default 0 (omni);
    /// mecanum ±45.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roller_angle_deg: Option<f64>,
}

/// The axle of a differential-drive base. Positive wheel speed drives the robot forward.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiffSpec {
    /// Distance between the two wheels' contact points. m.
    pub wheel_separation_m: f64,
    /// Left wheel's joint name (the model's first column).
    pub left_joint: String,
    /// Right wheel's joint name (the second column).
    pub right_joint: String,
    /// Left wheel radius. m.
    pub left_radius_m: f64,
    /// Right wheel radius. m.
    pub right_radius_m: f64,
}

/// Largest plausible wheel radius. m.
pub const MAX_WHEEL_RADIUS_M: f64 = 2.0;
/// Largest plausible distance of a wheel from the base's centre, or wheel separation. m.
pub const MAX_WHEEL_DISTANCE_M: f64 = 20.0;

/// Angle wrapped into (−π, π]. rad.
fn wrap_rad(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI { w - 2.0 * PI } else { w }
}

impl WheelSpec {
    /// Contact point in polar form: (distance m, angle rad).
    fn polar(&self, at: &str) -> Result<(f64, f64), RobotError> {
        let field = |f: &str| format!("{at}.{f}");
        match (self.x_m, self.y_m, self.distance_m, self.angle_deg) {
            (Some(x), Some(y), None, None) => {
                let (x, y) = (finite(field("x_m"), x)?, finite(field("y_m"), y)?);
                Ok((x.hypot(y), y.atan2(x)))
            }
            (None, None, Some(d), Some(a)) => {
                let d = finite(field("distance_m"), d)?;
                if d < 0.0 {
                    return Err(err(field("distance_m"), RobotProblem::Negative { value: d }));
                }
                Ok((d, finite(field("angle_deg"), a)?.to_radians()))
            }
            (None, None, None, None) => Err(err(at, RobotProblem::Position("neither is given"))),
            (Some(_), None, ..) | (None, Some(_), ..) => Err(err(at, RobotProblem::Position("only half of x_m, y_m"))),
            (None, None, ..) => Err(err(at, RobotProblem::Position("only half of distance_m, angle_deg"))),
            _ => Err(err(at, RobotProblem::Position("both forms are given"))),
        }
    }

    /// This wheel as a geometry [`Wheel`], checked.
    pub(super) fn to_wheel(&self, kind: BaseKind, at: &str) -> Result<Wheel, RobotError> {
        let field = |f: &str| format!("{at}.{f}");
        if self.joint.trim().is_empty() {
            return Err(err(field("joint"), RobotProblem::EmptyJoint));
        }
        let radius_m = positive(field("radius_m"), self.radius_m)?;
        let radius_m = plausible(field("radius_m"), radius_m, "wheel radius", MAX_WHEEL_RADIUS_M)?;
        let (distance_m, angle_rad) = self.polar(at)?;
        let place = if self.distance_m.is_some() { "distance_m" } else { "x_m" };
        plausible(field(place), distance_m, "distance from the centre", MAX_WHEEL_DISTANCE_M)?;
        let roller_deg = finite(field("roller_angle_deg"), self.roller_angle_deg.unwrap_or(0.0))?;
        match kind {
            BaseKind::Mecanum if ((roller_deg.abs() - 45.0).abs() > MECANUM_ROLLER_TOL_DEG) => {
                return Err(err(field("roller_angle_deg"), RobotProblem::MecanumRoller { value_deg: roller_deg }));
            }
            BaseKind::Skid if roller_deg != 0.0 => {
                return Err(err(
                    field("roller_angle_deg"),
                    RobotProblem::Layout("a skid-steer base's wheels have no rollers (leave roller_angle_deg out)"),
                ));
            }
            _ if roller_deg.abs() >= MAX_ROLLER_DEG => {
                return Err(err(field("roller_angle_deg"), RobotProblem::RollerTooSteep { value_deg: roller_deg }));
            }
            _ => {}
        }
        let drive_offset_rad = match (self.drive_deg, kind) {
            (Some(d), _) => wrap_rad(finite(field("drive_deg"), d)?.to_radians() - angle_rad - FRAC_PI_2),
            // Omni wheels push along the counter-clockwise tangent; mecanum and skid-steer wheels forward.
            (None, BaseKind::Mecanum | BaseKind::Skid) => -angle_rad - FRAC_PI_2,
            (None, _) => 0.0,
        };
        Ok(Wheel { radius_m, distance_m, angle_rad, drive_offset_rad, roller_angle_rad: roller_deg.to_radians() })
    }
}

impl DiffSpec {
    /// The two wheels as geometry (left at +y, right at −y, both driving forward), checked.
    pub(super) fn to_wheels(&self) -> Result<Vec<Wheel>, RobotError> {
        for (f, j) in [("diff.left_joint", &self.left_joint), ("diff.right_joint", &self.right_joint)] {
            if j.trim().is_empty() {
                return Err(err(f, RobotProblem::EmptyJoint));
            }
        }
        if self.left_joint == self.right_joint {
            return Err(err(
                "diff.right_joint",
                RobotProblem::DuplicateJoint { name: self.right_joint.clone(), other: "diff.left_joint".into() },
            ));
        }
        let separation = positive("diff.wheel_separation_m".into(), self.wheel_separation_m)?;
        let half =
            plausible("diff.wheel_separation_m".into(), separation, "wheel separation", MAX_WHEEL_DISTANCE_M)? / 2.0;
        let radius = |f: &str, v: f64| plausible(f.into(), positive(f.into(), v)?, "wheel radius", MAX_WHEEL_RADIUS_M);
        let left = radius("diff.left_radius_m", self.left_radius_m)?;
        let right = radius("diff.right_radius_m", self.right_radius_m)?;
        Ok(RobotGeometry::diff_drive(left, right, 2.0 * half).wheels)
    }
}
