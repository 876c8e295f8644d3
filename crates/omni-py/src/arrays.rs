//! numpy in and out: any array-like of numbers in (lists, int arrays, Fortran order; copied once), float64
//! arrays out. Shape errors are `ValueError`s that name the argument and show the shape Python-style.

use crate::errors::value_error;
use numpy::ndarray::{Array2, ArrayD};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLikeDyn, PyUntypedArrayMethods};
use omni_kin::StampedPose;
use pyo3::prelude::*;

/// `(5,)`, `(5, 3)`: a shape as Python prints it.
pub fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// A float64 copy of an array-like with `ndim` dimensions; `expected` is the shape for messages, e.g.
/// `(N, W)`.
pub fn float_array(obj: &Bound<'_, PyAny>, name: &str, ndim: usize, expected: &str) -> PyResult<ArrayD<f64>> {
    let a: PyArrayLikeDyn<'_, f64, AllowTypeChange> = obj
        .extract()
        .map_err(|e| value_error(format!("{name} must be an array of numbers with shape {expected} ({e})")))?;
    if a.ndim() != ndim {
        return Err(value_error(format!("{name} must have shape {expected}, got {}", shape_text(a.shape()))));
    }
    Ok(a.as_array().to_owned())
}

/// A 1-D float64 copy.
pub fn vector(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    Ok(float_array(obj, name, 1, "(N,)")?.into_iter().collect())
}

/// A row-major 2-D float64 copy and its shape.
pub fn matrix(obj: &Bound<'_, PyAny>, name: &str, expected: &str) -> PyResult<(Vec<f64>, usize, usize)> {
    let a = float_array(obj, name, 2, expected)?;
    let (r, c) = (a.shape()[0], a.shape()[1]);
    // `iter` walks in logical (row-major) order whatever the memory layout.
    Ok((a.iter().copied().collect(), r, c))
}

/// A `(rows, cols)` float64 array from row-major data.
pub fn to_matrix(py: Python<'_>, rows: usize, cols: usize, data: Vec<f64>) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let a = Array2::from_shape_vec((rows, cols), data)
        .map_err(|e| value_error(format!("internal shape error {rows}×{cols}: {e}")))?;
    Ok(a.into_pyarray(py))
}

/// A 1-D float64 array.
pub fn to_vector<'py>(py: Python<'py>, data: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    data.into_pyarray(py)
}

/// Stamped poses as an `(M, 4)` array: t_s, x_m, y_m, theta_rad.
pub fn poses_to_matrix<'py>(py: Python<'py>, poses: &[StampedPose]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let data = poses.iter().flat_map(|p| [p.t_s, p.pose.x_m, p.pose.y_m, p.pose.theta_rad]).collect();
    to_matrix(py, poses.len(), 4, data)
}

/// An `(M, 4)` array (t_s, x_m, y_m, theta_rad) as stamped poses.
pub fn matrix_to_poses(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<StampedPose>> {
    let (data, rows, cols) = matrix(obj, name, "(M, 4): t_s, x_m, y_m, theta_rad")?;
    if cols != 4 {
        return Err(value_error(format!(
            "{name} must have shape (M, 4): t_s, x_m, y_m, theta_rad, got {}",
            shape_text(&[rows, cols])
        )));
    }
    Ok(data.chunks_exact(4).map(|c| StampedPose { t_s: c[0], pose: omni_kin::Pose2::new(c[1], c[2], c[3]) }).collect())
}
