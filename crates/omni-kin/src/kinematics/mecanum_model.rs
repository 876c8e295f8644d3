//! The parametric model of a four-wheel base on a rectangle (`mecanum`): the wheel radii `r_a` … `r_d`
//! (m, in column order) and the half-extents `lx`, `ly` (m) of the rectangle the wheels sit on, in that
//! order. Each wheel keeps its design quadrant, drive direction and roller angle; as `lx`, `ly` change the
//! wheels move with the rectangle (`x_i = x_i° · lx / lx°`, `y_i` likewise, `lx°` the design's mean
//! `|x_i|`), so a design that is not exactly symmetric is still reproduced at its design values.
//!
//! The IK matrix is the least-squares inverse in rim speeds ([`RobotGeometry::twist_from_wheels`]):
//! with `G` the rim-speed forward matrix (row `i`: `[cos(β_i+γ_i), sin(β_i+γ_i), x_i sin(β_i+γ_i) −
//! y_i cos(β_i+γ_i)] / cos γ_i`, independent of the radii), `M = (GᵀG)⁻¹ Gᵀ diag(r)`. For mecanum wheels
//! at (±lx, ±ly) with rollers at ±45° this is the textbook `vx = Σ r_i ω_i / 4`, `vy = Σ ±r_i ω_i / 4`,
//! `ω = Σ ±r_i ω_i / (4 (lx + ly))`. Four omni wheels pushing along the diagonals (an X) are the same
//! family, so the model also serves them. Four wheels and three degrees of freedom: one wheel pattern
//! moves the robot nowhere, and the model (six parameters) cannot express a response to it.
//!
//! A model file stores the wheels as `geometry` does.

use super::diff_model::same_wheels;
use super::{BaseKinematics, BaseRecord, KinematicsKind, RecordError};
use crate::effect::ParamSpec;
use crate::error::{Domain, KinError};
use crate::geometry::RobotGeometry;
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// The `mecanum` model: per-wheel radius and the rectangle's half-extents are its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MecanumKinematics {
    /// Design geometry: four wheels, one in each quadrant.
    pub design: RobotGeometry,
}

/// What the model keeps from its design, per wheel.
#[derive(Clone, Copy, Debug)]
struct Corner {
    /// Design position over the design half-extents: `(x_i°/lx°, y_i°/ly°)`, about ±1.
    unit: (f64, f64),
    /// Absolute drive direction `β_i` and roller angle `γ_i`. rad.
    beta: f64,
    gamma: f64,
}

impl Corner {
    /// Row `i` of the rim-speed forward matrix `G` at half-extents `(lx, ly)`, and its derivative by `lx`
    /// and by `ly` (only the ω column depends on them).
    fn row(&self, lx: f64, ly: f64) -> ([f64; 3], f64, f64) {
        let (s, c) = (self.beta + self.gamma).sin_cos();
        let k = 1.0 / self.gamma.cos();
        let (x, y) = (self.unit.0 * lx, self.unit.1 * ly);
        ([c * k, s * k, (x * s - y * c) * k], self.unit.0 * s * k, -self.unit.1 * c * k)
    }
}

fn not_a_rectangle(why: &'static str) -> KinError {
    KinError::Layout { model: KinematicsKind::Mecanum, why }
}

/// Design half-extents and corners of a geometry, checked: four wheels off both axes, one per quadrant.
fn layout(g: &RobotGeometry) -> Result<((f64, f64), [Corner; 4]), KinError> {
    g.validate()?;
    if g.n_wheels() != 4 {
        return Err(not_a_rectangle("it needs exactly four wheels"));
    }
    let xy: Vec<(f64, f64)> =
        g.wheels.iter().map(|w| (w.distance_m * w.angle_rad.cos(), w.distance_m * w.angle_rad.sin())).collect();
    let lx = xy.iter().map(|p| p.0.abs()).sum::<f64>() / 4.0;
    let ly = xy.iter().map(|p| p.1.abs()).sum::<f64>() / 4.0;
    let mut quadrants: Vec<(bool, bool)> = xy.iter().map(|p| (p.0 > 0.0, p.1 > 0.0)).collect();
    quadrants.sort();
    quadrants.dedup();
    if xy.iter().any(|p| p.0.abs() < 1e-3 * lx || p.1.abs() < 1e-3 * ly) || quadrants.len() != 4 {
        return Err(not_a_rectangle("one wheel must sit in each quadrant, off both axes"));
    }
    let mut corners = [Corner { unit: (0.0, 0.0), beta: 0.0, gamma: 0.0 }; 4];
    for (c, (w, p)) in corners.iter_mut().zip(g.wheels.iter().zip(&xy)) {
        *c = Corner {
            unit: (p.0 / lx, p.1 / ly),
            beta: w.angle_rad + FRAC_PI_2 + w.drive_offset_rad,
            gamma: w.roller_angle_rad,
        };
    }
    Ok(((lx, ly), corners))
}

/// `(GᵀG)⁻¹ Gᵀ` (3 × 4) for the rim-speed forward matrix `G`.
fn rim_inverse(g: &DMatrix<f64>) -> Result<DMatrix<f64>, KinError> {
    let gt = g.transpose();
    let normal = (&gt * g).try_inverse().ok_or(not_a_rectangle("its wheels do not span every planar twist"))?;
    Ok(normal * gt)
}

impl MecanumKinematics {
    /// The model around a design geometry, checked: four wheels, one in each quadrant.
    pub fn new(design: RobotGeometry) -> Result<Self, KinError> {
        layout(&design)?;
        Ok(Self { design })
    }

    /// Radii, `lx`, `ly` from `p`, checked.
    fn unpack<'p>(&self, p: &'p [f64]) -> Result<(&'p [f64], f64, f64), KinError> {
        if p.len() != 6 {
            return Err(KinError::ParamCount { got: p.len(), expected: 6 });
        }
        let names = ["r_a", "r_b", "r_c", "r_d", "lx", "ly"];
        for (name, v) in names.iter().zip(p) {
            if !(v.is_finite() && *v > 0.0) {
                return Err(KinError::BadParam { name: name.to_string(), value: *v, must: Domain::Positive });
            }
        }
        Ok((&p[..4], p[4], p[5]))
    }

    /// `G` (4 × 3) and its derivatives by `lx` and `ly` (4 × 3, ω column only).
    fn forward(&self, lx: f64, ly: f64) -> Result<[DMatrix<f64>; 3], KinError> {
        let (_, corners) = layout(&self.design)?;
        let (mut g, mut gx, mut gy) = (DMatrix::zeros(4, 3), DMatrix::zeros(4, 3), DMatrix::zeros(4, 3));
        for (i, c) in corners.iter().enumerate() {
            let (row, dx, dy) = c.row(lx, ly);
            for (j, v) in row.iter().enumerate() {
                g[(i, j)] = *v;
            }
            gx[(i, 2)] = dx;
            gy[(i, 2)] = dy;
        }
        Ok([g, gx, gy])
    }

    /// The design geometry with the radii of `p` and the wheels moved to the rectangle `lx`, `ly`, each
    /// keeping its drive direction.
    fn at(&self, p: &[f64]) -> Result<RobotGeometry, KinError> {
        let (r, lx, ly) = self.unpack(p)?;
        let (_, corners) = layout(&self.design)?;
        let mut g = self.design.clone();
        for ((w, c), ri) in g.wheels.iter_mut().zip(&corners).zip(r) {
            let (x, y) = (c.unit.0 * lx, c.unit.1 * ly);
            w.radius_m = *ri;
            w.distance_m = x.hypot(y);
            w.angle_rad = y.atan2(x);
            w.drive_offset_rad = c.beta - w.angle_rad - FRAC_PI_2;
        }
        Ok(g)
    }
}

impl BaseKinematics for MecanumKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Mecanum
    }

    fn n_wheels(&self) -> usize {
        4
    }

    fn wheel_names(&self) -> Vec<String> {
        self.design.wheel_names.clone()
    }

    fn n_params(&self) -> usize {
        6
    }

    /// `r_a` … `r_d`, `lx`, `ly` at the design values, bounds ±10 %.
    fn params(&self) -> Vec<ParamSpec> {
        let (lx, ly) = layout(&self.design).map_or((f64::NAN, f64::NAN), |l| l.0);
        let mut p: Vec<ParamSpec> = self
            .design
            .wheels
            .iter()
            .enumerate()
            .map(|(i, w)| {
                let name = format!("r_{}", (b'a' + i as u8) as char);
                ParamSpec::new(name, "m", w.radius_m, 0.9 * w.radius_m, 1.1 * w.radius_m)
            })
            .collect();
        p.push(ParamSpec::new("lx", "m", lx, 0.9 * lx, 1.1 * lx));
        p.push(ParamSpec::new("ly", "m", ly, 0.9 * ly, 1.1 * ly));
        p
    }

    /// Their own magnitudes.
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        p.iter().map(|v| v.abs()).collect()
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        let (r, lx, ly) = self.unpack(p)?;
        let [g, ..] = self.forward(lx, ly)?;
        let n = rim_inverse(&g)?;
        IkMatrix::new(4, (0..12).map(|k| n[(k / 4, k % 4)] * r[k % 4]).collect())
    }

    /// Exact: `∂M/∂r_i` is column `i` of `(GᵀG)⁻¹Gᵀ`; `∂M/∂l = (−(GᵀG)⁻¹(EᵀG + GᵀE) N + (GᵀG)⁻¹Eᵀ) diag(r)`
    /// with `E = ∂G/∂l`, `N = (GᵀG)⁻¹Gᵀ`.
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let (r, lx, ly) = self.unpack(p)?;
        let [g, gx, gy] = self.forward(lx, ly)?;
        let n = rim_inverse(&g)?;
        let normal_inv = &n * n.transpose();
        let mut j = DMatrix::zeros(12, 6);
        for i in 0..4 {
            for row in 0..3 {
                j[(row * 4 + i, i)] = n[(row, i)];
            }
        }
        for (col, e) in [(4, gx), (5, gy)] {
            let dn = -&normal_inv * (e.transpose() * &g + g.transpose() * &e) * &n + &normal_inv * e.transpose();
            for k in 0..12 {
                j[(k, col)] = dn[(k / 4, k % 4)] * r[k % 4];
            }
        }
        Ok(j)
    }

    fn geometry_at(&self, p: &[f64]) -> Option<Result<RobotGeometry, KinError>> {
        Some(self.at(p))
    }

    /// The design's corner distance `hypot(lx, ly)`.
    fn lever_arm_m(&self) -> f64 {
        layout(&self.design).map_or(super::DEFAULT_LEVER_ARM_M, |((lx, ly), _)| lx.hypot(ly))
    }

    fn noun(&self) -> &'static str {
        "wheel layout"
    }

    /// `[[wheels]]` (at `p`) and `[[design_wheels]]`, as `geometry`.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        Ok(BaseRecord::of_wheels(&self.design, self.at(p)?))
    }

    /// The design from `[[design_wheels]]`; the parameters from `[[wheels]]`, which must be the design's
    /// wheels with other radii, moved with the rectangle.
    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        let w = record.wheels.as_ref().ok_or(RecordError::Missing { kind: "mecanum", key: "[[wheels]]" })?;
        let d = record.design_wheels.clone().unwrap_or_else(|| w.clone());
        let design = RobotGeometry { wheel_names: record.wheel_names.clone(), wheels: d };
        let model = Self::new(design).map_err(|error| RecordError::Invalid { key: "design_wheels", error })?;
        if w.len() != 4 {
            return Err(RecordError::WheelCounts { design_key: "design_wheels", key: "wheels" });
        }
        let fitted = RobotGeometry { wheel_names: record.wheel_names.clone(), wheels: w.clone() };
        let invalid = |error| RecordError::Invalid { key: "wheels", error };
        let ((lx, ly), _) = layout(&fitted).map_err(invalid)?;
        let mut p: Vec<f64> = w.iter().map(|w| w.radius_m).collect();
        p.extend([lx, ly]);
        let back = model.at(&p).map_err(invalid)?;
        if !same_wheels(&back.wheels, w) {
            return Err(invalid(not_a_rectangle(
                "[[wheels]] must be the design's wheels with other radii, moved with the rectangle (drive directions and rollers as designed)",
            )));
        }
        Ok((model, p))
    }

    /// The robot's geometry, which must have four wheels on a rectangle; there is no default robot.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        let g = robot.ok_or_else(|| {
            not_a_rectangle("the mecanum model needs the robot's geometry (a robot description or OptiOdom metadata)")
        })?;
        Self::new(g.clone())
    }
}
