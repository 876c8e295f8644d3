//! Design models: the one a dataset's robot declares, the one a fitted model was fitted around, and the
//! paper's; the model specs `design` / `paper` / FILE ([`crate::api::ModelSpec`]) resolve to them. The
//! command line and the Python binding look them up here.
//!
//! A dataset's robot is, in this order: `--robot` (a robot.toml or `apr02`), the data's own geometry
//! (OptiOdom metadata), a robot.toml found beside the data or in the working directory
//! ([`robot_file::design`]).
//!
//! Each run carries its own design: when a robot's inputs declare different geometries (OptiOdom sets whose
//! metadata give other wheel distances), every run is integrated with its own input's design wherever "the
//! design" is evaluated ([`designs`], [`declared_each`], [`designs_for`]: plain data, a [`RunModels`], for
//! the core), and pooled figures are the run-weighted means of the runs' own. Where one design is needed
//! (training's start, the model `--model design` stands for in diagnose and explore) it is the one the most
//! runs declare ([`crate::dataset::Dataset::declared_start`]).

use crate::dataset::{Dataset, Declared, group_designs};
use crate::robot_file::{self, Design, NoDesign, RobotFile, Source};
use omni_kin::robot::GeometryError;
use omni_kin::{FittedModel, IkMatrix, KinError, KinematicsKind, Model, RobotGeometry, RunModels};
use std::path::PathBuf;

/// Why a design model could not be built.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// The data names no robot, where one is needed.
    #[error(transparent)]
    NoDesign(#[from] NoDesign),
    /// A robot description's design is not a valid geometry or matrix.
    #[error("robot {robot}")]
    Robot {
        /// Where the description came from.
        robot: Source,
        /// What is wrong with it.
        source: GeometryError,
    },
    /// The geometry an input declares makes no design model.
    #[error("the design {} declares", input.display())]
    Declared {
        /// The input that declares it (empty for none).
        input: PathBuf,
        /// What is wrong with it.
        source: Box<DesignError>,
    },
    /// Runs without a design of their own, beside inputs that declare theirs, and no robot description.
    #[error(
        "run {run} declares no design and no robot description is given, while other inputs declare theirs: \
         give --robot FILE, or read these runs in a command of their own"
    )]
    Undeclared {
        /// The first such run.
        run: String,
    },
    /// The model refused the design (wheel names, kinematics).
    #[error(transparent)]
    Kin(#[from] KinError),
}

/// The design model of `kind` for a dataset's robot, or `None` when the dataset names no robot. A robot
/// description's `ik` design is its design matrix (the paper's Eq. 7 for APR-02; the closed form for diff).
pub fn model_of(kind: KinematicsKind, ds: &Dataset) -> Result<Option<Model>, DesignError> {
    Ok(Some(match robot_file::design(ds) {
        Some(Design::File(f)) => robot_model(kind, f)?,
        Some(Design::Data(g)) => Model::design(kind, Some(g))?,
        None => return Ok(None),
    }))
}

/// The design model of `kind` for a robot description, its wheels named after the description's joints
/// (model files carry them): `ik` around its design matrix, the other kinds around its geometry.
pub fn robot_model(kind: KinematicsKind, f: &RobotFile) -> Result<Model, DesignError> {
    let robot = |source| DesignError::Robot { robot: f.source.clone(), source };
    if kind == KinematicsKind::Ik {
        let ik = f.description.design_ik().map_err(robot)?;
        return Ok(Model::ik(ik).with_wheel_names(&f.description.joints())?);
    }
    let g = f.description.to_geometry().map_err(robot)?;
    Ok(Model::design(kind, Some(&g))?)
}

/// The base model `train` fits when none is named: the kind's own ([`omni_kin::BaseKind::default_model`]:
/// `diff` for a differential drive, three physical parameters where a 3 × 2 matrix has a fourth direction,
/// weakly determined, that trades the radii's ratio against the turning; `skid` for a skid-steer base),
/// else `ik`, the paper's matrix. Data that declares only a geometry (OptiOdom) is a differential drive
/// when it cannot move sideways.
pub fn default_kind(ds: &Dataset) -> KinematicsKind {
    match robot_file::design(ds) {
        Some(Design::File(f)) => f.description.kind.default_model(),
        Some(Design::Data(g)) if !g.is_omnidirectional() => KinematicsKind::Diff,
        _ => KinematicsKind::Ik,
    }
}

/// [`model_of`], where no robot is an error saying how to describe it.
pub fn model(kind: KinematicsKind, ds: &Dataset) -> Result<Model, DesignError> {
    model_of(kind, ds)?.ok_or_else(|| robot_file::no_design("the design model").into())
}

/// The design geometry of a dataset's robot; no robot is an error saying how to describe it.
pub fn geometry(ds: &Dataset) -> Result<RobotGeometry, DesignError> {
    match robot_file::design(ds) {
        Some(Design::File(f)) => {
            f.description.to_geometry().map_err(|source| DesignError::Robot { robot: f.source.clone(), source })
        }
        Some(Design::Data(g)) => Ok(g.clone()),
        None => Err(robot_file::no_design("the design geometry").into()),
    }
}

/// The design model the dataset's robot declares (`--model design`), nominal, or `None` when it names no
/// robot: a robot description's design matrix; the data's geometry as a geometry model (a two-wheel base,
/// OptiOdom's diff, as a diff model: it has no omnidirectional geometry model).
pub fn declared(ds: &Dataset) -> Result<Option<FittedModel>, DesignError> {
    let model = match robot_file::design(ds) {
        Some(Design::File(_)) => model_of(KinematicsKind::Ik, ds)?,
        Some(Design::Data(g)) => Some(declared_model(g)?),
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

/// The design model of each run of `sets` (datasets read with the same data options: training and
/// held-out runs), from `from_geometry` for the geometry its input declares and `from_file` for a robot
/// description: `--robot`'s for every run; else each input's declared geometry for its runs (a robot.toml
/// found beside the data for runs of inputs that declare none); else the found robot.toml's. The design of
/// the most runs comes first. `None` when the data names no robot.
fn each_run(
    sets: &[&Dataset],
    from_geometry: impl Fn(&RobotGeometry) -> Result<Model, DesignError>,
    from_file: impl Fn(&RobotFile) -> Result<Model, DesignError>,
) -> Result<Option<RunModels>, DesignError> {
    let file = sets.iter().find_map(|ds| ds.robot_file.as_ref());
    let named = file.filter(|f| !matches!(f.source, Source::Discovered(_)));
    let declared: Vec<&Declared> = sets.iter().flat_map(|ds| &ds.declared).collect();
    if let Some(f) = named.or(file.filter(|_| declared.is_empty())) {
        return Ok(Some(RunModels::from(FittedModel::nominal(from_file(f)?))));
    }
    let groups = group_designs(declared.iter().copied());
    let mut models = Vec::with_capacity(groups.len() + 1);
    for g in &groups {
        let names: Vec<String> = g.inputs.iter().flat_map(|d| d.runs.iter().cloned()).collect();
        let input = g.inputs.first().map_or_else(PathBuf::new, |d| d.source.clone());
        let model =
            from_geometry(g.geometry).map_err(|source| DesignError::Declared { input, source: Box::new(source) })?;
        models.push((FittedModel::nominal(model), names));
    }
    let covered: std::collections::BTreeSet<&str> =
        declared.iter().flat_map(|d| d.runs.iter().map(String::as_str)).collect();
    let rest: Vec<String> = sets
        .iter()
        .flat_map(|ds| &ds.runs)
        .map(|r| r.name().to_string())
        .filter(|n| !covered.contains(n.as_str()))
        .collect();
    match (rest.first(), file) {
        (None, _) => {}
        // No input declares a design and no robot description is found: the data names no robot.
        (Some(_), None) if declared.is_empty() => return Ok(None),
        (Some(_), Some(f)) => models.push((FittedModel::nominal(from_file(f)?), rest)),
        (Some(run), None) => return Err(DesignError::Undeclared { run: run.clone() }),
    }
    if models.is_empty() {
        return Ok(None);
    }
    Ok(Some(RunModels::new(models)?))
}

/// The design model of `kind` of each run of `sets` (see `each_run`), or `None` when the data names no
/// robot.
pub fn designs(kind: KinematicsKind, sets: &[&Dataset]) -> Result<Option<RunModels>, DesignError> {
    each_run(sets, |g| Ok(Model::design(kind, Some(g))?), |f| robot_model(kind, f))
}

/// The design model each run's robot declares, as [`declared`] builds it (`--model design`, run by run), or
/// `None` when the data names no robot.
pub fn declared_each(sets: &[&Dataset]) -> Result<Option<RunModels>, DesignError> {
    each_run(sets, declared_model, |f| robot_model(KinematicsKind::Ik, f))
}

/// The design model a declared geometry stands for: a geometry model (a base that cannot move sideways,
/// OptiOdom's diff, as a diff model: it has no omnidirectional geometry model).
fn declared_model(g: &RobotGeometry) -> Result<Model, DesignError> {
    Ok(if g.is_omnidirectional() { Model::geometry(g.clone()) } else { Model::design(KinematicsKind::Diff, Some(g))? })
}

/// The designs to compare `model` with on the runs of `sets`: each run's own design in `model`'s kinematics
/// and integration (no effects), from the data's robot ([`designs`]); where the data names none, or its
/// design cannot take `model`'s kinematics, the design `model` was fitted around ([`design_for`]).
pub fn designs_for(model: &FittedModel, sets: &[&Dataset]) -> RunModels {
    let kind = model.model.kinematics.kind();
    let integration = model.model.integration;
    match designs(kind, sets) {
        Ok(Some(d)) if d.models().iter().all(|m| m.model.n_wheels() == model.model.n_wheels()) => d.map(|m| {
            let base = Model { kinematics: m.model.kinematics.clone(), effects: Vec::new(), integration };
            FittedModel::nominal(base)
        }),
        _ => RunModels::from(design_for(model)),
    }
}
