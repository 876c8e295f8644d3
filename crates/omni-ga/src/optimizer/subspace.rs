//! A least-squares problem restricted to an affine subspace of its parameters, `x = origin + B z`: the
//! optimizers then move only along the columns of `B` (the fit layer's truncated update uses it to keep
//! unconstrained directions at their start).

use crate::optimizer::bounds::Bounds;
use crate::optimizer::problem::{LeastSquares, NormalEquations, Problem};
use nalgebra::{DMatrix, DVector};

/// `inner` restricted to `origin + basis · z`, unbounded in `z`.
pub struct Subspace<'p, P: LeastSquares + ?Sized> {
    inner: &'p P,
    origin: Vec<f64>,
    /// `n × k`, parameter units.
    basis: DMatrix<f64>,
    bounds: Bounds,
}

impl<'p, P: LeastSquares + ?Sized> Subspace<'p, P> {
    /// The subspace through `origin` (the inner problem's parameters) spanned by the columns of `basis`
    /// (`n × k`, parameter units).
    pub fn new(inner: &'p P, origin: Vec<f64>, basis: DMatrix<f64>) -> Self {
        let bounds = Bounds::unbounded(basis.ncols());
        Self { inner, origin, basis, bounds }
    }

    /// The inner problem's parameters at subspace coordinates `z`: `origin + basis · z`.
    pub fn point(&self, z: &[f64]) -> Vec<f64> {
        let dz = &self.basis * DVector::from_column_slice(z);
        self.origin.iter().zip(dz.iter()).map(|(o, d)| o + d).collect()
    }

    /// The subspace's dimension `k`.
    pub fn dim(&self) -> usize {
        self.basis.ncols()
    }
}

impl<P: LeastSquares + ?Sized> Problem for Subspace<'_, P> {
    fn bounds(&self) -> &Bounds {
        &self.bounds
    }
    fn cost(&self, z: &[f64]) -> f64 {
        self.inner.cost(&self.point(z))
    }
}

impl<P: LeastSquares + ?Sized> LeastSquares for Subspace<'_, P> {
    fn residuals(&self, z: &[f64]) -> Vec<f64> {
        self.inner.residuals(&self.point(z))
    }
    fn jacobian(&self, z: &[f64]) -> DMatrix<f64> {
        self.inner.jacobian(&self.point(z)) * &self.basis
    }
    fn residual_count(&self, z: &[f64]) -> usize {
        self.inner.residual_count(&self.point(z))
    }
    /// The inner problem's normal equations (blockwise, when it accumulates them so) projected on the
    /// basis `B`: `BᵀJᵀJB`, `BᵀJᵀr`.
    fn normal_equations(&self, z: &[f64]) -> NormalEquations {
        let ne = self.inner.normal_equations(&self.point(z));
        NormalEquations {
            jtj: self.basis.tr_mul(&ne.jtj) * &self.basis,
            jtr: self.basis.tr_mul(&ne.jtr),
            rtr: ne.rtr,
            rows: ne.rows,
        }
    }
}
