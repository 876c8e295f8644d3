//! The library API both front ends call: typed requests, validated once, and the work they describe.
//!
//! The command line's clap `Args` (what was typed, `cmd/`) convert into these requests (what to do); the
//! Python binding (omni-py) builds the same requests from its keyword arguments. Nothing here parses a
//! command line or names a CLI type: argument lists read into these requests (the Python wheel's fleet
//! workers) are [`crate::argv`]'s, a front end of its own.
//!
//! - [`ModelSpec`]: the model a command works with (`design`, `paper` or a model file).
//! - [`load::LoadRequest`] and [`load::DataOptions`]: which runs to read and how.
//! - [`fit::FitOptions`]: a preset's objective and identifiability overrides, and the refusals of a fit.
//! - [`train::TrainRequest`], [`diagnose::DiagnoseRequest`]: `omnical train` and `omnical diagnose`
//!   without a terminal.
//! - [`info::info`]: what ROS recordings hold and what a read makes of them (`omnical info`).
//! - [`imu::imu`]: an IMU's yaw rate as a rotation reference (`omnical imu`).
//! - [`simulate`]: simulated recordings with their lidar and IMU (`omnical simulate`).
//! - [`settings`]: every setting's one declaration (its flag, project-file key, `omnical config` row and
//!   Python keyword).

pub mod diagnose;
pub mod explore;
pub mod fit;
pub mod held_out;
pub mod imu;
pub mod info;
pub mod load;
pub mod noise;
pub mod plausibility;
pub mod settings;
pub mod simulate;
pub mod train;

use crate::dataset::Dataset;
use crate::design::{self, DesignError};
use crate::model_file::ModelFileError;
use crate::robot_file::{self, NoDesign};
use omni_kin::{FittedModel, RunModels};
use std::path::{Path, PathBuf};

/// Version of the layout of every `--json` document (docs/json.md): each carries it as `schema_version`,
/// with the command's name as `command`. Raised when a field changes meaning or is removed.
pub const JSON_SCHEMA_VERSION: u32 = 1;

/// A model named as the command line's `--model` names it: `design` (the design model the data's robot
/// declares, each run its own input's where they differ), `paper` (the paper's calibrated APR-02, Eq. 9)
/// or a model file (`train --out`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ModelSpec {
    /// The data's design model ([`design::declared`]).
    Design,
    /// The paper's calibrated APR-02 ([`design::paper_calibrated`]).
    Paper,
    /// A model file.
    File(PathBuf),
}

impl ModelSpec {
    /// The model file this spec reads, if any.
    pub fn file(&self) -> Option<&Path> {
        match self {
            Self::File(p) => Some(p),
            Self::Design | Self::Paper => None,
        }
    }

    /// The spec a path spells: `design` and `paper` are the built-in names, anything else a model file.
    pub fn from_path(path: &Path) -> Self {
        match path.to_str() {
            Some("design") => Self::Design,
            Some("paper") => Self::Paper,
            _ => Self::File(path.to_path_buf()),
        }
    }

    /// The one model this spec stands for on `ds`'s runs: `design` the one the most runs declare (none is
    /// an error), `paper`, or the model file read.
    pub fn resolve(&self, ds: &Dataset) -> Result<FittedModel, ResolveError> {
        match self {
            Self::Design => Ok(design::declared(ds)?.ok_or_else(|| robot_file::no_design("--model design"))?),
            Self::Paper => Ok(design::paper_calibrated()),
            Self::File(path) => {
                let model = crate::model_file::read(path).map_err(ResolveError::ModelFile)?;
                same_wheels(&model, ds, path)?;
                Ok(model)
            }
        }
    }

    /// Whether this spec is a model file marked interrupted ([`crate::model_file::ModelFile::interrupted`]);
    /// a file that cannot be read is not (reading it for the model says why).
    pub fn interrupted(&self) -> bool {
        match self {
            Self::File(path) => crate::model_file::read_marked(path).is_ok_and(|(_, interrupted)| interrupted),
            Self::Design | Self::Paper => false,
        }
    }

    /// The model of every run of `sets`: `design` each run's own ([`design::declared_each`]; none is an
    /// error), else [`ModelSpec::resolve`]'s one model for all.
    pub fn resolve_each(&self, sets: &[&Dataset]) -> Result<RunModels, ResolveError> {
        match (self, sets.first()) {
            (Self::Design, _) => {
                Ok(design::declared_each(sets)?.ok_or_else(|| robot_file::no_design("--model design"))?)
            }
            (_, Some(ds)) => Ok(RunModels::from(self.resolve(ds)?)),
            (_, None) => Err(ResolveError::NoRuns { spec: self.clone() }),
        }
    }
}

/// Refuses a model file whose wheels are named otherwise than the joints of the robot description the data
/// was read with (another robot's model, or the same wheels in another column order); either side's
/// default names (`wheel_a`, …) say nothing.
fn same_wheels(model: &FittedModel, ds: &Dataset, path: &Path) -> Result<(), ResolveError> {
    let Some(robot) = &ds.robot_file else { return Ok(()) };
    let (names, joints) = (model.model.kinematics.wheel_names(), robot.description.joints());
    let default = |v: &[String]| *v == omni_kin::geometry::default_wheel_names(v.len());
    if names == joints || default(&names) || default(&joints) {
        return Ok(());
    }
    Err(ResolveError::OtherWheels { model: path.to_path_buf(), names, robot: robot.source.clone(), joints })
}

/// Why a [`ModelSpec`] stands for no model.
#[derive(Debug, thiserror::Error)]
pub enum ResolveError {
    /// `design` on data that names no robot.
    #[error(transparent)]
    NoDesign(#[from] NoDesign),
    /// The design could not be built.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The model file could not be read.
    #[error("reading the model")]
    ModelFile(#[source] ModelFileError),
    /// A model file of wheels named otherwise than the robot description's joints.
    #[error(
        "{}: the model's wheels are {}, but {robot} names the robot's wheel joints {}: {}; use the model trained for \
         this robot (or give --robot the description it was trained with)",
        model.display(),
        names.join(", "),
        joints.join(", "),
        order_or_other(names, joints)
    )]
    OtherWheels {
        /// The model file.
        model: PathBuf,
        /// Its wheel names, in its column order.
        names: Vec<String>,
        /// The robot description.
        robot: robot_file::Source,
        /// Its wheel joints, in column order.
        joints: Vec<String>,
    },
    /// Nothing to resolve the spec for (a bug in the caller).
    #[error("no runs to resolve {spec} for (a bug)")]
    NoRuns {
        /// The spec.
        spec: ModelSpec,
    },
}

impl std::str::FromStr for ModelSpec {
    type Err = std::convert::Infallible;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(Self::from_path(Path::new(s)))
    }
}

impl std::fmt::Display for ModelSpec {
    /// As spelt on the command line (`design`, `paper`, the file's path).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Design => f.write_str("design"),
            Self::Paper => f.write_str("paper"),
            Self::File(p) => write!(f, "{}", p.display()),
        }
    }
}

/// Whether two lists of wheel names are the same wheels in another order, in words.
fn order_or_other(names: &[String], joints: &[String]) -> &'static str {
    let (mut a, mut b) = (names.to_vec(), joints.to_vec());
    a.sort();
    b.sort();
    if a == b { "the same wheels in another column order" } else { "a model of another robot" }
}
