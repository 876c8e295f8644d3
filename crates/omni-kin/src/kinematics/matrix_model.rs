//! The paper's non-parametric model (`ik`): every entry of the 3 × N IK matrix is a parameter, named
//! `m11` … `m3N` row by row (the paper's Eq. 5 order).
//!
//! Structural zeros: a row that is zero throughout the design is a motion the base cannot make (the `vy`
//! row of a differential drive, whose wheels cannot push sideways). Its entries are not parameters: they
//! stay at zero, whatever the runs say (ground-truth motion there, such as a marker off the axle seen
//! sideways while turning, belongs to an effect: `sensor_offset`). Every other design keeps all `3N`
//! entries free.

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
    /// Wheel (joint) names in column order, when known (a robot description's joints, `--joints`); empty
    /// for the default names `wheel_a`, `wheel_b`, ….
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub wheel_names: Vec<String>,
}

impl MatrixKinematics {
    /// The model around `design`, with the default wheel names.
    pub fn new(design: IkMatrix) -> Self {
        Self { design, wheel_names: Vec::new() }
    }

    /// Names to store: empty when they are the defaults (so that a model read back from a file equals the
    /// one written).
    fn stored_names(names: &[String], n_wheels: usize) -> Vec<String> {
        if names.len() != n_wheels || names == default_wheel_names(n_wheels).as_slice() {
            Vec::new()
        } else {
            names.to_vec()
        }
    }

    /// This model with these wheel names (column order); `KinError::Shape` unless there is one per wheel.
    pub fn with_wheel_names(mut self, names: &[String]) -> Result<Self, KinError> {
        let n = self.design.n_wheels();
        if names.len() != n {
            return Err(KinError::Shape { what: "wheel_names".into(), got: names.len(), expected: n });
        }
        self.wheel_names = Self::stored_names(names, n);
        Ok(self)
    }

    /// Indices (row-major, into [`IkMatrix::entries`]) of the entries that are parameters: all but the
    /// rows that are zero throughout the design.
    fn free_entries(&self) -> Vec<usize> {
        let n = self.design.n_wheels();
        (0..3 * n).filter(|&i| self.design.row(i / n).iter().any(|v| *v != 0.0)).collect()
    }

    /// The whole matrix (row-major) from the parameters `p`, structural zeros filled in.
    fn entries(&self, p: &[f64]) -> Result<Vec<f64>, KinError> {
        let free = self.free_entries();
        if p.len() != free.len() {
            return Err(KinError::ParamCount { got: p.len(), expected: free.len() });
        }
        let mut e = vec![0.0; self.design.entries().len()];
        for (&i, v) in free.iter().zip(p) {
            e[i] = *v;
        }
        Ok(e)
    }
}

impl BaseKinematics for MatrixKinematics {
    fn kind(&self) -> KinematicsKind {
        KinematicsKind::Ik
    }

    fn n_wheels(&self) -> usize {
        self.design.n_wheels()
    }

    /// The names it was given (a robot description's joints), else `wheel_a`, `wheel_b`, ….
    fn wheel_names(&self) -> Vec<String> {
        if self.wheel_names.len() == self.design.n_wheels() {
            self.wheel_names.clone()
        } else {
            default_wheel_names(self.design.n_wheels())
        }
    }

    fn n_params(&self) -> usize {
        self.free_entries().len()
    }

    /// `m11` … `m3N` at the design entries; units m (rows vx, vy) and rad (row ω) per wheel rad.
    fn params(&self) -> Vec<ParamSpec> {
        let n = self.design.n_wheels();
        let names = IkMatrix::entry_names(n);
        self.free_entries()
            .into_iter()
            .map(|i| {
                let (name, v) = (names[i].clone(), self.design.entries()[i]);
                let unit = if i / n == 2 { "rad" } else { "m" };
                ParamSpec::new(name, unit, v, v - 0.1 * v.abs(), v + 0.1 * v.abs())
            })
            .collect()
    }

    /// The largest magnitude in each entry's row of `p` (a zero entry, e.g. the paper's m12, still gets
    /// the row's scale).
    fn param_scales(&self, p: &[f64]) -> Vec<f64> {
        let n = self.design.n_wheels();
        let free = self.free_entries();
        if free.len() == p.len() && free.len() == 3 * n {
            return (0..p.len())
                .map(|i| p[(i / n) * n..(i / n + 1) * n].iter().fold(0.0f64, |m, x| m.max(x.abs())))
                .collect();
        }
        let e = self.entries(p).unwrap_or_else(|_| self.design.entries().to_vec());
        free.iter().map(|&i| e[(i / n) * n..(i / n + 1) * n].iter().fold(0.0f64, |m, x| m.max(x.abs()))).collect()
    }

    fn twist_from_wheels(&self, p: &[f64]) -> Result<IkMatrix, KinError> {
        if self.params_are_ik_entries() {
            // Every entry free (no structural zeros): the parameters are the matrix.
            return IkMatrix::new(self.design.n_wheels(), p.to_vec());
        }
        IkMatrix::new(self.design.n_wheels(), self.entries(p)?)
    }

    /// The identity (with structural zeros: the columns of the free entries).
    fn twist_from_wheels_jacobian(&self, p: &[f64]) -> Result<DMatrix<f64>, KinError> {
        let free = self.free_entries();
        if p.len() != free.len() {
            return Err(KinError::ParamCount { got: p.len(), expected: free.len() });
        }
        let mut j = DMatrix::zeros(self.design.entries().len(), free.len());
        for (c, &i) in free.iter().enumerate() {
            j[(i, c)] = 1.0;
        }
        Ok(j)
    }

    /// True unless the design has structural zeros.
    fn params_are_ik_entries(&self) -> bool {
        self.free_entries().len() == self.design.entries().len()
    }

    fn noun(&self) -> &'static str {
        "matrix"
    }

    /// `matrix` (at `p`) and `design_matrix`, rows vx, vy, ω; the wheel names.
    fn record(&self, p: &[f64]) -> Result<BaseRecord, KinError> {
        Ok(BaseRecord {
            wheel_names: self.wheel_names(),
            matrix: Some(self.twist_from_wheels(p)?.rows()),
            design_matrix: Some(self.design.rows()),
            ..BaseRecord::default()
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
        let wheel_names = Self::stored_names(&record.wheel_names, design.n_wheels());
        let model = Self { design, wheel_names };
        let free = model.free_entries();
        let e = fitted.entries();
        if let Some(i) = (0..e.len()).find(|i| e[*i] != 0.0 && !free.contains(i)) {
            let n = fitted.n_wheels();
            let error = KinError::Invalid {
                what: format!("entry m{}{}", i / n + 1, i % n + 1),
                why: format!(
                    "{} is not zero, but its row is zero throughout design_matrix (a motion the base cannot make)",
                    e[i]
                ),
            };
            return Err(RecordError::Invalid { key: "matrix", error });
        }
        let p = free.iter().map(|&i| e[i]).collect();
        Ok((model, p))
    }

    /// The robot's IK matrix (Eq. 3) and wheel names when its geometry is known, else the paper's Eq. 7.
    fn design_for(robot: Option<&RobotGeometry>) -> Result<Self, KinError> {
        match robot {
            Some(g) => Self::new(g.twist_from_wheels()?).with_wheel_names(&g.wheel_names),
            None => Ok(Self::new(IkMatrix::paper_design())),
        }
    }
}
