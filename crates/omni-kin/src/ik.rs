//! The inverse kinematic (IK) matrix `twist_from_wheels` (3 × N): body twist (vx, vy in m/s, ω in rad/s)
//! from wheel speeds (rad/s). The paper's Eq. 4 names its entries m11 … m33 row by row.
//!
//! The paper's matrices are kept with the digits as printed (hence the lint allowance below).
#![allow(clippy::excessive_precision)]

use crate::error::KinError;
use crate::pose::Twist2;
use serde::{Deserialize, Serialize};

/// A 3 × N IK matrix, stored row-major. Rows: vx (m/s), vy (m/s), ω (rad/s); columns: wheels (rad/s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IkMatrix {
    n_wheels: usize,
    entries: Vec<f64>,
}

impl IkMatrix {
    /// A matrix from its row-major entries (3 × `n_wheels`). Entries must be finite.
    pub fn new(n_wheels: usize, entries: Vec<f64>) -> Result<Self, KinError> {
        if entries.len() != 3 * n_wheels || n_wheels == 0 {
            return Err(KinError::Shape {
                what: "IK matrix".into(),
                got: entries.len(),
                expected: 3 * n_wheels.max(1),
            });
        }
        if let Some(i) = entries.iter().position(|v| !v.is_finite()) {
            return Err(KinError::Invalid {
                what: format!("IK matrix entry m{}{}", i / n_wheels + 1, i % n_wheels + 1),
                why: format!("{} is not finite", entries[i]),
            });
        }
        Ok(Self { n_wheels, entries })
    }

    /// A matrix from three rows of equal length.
    pub fn from_rows(rows: &[Vec<f64>]) -> Result<Self, KinError> {
        if rows.len() != 3 {
            return Err(KinError::Shape { what: "IK matrix rows".into(), got: rows.len(), expected: 3 });
        }
        let n = rows[0].len();
        for r in rows {
            if r.len() != n {
                return Err(KinError::Shape { what: "IK matrix row".into(), got: r.len(), expected: n });
            }
        }
        Self::new(n, rows.iter().flatten().copied().collect())
    }

    /// The paper's Eq. 7: the APR-02 design matrix, digits as printed.
    pub fn paper_design() -> Self {
        Self {
            n_wheels: 3,
            entries: vec![
                -0.0854478398400646,
                0.0,
                0.0854478398400646,
                0.049333333333333333,
                -0.09866666666666667,
                0.049333333333333333,
                0.2529914529914529,
                0.2529914529914529,
                0.2529914529914529,
            ],
        }
    }

    /// The paper's Eq. 8: the parametric calibration of ref. \[17\].
    pub fn paper_parametric() -> Self {
        Self {
            n_wheels: 3,
            entries: vec![
                -0.0892930568372762,
                -0.0005606566978203,
                0.0867466159313470,
                0.0520955668635434,
                -0.1010213675626970,
                0.0533117820461363,
                0.2364093797047320,
                0.2341358647406650,
                0.2353792947863630,
            ],
        }
    }

    /// The paper's Eq. 9: the non-parametric (GA) calibration; our simulator's default true robot.
    pub fn paper_calibrated() -> Self {
        Self {
            n_wheels: 3,
            entries: vec![
                -0.0883286476963123,
                0.0,
                0.0873330402667908,
                0.0522829495809178,
                -0.1008246738469390,
                0.0536189007203205,
                0.2357044251338890,
                0.2338948216993490,
                0.2348793373133590,
            ],
        }
    }

    /// Number of wheels (columns).
    pub fn n_wheels(&self) -> usize {
        self.n_wheels
    }

    /// Row-major entries (3 × N).
    pub fn entries(&self) -> &[f64] {
        &self.entries
    }

    /// Entry at row `r` (0 = vx, 1 = vy, 2 = ω) and wheel column `c`.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.entries[r * self.n_wheels + c]
    }

    /// The matrix with wheel column `c` times `factor`: the same robot with wheel `c`'s radius times
    /// `factor` (every column of a twist-from-wheel-speeds matrix is proportional to its wheel's radius).
    /// A column beyond the wheels leaves it unchanged.
    pub fn with_column_scaled(&self, c: usize, factor: f64) -> Self {
        let mut m = self.clone();
        if c < self.n_wheels {
            for r in 0..3 {
                m.entries[r * self.n_wheels + c] *= factor;
            }
        }
        m
    }

    /// The matrix with twist row `r` (0 = vx, 1 = vy, 2 = ω) times `factor`; a differential drive's ω row
    /// divided by `1 + e` is its wheel separation `1 + e` times longer.
    pub fn with_row_scaled(&self, r: usize, factor: f64) -> Self {
        let mut m = self.clone();
        if r < 3 {
            for v in &mut m.entries[r * self.n_wheels..(r + 1) * self.n_wheels] {
                *v *= factor;
            }
        }
        m
    }

    /// Row `r` as a slice.
    pub fn row(&self, r: usize) -> &[f64] {
        &self.entries[r * self.n_wheels..(r + 1) * self.n_wheels]
    }

    /// The three rows as vectors (for files and reports).
    pub fn rows(&self) -> Vec<Vec<f64>> {
        (0..3).map(|r| self.row(r).to_vec()).collect()
    }

    /// Body twist from one sample of wheel speeds (rad/s, one per wheel).
    #[inline]
    pub fn twist(&self, wheel_rad_s: &[f64]) -> Twist2 {
        debug_assert_eq!(wheel_rad_s.len(), self.n_wheels);
        let n = self.n_wheels;
        let dot =
            |r: usize| -> f64 { self.entries[r * n..(r + 1) * n].iter().zip(wheel_rad_s).map(|(a, b)| a * b).sum() };
        Twist2 { vx_m_s: dot(0), vy_m_s: dot(1), omega_rad_s: dot(2) }
    }

    /// Entry names `m11` … `m3N`, row by row (the paper's Eq. 5 order).
    pub fn entry_names(n_wheels: usize) -> Vec<String> {
        (0..3).flat_map(|r| (0..n_wheels).map(move |c| format!("m{}{}", r + 1, c + 1))).collect()
    }
}
