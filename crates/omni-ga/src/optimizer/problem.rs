//! Problems: what the optimizers minimise. A [`Problem`] has bounds and a cost; a [`LeastSquares`] problem
//! also has residuals whose squared norm is monotone in the cost, and a Jacobian (central differences by
//! default).

pub use crate::optimizer::bounds::Bounds;
use nalgebra::{DMatrix, DVector, DVectorView};
use rayon::prelude::*;

/// A bounded minimisation problem.
pub trait Problem: Sync {
    /// The bounds; their length is the dimension.
    fn bounds(&self) -> &Bounds;
    /// The cost at `x`. Pure; may return `f64::INFINITY` where `x` is infeasible.
    fn cost(&self, x: &[f64]) -> f64;
    /// Costs of many points, evaluated in parallel and returned in order (the only parallel spot).
    fn costs(&self, xs: &[Vec<f64>]) -> Vec<f64> {
        xs.par_iter().map(|x| self.cost(x)).collect()
    }
}

/// A problem with residuals, for Levenberg–Marquardt.
pub trait LeastSquares: Problem {
    /// Residual vector at `x`; its squared norm must be monotone in [`Problem::cost`].
    fn residuals(&self, x: &[f64]) -> Vec<f64>;
    /// Jacobian of the residuals (rows: residuals, columns: parameters). Default: central differences
    /// ([`finite_difference_jacobian`]).
    fn jacobian(&self, x: &[f64]) -> DMatrix<f64> {
        finite_difference_jacobian(x, |y| self.residuals(y), |_| false)
    }
    /// Number of residuals at `x` (the rows of [`Self::jacobian`]). Default: `residuals(x).len()`;
    /// problems that know it without evaluating override it.
    fn residual_count(&self, x: &[f64]) -> usize {
        self.residuals(x).len()
    }
    /// The Gauss–Newton normal equations at `x`: `JᵀJ`, `Jᵀr` and `rᵀr`. Default: from
    /// [`Self::residuals`] and [`Self::jacobian`]; problems with many residuals override it to accumulate
    /// block by block without ever holding the whole Jacobian.
    fn normal_equations(&self, x: &[f64]) -> NormalEquations {
        NormalEquations::from_rows(&self.residuals(x), &self.jacobian(x))
    }
}

/// The Gauss–Newton normal equations of a least-squares problem at a point: with `r` the residuals and
/// `J` their Jacobian, `JᵀJ`, `Jᵀr` and `rᵀr`. Built by adding blocks of rows in a fixed order
/// ([`Self::add_rows`]), so sums are deterministic.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalEquations {
    /// `JᵀJ` (parameters × parameters).
    pub jtj: DMatrix<f64>,
    /// `Jᵀr` (one entry per parameter): the gradient of `½ rᵀr`.
    pub jtr: DVector<f64>,
    /// `rᵀr`: the sum of squared residuals.
    pub rtr: f64,
    /// Number of residuals added.
    pub rows: usize,
}

impl NormalEquations {
    /// Empty sums for `n` parameters.
    pub fn zeros(n: usize) -> Self {
        Self { jtj: DMatrix::zeros(n, n), jtr: DVector::zeros(n), rtr: 0.0, rows: 0 }
    }

    /// The normal equations of residuals `r` with Jacobian `j` (`r.len() × n`).
    pub fn from_rows(r: &[f64], j: &DMatrix<f64>) -> Self {
        let mut ne = Self::zeros(j.ncols());
        ne.add_rows(r, j);
        ne
    }

    /// Adds a block of rows: residuals `r` and their Jacobian `j` (`r.len() × n`).
    pub fn add_rows(&mut self, r: &[f64], j: &DMatrix<f64>) {
        debug_assert_eq!(r.len(), j.nrows());
        debug_assert_eq!(j.ncols(), self.jtr.len());
        let rv = DVectorView::from_slice(r, r.len());
        // `JᵀJ` by one matrix product: nalgebra hands a product of dynamic matrices to `matrixmultiply`'s
        // blocked kernel (beyond 5 columns), one pass over `J` where `tr_mul` takes a dot product per
        // entry, each a pass over all of J's rows. The copy `Jᵀ` costs one pass.
        self.jtj.gemm(1.0, &j.transpose(), j, 1.0);
        self.jtr += j.tr_mul(&rv);
        self.rtr += rv.dot(&rv);
        self.rows += r.len();
    }

    /// True when every sum is finite.
    pub fn is_finite(&self) -> bool {
        self.rtr.is_finite() && self.jtr.iter().all(|v| v.is_finite()) && self.jtj.iter().all(|v| v.is_finite())
    }
}

/// Finite-difference Jacobian of `residuals` at `x`: central differences with step
/// `h_i = 1e-6 · max(|x_i|, 1e-3)`, or forward differences for the parameters where `forward(i)` is true
/// (e.g. one sitting on the end of its physical range). Columns are computed in parallel and collected in
/// order (deterministic).
pub fn finite_difference_jacobian<R, F>(x: &[f64], residuals: R, forward: F) -> DMatrix<f64>
where
    R: Fn(&[f64]) -> Vec<f64> + Sync,
    F: Fn(usize) -> bool + Sync,
{
    let cols = finite_difference_columns(x, 0..x.len(), residuals, forward);
    let m = cols.first().map_or(0, Vec::len);
    DMatrix::from_fn(m, x.len(), |r, c| cols[c].get(r).copied().unwrap_or(f64::NAN))
}

/// The columns `cols` of [`finite_difference_jacobian`], in order.
pub fn finite_difference_columns<R, F>(
    x: &[f64],
    cols: std::ops::Range<usize>,
    residuals: R,
    forward: F,
) -> Vec<Vec<f64>>
where
    R: Fn(&[f64]) -> Vec<f64> + Sync,
    F: Fn(usize) -> bool + Sync,
{
    let r0 = if cols.clone().any(&forward) { Some(residuals(x)) } else { None };
    cols.into_par_iter()
        .map(|i| {
            let h = 1e-6 * x[i].abs().max(1e-3);
            let mut xp = x.to_vec();
            xp[i] += h;
            let rp = residuals(&xp);
            match (&r0, forward(i)) {
                (Some(r0), true) => rp.iter().zip(r0).map(|(a, b)| (a - b) / h).collect(),
                _ => {
                    let mut xm = x.to_vec();
                    xm[i] -= h;
                    let rm = residuals(&xm);
                    rp.iter().zip(&rm).map(|(a, b)| (a - b) / (2.0 * h)).collect()
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocked product gives `JᵀJ` as the column dot products do (to rounding), narrow and wide.
    #[test]
    fn normal_equations_match_the_column_dot_products() {
        for n in [3, 9, 16] {
            let m = 1_001;
            let j = DMatrix::from_fn(m, n, |r, c| ((r * 7 + c * 13) % 17) as f64 / 17.0 - 0.4 + 1e-3 * c as f64);
            let r: Vec<f64> = (0..m).map(|i| ((i * 5) % 11) as f64 / 11.0 - 0.5).collect();
            let mut ne = NormalEquations::from_rows(&r[..500], &j.rows(0, 500).into_owned());
            ne.add_rows(&r[500..], &j.rows(500, m - 500).into_owned());
            let want = j.tr_mul(&j);
            let scale = want.amax();
            assert!((&ne.jtj - &want).amax() < 1e-12 * scale, "n = {n}: {}", (&ne.jtj - &want).amax() / scale);
            let g = j.tr_mul(&DVector::from_column_slice(&r));
            assert!((&ne.jtr - &g).amax() < 1e-12 * g.amax(), "n = {n}");
            assert_eq!(ne.rows, m);
            assert!((ne.rtr - r.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-12 * ne.rtr);
        }
    }
}
