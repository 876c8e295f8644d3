//! Errors of the kinematics core. Each variant carries the values that locate the problem.

use thiserror::Error;

/// What a run's value belongs to, in [`KinError`]'s messages: readers map a bad one back to its line or
/// message by it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sample {
    /// A wheel sample (time and one speed per wheel).
    Wheel,
    /// A ground-truth pose.
    Truth,
}

impl std::fmt::Display for Sample {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Wheel => "wheel sample",
            Self::Truth => "ground-truth pose",
        })
    }
}

/// What can be wrong with a robot description, a model or a run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum KinError {
    /// A wheel description is not physical.
    #[error("wheel {wheel}: {field} = {value} is not valid ({why})")]
    BadWheel {
        /// Wheel index (0-based).
        wheel: usize,
        /// Field name, e.g. `radius_m`.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// Why it is rejected.
        why: &'static str,
    },
    /// The wheels cannot produce the twists the base needs.
    #[error("robot with {wheels} wheels cannot produce {} (the wheel matrix has rank {rank} < {needed})", twists_named(*needed))]
    Singular {
        /// Wheel count.
        wheels: usize,
        /// Numerical rank found.
        rank: usize,
        /// Rank the base needs: 3 (every planar twist) for an omnidirectional base.
        needed: usize,
    },
    /// A matrix or vector has the wrong size.
    #[error("{what} has {got} entries, expected {expected}")]
    Shape {
        /// What was being built.
        what: String,
        /// Entries found.
        got: usize,
        /// Entries expected.
        expected: usize,
    },
    /// A run has too few samples or poses.
    #[error("run {run}: {what} has {got} entries, at least {min} are needed")]
    TooShort {
        /// Run name.
        run: String,
        /// `wheel samples` or `ground-truth poses`.
        what: &'static str,
        /// Count found.
        got: usize,
        /// Minimum count.
        min: usize,
    },
    /// A value is NaN or infinite.
    #[error("run {run}: {what} {index} has non-finite {field} {value}")]
    NonFinite {
        /// Run name.
        run: String,
        /// A wheel sample or a ground-truth pose.
        what: Sample,
        /// Index of the sample or pose (0-based).
        index: usize,
        /// Field, e.g. `t_s` or `wheel_rad_s[2]`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A finite value beyond what any real recording holds (a corrupted or misscaled field).
    #[error("run {run}: {what} {index} has {field} = {value}, beyond the plausible limit ±{limit}")]
    Implausible {
        /// Run name.
        run: String,
        /// A wheel sample or a ground-truth pose.
        what: Sample,
        /// Index of the sample or pose (0-based).
        index: usize,
        /// Field, e.g. `t_s` or `wheel_rad_s[2]`.
        field: String,
        /// The value.
        value: f64,
        /// The limit on its magnitude, in the field's unit (named by its suffix: `_s`, `_rad_s`, `_m`, `_rad`).
        limit: f64,
    },
    /// Time stamps do not strictly increase.
    #[error(
        "run {run}: {what} {index} has time {t_s} s, not after the previous {prev_s} s (stamps must strictly increase)"
    )]
    NotIncreasing {
        /// Run name.
        run: String,
        /// A wheel sample or a ground-truth pose.
        what: Sample,
        /// Index (0-based).
        index: usize,
        /// Its time. s.
        t_s: f64,
        /// The previous time. s.
        prev_s: f64,
    },
    /// Wheel samples do not cover the ground-truth time span.
    #[error(
        "run {run}: wheel samples span {wheel_start_s}..{wheel_end_s} s but ground truth spans {truth_start_s}..{truth_end_s} s (wheel data must cover the ground truth)"
    )]
    Coverage {
        /// Run name.
        run: String,
        /// First wheel stamp. s.
        wheel_start_s: f64,
        /// Last wheel stamp. s.
        wheel_end_s: f64,
        /// First ground-truth stamp. s.
        truth_start_s: f64,
        /// Last ground-truth stamp. s.
        truth_end_s: f64,
    },
    /// A run's wheel count does not match the model's.
    #[error("run {run} has {got} wheels but the model has {expected}")]
    WheelCount {
        /// Run name.
        run: String,
        /// Wheels in the run.
        got: usize,
        /// Wheels in the model.
        expected: usize,
    },
    /// A parameter vector does not match the model.
    #[error("parameter vector has {got} entries but the model has {expected} parameters")]
    ParamCount {
        /// Entries given.
        got: usize,
        /// Parameters of the model.
        expected: usize,
    },
    /// An unknown effect or parameter name.
    #[error("unknown {what} {name:?}; known: {known}")]
    Unknown {
        /// `effect` or `parameter`.
        what: &'static str,
        /// The name given.
        name: String,
        /// The accepted names, comma-separated.
        known: String,
    },
    /// An invalid setting or value.
    #[error("{what}: {why}")]
    Invalid {
        /// What was being set.
        what: String,
        /// Why it is rejected.
        why: String,
    },
}

/// What a base with forward-kinematics rank `needed` must produce, for [`KinError::Singular`].
fn twists_named(needed: usize) -> String {
    if needed >= crate::geometry::PLANAR_TWIST_DIMENSIONS {
        "every planar twist".to_string()
    } else {
        format!("{needed} independent twist directions")
    }
}
