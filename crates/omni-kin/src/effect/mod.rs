//! Physical effects that the 3 × N IK matrix cannot express (or can only absorb), each a small documented
//! model with named parameters that does nothing at its null value.
//!
//! An effect acts at one stage of the odometry pipeline:
//!
//! | stage | hook | examples |
//! |---|---|---|
//! | clock | [`Effect::clock_lag_s`] | `time_offset` |
//! | wheel speeds (per run, may carry state) | [`Effect::wheel_rates`] | `wheel_asymmetry`, `backlash`, `wheel_eccentricity` |
//! | body twist (per sample) | [`Effect::twist`], [`Effect::twist_at`] (with pose and time) | `rotation_slip`, `turn_scrub`, `world_drift`, `learned:world` |
//! | integration | [`Effect::uses_stamps`] | `sample_timing` |
//! | measurement | [`Effect::sensor_from_body`] | `sensor_offset` |
//!
//! The simulator injects effects through exactly these hooks (at its fine step), so the model that is
//! fitted is the model that generated the data. Law (checked by tests): at the null parameters an effect
//! leaves the trajectory bit-identical.

mod builtin;
pub mod learned;

pub use learned::{Family, Learned};

pub use builtin::{
    AccelSlip, Backlash, RotationSlip, SampleTiming, SensorOffset, SpeedScale, TimeOffset, TurnScrub, WheelAsymmetry,
    WheelEccentricity, WorldDrift,
};

use crate::error::KinError;
use crate::pose::{Pose2, Twist2};
use serde::{Deserialize, Serialize};

/// Body speed (`|(vx, vy)|`) above which the robot counts as moving. m/s. 5 mm/s: above the jitter of a
/// standing robot's odometry (wheel-speed noise of a few mrad/s × a 5 cm wheel is below 0.3 mm/s), below
/// any commanded motion.
pub const MOVING_SPEED_M_S: f64 = 0.005;
/// Yaw rate above which the robot counts as moving. rad/s. 0.02 rad/s ≈ 1.1 °/s, the same order as
/// [`MOVING_SPEED_M_S`] at a lever arm of 0.25 m.
pub const MOVING_OMEGA_RAD_S: f64 = 0.02;

/// Whether the robot moves, judged on its body twist `t` (m/s, rad/s) — the one predicate of every effect
/// that acts only while moving (`world_drift`, the `learned:world` and `learned:time` terms): faster than
/// [`MOVING_SPEED_M_S`] or turning faster than [`MOVING_OMEGA_RAD_S`]. On the body twist rather than the
/// wheel speeds, so wheels fighting each other while the robot stands still do not count.
pub fn moving(t: &Twist2) -> bool {
    t.omega_rad_s.abs() > MOVING_OMEGA_RAD_S || longer_than(t.vx_m_s, t.vy_m_s, MOVING_SPEED_M_S)
}

/// `x.hypot(y) > r`, decided on the squares (`x² + y²` against `r²`) except within rounding of the
/// threshold, where `hypot` itself decides: the same answer at a fraction of the cost (a step's hook).
#[inline]
pub fn longer_than(x: f64, y: f64, r: f64) -> bool {
    let (q, r2) = (x * x + y * y, r * r);
    if (q - r2).abs() > 1e-9 * r2 { q > r2 } else { x.hypot(y) > r }
}
use std::fmt;
use std::sync::Arc;

/// One parameter of a model or effect.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamSpec {
    /// Name, unique within the model, e.g. `tau_s`, `a_wheel_b`, `m23`.
    pub name: String,
    /// Unit, e.g. `s`, `m`, `rad`, `1`.
    pub unit: String,
    /// Value at which it does nothing (effects) or the design value (kinematics).
    pub null: f64,
    /// Default lower bound for searches.
    pub lower: f64,
    /// Default upper bound for searches.
    pub upper: f64,
}

impl ParamSpec {
    /// A parameter spec.
    pub fn new(name: impl Into<String>, unit: &str, null: f64, lower: f64, upper: f64) -> Self {
        Self { name: name.into(), unit: unit.into(), null, lower, upper }
    }
}

/// The pipeline stage an effect acts on (for reports and for the equivalence analysis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// How wheel stamps map to ground-truth time.
    Clock,
    /// Wheel speeds, before the IK matrix.
    Wheel,
    /// The body twist, after the IK matrix.
    Twist,
    /// How the twist is integrated.
    Integration,
    /// How the ground-truth sensor sees the body.
    Measurement,
}

/// What a wheel-stage effect sees of a run.
#[derive(Debug)]
pub struct WheelContext<'a> {
    /// Number of wheels.
    pub n_wheels: usize,
    /// Sample stamps on the ground-truth clock. s.
    pub t_s: &'a [f64],
    /// Step length integrated for each sample. s.
    pub dt_s: &'a [f64],
    /// Wheel angle at the first sample, one per wheel (0 when unknown). rad.
    pub start_angle_rad: &'a [f64],
}

/// Where the robot is when a twist-stage effect acts on one step: what the odometry walk (and the
/// simulator) knows besides the twist and the wheel speeds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TwistAt {
    /// Body pose in the ground-truth (world) frame at the start of the step (m, m, rad).
    pub pose: Pose2,
    /// Time since the run's first ground-truth pose, at the middle of the step. s.
    pub since_start_s: f64,
}

/// A physical effect that the IK matrix cannot express. Implement only the hook of its stage.
///
/// Downstream crates implement this trait for their own effects and add them with [`EffectKind::Custom`].
pub trait Effect: fmt::Debug + Send + Sync {
    /// Stable id used by CLI flags, model files, reports and Python: `"time_offset"`.
    fn id(&self) -> &str;
    /// One line of physics for reports.
    fn describe(&self) -> String;
    /// The stage it acts on.
    fn stage(&self) -> Stage;
    /// One spec per parameter: name, unit, null value, bounds.
    fn params(&self) -> Vec<ParamSpec>;
    /// Wheel stage: rewrite a run's wheel speeds (row-major `n_samples × n_wheels`, rad/s) in place.
    fn wheel_rates(&self, _p: &[f64], _ctx: &WheelContext<'_>, _wheel_rad_s: &mut [f64]) {}
    /// Wheel stage: whether [`Effect::wheel_rates`] is affine in the parameters, each parameter's part
    /// taken from the measured speeds alone: `wheel_rates(p)` gives `w + Σ_i p_i (wheel_rates(e_i) − w)`
    /// (to rounding; `e_i` the unit vector of parameter `i`). The fast path then computes each
    /// parameter's part once per dataset instead of rewriting the speeds on every evaluation. Default
    /// false.
    fn wheel_rates_affine(&self) -> bool {
        false
    }
    /// Twist stage: change one sample's body twist (the wheel speeds it came from are given).
    fn twist(&self, _p: &[f64], twist: Twist2, _wheel_rad_s: &[f64]) -> Twist2 {
        twist
    }
    /// Twist stage, for effects that depend on where the robot is (its heading in the world frame, the
    /// time since the run started): change one step's body twist. By default [`Effect::twist`].
    fn twist_at(&self, p: &[f64], twist: Twist2, wheel_rad_s: &[f64], _at: &TwistAt) -> Twist2 {
        self.twist(p, twist, wheel_rad_s)
    }
    /// Clock stage: how late the wheel stamps run against the ground-truth clock. s.
    fn clock_lag_s(&self, _p: &[f64]) -> f64 {
        0.0
    }
    /// Measurement stage: the pose of the ground-truth sensor in the body frame.
    fn sensor_from_body(&self, _p: &[f64]) -> Pose2 {
        Pose2::IDENTITY
    }
    /// Integration stage: integrate with each sample's measured interval instead of a fixed step.
    fn uses_stamps(&self) -> bool {
        false
    }
}

/// The built-in effects, plus user effects behind [`EffectKind::Custom`]. Matching on the enum keeps
/// dynamic dispatch out of the hot loop for the built-ins.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum EffectKind {
    /// Ground-truth sensor away from the rotation centre.
    SensorOffset(SensorOffset),
    /// Wheel clock lags the ground-truth clock.
    TimeOffset(TimeOffset),
    /// Forward/backward radius difference per wheel.
    WheelAsymmetry(WheelAsymmetry),
    /// Radius changes with wheel speed.
    SpeedScale(SpeedScale),
    /// Translation turned by slip while rotating.
    RotationSlip(RotationSlip),
    /// Turn rate scaled by the translation speed (scrub while turning and driving).
    TurnScrub(TurnScrub),
    /// Traction lost while a wheel speeds up.
    AccelSlip(AccelSlip),
    /// Lost motion after a wheel reverses.
    Backlash(Backlash),
    /// Out-of-round wheels.
    WheelEccentricity(WheelEccentricity),
    /// Integrate with measured stamps.
    SampleTiming(SampleTiming),
    /// World-frame drift while moving.
    WorldDrift(WorldDrift),
    /// A correction learned by the explorer over one family of features (`learned:world`, …).
    Learned(Learned),
    /// A user effect (not stored in model files by value; only its id is).
    #[serde(skip)]
    Custom(Arc<dyn Effect>),
}

/// Makes a built-in effect for a robot of `n` wheels.
type MakeEffect = fn(usize) -> EffectKind;

/// The built-in catalogue, in catalogue order: each effect's id (its struct's `ID`, the one place it is
/// spelt) and how to make it for a robot of `n` wheels. [`CATALOGUE`] and [`EffectKind::from_id`] read it.
const BUILTIN: [(&str, MakeEffect); 11] = [
    (SensorOffset::ID, |_| EffectKind::SensorOffset(SensorOffset { with_yaw: false })),
    (TimeOffset::ID, |_| EffectKind::TimeOffset(TimeOffset {})),
    (WheelAsymmetry::ID, |n_wheels| EffectKind::WheelAsymmetry(WheelAsymmetry { n_wheels })),
    (SpeedScale::ID, |n_wheels| EffectKind::SpeedScale(SpeedScale { n_wheels })),
    (RotationSlip::ID, |_| EffectKind::RotationSlip(RotationSlip {})),
    (TurnScrub::ID, |_| EffectKind::TurnScrub(TurnScrub {})),
    (AccelSlip::ID, |n_wheels| EffectKind::AccelSlip(AccelSlip { n_wheels })),
    (Backlash::ID, |n_wheels| EffectKind::Backlash(Backlash { n_wheels })),
    (WheelEccentricity::ID, |n_wheels| EffectKind::WheelEccentricity(WheelEccentricity { n_wheels })),
    (SampleTiming::ID, |_| EffectKind::SampleTiming(SampleTiming {})),
    (WorldDrift::ID, |_| EffectKind::WorldDrift(WorldDrift {})),
];

/// Ids of the built-in catalogue, in catalogue order (one table, `BUILTIN`, spells them with their makers).
pub const CATALOGUE: &[&str] = &{
    let mut ids = [""; BUILTIN.len()];
    let mut i = 0;
    while i < BUILTIN.len() {
        ids[i] = BUILTIN[i].0;
        i += 1;
    }
    ids
};

/// Every id [`EffectKind::from_id`] accepts, for help texts and messages: the [`CATALOGUE`] with
/// `sensor_offset_yaw` after `sensor_offset`, then the learned corrections (`learned:wheel`, …).
pub fn ids() -> Vec<String> {
    let mut ids: Vec<String> = CATALOGUE.iter().map(|s| s.to_string()).collect();
    if let Some(i) = ids.iter().position(|id| id == SensorOffset::ID) {
        ids.insert(i + 1, SensorOffset::ID_YAW.into());
    }
    ids.extend(learned::ids());
    ids
}

impl EffectKind {
    /// A built-in effect by id for a robot with `n_wheels` wheels. `sensor_offset_yaw` is `sensor_offset`
    /// with a yaw parameter.
    pub fn from_id(id: &str, n_wheels: usize) -> Result<Self, KinError> {
        if id == SensorOffset::ID_YAW {
            return Ok(Self::SensorOffset(SensorOffset { with_yaw: true }));
        }
        if let Some((_, make)) = BUILTIN.iter().find(|(known, _)| *known == id) {
            return Ok(make(n_wheels));
        }
        if id.starts_with(learned::PREFIX) {
            return Ok(Self::Learned(Learned::from_id(id, n_wheels)?));
        }
        Err(KinError::unknown("effect", id, &ids()))
    }

    /// The whole built-in catalogue for `n_wheels` wheels.
    pub fn catalogue(n_wheels: usize) -> Vec<Self> {
        CATALOGUE.iter().filter_map(|id| Self::from_id(id, n_wheels).ok()).collect()
    }

    fn inner(&self) -> &dyn Effect {
        match self {
            Self::SensorOffset(e) => e,
            Self::TimeOffset(e) => e,
            Self::WheelAsymmetry(e) => e,
            Self::SpeedScale(e) => e,
            Self::RotationSlip(e) => e,
            Self::TurnScrub(e) => e,
            Self::AccelSlip(e) => e,
            Self::Backlash(e) => e,
            Self::WheelEccentricity(e) => e,
            Self::SampleTiming(e) => e,
            Self::WorldDrift(e) => e,
            Self::Learned(e) => e,
            Self::Custom(e) => e.as_ref(),
        }
    }
}

impl Effect for EffectKind {
    fn id(&self) -> &str {
        match self {
            Self::SensorOffset(e) if e.with_yaw => SensorOffset::ID_YAW,
            _ => self.inner().id(),
        }
    }
    fn describe(&self) -> String {
        self.inner().describe()
    }
    fn stage(&self) -> Stage {
        self.inner().stage()
    }
    fn params(&self) -> Vec<ParamSpec> {
        self.inner().params()
    }
    fn wheel_rates(&self, p: &[f64], ctx: &WheelContext<'_>, w: &mut [f64]) {
        self.inner().wheel_rates(p, ctx, w)
    }
    fn wheel_rates_affine(&self) -> bool {
        self.inner().wheel_rates_affine()
    }
    // Every stage goes through `inner`, whose match is exhaustive: an effect added to the enum is dispatched
    // (an effect of another stage keeps the trait's defaults, the twist unchanged).
    fn twist(&self, p: &[f64], twist: Twist2, w: &[f64]) -> Twist2 {
        self.inner().twist(p, twist, w)
    }
    fn twist_at(&self, p: &[f64], twist: Twist2, w: &[f64], at: &TwistAt) -> Twist2 {
        self.inner().twist_at(p, twist, w, at)
    }
    fn clock_lag_s(&self, p: &[f64]) -> f64 {
        self.inner().clock_lag_s(p)
    }
    fn sensor_from_body(&self, p: &[f64]) -> Pose2 {
        self.inner().sensor_from_body(p)
    }
    fn uses_stamps(&self) -> bool {
        self.inner().uses_stamps()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_catalogue_id_is_spelt_once_and_makes_its_own_effect() {
        assert_eq!(CATALOGUE.len(), BUILTIN.len());
        for (id, make) in BUILTIN {
            let e = make(4);
            assert_eq!(e.id(), id, "the table's id and the effect's own");
            assert_eq!(EffectKind::from_id(id, 4).map(|e| e.id().to_string()).ok().as_deref(), Some(id));
        }
        let yaw = EffectKind::from_id(SensorOffset::ID_YAW, 3).ok();
        assert!(matches!(yaw, Some(EffectKind::SensorOffset(SensorOffset { with_yaw: true }))));
        assert_eq!(ids()[..3], [SensorOffset::ID, SensorOffset::ID_YAW, TimeOffset::ID]);
        let err = EffectKind::from_id("wobble", 3).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err.contains("\"wobble\"") && err.contains("world_drift"), "{err}");
    }
}
