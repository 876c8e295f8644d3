//! What is wrong with a description ([`RobotError`]: the field and its [`RobotProblem`]), and the checks on
//! single values that find it (finite, positive, plausible).

use super::BaseKind;
#[cfg(doc)]
use super::RobotDescription;
use super::wheels::MAX_ROLLER_DEG;
use thiserror::Error;

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

pub(super) fn err(field: impl Into<String>, problem: RobotProblem) -> RobotError {
    RobotError { field: field.into(), problem }
}

pub(super) fn finite(field: String, v: f64) -> Result<f64, RobotError> {
    if v.is_finite() { Ok(v) } else { Err(err(field, RobotProblem::NotFinite { value: v })) }
}

pub(super) fn positive(field: String, v: f64) -> Result<f64, RobotError> {
    let v = finite(field.clone(), v)?;
    if v > 0.0 { Ok(v) } else { Err(err(field, RobotProblem::NotPositive { value: v })) }
}

/// `v` when it is at most `max_m`, else what it looks like.
pub(super) fn plausible(field: String, v: f64, what: &'static str, max_m: f64) -> Result<f64, RobotError> {
    if v <= max_m { Ok(v) } else { Err(err(field, RobotProblem::Implausible { value: v, what, max_m })) }
}
