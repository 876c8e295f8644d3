//! The paper's non-parametric model (`ik`): every entry of the 3 × N IK matrix is a parameter, named
//! `m11` … `m3N` row by row (the paper's Eq. 5 order).

use super::{BaseKinematics, BaseRecord, KinematicsKind, RecordError};
use crate::effect::ParamSpec;
use crate::error::KinError;
use crate::geometry::{RobotGeometry, default_wheel_names};
use crate::ik::IkMatrix;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// The `ik` model: the IK matrix's entries are its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatrixKinematics {
    /// Design matrix (the start and centre of the search).
    pub design: IkMatrix,
}

impl BaseKinematics for MatrixKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Ik
    }

    fn n_wheels(&self) -> usize {
        self.design.n_wheels()
    }

    /// The default names `wheel_a`, `wheel_b`, … (a matrix does not name its wheels).
    fn wheel_names(&self) -> Vec<String> {
        default_wheel_names(self.design.n_wheels())
    }

    fn n_params(&self) -> usize {
        self.design.entries().len()
    }

    /// `m11` … `m3N` at the design entries; units m (rows vx, vy) and rad (row ω) per wheel rad.
    fn params(&self) -> Vec<ParamSpec> {
        let n = self.design.n_wheels();
        IkMatrix::entry_names(n)
            .into_iter()
            .zip(self.design.entries())
            .enumerate()
            .map(|(i, (name, &v))| {
                let unit = if i / n == 2 { "rad" } else { "m" };
                ParamSpec::new(name, unit, v, v - 0.1 * v.abs(), v + 0.1 * v.abs())
            })
            .collect()
    }

    /// The largest magnitude in each entry's row of `p` (a zero entry, e.g. the paper's m12, still gets
    /// the row's scale).
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        let n = self.design.n_wheels();
        (0..p.len()).map(|i| p[(i / n) * n..(i / n + 1) * n].iter().fold(0.0f64, |m, x| m.max(x.abs()))).collect()
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        IkMatrix::new(self.design.n_wheels(), p.to_vec())
    }

    /// The identity.
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let n = self.n_params();
        if p.len() != n {
            return Err(KinError::ParamCount { got: p.len(), expected: n });
        }
        Ok(DMatrix::identity(n, n))
    }

    fn params_are_ik_entries(&self) -> bool {
        true
    }

    fn noun(&self) -> &'static str {
        "matrix"
    }

    /// `matrix` (at `p`) and `design_matrix`, rows vx, vy, ω; default wheel names.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        Ok(BaseRecord {
            wheel_names: self.wheel_names(),
            matrix: Some(self.twist_from_wheels(p)?.rows()),
            design_matrix: Some(self.design.rows()),
            wheels: None,
            design_wheels: None,
        })
    }

    fn from_record(record: &BaseRecord) -> Result<(Self, Vec<f64>), RecordError> {
        let m = record.matrix.as_ref().ok_or(RecordError::Missing { kind: "ik", key: "matrix" })?;
        let fitted = IkMatrix::from_rows(m).map_err(|error| RecordError::Invalid { key: "matrix", error })?;
        let design = match &record.design_matrix {
            Some(d) => IkMatrix::from_rows(d).map_err(|error| RecordError::Invalid { key: "design_matrix", error })?,
            None => fitted.clone(),
        };
        if design.n_wheels() != fitted.n_wheels() {
            return Err(RecordError::WheelCounts { design_key: "design_matrix", key: "matrix" });
        }
        Ok((Self { design }, fitted.entries().to_vec()))
    }

    /// The robot's IK matrix (Eq. 3) when its geometry is known, else the paper's Eq. 7.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        let design = match robot {
            Some(g) => g.twist_from_wheels()?,
            None => IkMatrix::paper_design(),
        };
        Ok(Self { design })
    }
}
