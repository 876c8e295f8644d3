//! A model: base kinematics (`ik` or `geometry`) + physical effects + how odometry is integrated, with
//! one flat parameter vector (base parameters first, then each effect's, in order).
//!
//! Parameter names are `m11` … `m3N` (`ik`), `r_a`, `R_a`, `delta_a`, … (`geometry`), and
//! `<effect id>.<name>` for effects, e.g. `time_offset.tau_s`.

use crate::choice::Choice;
use crate::effect::{Effect, EffectKind, ParamSpec, Stage};
use crate::error::KinError;
use crate::geometry::{RobotGeometry, Wheel, default_wheel_names};
use crate::ik::IkMatrix;
use crate::pose::Pose2;
use serde::{Deserialize, Serialize};

/// Step of the paper's odometry (Eq. 1). s.
pub const PAPER_STEP_S: f64 = 0.010;

/// The base kinematics a model fits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kinematics {
    /// The paper's non-parametric model: every entry of the 3 × N IK matrix is free.
    Ik {
        /// Design matrix (the start and centre of the search).
        design: IkMatrix,
    },
    /// The parametric model of the paper's ref. \[17\]: per wheel r_i, R_i, δ_i.
    Geometry {
        /// Design geometry.
        design: RobotGeometry,
    },
}

impl Kinematics {
    /// Number of wheels.
    pub fn n_wheels(&self) -> usize {
        match self {
            Self::Ik { design } => design.n_wheels(),
            Self::Geometry { design } => design.n_wheels(),
        }
    }

    /// `ik` or `geometry`.
    pub fn id(&self) -> &'static str {
        self.kind().id()
    }

    /// Which kind of base kinematics this is.
    pub fn kind(&self) -> KinematicsKind {
        match self {
            Self::Ik { .. } => KinematicsKind::Ik,
            Self::Geometry { .. } => KinematicsKind::Geometry,
        }
    }

    /// Parameter specs at the design values (bounds: ±10 % of each design value, as the paper).
    pub fn params(&self) -> Vec<ParamSpec> {
        match self {
            Self::Ik { design } => {
                let names = IkMatrix::entry_names(design.n_wheels());
                names
                    .into_iter()
                    .zip(design.entries())
                    .enumerate()
                    .map(|(i, (name, &v))| {
                        let unit = if i / design.n_wheels() == 2 { "rad" } else { "m" };
                        ParamSpec::new(name, unit, v, v - 0.1 * v.abs(), v + 0.1 * v.abs())
                    })
                    .collect()
            }
            Self::Geometry { design } => {
                let letters: Vec<String> =
                    (0..design.n_wheels()).map(|i| ((b'a' + i as u8) as char).to_string()).collect();
                let mut p = Vec::new();
                for (l, w) in letters.iter().zip(&design.wheels) {
                    p.push(ParamSpec::new(format!("r_{l}"), "m", w.radius_m, 0.9 * w.radius_m, 1.1 * w.radius_m));
                }
                for (l, w) in letters.iter().zip(&design.wheels) {
                    p.push(ParamSpec::new(format!("R_{l}"), "m", w.distance_m, 0.9 * w.distance_m, 1.1 * w.distance_m));
                }
                for (l, w) in letters.iter().zip(&design.wheels) {
                    let d = w.angle_rad;
                    p.push(ParamSpec::new(format!("delta_{l}"), "rad", d, d - 0.1 * d.abs(), d + 0.1 * d.abs()));
                }
                p
            }
        }
    }

    /// The IK matrix for base parameters `p`.
    pub fn ik(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        match self {
            Self::Ik { design } => IkMatrix::new(design.n_wheels(), p.to_vec()),
            Self::Geometry { design } => self.geometry(p, design)?.twist_from_wheels(),
        }
    }

    fn geometry(&self, p: &[f64], design: &RobotGeometry) -> Result<RobotGeometry, KinError> {
        let n = design.n_wheels();
        let wheels = design
            .wheels
            .iter()
            .enumerate()
            .map(|(i, w)| Wheel { radius_m: p[i], distance_m: p[n + i], angle_rad: p[2 * n + i], ..w.clone() })
            .collect();
        let g = RobotGeometry { wheel_names: design.wheel_names.clone(), wheels };
        g.validate()?;
        Ok(g)
    }

    /// The robot geometry for base parameters `p` (`geometry` models only).
    pub fn geometry_at(&self, p: &[f64]) -> Option<Result<RobotGeometry, KinError>> {
        match self {
            Self::Geometry { design } => Some(self.geometry(p, design)),
            Self::Ik { .. } => None,
        }
    }

    /// Wheel names.
    pub fn wheel_names(&self) -> Vec<String> {
        match self {
            Self::Geometry { design } => design.wheel_names.clone(),
            Self::Ik { design } => default_wheel_names(design.n_wheels()),
        }
    }
}

/// Which base kinematics a model fits, without its design: what the command line's `--model`, a model
/// file's `kinematics` and Python's `kinematics=` name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KinematicsKind {
    /// [`Kinematics::Ik`].
    Ik,
    /// [`Kinematics::Geometry`].
    Geometry,
}

crate::choice!(KinematicsKind, "kinematics", default = Ik, {
    Ik => "ik": "Every entry of the IK matrix (the paper)",
    Geometry => "geometry": "Wheel radii, distances and angles (the paper's ref. [17])",
});

impl KinematicsKind {
    /// The design model of this kind (nominal parameters, no effects, default integration) for `robot`:
    /// its IK matrix (Eq. 3) or its geometry; without a robot, the paper's APR-02: the Eq. 7 matrix as
    /// printed, or the APR-02 geometry.
    pub fn design_model(self, robot: Option<&RobotGeometry>) -> Result<Model, KinError> {
        Ok(match (self, robot) {
            (Self::Ik, Some(g)) => Model::ik(g.twist_from_wheels()?),
            (Self::Ik, None) => Model::ik(IkMatrix::paper_design()),
            (Self::Geometry, Some(g)) => Model::geometry(g.clone()),
            (Self::Geometry, None) => Model::geometry(RobotGeometry::apr02()),
        })
    }
}

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
    /// The paper's `ik` model around `design`, with default integration.
    pub fn ik(design: IkMatrix) -> Self {
        Self { kinematics: Kinematics::Ik { design }, effects: Vec::new(), integration: Integration::DEFAULT }
    }

    /// The `geometry` model around `design`, with default integration.
    pub fn geometry(design: RobotGeometry) -> Self {
        Self { kinematics: Kinematics::Geometry { design }, effects: Vec::new(), integration: Integration::DEFAULT }
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
        self.kinematics.params().len()
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
            return Err(KinError::Invalid {
                what: format!("parameter {name}"),
                why: format!("{} is not finite", params[i]),
            });
        }
        let nb = self.n_base();
        let ik = self.kinematics.ik(&params[..nb])?;
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
        self.model.kinematics.ik(&self.params[..self.model.n_base()])
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
            None => Err(KinError::Unknown {
                what: "parameter",
                name: name.into(),
                known: specs.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", "),
            }),
        }
    }

    /// The same model with an effect appended at its null parameters.
    pub fn with_effect(&self, e: EffectKind) -> Self {
        let mut params = self.params.clone();
        params.extend(e.params().iter().map(|p| p.null));
        Self { model: self.model.clone().with_effect(e), params }
    }
}
