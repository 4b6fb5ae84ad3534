//! numpy ↔ nalgebra conversions and the checks that give a wrong shape a typed error naming
//! the argument.

use crate::errors::shape_err;
use nalgebra::{Matrix3, SMatrix, Vector3};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use preint::ImuSample;
use pyo3::prelude::*;

/// A 3-vector from any sequence of three numbers (list, tuple, numpy array).
pub(crate) fn vec3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vector3<f64>> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected three numbers")))?;
    if v.len() != 3 {
        return Err(shape_err(format!(
            "{name}: expected three numbers, got {}",
            v.len()
        )));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// An `R×C` matrix from nested sequences (a list of rows or a 2-D numpy array).
pub(crate) fn matrix<const R: usize, const C: usize>(
    name: &str,
    obj: &Bound<'_, PyAny>,
) -> PyResult<SMatrix<f64, R, C>> {
    let rows: Vec<Vec<f64>> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected a {R}×{C} matrix of numbers")))?;
    if rows.len() != R || rows.iter().any(|r| r.len() != C) {
        return Err(shape_err(format!("{name}: expected a {R}×{C} matrix")));
    }
    Ok(SMatrix::<f64, R, C>::from_fn(|i, j| rows[i][j]))
}

/// A 3×3 covariance: a 3×3 matrix, or a number `s` meaning `s·I`.
pub(crate) fn cov3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<f64>> {
    if let Ok(s) = obj.extract::<f64>() {
        return Ok(Matrix3::identity() * s);
    }
    matrix::<3, 3>(name, obj)
}

/// A matrix as a new `R×C` numpy array (row-major).
pub(crate) fn mat_py<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// A 3-vector as a new numpy array.
pub(crate) fn vec_py<'py>(py: Python<'py>, v: &Vector3<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from_iter(v.iter().copied()).into_pyarray(py)
}

/// An `N`-vector as a new numpy array.
pub(crate) fn svec_py<'py, const N: usize>(
    py: Python<'py>,
    v: &SMatrix<f64, N, 1>,
) -> Bound<'py, PyArray1<f64>> {
    Array1::from_iter(v.iter().copied()).into_pyarray(py)
}

/// The samples of the arrays `t_ns` (int64[N], nanoseconds), `gyro` (float64[N, 3], rad/s)
/// and `acc` (float64[N, 3], m/s²). Shapes and dtypes are checked here, values (finite,
/// increasing timestamps) by the preintegrator, which names the sample.
pub(crate) fn samples(
    t_ns: &Bound<'_, PyAny>,
    gyro: &Bound<'_, PyAny>,
    acc: &Bound<'_, PyAny>,
) -> PyResult<Vec<ImuSample>> {
    let t = t_ns
        .cast::<PyArray1<i64>>()
        .map_err(|_| shape_err("t_ns: expected a 1-D numpy array of dtype int64 (nanoseconds)"))?;
    let g = rows3("gyro", gyro)?;
    let a = rows3("acc", acc)?;
    let t = t.readonly();
    let (g, a) = (g.readonly(), a.readonly());
    let n = t.len();
    if g.shape()[0] != n || a.shape()[0] != n {
        return Err(shape_err(format!(
            "t_ns, gyro and acc must have the same length: {n}, {}, {}",
            g.shape()[0],
            a.shape()[0]
        )));
    }
    let (t, g, a) = (t.as_array(), g.as_array(), a.as_array());
    Ok((0..n)
        .map(|k| {
            ImuSample::new(
                t[k],
                Vector3::new(g[(k, 0)], g[(k, 1)], g[(k, 2)]),
                Vector3::new(a[(k, 0)], a[(k, 1)], a[(k, 2)]),
            )
        })
        .collect())
}

/// An `N×3` float64 array argument.
fn rows3<'a, 'py>(
    name: &str,
    obj: &'a Bound<'py, PyAny>,
) -> PyResult<&'a Bound<'py, PyArray2<f64>>> {
    let arr = obj.cast::<PyArray2<f64>>().map_err(|_| {
        shape_err(format!(
            "{name}: expected a numpy array of dtype float64 and shape (N, 3)"
        ))
    })?;
    if arr.shape()[1] != 3 {
        return Err(shape_err(format!(
            "{name}: expected shape (N, 3), got ({}, {})",
            arr.shape()[0],
            arr.shape()[1]
        )));
    }
    Ok(arr)
}
