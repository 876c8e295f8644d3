//! `omnical export --robot-config DIR`: put a calibration back on the robot (docs/applying.md).
//!
//! Writes three files:
//! - [`ODOMETRY_YAML`]: the fitted IK matrix as a ROS 2 parameter file (`/**: ros__parameters:`; the matrix
//!   flattened row-major, as ROS parameters hold no nested lists), with the wheel order, the odometry
//!   formula and the integration it was fitted with;
//! - [`ODOMETRY_HEADER`]: the same as a C header (`static const double`, a twist function and one
//!   integration step identical to omnical's), for a custom odometry node or firmware;
//! - [`CONTROLLER_YAML`]: the parameters of the ros2_controllers drive controller that matches the base,
//!   from the nearest parametric fit ([`crate::controller`]), with the accuracy its simpler model gives up
//!   on the runs given.
//!
//! Numbers are written in shortest round-trip form with a decimal point or exponent (`1.0`, not `1`), so
//! the matrix reads back bit for bit and ROS 2 types every value as a double.
//!
//! This module computes what the files say ([`build`]: the controller fit and the accuracies) and writes
//! them ([`write()`]); the text of the matrix files is made in `odometry`, that of the controller file and of
//! the command's summary in `ros2_controllers`.

mod noise;
mod odometry;
mod ros2_controllers;

pub use noise::{
    AMCL_YAML, ROBOT_LOCALIZATION_YAML, TypicalMotion, amcl_yaml, pose_diagonal, robot_localization_yaml,
    twist_diagonal,
};
pub use odometry::{num, odometry_header, odometry_yaml, wrap};
pub use ros2_controllers::{accuracy_lines, controller_yaml, params_text, summary, warning_lines};

use crate::controller::{self, ControllerFit, ControllerKind, FitOptions};
use omni_kin::cost::{self, CostKind};
use omni_kin::effect::Effect;
use omni_kin::{FittedModel, IkMatrix, Integration, KinError, Model, Run, RunModels};
use std::path::{Path, PathBuf};

/// Why the robot configuration could not be computed or written.
#[derive(Debug, thiserror::Error)]
pub enum RobotConfigError {
    /// The joint names do not match the model's wheels.
    #[error("{names} wheel names for a model with {wheels} wheels")]
    WheelNames {
        /// Joint names given.
        names: usize,
        /// The model's wheels.
        wheels: usize,
    },
    /// No ros2_controllers drive controller matches the base.
    #[error("no ros2_controllers drive controller fits a base with {wheels} wheel(s)")]
    NoController {
        /// The base's wheels.
        wheels: usize,
    },
    /// The controller's parameters could not be fitted to the model's matrix.
    #[error("fitting {kind} to the matrix of {spec}")]
    Fit {
        /// The controller.
        kind: ControllerKind,
        /// How the model was named.
        spec: String,
        /// Why.
        source: KinError,
    },
    /// The model or the runs are not usable (runs, matrix, accuracy).
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The folder could not be created.
    #[error("creating {}", dir.display())]
    CreateDir {
        /// The folder.
        dir: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// The matrix as a ROS 2 parameter file.
pub const ODOMETRY_YAML: &str = "omnical_odometry.yaml";
/// The matrix as a C header.
pub const ODOMETRY_HEADER: &str = "omnical_odometry.h";
/// The drive controller's parameters (controller_manager style).
pub const CONTROLLER_YAML: &str = "ros2_controllers.yaml";

/// Eq. 6 cost and path RMS of one model on the runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Accuracy {
    /// The paper's Eq. 6: mean end-pose error (m and rad mixed).
    pub end_pose: f64,
    /// RMS error over every ground-truth pose (1 m/rad).
    pub path_rms: f64,
}

/// One effect of the model that a plain matrix cannot carry.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectSummary {
    /// Effect id, e.g. `time_offset`.
    pub id: String,
    /// Parameter name, unit and value.
    pub params: Vec<(String, String, f64)>,
}

/// What the accuracy figures are measured against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Against {
    /// The runs' ground truth.
    GroundTruth,
    /// The calibrated model's own odometry, for runs without ground truth (`export --robot-config` needs
    /// none): the design's and the controller's figures are their distance from the model.
    ModelOdometry,
}

impl Against {
    /// Its id in JSON.
    pub fn id(self) -> &'static str {
        match self {
            Against::GroundTruth => "ground_truth",
            Against::ModelOdometry => "model_odometry",
        }
    }

    /// Words after "on N runs": nothing, or what stands in for the ground truth.
    pub fn words(self) -> &'static str {
        match self {
            Against::GroundTruth => "",
            Against::ModelOdometry => " against the calibrated model's odometry (no ground truth)",
        }
    }
}

/// What to export.
#[derive(Debug)]
pub struct Request<'a> {
    /// The fitted model.
    pub model: &'a FittedModel,
    /// Its design (the same structure at its design values): the controller's nominal parameters.
    pub design: &'a FittedModel,
    /// Each run's design (its own input's, `crate::design::designs_for`), for the design's accuracy.
    pub designs: &'a RunModels,
    /// How the model was named on the command line (file path or `design`).
    pub spec: &'a str,
    /// Runs to weight the controller fit with and to measure accuracy on (preferably held out).
    pub runs: &'a [Run],
    /// What the runs' poses are: ground truth, or the model's own odometry.
    pub against: Against,
    /// Joint names in the model's column order.
    pub wheel_names: Vec<String>,
    /// Controller to fit (default: the one that matches the base).
    pub controller: Option<ControllerKind>,
    /// The model file's odometry noise model, if it has one (issue 46): the covariance diagonals, Nav2 AMCL
    /// and robot_localization files are written from it.
    pub noise: Option<omni_kin::noise::OdometryNoise>,
}

/// Everything the files say, computed once.
#[derive(Clone, Debug)]
pub struct RobotConfig {
    /// How the model was named.
    pub spec: String,
    /// Joint names in column order.
    pub wheel_names: Vec<String>,
    /// The fitted matrix (3 × N).
    pub matrix: IkMatrix,
    /// Integration the model was fitted with.
    pub integration: Integration,
    /// The model's effects.
    pub effects: Vec<EffectSummary>,
    /// The nearest controller.
    pub fit: ControllerFit,
    /// The same controller fitted to the design matrix (the nominal values the multipliers scale).
    pub design_fit: Option<ControllerFit>,
    /// Number of runs the accuracy is measured on.
    pub n_runs: usize,
    /// What the accuracy is measured against.
    pub against: Against,
    /// The design model.
    pub design_accuracy: Accuracy,
    /// The full model (matrix and effects).
    pub model_accuracy: Accuracy,
    /// The matrix alone, when the model has effects.
    pub matrix_accuracy: Option<Accuracy>,
    /// The controller's odometry.
    pub controller_accuracy: Accuracy,
    /// The odometry noise model, if the model file has one.
    pub noise: Option<omni_kin::noise::OdometryNoise>,
    /// The runs' RMS speed and turn rate under the fitted matrix (the twist diagonal's operating point).
    pub motion: TypicalMotion,
    /// What the base's own model says about the controller, besides the fit (a skid-steer base's
    /// effective track and the slip a differential controller cannot express).
    pub base_notes: Vec<String>,
}

impl RobotConfig {
    /// The controller.
    pub fn kind(&self) -> ControllerKind {
        self.fit.model.params.kind()
    }

    /// Relative loss of the controller against the full model, in % (Eq. 6, path RMS).
    pub fn loss_pct(&self) -> (f64, f64) {
        let pct = |c: f64, m: f64| 100.0 * (c - m) / m;
        (
            pct(self.controller_accuracy.end_pose, self.model_accuracy.end_pose),
            pct(self.controller_accuracy.path_rms, self.model_accuracy.path_rms),
        )
    }

    /// Joint names the controller must see reversed.
    pub fn reversed_joints(&self) -> Vec<&str> {
        let l = &self.fit.model.layout;
        l.columns.iter().zip(&l.reversed).filter(|(_, r)| **r).map(|(c, _)| self.wheel_names[*c].as_str()).collect()
    }
}

/// The design's roller angles, when the model knows its geometry.
fn design_geometry(design: &FittedModel) -> Option<omni_kin::RobotGeometry> {
    let nb = design.model.n_base();
    match &design.model.kinematics {
        omni_kin::kinematics::Kinematics::Skid(k) => Some(k.design.clone()),
        kinematics => kinematics.geometry_at(&design.params[..nb])?.ok(),
    }
}

fn accuracy(fm: &FittedModel, runs: &[Run]) -> Result<Accuracy, KinError> {
    accuracy_each(&RunModels::from(fm), runs)
}

/// [`accuracy`] with each run under its own model.
fn accuracy_each(models: &RunModels, runs: &[Run]) -> Result<Accuracy, KinError> {
    let errors = models.errors(runs, CostKind::PATH.selection())?;
    Ok(Accuracy { end_pose: errors.end_pose_cost(), path_rms: errors.path_cost(CostKind::PATH.heading_weight()) })
}

fn effects_of(fm: &FittedModel) -> Vec<EffectSummary> {
    fm.model
        .effects
        .iter()
        .zip(fm.model.effect_ranges())
        .map(|(e, r)| EffectSummary {
            id: e.id().to_string(),
            params: e.params().into_iter().zip(&fm.params[r]).map(|(s, &v)| (s.name, s.unit.to_string(), v)).collect(),
        })
        .collect()
}

/// Fit the controller and measure every model on the runs.
pub fn build(req: &Request<'_>) -> Result<RobotConfig, RobotConfigError> {
    let model = req.model;
    let n = model.model.n_wheels();
    if req.wheel_names.len() != n {
        return Err(RobotConfigError::WheelNames { names: req.wheel_names.len(), wheels: n });
    }
    cost::check_runs(&model.model, req.runs)?;
    let matrix = model.ik()?;
    let kind = match req.controller {
        Some(k) => k,
        None => match design_geometry(req.design) {
            Some(g) => ControllerKind::for_base(n, Some(&g)),
            // Only a matrix: a base whose design cannot push sideways (a zero vy row) on an even number of
            // wheels is driven as a differential base.
            None if ControllerKind::DiffDrive.accepts(n)
                && req.design.ik().is_ok_and(|m| (0..n).all(|c| m.get(1, c) == 0.0)) =>
            {
                Some(ControllerKind::DiffDrive)
            }
            None => ControllerKind::for_base(n, None),
        }
        .ok_or(RobotConfigError::NoController { wheels: n })?,
    };
    let s = controller::wheel_second_moment(req.runs)?;
    let opts = FitOptions::default();
    let fit = controller::fit(kind, &matrix, &s, &opts).map_err(|source| RobotConfigError::Fit {
        kind,
        spec: req.spec.to_string(),
        source,
    })?;
    let design_fit = req.design.ik().ok().and_then(|d| controller::fit(kind, &d, &s, &opts).ok());
    let integration = model.model.integration;
    let plain = |m: &IkMatrix| FittedModel::nominal(Model::ik(m.clone()).with_integration(integration));
    let effects = effects_of(model);
    Ok(RobotConfig {
        spec: req.spec.to_string(),
        wheel_names: req.wheel_names.clone(),
        matrix: matrix.clone(),
        integration,
        design_accuracy: accuracy_each(req.designs, req.runs)?,
        model_accuracy: accuracy(model, req.runs)?,
        matrix_accuracy: if effects.is_empty() { None } else { Some(accuracy(&plain(&matrix), req.runs)?) },
        controller_accuracy: accuracy(&plain(&fit.twist_from_wheels), req.runs)?,
        effects,
        fit,
        design_fit,
        n_runs: req.runs.len(),
        against: req.against,
        noise: req.noise.clone(),
        motion: typical_motion(&matrix, req.runs),
        base_notes: base_notes(model, kind),
    })
}

/// A skid-steer model seen by a differential controller: the effective track it takes as
/// `wheel_separation`, and the ICR offsets it cannot express (ICR-based extended differential drive,
/// [`omni_kin::kinematics::SkidKinematics`]).
fn base_notes(model: &FittedModel, kind: ControllerKind) -> Vec<String> {
    let omni_kin::kinematics::Kinematics::Skid(k) = &model.model.kinematics else { return Vec::new() };
    let nb = model.model.n_base();
    let (p, Ok(d)) = (&model.params[..nb], k.design_params()) else { return Vec::new() };
    let (track, design_track) = (p[2] - p[3], d[2] - d[3]);
    let mut v = vec![format!(
        "skid-steer base (the ICR-based extended differential drive): its effective track is y_icr_left − \
         y_icr_right = {track:.4} m, {:.3} times the wheels' {design_track:.4} m (the track expansion factor){}.",
        track / design_track,
        if kind == ControllerKind::DiffDrive { ", which the controller takes as its wheel separation" } else { "" }
    )];
    let (mid, x) = (0.5 * (p[2] + p[3]), p[4]);
    if mid.abs() > 1e-3 || (x - d[4]).abs() > 1e-3 || x.abs() > 1e-3 {
        v.push(format!(
            "a differential controller cannot express the robot's centre of rotation at x = {x:.4} m, y = {mid:.4} m \
             from the base's origin: turning at ω, the origin slips sideways at −x·ω and moves forward at y·ω. \
             Publishing the odometry for a frame at that point (a static transform from base_link) removes both; \
             omnical_odometry.yaml's matrix carries them as they are."
        ));
    }
    v
}

/// The RMS speed and turn rate of the runs' wheel samples under `matrix`.
fn typical_motion(matrix: &IkMatrix, runs: &[Run]) -> TypicalMotion {
    let (mut v2, mut w2, mut n) = (0.0, 0.0, 0usize);
    for r in runs {
        for k in 0..r.n_samples() {
            let t = matrix.twist(r.wheel_sample(k));
            v2 += t.vx_m_s * t.vx_m_s + t.vy_m_s * t.vy_m_s;
            w2 += t.omega_rad_s * t.omega_rad_s;
            n += 1;
        }
    }
    let rms = |s: f64| if n == 0 { 0.0 } else { (s / n as f64).sqrt() };
    TypicalMotion { speed_m_s: rms(v2), turn_rad_s: rms(w2) }
}

/// Write the three files into `dir` (created if needed).
pub fn write(dir: &Path, c: &RobotConfig) -> Result<(), RobotConfigError> {
    std::fs::create_dir_all(dir).map_err(|source| RobotConfigError::CreateDir { dir: dir.to_path_buf(), source })?;
    let mut files = vec![
        (ODOMETRY_YAML, odometry_yaml(c)),
        (ODOMETRY_HEADER, odometry_header(c)),
        (CONTROLLER_YAML, controller_yaml(c)),
    ];
    if let Some(n) = &c.noise {
        files.push((AMCL_YAML, amcl_yaml(c, n)));
        files.push((ROBOT_LOCALIZATION_YAML, robot_localization_yaml(c, n)));
    }
    for (name, text) in files {
        let path = dir.join(name);
        crate::atomic::write_atomic(&path, text.as_bytes())
            .map_err(|source| RobotConfigError::Write { path: path.clone(), source })?;
    }
    Ok(())
}
