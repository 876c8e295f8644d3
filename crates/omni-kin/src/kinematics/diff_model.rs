//! The parametric model of a differential drive (`diff`): the right and left wheel radii `r_right`,
//! `r_left` (m) and the wheel separation `b` (m), in that order, whatever the wheels' column order.
//!
//! Two wheels on one axle, driving along x: wheel `i` at lateral offset `y_i` with rim speed
//! `σ_i r_i ω_i = vx − y_i ω` (`σ_i = ±1`: which way positive wheel speed pushes). Its inverse, with
//! `b = y_L − y_R` and `κ = −y_R / b` (½ for a centred axle, kept from the design as `b` changes):
//!
//! ```text
//! vx = (1 − κ) σ_R r_R ω_R + κ σ_L r_L ω_L      vy = 0      ω = (σ_R r_R ω_R − σ_L r_L ω_L) / b
//! ```
//!
//! The wheels cannot move the robot sideways, so the IK matrix's `vy` row is zero by construction: the
//! model has no parameter there. (The non-parametric `ik` model holds a design row that is zero at zero
//! too; see `MatrixKinematics`.) A model file stores the wheels as `geometry` does.

use super::{BaseKinematics, BaseRecord, KinematicsKind, RecordError};
use crate::effect::ParamSpec;
use crate::error::{Domain, KinError};
use crate::geometry::{RobotGeometry, Wheel};
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// The `diff` model: both wheel radii and the separation are its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiffKinematics {
    /// Design geometry: two wheels on one axle.
    pub design: RobotGeometry,
}

/// Where a differential drive's wheels are, read from its geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Axle {
    /// Column of the right wheel (y < 0) and of the left one.
    right: usize,
    left: usize,
    /// `σ`: +1 when positive wheel speed drives forward, per column.
    sign: [f64; 2],
    /// Separation `y_L − y_R`. m.
    separation_m: f64,
    /// `−y_R / b`: the centre's share of the way from the right wheel to the left one.
    kappa: f64,
}

fn not_an_axle(why: &'static str) -> KinError {
    KinError::Layout { model: KinematicsKind::Diff, why }
}

impl Axle {
    fn of(g: &RobotGeometry) -> Result<Self, KinError> {
        if g.n_wheels() != 2 || g.wheel_names.len() != 2 {
            return Err(not_an_axle("a differential drive has exactly two wheels (and two wheel names)"));
        }
        let mut y = [0.0; 2];
        let mut sign = [0.0; 2];
        for (i, w) in g.wheels.iter().enumerate() {
            let beta = w.angle_rad + FRAC_PI_2 + w.drive_offset_rad;
            if !(w.radius_m > 0.0 && w.radius_m.is_finite()) {
                return Err(KinError::BadWheel { wheel: i, field: "radius_m", value: w.radius_m, why: "must be > 0" });
            }
            if !w.drives_along_x() {
                return Err(not_an_axle("both wheels must drive along x (a common axle), without rollers"));
            }
            y[i] = w.distance_m * w.angle_rad.sin();
            sign[i] = beta.cos().signum();
        }
        let (right, left) = if y[0] < y[1] { (0, 1) } else { (1, 0) };
        let separation_m = y[left] - y[right];
        if !(y[right] < 0.0 && y[left] > 0.0 && separation_m.is_finite()) {
            return Err(not_an_axle("one wheel must sit on each side of the centre (y < 0 and y > 0)"));
        }
        Ok(Self { right, left, sign, separation_m, kappa: -y[right] / separation_m })
    }
}

impl DiffKinematics {
    /// The model around a design geometry, checked: two wheels on one axle, one on each side.
    pub fn new(design: RobotGeometry) -> Result<Self, KinError> {
        Axle::of(&design)?;
        Ok(Self { design })
    }

    fn axle(&self) -> Result<Axle, KinError> {
        Axle::of(&self.design)
    }

    /// `(r_R, r_L, b)` from `p`, checked.
    fn unpack(&self, p: &[f64]) -> Result<[f64; 3], KinError> {
        if p.len() != 3 {
            return Err(KinError::ParamCount { got: p.len(), expected: 3 });
        }
        for (name, v) in ["r_right", "r_left", "b"].iter().zip(p) {
            if !(v.is_finite() && *v > 0.0) {
                return Err(KinError::BadParam { name: name.to_string(), value: *v, must: Domain::Positive });
            }
        }
        Ok([p[0], p[1], p[2]])
    }

    /// The design geometry with the radii of `p` and the wheels moved along their position vectors so
    /// that the separation is `b`.
    fn at(&self, p: &[f64]) -> Result<RobotGeometry, KinError> {
        let a = self.axle()?;
        let [rr, rl, b] = self.unpack(p)?;
        let scale = b / a.separation_m;
        let mut g = self.design.clone();
        for (i, w) in g.wheels.iter_mut().enumerate() {
            w.radius_m = if i == a.right { rr } else { rl };
            w.distance_m *= scale;
        }
        Ok(g)
    }
}

impl BaseKinematics for DiffKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Diff
    }

    fn n_wheels(&self) -> usize {
        2
    }

    fn wheel_names(&self) -> Vec<String> {
        self.design.wheel_names.clone()
    }

    fn n_params(&self) -> usize {
        3
    }

    /// `r_right`, `r_left`, `b` at the design values, bounds ±10 %.
    fn params(&self) -> Vec<ParamSpec> {
        let (rr, rl, b) = match self.axle() {
            Ok(a) => (self.design.wheels[a.right].radius_m, self.design.wheels[a.left].radius_m, a.separation_m),
            Err(_) => (f64::NAN, f64::NAN, f64::NAN),
        };
        [("r_right", rr), ("r_left", rl), ("b", b)]
            .into_iter()
            .map(|(name, v)| ParamSpec::new(name, "m", v, 0.9 * v, 1.1 * v))
            .collect()
    }

    /// Their own magnitudes.
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        p.iter().map(|v| v.abs()).collect()
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        let a = self.axle()?;
        let [rr, rl, b] = self.unpack(p)?;
        let (kr, kl) = (a.sign[a.right] * rr, a.sign[a.left] * rl);
        let mut m = [0.0; 6];
        m[a.right] = (1.0 - a.kappa) * kr;
        m[a.left] = a.kappa * kl;
        m[4 + a.right] = kr / b;
        m[4 + a.left] = -kl / b;
        IkMatrix::new(2, m.to_vec())
    }

    /// Exact: each radius scales its wheel's column, `b` divides the ω row.
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let a = self.axle()?;
        let [rr, rl, b] = self.unpack(p)?;
        let (sr, sl) = (a.sign[a.right], a.sign[a.left]);
        let mut j = DMatrix::zeros(6, 3);
        j[(a.right, 0)] = (1.0 - a.kappa) * sr;
        j[(4 + a.right, 0)] = sr / b;
        j[(a.left, 1)] = a.kappa * sl;
        j[(4 + a.left, 1)] = -sl / b;
        j[(4 + a.right, 2)] = -sr * rr / (b * b);
        j[(4 + a.left, 2)] = sl * rl / (b * b);
        Ok(j)
    }

    fn geometry_at(&self, p: &[f64]) -> Option<Result<RobotGeometry, KinError>> {
        Some(self.at(p))
    }

    /// Half the design separation.
    fn lever_arm_m(&self) -> f64 {
        self.axle().map_or(super::DEFAULT_LEVER_ARM_M, |a| 0.5 * a.separation_m)
    }

    fn noun(&self) -> &'static str {
        "axle"
    }

    /// `[[wheels]]` (at `p`) and `[[design_wheels]]`, as `geometry`.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        Ok(BaseRecord::of_wheels(&self.design, self.at(p)?))
    }

    /// The design from `[[design_wheels]]`; the parameters from `[[wheels]]`, which must be the design's
    /// wheels with other radii and separation.
    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        let w = record.wheels.as_ref().ok_or(RecordError::Missing { kind: "diff", key: "[[wheels]]" })?;
        let d = record.design_wheels.clone().unwrap_or_else(|| w.clone());
        let design = RobotGeometry { wheel_names: record.wheel_names.clone(), wheels: d };
        let model = Self::new(design).map_err(|error| RecordError::Invalid { key: "design_wheels", error })?;
        if w.len() != 2 {
            return Err(RecordError::WheelCounts { design_key: "design_wheels", key: "wheels" });
        }
        let fitted = RobotGeometry { wheel_names: record.wheel_names.clone(), wheels: w.clone() };
        let invalid = |error| RecordError::Invalid { key: "wheels", error };
        let a = Axle::of(&fitted).map_err(invalid)?;
        let p = vec![w[a.right].radius_m, w[a.left].radius_m, a.separation_m];
        let back = model.at(&p).map_err(invalid)?;
        if !same_wheels(&back.wheels, w) {
            return Err(invalid(not_an_axle(
                "[[wheels]] must be the design's wheels with other radii and separation (angles and drive offsets as designed)",
            )));
        }
        Ok((model, p))
    }

    /// The robot's geometry, which must be a differential drive; there is no default robot.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        let g = robot.ok_or_else(|| {
            not_an_axle("the diff model needs the robot's geometry (a robot description or OptiOdom metadata)")
        })?;
        Self::new(g.clone())
    }
}

/// Two wheel lists equal to rounding (lengths 1e-9 relative, angles 1e-9 rad modulo 2π).
pub(super) fn same_wheels(a: &[Wheel], b: &[Wheel]) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0);
    let same_angle = |x: f64, y: f64| (x - y).sin().abs() <= 1e-9 && (x - y).cos() > 0.0;
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| {
            close(p.radius_m, q.radius_m)
                && close(p.distance_m, q.distance_m)
                && same_angle(p.angle_rad, q.angle_rad)
                && same_angle(p.drive_offset_rad, q.drive_offset_rad)
                && same_angle(p.roller_angle_rad, q.roller_angle_rad)
        })
}
