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
    /// An unknown effect or parameter name; the message names the known name it most likely meant
    /// ([`nearest_name`]).
    #[error("unknown {what} {name:?}{}; known: {known}", did_you_mean(name, known))]
    Unknown {
        /// `effect` or `parameter`.
        what: &'static str,
        /// The name given.
        name: String,
        /// The accepted names, comma-separated.
        known: String,
    },
    /// A model parameter's value outside its domain (a radius that is not > 0, a value that is not finite).
    #[error("parameter {name}: {value} is not {must}")]
    BadParam {
        /// The parameter's name, e.g. `r_a`.
        name: String,
        /// The value given.
        value: f64,
        /// What it must be.
        must: Domain,
    },
    /// A design geometry the model's kinematics cannot describe (a mecanum base off its rectangle, a diff
    /// drive without a common axle).
    #[error("the {model} model's geometry: {why}")]
    Layout {
        /// The model whose layout it is not.
        model: crate::KinematicsKind,
        /// What the model needs of it.
        why: &'static str,
    },
    /// A setting of the simulator or its lidar outside its range.
    #[error("{of} {field}: {why}")]
    Setting {
        /// Whose setting.
        of: Settings,
        /// The field, e.g. `duration_s` or `commands[2].alpha_rad`.
        field: String,
        /// Why it is rejected.
        why: String,
    },
    /// Anything else that is refused, with what it concerns: the failures that are one of a kind (a run
    /// without wheel columns, run-to-design maps, the reference's and the gyro's windows, lidar scans and
    /// rooms, an IK matrix entry, the controller fit). A group of them that grows gets its own variant.
    #[error("{what}: {why}")]
    Invalid {
        /// What was being set.
        what: String,
        /// Why it is rejected.
        why: String,
    },
}

/// What a value must be, in [`KinError::BadParam`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// Finite (no NaN or infinity).
    Finite,
    /// Finite and above zero.
    Positive,
}

impl std::fmt::Display for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Finite => "finite",
            Self::Positive => "> 0",
        })
    }
}

/// Whose settings a [`KinError::Setting`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Settings {
    /// The simulator's (`SimConfig`, its commands and legs).
    Simulator,
    /// The simulated lidar's (`ScanSettings`).
    Lidar,
}

impl std::fmt::Display for Settings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Simulator => "simulator",
            Self::Lidar => "lidar",
        })
    }
}

/// What a base with forward-kinematics rank `needed` must produce, for [`KinError::Singular`].
fn twists_named(needed: usize) -> String {
    if needed >= crate::geometry::PLANAR_TWIST_DIMENSIONS {
        "every planar twist".to_string()
    } else {
        format!("{needed} independent twist directions")
    }
}

/// `" (did you mean \"x\"?)"` for the [`nearest_name`] of `name` among the comma-separated `known`, or
/// nothing.
fn did_you_mean(name: &str, known: &str) -> String {
    nearest_name(name, known.split(", ")).map_or_else(String::new, |n| format!(" (did you mean {n:?}?)"))
}

/// The known name a mistyped `name` most likely meant: the only one it begins, else the nearest a typo away
/// (Damerau–Levenshtein distance at most 1 for names up to five letters, else at most a third of the
/// name's length).
pub fn nearest_name<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let names: Vec<&str> = known.into_iter().collect();
    let prefixed: Vec<&str> = names.iter().copied().filter(|k| !name.is_empty() && k.starts_with(name)).collect();
    if let [only] = prefixed[..] {
        return Some(only);
    }
    let limit = (name.chars().count() / 3).max(1);
    names
        .iter()
        .map(|k| (strsim::damerau_levenshtein(name, k), *k))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

impl KinError {
    /// An unknown `what` named `name`, among the `known` names.
    pub fn unknown(what: &'static str, name: &str, known: &[impl AsRef<str>]) -> Self {
        let known: Vec<&str> = known.iter().map(AsRef::as_ref).collect();
        Self::Unknown { what, name: name.into(), known: known.join(", ") }
    }
}
