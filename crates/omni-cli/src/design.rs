//! Design models: the one a dataset declares, the one a fitted model was fitted around, and the model
//! specs `design` / `paper` / FILE. The command line and the Python binding look them up here.

use anyhow::Context;
use omni_kin::{FittedModel, IkMatrix, Model, RobotGeometry};
use std::path::Path;

/// The design model a dataset declares: its geometry (nominal), else the paper's APR-02 matrix (Eq. 7).
pub fn design_of(robot: Option<&RobotGeometry>) -> FittedModel {
    match robot {
        Some(g) => FittedModel::nominal(Model::geometry(g.clone())),
        None => FittedModel::paper_design(),
    }
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

/// A model given on the command line: `design` ([`design_of`] the data's robot), `paper`
/// ([`paper_calibrated`]) or a model file.
pub fn resolve(spec: &str, robot: Option<&RobotGeometry>) -> anyhow::Result<FittedModel> {
    match spec {
        "design" => Ok(design_of(robot)),
        "paper" => Ok(paper_calibrated()),
        path => crate::model_file::read(Path::new(path)).context("reading the model"),
    }
}
