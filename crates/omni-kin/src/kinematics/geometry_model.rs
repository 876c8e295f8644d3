//! The parametric model of the paper's ref. \[17\] (`geometry`): per wheel the radius `r_i` (m), the
//! distance `R_i` (m) and the angle `δ_i` (rad) are parameters, in that order (all radii, then all
//! distances, then all angles); drive offsets and roller angles stay at their design values. The IK matrix
//! is the geometry's ([`RobotGeometry::twist_from_wheels`]).

use super::{BaseKinematics, BaseRecord, KinematicsKind, RecordError};
use crate::effect::ParamSpec;
use crate::error::KinError;
use crate::geometry::{RobotGeometry, Wheel};
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// The `geometry` model: wheel radii, distances and angles are its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeometryKinematics {
    /// Design geometry.
    pub design: RobotGeometry,
}

/// Relative step of the central differences of [`GeometryKinematics::twist_from_wheels_jacobian`].
const JACOBIAN_STEP: f64 = 1e-7;

impl GeometryKinematics {
    /// The design geometry with the radii, distances and angles of `p`, validated.
    fn at(&self, p: &[f64]) -> Result<RobotGeometry, KinError> {
        let n = self.design.n_wheels();
        if p.len() != 3 * n {
            return Err(KinError::ParamCount { got: p.len(), expected: 3 * n });
        }
        let wheels = self
            .design
            .wheels
            .iter()
            .enumerate()
            .map(|(i, w)| Wheel { radius_m: p[i], distance_m: p[n + i], angle_rad: p[2 * n + i], ..w.clone() })
            .collect();
        let g = RobotGeometry { wheel_names: self.design.wheel_names.clone(), wheels };
        g.validate()?;
        Ok(g)
    }
}

impl BaseKinematics for GeometryKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Geometry
    }

    fn n_wheels(&self) -> usize {
        self.design.n_wheels()
    }

    fn wheel_names(&self) -> Vec<String> {
        self.design.wheel_names.clone()
    }

    fn n_params(&self) -> usize {
        3 * self.design.n_wheels()
    }

    /// `r_a` …, `R_a` …, `delta_a` … at the design values, bounds ±10 %.
    fn params(&self) -> Vec<ParamSpec> {
        let letters: Vec<String> =
            (0..self.design.n_wheels()).map(|i| ((b'a' + i as u8) as char).to_string()).collect();
        let wheels = &self.design.wheels;
        let mut p = Vec::with_capacity(3 * wheels.len());
        for (l, w) in letters.iter().zip(wheels) {
            p.push(ParamSpec::new(format!("r_{l}"), "m", w.radius_m, 0.9 * w.radius_m, 1.1 * w.radius_m));
        }
        for (l, w) in letters.iter().zip(wheels) {
            p.push(ParamSpec::new(format!("R_{l}"), "m", w.distance_m, 0.9 * w.distance_m, 1.1 * w.distance_m));
        }
        for (l, w) in letters.iter().zip(wheels) {
            let d = w.angle_rad;
            p.push(ParamSpec::new(format!("delta_{l}"), "rad", d, d - 0.1 * d.abs(), d + 0.1 * d.abs()));
        }
        p
    }

    /// Radii and distances: their own magnitude; angles: 1 rad.
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        let n = self.design.n_wheels();
        p.iter().enumerate().map(|(i, v)| if i >= 2 * n { 1.0 } else { v.abs() }).collect()
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        self.at(p)?.twist_from_wheels()
    }

    /// By central differences of the (cheap) map from geometry to IK matrix, step
    /// `1e-7 · max(|p_k|, 1e-3)` per parameter.
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let nb = self.n_params();
        let entries = 3 * self.design.n_wheels();
        if p.len() != nb {
            return Err(KinError::ParamCount { got: p.len(), expected: nb });
        }
        let mut dm = DMatrix::zeros(entries, nb);
        for c in 0..nb {
            let h = JACOBIAN_STEP * p[c].abs().max(1e-3);
            let (mut xp, mut xm) = (p.to_vec(), p.to_vec());
            xp[c] += h;
            xm[c] -= h;
            let mp = self.twist_from_wheels(&xp)?;
            let mm = self.twist_from_wheels(&xm)?;
            for (i, (a, b)) in mp.entries().iter().zip(mm.entries()).enumerate() {
                dm[(i, c)] = (a - b) / (2.0 * h);
            }
        }
        Ok(dm)
    }

    fn geometry_at(&self, p: &[f64]) -> Option<Result<RobotGeometry, KinError>> {
        Some(self.at(p))
    }

    /// The mean design wheel distance.
    fn lever_arm_m(&self) -> f64 {
        let wheels = &self.design.wheels;
        wheels.iter().map(|w| w.distance_m).sum::<f64>() / wheels.len().max(1) as f64
    }

    fn noun(&self) -> &'static str {
        "geometry"
    }

    /// `[[wheels]]` (at `p`) and `[[design_wheels]]`, with the design's wheel names.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        Ok(BaseRecord::of_wheels(&self.design, self.at(p)?))
    }

    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        let w = record.wheels.as_ref().ok_or(RecordError::Missing { kind: "geometry", key: "[[wheels]]" })?;
        let d = record.design_wheels.clone().unwrap_or_else(|| w.clone());
        let names = record.wheel_names.clone();
        let design = RobotGeometry { wheel_names: names.clone(), wheels: d };
        design.validate().map_err(|error| RecordError::Invalid { key: "design_wheels", error })?;
        let fitted = RobotGeometry { wheel_names: names, wheels: w.clone() };
        fitted.validate().map_err(|error| RecordError::Invalid { key: "wheels", error })?;
        if fitted.n_wheels() != design.n_wheels() {
            return Err(RecordError::WheelCounts { design_key: "design_wheels", key: "wheels" });
        }
        let mut p: Vec<f64> = fitted.wheels.iter().map(|w| w.radius_m).collect();
        p.extend(fitted.wheels.iter().map(|w| w.distance_m));
        p.extend(fitted.wheels.iter().map(|w| w.angle_rad));
        Ok((Self { design }, p))
    }

    /// The robot's geometry when known, else the paper's APR-02.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        Ok(Self { design: robot.cloned().unwrap_or_else(RobotGeometry::apr02) })
    }
}
