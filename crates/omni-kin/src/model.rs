//! A model: base kinematics (`ik` or `geometry`) + physical effects + how odometry is integrated, with
//! one flat parameter vector (base parameters first, then each effect's, in order).
//!
//! Parameter names are `m11` … `m3N` (`ik`), `r_a`, `R_a`, `delta_a`, … (`geometry`), and
//! `<effect id>.<name>` for effects, e.g. `time_offset.tau_s`.

use crate::effect::{Effect, EffectKind, ParamSpec, Stage};
use crate::error::{Domain, KinError};
use crate::geometry::RobotGeometry;
use crate::ik::IkMatrix;
pub use crate::kinematics::Kinematics;
use crate::kinematics::{GeometryKinematics, KinematicsKind, MatrixKinematics};
use crate::pose::Pose2;
use serde::{Deserialize, Serialize};

/// Step of the paper's odometry (Eq. 1). s.
pub const PAPER_STEP_S: f64 = 0.010;

/// How each wheel sample is turned into a step length.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "step", rename_all = "snake_case")]
pub enum StepMode {
    /// Every sample is one fixed step (the paper's Eq. 1). `dt_s: None` takes each run's median sample
    /// interval.
    Fixed {
        /// Step. s. Paper: 0.010.
        dt_s: Option<f64>,
    },
    /// Each sample is integrated over its measured interval since the previous sample.
    Stamps,
}

/// How a constant twist is integrated over one step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Eq. 1: first-order step along the heading at the start of the step.
    Euler,
    /// The twist held over the step, integrated exactly on SE(2) (an arc).
    ExactArc,
}

/// Integration settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Integration {
    /// Step lengths.
    #[serde(flatten)]
    pub step: StepMode,
    /// Step scheme.
    pub scheme: Scheme,
}

impl Integration {
    /// The paper's Eq. 1: Euler steps of exactly 10 ms.
    pub const PAPER: Integration =
        Integration { step: StepMode::Fixed { dt_s: Some(PAPER_STEP_S) }, scheme: Scheme::Euler };
    /// Our default: exact arcs, fixed steps of each run's median sample interval. Exact arcs remove Eq. 1's
    /// first-order bias (≈ path length × |ω| × dt / 2), which would otherwise look like a physical effect;
    /// fixed steps keep `sample_timing` a testable effect rather than an assumption.
    pub const DEFAULT: Integration = Integration { step: StepMode::Fixed { dt_s: None }, scheme: Scheme::ExactArc };
}

impl Default for Integration {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A model structure. Its parameters live in a separate vector (see [`Model::params`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Model {
    /// Base kinematics.
    pub kinematics: Kinematics,
    /// Effects, applied in order within their stage.
    #[serde(default)]
    pub effects: Vec<EffectKind>,
    /// Integration settings.
    #[serde(default)]
    pub integration: Integration,
}

impl Model {
    /// A model of these base kinematics, without effects, with default integration.
    pub fn new(kinematics: Kinematics) -> Self {
        Self { kinematics, effects: Vec::new(), integration: Integration::DEFAULT }
    }

    /// The paper's `ik` model around `design`, with default integration.
    pub fn ik(design: IkMatrix) -> Self {
        Self::new(Kinematics::Ik(MatrixKinematics::new(design)))
    }

    /// The `geometry` model around `design`, with default integration.
    pub fn geometry(design: RobotGeometry) -> Self {
        Self::new(Kinematics::Geometry(GeometryKinematics { design }))
    }

    /// The design model of `kind` for a robot (its geometry when known, else the paper's APR-02), with
    /// default integration: `ik` around the robot's IK matrix (Eq. 3; Eq. 7 for APR-02), `geometry` around
    /// its geometry.
    pub fn design(kind: KinematicsKind, robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        Ok(Self::new(Kinematics::design(kind, robot)?))
    }

    /// This model with these wheel (joint) names in column order (a robot description's joints), written
    /// into model files; one per wheel, else `KinError::Shape`.
    pub fn with_wheel_names(mut self, names: &[String]) -> Result<Self, KinError> {
        self.kinematics = self.kinematics.with_wheel_names(names)?;
        Ok(self)
    }

    /// This model with another effect appended.
    pub fn with_effect(mut self, e: EffectKind) -> Self {
        self.effects.push(e);
        self
    }

    /// This model with other integration settings.
    pub fn with_integration(mut self, i: Integration) -> Self {
        self.integration = i;
        self
    }

    /// Number of wheels.
    pub fn n_wheels(&self) -> usize {
        self.kinematics.n_wheels()
    }

    /// Number of base (kinematic) parameters.
    pub fn n_base(&self) -> usize {
        self.kinematics.n_params()
    }

    /// Every parameter spec: base first, then effects with names qualified as `<effect>.<name>`.
    pub fn params(&self) -> Vec<ParamSpec> {
        let mut v = self.kinematics.params();
        for e in &self.effects {
            let id = e.id().to_string();
            v.extend(e.params().into_iter().map(|mut p| {
                p.name = format!("{id}.{}", p.name);
                p
            }));
        }
        v
    }

    /// Parameter count.
    pub fn n_params(&self) -> usize {
        self.params().len()
    }

    /// The design / null parameter vector: where searches start.
    pub fn nominal(&self) -> Vec<f64> {
        self.params().iter().map(|p| p.null).collect()
    }

    /// Index ranges of each effect's parameters in the full vector.
    pub fn effect_ranges(&self) -> Vec<std::ops::Range<usize>> {
        let mut start = self.n_base();
        self.effects
            .iter()
            .map(|e| {
                let n = e.params().len();
                let r = start..start + n;
                start += n;
                r
            })
            .collect()
    }

    /// Resolve a parameter vector once (the IK matrix, clock lag, sensor pose) for use over many runs.
    pub fn resolve<'m>(&'m self, params: &'m [f64]) -> Result<Resolved<'m>, KinError> {
        let n = self.n_params();
        if params.len() != n {
            return Err(KinError::ParamCount { got: params.len(), expected: n });
        }
        if let Some(i) = params.iter().position(|v| !v.is_finite()) {
            let name = self.params()[i].name.clone();
            return Err(KinError::BadParam { name, value: params[i], must: Domain::Finite });
        }
        let nb = self.n_base();
        let ik = self.kinematics.twist_from_wheels(&params[..nb])?;
        let mut clock_lag_s = 0.0;
        let mut sensor_from_body = Pose2::IDENTITY;
        let mut stamps = matches!(self.integration.step, StepMode::Stamps);
        let mut wheel_effects = Vec::new();
        let mut twist_effects = Vec::new();
        for (e, r) in self.effects.iter().zip(self.effect_ranges()) {
            let p = &params[r];
            clock_lag_s += e.clock_lag_s(p);
            sensor_from_body = sensor_from_body.compose(&e.sensor_from_body(p));
            stamps |= e.uses_stamps();
            match e.stage() {
                Stage::Wheel => wheel_effects.push((e, p)),
                Stage::Twist => twist_effects.push((e, p)),
                _ => {}
            }
        }
        Ok(Resolved {
            ik,
            clock_lag_s,
            sensor_from_body,
            stamps,
            fixed_dt_s: match self.integration.step {
                StepMode::Fixed { dt_s } => dt_s,
                StepMode::Stamps => None,
            },
            scheme: self.integration.scheme,
            wheel_effects,
            twist_effects,
        })
    }
}

/// A model with its parameters resolved: what the integrator needs, computed once per parameter vector.
#[derive(Debug)]
pub struct Resolved<'m> {
    /// The IK matrix.
    pub ik: IkMatrix,
    /// Total wheel-clock lag. s.
    pub clock_lag_s: f64,
    /// Pose of the ground-truth sensor in the body frame.
    pub sensor_from_body: Pose2,
    /// Integrate measured intervals instead of fixed steps.
    pub stamps: bool,
    /// Fixed step when not `stamps` (`None`: each run's median interval). s.
    pub fixed_dt_s: Option<f64>,
    /// Step scheme.
    pub scheme: Scheme,
    /// Wheel-stage effects with their parameters.
    pub wheel_effects: Vec<(&'m EffectKind, &'m [f64])>,
    /// Twist-stage effects with their parameters.
    pub twist_effects: Vec<(&'m EffectKind, &'m [f64])>,
}

/// A model with fitted (or chosen) parameter values: what a model file holds.
#[derive(Clone, Debug)]
pub struct FittedModel {
    /// The structure.
    pub model: Model,
    /// Its parameters, in [`Model::params`] order.
    pub params: Vec<f64>,
}

impl FittedModel {
    /// The model at its nominal (design / null) parameters.
    pub fn nominal(model: Model) -> Self {
        let params = model.nominal();
        Self { model, params }
    }

    /// The design model of the paper's APR-02 (Eq. 7).
    pub fn paper_design() -> Self {
        Self::nominal(Model::ik(IkMatrix::paper_design()))
    }

    /// Builds and checks the parameter count.
    pub fn new(model: Model, params: Vec<f64>) -> Result<Self, KinError> {
        model.resolve(&params)?;
        Ok(Self { model, params })
    }

    /// The IK matrix these parameters give.
    pub fn ik(&self) -> Result<IkMatrix, KinError> {
        self.model.kinematics.twist_from_wheels(&self.params[..self.model.n_base()])
    }

    /// Value of a parameter by its qualified name.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.model.params().iter().position(|p| p.name == name).map(|i| self.params[i])
    }

    /// Set a parameter by its qualified name.
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), KinError> {
        let specs = self.model.params();
        match specs.iter().position(|p| p.name == name) {
            Some(i) => {
                self.params[i] = value;
                Ok(())
            }
            None => {
                Err(KinError::unknown("parameter", name, &specs.iter().map(|p| p.name.as_str()).collect::<Vec<_>>()))
            }
        }
    }

    /// The same model with an effect appended at its null parameters.
    pub fn with_effect(&self, e: EffectKind) -> Self {
        let mut params = self.params.clone();
        params.extend(e.params().iter().map(|p| p.null));
        Self { model: self.model.clone().with_effect(e), params }
    }
}
