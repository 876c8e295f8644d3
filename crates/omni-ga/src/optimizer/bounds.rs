//! The search box of a problem.

use crate::optimizer::error::OptimizeError;
use serde::{Deserialize, Serialize};

/// A box: one `[lower, upper]` interval per parameter (`lower == upper` fixes a parameter; infinite bounds
/// are allowed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Lower bounds.
    pub lower: Vec<f64>,
    /// Upper bounds.
    pub upper: Vec<f64>,
}

impl Bounds {
    /// Checks sizes and order.
    pub fn new(lower: Vec<f64>, upper: Vec<f64>) -> Result<Self, OptimizeError> {
        if lower.len() != upper.len() {
            return Err(OptimizeError::DimensionMismatch { start: lower.len(), bounds: upper.len() });
        }
        for (i, (&l, &u)) in lower.iter().zip(&upper).enumerate() {
            if l.is_nan() || u.is_nan() || l > u {
                return Err(OptimizeError::BadBounds { index: i, lower: l, upper: u });
            }
        }
        Ok(Self { lower, upper })
    }
    /// No bounds on `n` parameters: every interval is `(−∞, ∞)`.
    pub fn unbounded(n: usize) -> Self {
        Self { lower: vec![f64::NEG_INFINITY; n], upper: vec![f64::INFINITY; n] }
    }
    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.lower.len()
    }
    /// True when there are no parameters.
    pub fn is_empty(&self) -> bool {
        self.lower.is_empty()
    }
    /// True when `x` lies inside (bounds included).
    pub fn contains(&self, x: &[f64]) -> bool {
        x.len() == self.len() && x.iter().enumerate().all(|(i, v)| *v >= self.lower[i] && *v <= self.upper[i])
    }
    /// `x` clamped into the box.
    pub fn clamp(&self, x: &[f64]) -> Vec<f64> {
        x.iter().enumerate().map(|(i, v)| v.clamp(self.lower[i], self.upper[i])).collect()
    }
    /// True when parameter `i` is fixed.
    pub fn is_fixed(&self, i: usize) -> bool {
        self.lower[i] == self.upper[i]
    }
    /// Width of parameter `i`'s interval.
    pub fn width(&self, i: usize) -> f64 {
        self.upper[i] - self.lower[i]
    }
}
