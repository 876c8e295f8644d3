//! `robot=`: the robot a design comes from, a robot.toml or the built-in `"apr02"`, looked up as the
//! command line's `--robot` (omni_cli::robot_file, omni_cli::design); and the model a call works with when
//! none is given. A call that needs the robot's design and has none raises `ValueError` saying how to give
//! one: there is no silent default robot.

use crate::effect::PyEffect;
use crate::errors::{io_error, value_error};
use crate::model::model_arg;
use omni_cli::robot_file::{self, RobotFile, RobotFileError, Spelling};
use omni_kin::{FittedModel, KinematicsKind};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// How Python names the robot in the no-design message.
const SPELLING: Spelling<'static> =
    Spelling { none: "model= or robot=", file: "robot=\"robot.toml\"", apr02: "robot=\"apr02\"" };

/// A robot description that cannot be read: `FileNotFoundError` / `OSError` for the file, `ValueError`
/// naming the file, line and field for its contents.
pub fn robot_error(e: RobotFileError) -> PyErr {
    let message = e.to_string();
    match &e {
        RobotFileError::Io { error, .. } => io_error(message, error),
        _ => value_error(message),
    }
}

/// `robot=`: None, `"apr02"` (the paper's robot, built in) or the path of a robot.toml.
pub fn robot_arg(robot: Option<&PathBuf>) -> PyResult<Option<RobotFile>> {
    robot.map(|p| robot_file::from_arg(&p.to_string_lossy()).map_err(robot_error)).transpose()
}

/// The design model of `kind` for a robot description, at its design values, wheels named after its joints.
pub fn robot_design(robot: &RobotFile, kind: KinematicsKind) -> PyResult<FittedModel> {
    omni_cli::design::robot_model(kind, robot).map(FittedModel::nominal).map_err(|e| value_error(format!("{e:#}")))
}

/// The `ValueError` of `what` (`"omnical.train"`) when no design is known.
pub fn no_design(what: &str) -> PyErr {
    value_error(robot_file::no_design_text(what, &SPELLING))
}

/// The model `what` works with: `model`, else the `ik` design of `robot`, else the design the data
/// declares (`data`: a Dataset's robot); none of them raises [`no_design`]. `model` and `robot` together
/// are refused (which one would count is not obvious).
pub fn model_or_design(
    model: Option<&Bound<'_, PyAny>>,
    robot: Option<&PathBuf>,
    data: Option<FittedModel>,
    what: &str,
) -> PyResult<(FittedModel, Vec<Arc<PyEffect>>)> {
    if let (Some(_), Some(r)) = (model, robot) {
        return Err(value_error(format!(
            "{what}: give model= or robot=, not both (robot={:?} stands for its design model; for another \
             kinematics pass model=omnical.Model.design(robot=..., kinematics=...))",
            r.to_string_lossy()
        )));
    }
    if let Some(m) = model {
        return model_arg(m);
    }
    if let Some(r) = robot_arg(robot)? {
        return Ok((robot_design(&r, KinematicsKind::Ik)?, Vec::new()));
    }
    data.map(|d| (d, Vec::new())).ok_or_else(|| no_design(what))
}
