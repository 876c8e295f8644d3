//! Robot descriptions: the schema of `robot.toml` (docs/formats.md, "Robot description"), its checks, and
//! its conversion into a [`RobotGeometry`] and the design IK matrix.
//!
//! A description names the base kind and its wheels in the order of the model's columns:
//! - `omni`: N ≥ 3 omni wheels. Each wheel has a position (`x_m`, `y_m`, or polar `distance_m`,
//!   `angle_deg`), a radius, and the direction its rim pushes the robot at positive wheel speed
//!   (`drive_deg`, default: the tangent `angle_deg + 90°`, counter-clockwise).
//! - `mecanum`: 4 mecanum wheels; rollers at ±45° (`roller_angle_deg`), driving forward by default.
//! - `diff`: 2 wheels on one axle, `[diff]` with `wheel_separation_m`, the two radii and joints (left
//!   first). Positive wheel speed drives forward. The design matrix's `vy` row is zero.
//! - `skid`: 4 or more wheels on two sides (`y_m > 0` left, `< 0` right), driving forward by default
//!   (`drive_deg` 0, or 180 for a joint that turns the other way), without rollers. The design is the
//!   differential drive of the sides' mean positions ([`crate::kinematics::SkidKinematics`]).
//!
//! Angles in the file are degrees (`_deg`), lengths metres (`_m`); the geometry stores radians. A
//! description that matches the paper's APR-02 to 1e-12 gives exactly [`RobotGeometry::apr02`] and the
//! paper's printed Eq. 7 ([`IkMatrix::paper_design`]), so results on the paper's robot do not depend on
//! how its file spells the angles.
//!
//! Nothing here reads files: omni-cli parses the TOML text into [`RobotDescription`] (serde, unknown keys
//! refused) and reports [`RobotError`]s with the file and line.
//!
//! - `wheels.rs`: the wheels (`[[wheels]]`, `[diff]`) and their checks, turned into geometry wheels.
//! - `recording.rs`: where the data is: topics, ground-truth frames, a ground-truth file.
//! - `priors.rs`: the design values' uncertainties and the search box they give.
//! - `error.rs`: `RobotError`, `RobotProblem`, and the checks of single values.
//! - `wheel_data.rs`: the units of the wheels' joint data in a recording.

mod error;
mod priors;
mod recording;
#[cfg(test)]
mod tests;
mod wheel_data;
mod wheels;

pub use error::{RobotError, RobotProblem};
pub use priors::{PRIOR_BOX_SIGMAS, Priors};
pub use recording::{Frames, GroundTruthFile, Topics};
pub use wheel_data::{PositionUnit, VelocityUnit, WheelData, WheelField};
pub use wheels::{DiffSpec, MAX_WHEEL_DISTANCE_M, MAX_WHEEL_RADIUS_M, WheelSpec};

use crate::geometry::{RobotGeometry, Wheel};
use crate::ik::IkMatrix;
use crate::kinematics::{BaseKinematics, SkidKinematics};
use error::err;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use thiserror::Error;

/// Two descriptions closer than this (m, rad) are the same robot (used to recognise APR-02).
const SAME_ROBOT_TOL: f64 = 1e-12;

/// The kind of wheeled base.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BaseKind {
    /// N ≥ 3 omni wheels (free rollers across the drive direction).
    Omni,
    /// Four mecanum wheels (rollers at ±45°).
    Mecanum,
    /// Differential drive: two wheels on one axle.
    Diff,
    /// Skid-steer: 4, 6 or more wheels on two sides, driving along x without steering (Husky, Jackal).
    Skid,
}

crate::choice!(BaseKind, {
    Omni => "omni": "N ≥ 3 omni wheels",
    Mecanum => "mecanum": "Four mecanum wheels",
    Diff => "diff": "Differential drive",
    Skid => "skid": "Skid-steer: wheels on two sides, driving along x",
});

impl BaseKind {
    /// The name used in `robot.toml`: `omni`, `mecanum`, `diff`, `skid` (its [`crate::Choice`] id).
    pub fn name(self) -> &'static str {
        self.id()
    }

    /// Degrees of freedom of the body twist the base can produce (rank of its forward matrix).
    pub fn dof(self) -> usize {
        match self {
            Self::Omni | Self::Mecanum => 3,
            Self::Diff | Self::Skid => 2,
        }
    }

    /// The base model `train` fits when none is named: the robot's own parametric model where it has one
    /// that every robot of the kind obeys (`diff`, `skid`), else the paper's IK matrix (`ik`), which holds
    /// any wheel layout.
    pub fn default_model(self) -> crate::KinematicsKind {
        match self {
            Self::Omni | Self::Mecanum => crate::KinematicsKind::Ik,
            Self::Diff => crate::KinematicsKind::Diff,
            Self::Skid => crate::KinematicsKind::Skid,
        }
    }
}

/// A robot description: the contents of a `robot.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotDescription {
    /// A name for messages and reports. Optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The base kind.
    pub kind: BaseKind,
    /// The wheels (`omni`, `mecanum`), in the order of the model's columns.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub wheels: Vec<WheelSpec>,
    /// The axle of a differential-drive base (`diff` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff: Option<DiffSpec>,
    /// Where the data is in a recording.
    #[serde(default, skip_serializing_if = "Topics::is_empty")]
    pub topics: Topics,
    /// Frames of the ground truth in a TF topic.
    #[serde(default, skip_serializing_if = "Frames::is_empty")]
    pub frames: Frames,
    /// Ground truth from a separate file instead of a topic (`--gt`). Optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<GroundTruthFile>,
    /// How well the design values are known. Optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub priors: Option<Priors>,
    /// The units of the wheels' joint data in a recording. Default: rad and rad/s on the wheel's shaft.
    #[serde(default, skip_serializing_if = "WheelData::is_default")]
    pub wheel_data: WheelData,
}

impl RobotDescription {
    /// The paper's APR-02: three omni wheels, r = 0.148 m, R = 0.195 m, δ = 60°, 180°, 300°, joints
    /// `wheel_a`, `wheel_b`, `wheel_c` (the names the simulator writes).
    pub fn apr02() -> Self {
        let wheel = |joint: &str, angle_deg: f64| WheelSpec {
            joint: joint.into(),
            distance_m: Some(0.195),
            angle_deg: Some(angle_deg),
            radius_m: 0.148,
            ..WheelSpec::default()
        };
        Self {
            name: Some("APR-02 (the paper's robot)".into()),
            kind: BaseKind::Omni,
            wheels: vec![wheel("wheel_a", 60.0), wheel("wheel_b", 180.0), wheel("wheel_c", 300.0)],
            diff: None,
            topics: Topics::default(),
            frames: Frames::default(),
            ground_truth: None,
            priors: None,
            wheel_data: Default::default(),
        }
    }

    /// The wheel joint names in the order of the model's columns (left, right for `diff`).
    pub fn joints(&self) -> Vec<String> {
        match (&self.kind, &self.diff) {
            (BaseKind::Diff, Some(d)) => vec![d.left_joint.clone(), d.right_joint.clone()],
            _ => self.wheels.iter().map(|w| w.joint.clone()).collect(),
        }
    }

    /// Checks everything: the wheel count and tables for the kind, joint names (present, distinct), every
    /// value (finite, radii and separation > 0), mecanum rollers at ±45°, the rank of the wheels' forward
    /// matrix (3 for omni and mecanum, 2 for diff), the priors.
    pub fn validate(&self) -> Result<(), RobotError> {
        self.unchecked_geometry().map(|_| ())
    }

    /// The geometry as written, after every check of [`validate`](Self::validate) (the geometry's own
    /// checks are [`to_geometry`](Self::to_geometry)'s).
    pub fn unchecked_geometry(&self) -> Result<RobotGeometry, RobotError> {
        let wheels = match self.kind {
            BaseKind::Diff => {
                if !self.wheels.is_empty() {
                    return Err(err("wheels", RobotProblem::Layout("a diff base takes [diff], not [[wheels]]")));
                }
                let d = self.diff.as_ref().ok_or_else(|| {
                    err("diff", RobotProblem::Layout("a diff base needs a [diff] table (wheel_separation_m, …)"))
                })?;
                d.to_wheels()?
            }
            kind => {
                if self.diff.is_some() {
                    return Err(err("diff", RobotProblem::Layout("[diff] is only for kind = \"diff\"")));
                }
                self.checked_wheels(kind)?
            }
        };
        if let Some(p) = &self.priors {
            p.validate()?;
        }
        self.wheel_data.validate()?;
        let g = RobotGeometry { wheel_names: self.joints(), wheels };
        let rank = g.rank();
        if rank < self.kind.dof() {
            let field = if self.kind == BaseKind::Diff { "diff" } else { "wheels" };
            return Err(err(field, RobotProblem::Rank { kind: self.kind, rank, needed: self.kind.dof() }));
        }
        Ok(g)
    }

    fn checked_wheels(&self, kind: BaseKind) -> Result<Vec<Wheel>, RobotError> {
        let n = self.wheels.len();
        let expected = match kind {
            BaseKind::Mecanum if n != 4 => Some("exactly 4"),
            BaseKind::Skid if n < 4 || !n.is_multiple_of(2) => {
                Some("an even number, at least 4 (2 wheels: kind = \"diff\")")
            }
            BaseKind::Omni if n < 3 => Some("at least 3 (2 wheels on one axle: kind = \"diff\")"),
            _ => None,
        };
        if let Some(expected) = expected {
            return Err(err("wheels", RobotProblem::WheelCount { kind, expected, got: n }));
        }
        let mut out = Vec::with_capacity(n);
        for (i, w) in self.wheels.iter().enumerate() {
            let at = format!("wheels[{i}]");
            if let Some(j) = self.wheels[..i].iter().position(|o| o.joint == w.joint) {
                return Err(err(
                    format!("{at}.joint"),
                    RobotProblem::DuplicateJoint { name: w.joint.clone(), other: format!("wheels[{j}]") },
                ));
            }
            out.push(w.to_wheel(kind, &at)?);
        }
        if kind == BaseKind::Skid {
            let sides: Vec<f64> = out.iter().map(|w| (w.distance_m * w.angle_rad.sin()).signum()).collect();
            let left = sides.iter().filter(|s| **s > 0.0).count();
            if left * 2 != n || sides.contains(&0.0) {
                return Err(err(
                    "wheels",
                    RobotProblem::Layout("a skid-steer base has as many wheels left (y_m > 0) as right (y_m < 0)"),
                ));
            }
        }
        let angles: Vec<f64> = self.wheels.iter().filter_map(|w| w.angle_deg).collect();
        let spread = angles.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - angles.iter().copied().fold(f64::INFINITY, f64::min);
        if angles.len() == n && n >= 3 && angles.iter().all(|a| a.abs() <= 2.0 * PI + 1e-9) && spread > 1.0 {
            let values: Vec<String> = angles.iter().map(|a| format!("{a}")).collect();
            return Err(err("wheels", RobotProblem::AnglesInRadians { values: values.join(", ") }));
        }
        Ok(out)
    }

    /// The design geometry, checked (also by [`RobotGeometry::validate_for`] the kind's rank: 2 for diff). A description within 1e-12 of
    /// APR-02 gives [`RobotGeometry::apr02`]'s values exactly, with this description's joint names.
    pub fn to_geometry(&self) -> Result<RobotGeometry, GeometryError> {
        let g = self.unchecked_geometry()?;
        let g = if is_apr02(&g) { RobotGeometry { wheel_names: g.wheel_names, ..RobotGeometry::apr02() } } else { g };
        g.validate_for(self.kind.dof())?;
        Ok(g)
    }

    /// The design IK matrix (3 × N, `twist_from_wheels`). APR-02: the paper's Eq. 7 as printed. Diff: the
    /// closed form `vx = (r_l ω_l + r_r ω_r)/2`, `vy = 0`, `ω = (r_r ω_r − r_l ω_l)/s`. Otherwise the
    /// (least-squares) inverse of the wheels' forward matrix.
    pub fn design_ik(&self) -> Result<IkMatrix, GeometryError> {
        let g = self.unchecked_geometry()?;
        if is_apr02(&g) {
            return Ok(IkMatrix::paper_design());
        }
        match (self.kind, &self.diff) {
            (BaseKind::Diff, Some(d)) => {
                let (rl, rr, s) = (d.left_radius_m, d.right_radius_m, d.wheel_separation_m);
                Ok(IkMatrix::new(2, vec![rl / 2.0, rr / 2.0, 0.0, 0.0, -rl / s, rr / s])?)
            }
            (BaseKind::Skid, _) => {
                let k = SkidKinematics::new(g).map_err(GeometryError::Geometry)?;
                let p = k.design_params()?;
                Ok(k.twist_from_wheels(&p)?)
            }
            _ => Ok(g.twist_from_wheels()?),
        }
    }

    /// The forward matrix (N × 3): wheel speeds (rad/s) from a body twist (vx, vy m/s, ω rad/s).
    pub fn wheels_from_twist(&self) -> Result<DMatrix<f64>, RobotError> {
        Ok(self.unchecked_geometry()?.wheels_from_twist())
    }
}

/// Whether a geometry is the paper's APR-02 (every value within 1e-12), whatever the wheel names.
fn is_apr02(g: &RobotGeometry) -> bool {
    let apr = RobotGeometry::apr02();
    g.wheels.len() == apr.wheels.len()
        && g.wheels.iter().zip(&apr.wheels).all(|(a, b)| {
            [
                (a.radius_m, b.radius_m),
                (a.distance_m, b.distance_m),
                (a.angle_rad, b.angle_rad),
                (a.drive_offset_rad, b.drive_offset_rad),
                (a.roller_angle_rad, b.roller_angle_rad),
            ]
            .iter()
            .all(|(x, y)| (x - y).abs() <= SAME_ROBOT_TOL)
        })
}

/// A description that is valid on its own but not (yet) as a [`RobotGeometry`].
#[derive(Clone, Debug, PartialEq, Error)]
pub enum GeometryError {
    /// The description itself is wrong.
    #[error(transparent)]
    Description(#[from] RobotError),
    /// The geometry check refused it.
    #[error(transparent)]
    Geometry(#[from] crate::error::KinError),
}
