//! Base kinematic models: what a model fits before any physical effect. Each model owns its parameters.
//!
//! [`BaseKinematics`] is the one trait every base model implements: its id, wheels, parameter specs and
//! scales, the IK matrix `twist_from_wheels` (3 × N) at a parameter vector and its derivative by the
//! parameters, the robot geometry at a parameter vector (if it has one), what an unconstrained direction
//! of its parameters means physically ([`UnexcitedBase`]), and what a model file stores ([`BaseRecord`]).
//!
//! [`Kinematics`] is the closed set of models a [`crate::Model`] can hold; it dispatches to the trait by
//! `match` (no `dyn` in the hot loops), and its serde form (`kind = "ik"`, `design = …`) is the model's.
//!
//! | id | model | parameters (in order) |
//! |---|---|---|
//! | `ik` | [`MatrixKinematics`]: the paper's non-parametric model, every IK entry free | `m11` … `m3N` |
//! | `geometry` | [`GeometryKinematics`]: the paper's ref. \[17\], per-wheel radius, distance, angle | `r_a` …, `R_a` …, `delta_a` … |
//! | `diff` | [`DiffKinematics`]: a differential drive, both radii and the separation (`vy` row zero) | `r_right`, `r_left`, `b` |
//! | `mecanum` | [`MecanumKinematics`]: four wheels on a rectangle (mecanum, or omni wheels in an X), per-wheel radius and the half-extents | `r_a` … `r_d`, `lx`, `ly` |
//! | `skid` | [`SkidKinematics`]: a skid-steer base, the ICR-based extended differential drive | `r_right`, `r_left`, `y_icr_left`, `y_icr_right`, `x_icr` |
//!
//! To add a robot type: a new file implementing [`BaseKinematics`], and one variant in [`Kinematics`] and
//! [`KinematicsKind`] (this file).

mod diff_model;
mod geometry_model;
mod matrix_model;
mod mecanum_model;
mod skid_model;

pub use diff_model::DiffKinematics;
pub use geometry_model::GeometryKinematics;
pub use matrix_model::MatrixKinematics;
pub use mecanum_model::MecanumKinematics;
pub use skid_model::{SKID_PARAMS, SkidKinematics, SkidRecord};

use crate::effect::ParamSpec;
use crate::error::KinError;
use crate::geometry::{RobotGeometry, Wheel};
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// A typical wheel lever arm when a model does not know its wheel positions (an IK matrix). m.
pub const DEFAULT_LEVER_ARM_M: f64 = 0.2;

/// A base kinematic model: everything the fit, the diagnosis, the reports and the model files need to
/// know about it. Parameter vectors `p` are the model's own (length [`Self::n_params`]), in the order of
/// [`Self::params`].
pub trait BaseKinematics {
    /// Which model this is; its id (`ik`, `geometry`) names it in model files, the CLI and Python.
    fn kind(&self) -> KinematicsKind;

    /// Number of wheels (columns of the IK matrix).
    fn n_wheels(&self) -> usize;

    /// Wheel (joint) names, in column order.
    fn wheel_names(&self) -> Vec<String>;

    /// Number of parameters (`params().len()`, without building the specs).
    fn n_params(&self) -> usize;

    /// One spec per parameter: name, unit, design value (`null`, where searches start) and default bounds
    /// (±10 % of each design value, as the paper).
    fn params(&self) -> Vec<ParamSpec>;

    /// Each parameter's natural scale at `p` (same unit as the parameter): the size of a typical
    /// calibration correction is a small fraction of it. Sets the search box of
    /// `BoxRule::PerRow` (at the start) and the identifiability analysis' units (at the design).
    fn param_scales(&self, p: &[f64]) -> Vec<f64>;

    /// The IK matrix (3 × N: body twist in m/s, m/s, rad/s from wheel speeds in rad/s) at `p`.
    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError>;

    /// The IK matrix's derivative by the parameters at `p`: `3N × n_params`, row `r·N + c` is the entry
    /// (r, c) in [`IkMatrix::entries`] order, column `k` the parameter `k` (entry unit per parameter unit).
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError>;

    /// True when the parameters are the IK matrix's entries themselves (its derivative is the identity), so
    /// a display of the matrix already shows them.
    fn params_are_ik_entries(&self) -> bool {
        false
    }

    /// The robot geometry at `p`, for models that have one.
    fn geometry_at(&self, _p: &[f64]) -> Option<Result<RobotGeometry, KinError>> {
        None
    }

    /// A typical wheel lever arm: the length that makes a rotation rate (rad/s) comparable with a
    /// speed (m/s). m. Default [`DEFAULT_LEVER_ARM_M`].
    fn lever_arm_m(&self) -> f64 {
        DEFAULT_LEVER_ARM_M
    }

    /// What is fitted, as a noun for labels: `matrix`, `geometry`.
    fn noun(&self) -> &'static str;

    /// What a direction `dir` of the parameters (scaled: parameter `k` moves by `dir[k] · scales[k]`) means
    /// physically at `p`, when the runs do not constrain it: the wheel-speed pattern whose response it
    /// changes most, and that pattern's motion under the design. `None` when the IK matrix cannot be
    /// evaluated around `p` or at the design. The default works for any model through
    /// [`Self::twist_from_wheels`].
    fn unexcited(&self, p: &[f64], dir: &[f64], scales: &[f64]) -> Option<UnexcitedBase> {
        unexcited_by_differences(self, p, dir, scales)
    }

    /// What a model file stores about this model with parameters `p`.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError>;

    /// The model and its parameters from a model file's record (the inverse of [`Self::record`]).
    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError>
    where
        Self: Sized;

    /// The design model of a robot: from its geometry when the runs declare one, else the paper's APR-02.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError>
    where
        Self: Sized;
}

/// Which base model: the id in model files (`kinematics = "ik"`), CLI options and Python.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KinematicsKind {
    /// [`MatrixKinematics`].
    Ik,
    /// [`GeometryKinematics`].
    Geometry,
    /// [`DiffKinematics`].
    Diff,
    /// [`MecanumKinematics`].
    Mecanum,
    /// [`SkidKinematics`].
    Skid,
}

crate::choice!(KinematicsKind, default = Ik, {
    Ik => "ik": "Every entry of the IK matrix (the paper)",
    Geometry => "geometry": "Per-wheel radius, distance from the centre and mounting angle (parametric)",
    Diff => "diff": "A differential drive: both wheel radii and the separation",
    Mecanum => "mecanum": "Four wheels on a rectangle (mecanum, omni X): per-wheel radius and the half-extents",
    Skid => "skid": "A skid-steer base: each side's radius and the ICRs of the treads and of the robot",
});

/// What a model file stores about the base kinematics (the keys of `omnical-model/1` besides `format`,
/// `kinematics`, `integration`, `effects` and `fit`). Each model uses the keys it needs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaseRecord {
    /// Wheel (joint) names in column order.
    pub wheel_names: Vec<String>,
    /// Fitted IK matrix (`ik`): 3 rows × N wheels.
    pub matrix: Option<Vec<Vec<f64>>>,
    /// Design IK matrix (`ik`); default: the fitted one.
    pub design_matrix: Option<Vec<Vec<f64>>>,
    /// Fitted wheels (`geometry`).
    pub wheels: Option<Vec<Wheel>>,
    /// Design wheels (`geometry`); default: the fitted ones.
    pub design_wheels: Option<Vec<Wheel>>,
    /// A skid-steer base's parameters (`skid`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skid: Option<SkidRecord>,
}

impl BaseRecord {
    /// The record of a model whose parameters are wheel positions, radii and angles (`geometry`, `diff`,
    /// `mecanum`): the design's wheel names, the fitted wheels `fitted` (wheels in m and rad) and the
    /// design's wheels; no matrix.
    pub fn of_wheels(design: &RobotGeometry, fitted: RobotGeometry) -> Self {
        BaseRecord {
            wheel_names: design.wheel_names.clone(),
            matrix: None,
            design_matrix: None,
            wheels: Some(fitted.wheels),
            design_wheels: Some(design.wheels.clone()),
            skid: None,
        }
    }

    /// The model of `kind` this record describes, and its parameters ([`Kinematics::from_record`]).
    pub fn read(&self, kind: KinematicsKind) -> Result<(Kinematics, Vec<f64>), RecordError> {
        Kinematics::from_record(kind, self)
    }
}

/// A model file's record does not make a model. Keys are the file's (`matrix`, `[[wheels]]`, …).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RecordError {
    /// A key the model needs is missing.
    #[error("kinematics = {kind:?} needs `{key}`")]
    Missing {
        /// The model's id.
        kind: &'static str,
        /// The key, as written in the file (`matrix`, `[[wheels]]`).
        key: &'static str,
    },
    /// A key's value makes no valid model.
    #[error("{key}: {error}")]
    Invalid {
        /// The key.
        key: &'static str,
        /// What is wrong.
        error: KinError,
    },
    /// The fitted and design values have different wheel counts.
    #[error("{design_key} and {key} have different wheel counts")]
    WheelCounts {
        /// The design key (`design_matrix`, `design_wheels`).
        design_key: &'static str,
        /// The fitted key (`matrix`, `wheels`).
        key: &'static str,
    },
}

/// What an unconstrained direction of the base parameters means physically ([`BaseKinematics::unexcited`]).
#[derive(Clone, Debug, PartialEq)]
pub struct UnexcitedBase {
    /// The wheel-speed pattern whose response the direction changes most (unit vector, one entry per
    /// wheel), signed so that its design motion moves forward or turns left.
    pub wheel_pattern: Vec<f64>,
    /// The design twist of that pattern per unit wheel speed: (vx m/s, vy m/s, ω rad/s).
    pub motion: [f64; 3],
}

/// The default [`BaseKinematics::unexcited`]: the change of the IK matrix along `dir` by a small central
/// difference (exact for `ik`), its dominant right singular vector `u` (`ΔM ≈ a uᵀ`), and `u`'s twist
/// under the design matrix.
fn unexcited_by_differences<K: BaseKinematics + ?Sized>(
    k: &K,
    p: &[f64],
    dir: &[f64],
    scales: &[f64],
) -> Option<UnexcitedBase> {
    let nb = k.n_params();
    let nw = k.n_wheels();
    let h = 1e-4;
    let step = |sign: f64| -> Option<Vec<f64>> {
        let q: Vec<f64> = (0..nb).map(|i| p[i] + sign * h * dir[i] * scales[i]).collect();
        k.twist_from_wheels(&q).ok().map(|m| m.entries().to_vec())
    };
    let (mp, mm) = (step(1.0)?, step(-1.0)?);
    let dm = DMatrix::from_fn(3, nw, |r, c| (mp[r * nw + c] - mm[r * nw + c]) / (2.0 * h));
    let svd = dm.try_svd(true, true, f64::EPSILON, 10_000)?;
    let vt = svd.v_t?;
    let top =
        (0..svd.singular_values.len()).max_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))?;
    let mut u: Vec<f64> = (0..nw).map(|c| vt[(top, c)]).collect();
    let nominal: Vec<f64> = k.params().iter().map(|s| s.null).collect();
    let design = k.twist_from_wheels(&nominal).ok()?;
    let mut t = design.twist(&u);
    // Prefer the sign that moves forward / turns left, for readable advice.
    let key = [t.vx_m_s, t.vy_m_s, t.omega_rad_s * k.lever_arm_m()];
    let dominant = key.iter().copied().fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
    if dominant < 0.0 {
        u.iter_mut().for_each(|x| *x = -*x);
        t = design.twist(&u);
    }
    Some(UnexcitedBase { wheel_pattern: u, motion: [t.vx_m_s, t.vy_m_s, t.omega_rad_s] })
}

/// The base kinematics a model fits: one variant per [`BaseKinematics`] implementation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kinematics {
    /// The paper's non-parametric model: every entry of the 3 × N IK matrix is free.
    Ik(MatrixKinematics),
    /// The parametric model of the paper's ref. \[17\]: per wheel r_i, R_i, δ_i.
    Geometry(GeometryKinematics),
    /// A differential drive: r_R, r_L, b.
    Diff(DiffKinematics),
    /// Four wheels on a rectangle: per-wheel radius, lx, ly.
    Mecanum(MecanumKinematics),
    /// A skid-steer base: r_R, r_L, y_ICR,L, y_ICR,R, x_ICR.
    Skid(SkidKinematics),
}

/// Delegates each listed method to the model inside a [`Kinematics`]: the only `match` on its variants
/// besides the constructors by [`KinematicsKind`].
macro_rules! delegate {
    ($(#[$doc:meta] fn $name:ident(&self $(, $arg:ident: $ty:ty)*) -> $ret:ty;)*) => {
        $(
            #[$doc]
            pub fn $name(&self $(, $arg: $ty)*) -> $ret {
                match self {
                    Kinematics::Ik(k) => k.$name($($arg),*),
                    Kinematics::Geometry(k) => k.$name($($arg),*),
                    Kinematics::Diff(k) => k.$name($($arg),*),
                    Kinematics::Mecanum(k) => k.$name($($arg),*),
                    Kinematics::Skid(k) => k.$name($($arg),*),
                }
            }
        )*
    };
}

impl Kinematics {
    /// The design model of `kind` for a robot: from its geometry when known, else the paper's APR-02
    /// (`ik`: Eq. 7).
    pub fn design(kind: KinematicsKind, robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        Ok(match kind {
            KinematicsKind::Ik => Self::Ik(MatrixKinematics::design_for(robot)?),
            KinematicsKind::Geometry => Self::Geometry(GeometryKinematics::design_for(robot)?),
            KinematicsKind::Diff => Self::Diff(DiffKinematics::design_for(robot)?),
            KinematicsKind::Mecanum => Self::Mecanum(MecanumKinematics::design_for(robot)?),
            KinematicsKind::Skid => Self::Skid(SkidKinematics::design_for(robot)?),
        })
    }

    /// A model of `kind` and its parameters from a model file's record.
    pub fn from_record(kind: KinematicsKind, record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        Ok(match kind {
            KinematicsKind::Ik => {
                let (k, p) = MatrixKinematics::from_record(record)?;
                (Self::Ik(k), p)
            }
            KinematicsKind::Geometry => {
                let (k, p) = GeometryKinematics::from_record(record)?;
                (Self::Geometry(k), p)
            }
            KinematicsKind::Diff => {
                let (k, p) = DiffKinematics::from_record(record)?;
                (Self::Diff(k), p)
            }
            KinematicsKind::Mecanum => {
                let (k, p) = MecanumKinematics::from_record(record)?;
                (Self::Mecanum(k), p)
            }
            KinematicsKind::Skid => {
                let (k, p) = SkidKinematics::from_record(record)?;
                (Self::Skid(k), p)
            }
        })
    }

    /// This model with these wheel (joint) names, in column order: one per wheel, else `KinError::Shape`.
    pub fn with_wheel_names(self, names: &[String]) -> Result<Self, KinError> {
        let n = self.n_wheels();
        if names.len() != n {
            return Err(KinError::Shape { what: "wheel_names".into(), got: names.len(), expected: n });
        }
        let named = |mut g: RobotGeometry| {
            g.wheel_names = names.to_vec();
            g
        };
        Ok(match self {
            Self::Ik(k) => Self::Ik(k.with_wheel_names(names)?),
            Self::Geometry(k) => Self::Geometry(GeometryKinematics { design: named(k.design) }),
            Self::Diff(k) => Self::Diff(DiffKinematics { design: named(k.design) }),
            Self::Mecanum(k) => Self::Mecanum(MecanumKinematics { design: named(k.design) }),
            Self::Skid(k) => Self::Skid(SkidKinematics { design: named(k.design) }),
        })
    }

    /// The id: `ik`, `geometry`.
    pub fn id(&self) -> &'static str {
        self.kind().id()
    }

    delegate! {
        /// [`BaseKinematics::kind`].
        fn kind(&self) -> KinematicsKind;
        /// [`BaseKinematics::n_wheels`].
        fn n_wheels(&self) -> usize;
        /// [`BaseKinematics::wheel_names`].
        fn wheel_names(&self) -> Vec<String>;
        /// [`BaseKinematics::n_params`].
        fn n_params(&self) -> usize;
        /// [`BaseKinematics::params`].
        fn params(&self) -> Vec<ParamSpec>;
        /// [`BaseKinematics::param_scales`].
        fn param_scales(&self, p: &[f64]) -> Vec<f64>;
        /// [`BaseKinematics::twist_from_wheels`].
        fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError>;
        /// [`BaseKinematics::twist_from_wheels_jacobian`].
        fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError>;
        /// [`BaseKinematics::params_are_ik_entries`].
        fn params_are_ik_entries(&self) -> bool;
        /// [`BaseKinematics::geometry_at`].
        fn geometry_at(&self, p: &[f64]) -> Option<Result<RobotGeometry, KinError>>;
        /// [`BaseKinematics::lever_arm_m`].
        fn lever_arm_m(&self) -> f64;
        /// [`BaseKinematics::noun`].
        fn noun(&self) -> &'static str;
        /// [`BaseKinematics::unexcited`].
        fn unexcited(&self, p: &[f64], dir: &[f64], scales: &[f64]) -> Option<UnexcitedBase>;
        /// [`BaseKinematics::record`].
        fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError>;
    }
}

#[cfg(test)]
mod robot_type_tests;
#[cfg(test)]
mod tests;
