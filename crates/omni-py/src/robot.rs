//! `robot=`: the robot a design comes from, a robot.toml or the built-in `"apr02"`, looked up as the
//! command line's `--robot` (omni_cli::robot_file, omni_cli::design); and the model a call works with when
//! none is given. A call that needs the robot's design and has none raises `ValueError` saying how to give
//! one: there is no silent default robot.

use crate::effect::PyEffect;
use crate::errors::{chain_text, io_error, value_error};
use crate::model::model_arg;
use omni_cli::api::ModelSpec;
use omni_cli::robot_file::{self, RobotFile, RobotFileError, Spelling};
use omni_kin::{FittedModel, KinematicsKind, RunModels};
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
    omni_cli::design::robot_model(kind, robot).map(FittedModel::nominal).map_err(|e| value_error(chain_text(&e)))
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

/// A model argument spelt as the command line's `--model`: an `omnical.Model`, `"design"` (the design
/// model of `robot=`, else of the data's robot), `"paper"` (the paper's Eq. 9) or the path of a model file
/// (`train --out`). Returns the model, its Python effects and how outputs name it (the spelling, as the
/// CLI's `--model` value; `"the model"` for a Model object).
pub fn model_spec(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    robot: Option<&PathBuf>,
    data: Option<FittedModel>,
    what: &str,
) -> PyResult<(FittedModel, Vec<Arc<PyEffect>>, String)> {
    if model.is_instance_of::<crate::model::PyModel>() {
        let (m, adapters) = model_or_design(Some(model), robot, data, what)?;
        return Ok((m, adapters, "the model".to_string()));
    }
    let Ok(spec) = model.extract::<PathBuf>() else {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{what}: model must be an omnical.Model, \"design\", \"paper\" or a model file path, got {}",
            model.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        )));
    };
    let label = spec.to_string_lossy().into_owned();
    match ModelSpec::from_path(&spec) {
        ModelSpec::Design => Ok((model_or_design(None, robot, data, what)?.0, Vec::new(), label)),
        ModelSpec::Paper => Ok((omni_cli::design::paper_calibrated(), Vec::new(), label)),
        ModelSpec::File(spec) => {
            if let Some(r) = robot {
                return Err(value_error(format!(
                    "{what}: robot={:?} names a design, and the model file {label:?} is its own model: give \
                     model=\"design\" with robot=, or the model file alone",
                    r.to_string_lossy()
                )));
            }
            let m = crate::model::load_model(py, spec, Vec::new())?;
            Ok((m.inner.clone(), m.py_effects.clone(), label))
        }
    }
}

/// Whether `o` holds runs (a Dataset, a Run, or a list/tuple whose first item is a Run).
fn looks_like_runs(o: &Bound<'_, PyAny>) -> bool {
    use crate::run::{PyDataset, PyRun};
    if o.is_instance_of::<PyDataset>() || o.is_instance_of::<PyRun>() {
        return true;
    }
    let first = o.cast::<pyo3::types::PyList>().ok().and_then(|l| l.get_item(0).ok());
    let first = first.or_else(|| o.cast::<pyo3::types::PyTuple>().ok().and_then(|t| t.get_item(0).ok()));
    first.is_some_and(|f| f.is_instance_of::<PyRun>())
}

/// The argument order every call shares (`model, runs`, as the CLI's `--model M RUNS`): runs given first
/// (the old `evaluate(runs, model)` order) is a `TypeError` showing the right spelling.
pub fn check_order(model: &Bound<'_, PyAny>, runs: &Bound<'_, PyAny>, what: &str) -> PyResult<()> {
    if looks_like_runs(model) && !looks_like_runs(runs) {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{what}(model, runs, ...): the model comes first, then the runs (as in omnical.train, evaluate, \
             diagnose, report and explore, and the CLI's --model M RUNS): e.g. {what}(\"design\", runs, \
             robot=\"apr02\") or {what}(fit.model, runs)"
        )));
    }
    Ok(())
}

/// The designs `model` is compared with (diagnose, report, export), as the CLI's
/// `omni_cli::design::designs_for`: with `robot=` its design for every run; else each run's own input's
/// design for runs given as Datasets (`origins`: [`crate::run::origin_of`]), else the design `model` was
/// fitted around.
pub fn designs_for(model: &FittedModel, robot: Option<&PathBuf>, origins: &[omni_cli::dataset::Dataset]) -> RunModels {
    match robot {
        Some(_) => RunModels::from(omni_cli::design::design_for(model)),
        None => omni_cli::design::designs_for(model, &origins.iter().collect::<Vec<_>>()),
    }
}

/// `model` for each run, as the CLI's `--model` in `eval` and `export`: `"design"` without `robot=` is each
/// run's own input's design (runs given as a Dataset whose inputs declare different designs), anything
/// else `model` for every run.
pub fn per_run(
    model: FittedModel,
    spelled: &str,
    robot: Option<&PathBuf>,
    origin: &omni_cli::dataset::Dataset,
) -> PyResult<RunModels> {
    if ModelSpec::from_path(std::path::Path::new(spelled)) != ModelSpec::Design || robot.is_some() {
        return Ok(RunModels::from(model));
    }
    match omni_cli::design::declared_each(&[origin]).map_err(|e| value_error(chain_text(&e)))? {
        Some(each) if each.single().is_none() => Ok(each),
        _ => Ok(RunModels::from(model)),
    }
}
