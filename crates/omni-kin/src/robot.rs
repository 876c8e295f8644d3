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
//!
//! Angles in the file are degrees (`_deg`), lengths metres (`_m`); the geometry stores radians. A
//! description that matches the paper's APR-02 to 1e-12 gives exactly [`RobotGeometry::apr02`] and the
//! paper's printed Eq. 7 ([`IkMatrix::paper_design`]), so results on the paper's robot do not depend on
//! how its file spells the angles.
//!
//! Nothing here reads files: omni-cli parses the TOML text into [`RobotDescription`] (serde, unknown keys
//! refused) and reports [`RobotError`]s with the file and line.

use crate::geometry::{RobotGeometry, Wheel};
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};
use thiserror::Error;

/// Two descriptions closer than this (m, rad) are the same robot (used to recognise APR-02).
const SAME_ROBOT_TOL: f64 = 1e-12;
/// Largest roller angle of an omni wheel. deg. (At 90° the rollers run along the drive: no traction.)
const MAX_ROLLER_DEG: f64 = 80.0;
/// Mecanum rollers sit at ±45° within this tolerance. deg.
const MECANUM_ROLLER_TOL_DEG: f64 = 1e-9;

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
}

crate::choice!(BaseKind, {
    Omni => "omni": "N ≥ 3 omni wheels",
    Mecanum => "mecanum": "Four mecanum wheels",
    Diff => "diff": "Differential drive",
});

impl BaseKind {
    /// The name used in `robot.toml`: `omni`, `mecanum`, `diff` (its [`crate::Choice`] id).
    pub fn name(self) -> &'static str {
        self.id()
    }

    /// Degrees of freedom of the body twist the base can produce (rank of its forward matrix).
    pub fn dof(self) -> usize {
        match self {
            Self::Omni | Self::Mecanum => 3,
            Self::Diff => 2,
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
    /// `angle + 90` (counter-clockwise tangent), mecanum `0` (forward).
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

/// Topics of a recording (ROS 2 MCAP). Each replaces the automatic choice; command-line flags override.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Topics {
    /// The wheels' `sensor_msgs/JointState` topic (`--joints-topic`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_states: Option<String>,
    /// The ground-truth topic (`--gt-topic`): PoseStamped, Odometry, or TF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<String>,
    /// The motion command topic (Twist or TwistStamped). Default `/cmd_vel`, else the only one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub command: Option<String>,
}

impl Topics {
    fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Frames of the ground truth in a TF topic.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frames {
    /// The ground truth's world frame, e.g. `map` (`--gt-parent-frame`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth_parent: Option<String>,
    /// The tracked frame on the robot, e.g. `base_link` (`--gt-child-frame`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth_child: Option<String>,
}

impl Frames {
    fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// Ground truth from a separate file (`[ground_truth]`): a TUM or CSV trajectory, e.g. from motion capture.
/// Command-line flags (`--gt`, `--gt-time-offset`, `--gt-columns`, `--gt-units`) override each entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundTruthFile {
    /// The file (one recording) or a folder of files named after the recordings, relative to the robot
    /// description's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Forced clock offset, `t_wheel = t_truth + offset`. s. Default: estimated from the data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_offset_s: Option<f64>,
    /// CSV column names: keys `t`, `x`, `y`, `yaw`. Default: the columns named `t`, `x`, `y`, `yaw` (or a
    /// quaternion `qx`, `qy`, `qz`, `qw`).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub columns: std::collections::BTreeMap<String, String>,
    /// CSV units: `time` (s, ms, us, ns), `length` (m, cm, mm), `angle` (rad, deg). Default s, m, rad.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub units: std::collections::BTreeMap<String, String>,
}

/// One-sigma uncertainties of the design values, as measured or as the drawings promise. Checked: finite
/// and positive. A parametric fit (`geometry`, `diff`, `mecanum`) searches the design ± [`PRIOR_BOX_SIGMAS`]
/// σ of each parameter they cover ([`Priors::std_of`]) instead of ±10 %, and reports its fitted values in σ.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Priors {
    /// Wheel radius. m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_std_m: Option<f64>,
    /// Wheel position (each axis, or the distance). m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_std_m: Option<f64>,
    /// Wheel angle and drive direction. deg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_std_deg: Option<f64>,
    /// Wheel separation (`diff`). m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separation_std_m: Option<f64>,
}

/// What is wrong with a description, at which field (`wheels[2].radius_m`, `diff.left_joint`, `kind`).
#[derive(Clone, Debug, PartialEq, Error)]
#[error("{field}: {problem}")]
pub struct RobotError {
    /// The field, as a TOML path: `wheels[2].radius_m` (wheel indices from 0).
    pub field: String,
    /// The problem.
    pub problem: RobotProblem,
}

/// The problems [`RobotDescription::validate`] finds.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum RobotProblem {
    /// Too few or too many wheels for the kind.
    #[error("a {kind} base needs {expected} wheels, this one has {got}")]
    WheelCount {
        /// The kind.
        kind: BaseKind,
        /// `at least 3`, `exactly 4`.
        expected: &'static str,
        /// Wheels given.
        got: usize,
    },
    /// A table that the kind does not use, or one that it needs, is missing.
    #[error("{0}")]
    Layout(&'static str),
    /// Two wheels share a joint name.
    #[error("joint {name:?} is also the joint of {other}; each wheel needs its own joint")]
    DuplicateJoint {
        /// The name.
        name: String,
        /// The other field naming it.
        other: String,
    },
    /// An empty joint name.
    #[error("the joint name is empty")]
    EmptyJoint,
    /// A value that must be positive is not.
    #[error("{value} must be > 0")]
    NotPositive {
        /// The value.
        value: f64,
    },
    /// A length no wheeled robot has (a value in millimetres, a typo).
    #[error("{value} m is not a plausible {what} (at most {max_m} m): is it in millimetres?")]
    Implausible {
        /// The value. m.
        value: f64,
        /// What it is (`wheel radius`, `distance from the centre`, …).
        what: &'static str,
        /// The largest plausible value. m.
        max_m: f64,
    },
    /// Every wheel angle within a few degrees of 0 on a base that needs them spread round it.
    #[error(
        "the wheel angles ({values}) all lie within ±2π, which puts the wheels within a few degrees of each \
         other: angle_deg is in degrees (are these radians?)"
    )]
    AnglesInRadians {
        /// The angles as written. deg.
        values: String,
    },
    /// A value that must not be negative is.
    #[error("{value} must be ≥ 0")]
    Negative {
        /// The value.
        value: f64,
    },
    /// NaN or infinite.
    #[error("{value} is not a finite number")]
    NotFinite {
        /// The value.
        value: f64,
    },
    /// The position is given in neither or both forms, or half of one.
    #[error("give the position as x_m and y_m, or as distance_m and angle_deg ({0})")]
    Position(&'static str),
    /// A mecanum roller not at ±45°.
    #[error("{value_deg}° is not a mecanum roller angle (±45)")]
    MecanumRoller {
        /// The value. deg.
        value_deg: f64,
    },
    /// A roller angle beyond what transmits force.
    #[error("{value_deg}° is beyond ±{MAX_ROLLER_DEG}° (rollers along the drive give no traction)")]
    RollerTooSteep {
        /// The value. deg.
        value_deg: f64,
    },
    /// The wheels cannot produce every motion of the kind (collinear or parallel drive directions).
    #[error(
        "the wheels can produce only {rank} of the {needed} independent body motions (vx, vy, ω) a {kind} base \
         needs: their drive directions are parallel or their lines of action meet in one point"
    )]
    Rank {
        /// The kind.
        kind: BaseKind,
        /// Numerical rank of the forward matrix.
        rank: usize,
        /// The kind's degrees of freedom.
        needed: usize,
    },
}

fn err(field: impl Into<String>, problem: RobotProblem) -> RobotError {
    RobotError { field: field.into(), problem }
}

fn finite(field: String, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() { Ok(v) } else { Err(err(field, RobotProblem::NotFinite { value: v })) }
}

fn positive(field: String, v: f64) -> Result<f64, RobotError> {
    let v = finite(field.clone(), v)?;
    if v > 0.0 { Ok(v) } else { Err(err(field, RobotProblem::NotPositive { value: v })) }
}

/// Largest plausible wheel radius. m.
pub const MAX_WHEEL_RADIUS_M: f64 = 2.0;
/// Largest plausible distance of a wheel from the base's centre, or wheel separation. m.
pub const MAX_WHEEL_DISTANCE_M: f64 = 20.0;

/// `v` when it is at most `max_m`, else what it looks like.
fn plausible(field: String, v: f64, what: &'static str, max_m: f64) -> Result<f64, RobotError> {
    if v <= max_m { Ok(v) } else { Err(err(field, RobotProblem::Implausible { value: v, what, max_m })) }
}

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
    fn to_wheel(&self, kind: BaseKind, at: &str) -> Result<Wheel, RobotError> {
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
            _ if roller_deg.abs() >= MAX_ROLLER_DEG => {
                return Err(err(field("roller_angle_deg"), RobotProblem::RollerTooSteep { value_deg: roller_deg }));
            }
            _ => {}
        }
        let drive_offset_rad = match (self.drive_deg, kind) {
            (Some(d), _) => wrap_rad(finite(field("drive_deg"), d)?.to_radians() - angle_rad - FRAC_PI_2),
            // Omni wheels push along the counter-clockwise tangent; mecanum wheels forward.
            (None, BaseKind::Mecanum) => -angle_rad - FRAC_PI_2,
            (None, _) => 0.0,
        };
        Ok(Wheel { radius_m, distance_m, angle_rad, drive_offset_rad, roller_angle_rad: roller_deg.to_radians() })
    }
}

impl DiffSpec {
    /// The two wheels as geometry (left at +y, right at −y, both driving forward), checked.
    fn to_wheels(&self) -> Result<Vec<Wheel>, RobotError> {
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

/// How many standard deviations of a prior the GA's search box spans on each side of the design value.
pub const PRIOR_BOX_SIGMAS: f64 = 3.0;

impl Priors {
    /// The one-sigma uncertainty of a base parameter, by its name, in the parameter's unit (rad for
    /// angles): `radius_std_m` for the radii `r_*` (geometry, mecanum, diff), `position_std_m` for the
    /// distances `R_*` and the half-extents `lx`, `ly`, `angle_std_deg` for the angles `delta_*`,
    /// `separation_std_m` for `b`. `None` for what the priors do not cover (an `ik` matrix entry, a prior
    /// not given).
    pub fn std_of(&self, param: &str) -> Option<f64> {
        if param.starts_with("r_") {
            self.radius_std_m
        } else if param.starts_with("R_") || param == "lx" || param == "ly" {
            self.position_std_m
        } else if param.starts_with("delta_") {
            self.angle_std_deg.map(f64::to_radians)
        } else if param == "b" {
            self.separation_std_m
        } else {
            None
        }
    }

    fn validate(&self) -> Result<(), RobotError> {
        let all = [
            ("radius_std_m", self.radius_std_m),
            ("position_std_m", self.position_std_m),
            ("angle_std_deg", self.angle_std_deg),
            ("separation_std_m", self.separation_std_m),
        ];
        for (f, v) in all {
            if let Some(v) = v {
                positive(format!("priors.{f}"), v)?;
            }
        }
        Ok(())
    }
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

#[cfg(test)]
mod tests;
mod wheel_data;

pub use wheel_data::{PositionUnit, VelocityUnit, WheelData};
