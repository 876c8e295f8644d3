//! Design models: the one a dataset's robot declares, the one a fitted model was fitted around, and the
//! model specs `design` / `paper` / FILE. The command line and the Python binding look them up here.
//!
//! A dataset's robot is, in this order: `--robot` (a robot.toml or `apr02`), the data's own geometry
//! (OptiOdom metadata), a robot.toml found beside the data or in the working directory
//! ([`robot_file::design`]).

use crate::dataset::Dataset;
use crate::robot_file::{self, Design, RobotFile};
use anyhow::Context;
use omni_kin::{FittedModel, IkMatrix, KinematicsKind, Model, RobotGeometry};
use std::path::Path;

/// The design model of `kind` for a dataset's robot, or `None` when the dataset names no robot. A robot
/// description's `ik` design is its design matrix (the paper's Eq. 7 for APR-02; the closed form for diff).
pub fn model_of(kind: KinematicsKind, ds: &Dataset) -> anyhow::Result<Option<Model>> {
    Ok(Some(match robot_file::design(ds) {
        Some(Design::File(f)) => robot_model(kind, f)?,
        Some(Design::Data(g)) => Model::design(kind, Some(g))?,
        None => return Ok(None),
    }))
}

/// The design model of `kind` for a robot description, its wheels named after the description's joints
/// (model files carry them): `ik` around its design matrix, the other kinds around its geometry.
pub fn robot_model(kind: KinematicsKind, f: &RobotFile) -> anyhow::Result<Model> {
    let context = || format!("robot {}", f.source);
    if kind == KinematicsKind::Ik {
        let ik = f.description.design_ik().with_context(context)?;
        return Ok(Model::ik(ik).with_wheel_names(&f.description.joints())?);
    }
    let g = f.description.to_geometry().with_context(context)?;
    Ok(Model::design(kind, Some(&g))?)
}

/// [`model_of`], where no robot is an error saying how to describe it.
pub fn model(kind: KinematicsKind, ds: &Dataset) -> anyhow::Result<Model> {
    model_of(kind, ds)?.ok_or_else(|| robot_file::no_design("the design model"))
}

/// The design geometry of a dataset's robot; no robot is an error saying how to describe it.
pub fn geometry(ds: &Dataset) -> anyhow::Result<RobotGeometry> {
    match robot_file::design(ds) {
        Some(Design::File(f)) => f.description.to_geometry().with_context(|| format!("robot {}", f.source)),
        Some(Design::Data(g)) => Ok(g.clone()),
        None => Err(robot_file::no_design("the design geometry")),
    }
}

/// The design model the dataset's robot declares (`--model design`), nominal, or `None` when it names no
/// robot: a robot description's design matrix; the data's geometry as a geometry model (a two-wheel base,
/// OptiOdom's diff, as a diff model: it has no omnidirectional geometry model).
pub fn declared(ds: &Dataset) -> anyhow::Result<Option<FittedModel>> {
    let model = match robot_file::design(ds) {
        Some(Design::File(_)) => model_of(KinematicsKind::Ik, ds)?,
        Some(Design::Data(g)) if g.n_wheels() == 2 => Some(Model::design(KinematicsKind::Diff, Some(g))?),
        Some(Design::Data(g)) => Some(Model::geometry(g.clone())),
        None => None,
    };
    Ok(model.map(FittedModel::nominal))
}

/// The design model matching a fitted model's base (same kinematics and wheels, same integration, no
/// effects), at nominal parameters.
pub fn design_for(model: &FittedModel) -> FittedModel {
    let base =
        Model { kinematics: model.model.kinematics.clone(), effects: Vec::new(), integration: model.model.integration };
    FittedModel::nominal(base)
}

/// The paper's calibrated APR-02 (Eq. 9) as a model of its own (its design is the Eq. 9 matrix too): the
/// simulator's default true robot.
pub fn paper_calibrated() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()))
}

/// A model given on the command line: `design` ([`declared`] by the data's robot; none is an error),
/// `paper` ([`paper_calibrated`]) or a model file.
pub fn resolve(spec: &str, ds: &Dataset) -> anyhow::Result<FittedModel> {
    match spec {
        "design" => declared(ds)?.ok_or_else(|| robot_file::no_design("--model design")),
        "paper" => Ok(paper_calibrated()),
        path => crate::model_file::read(Path::new(path)).context("reading the model"),
    }
}
