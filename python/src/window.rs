//! Inside a window: the deltas and states at any times between the keyframes (`deltas_at`,
//! `states_at`, `deskew_points`: what lidar deskewing needs) and the embedded truncation-error estimate of a window
//! (`truncation_estimate`, `inflate`), and the second-order covariance term of a long window
//! (`second_order_covariance`, `add_covariance`).

use crate::convert::{SampleArrays, WINDOW_MARGIN, svec_py};
use crate::errors::{preint_err, shape_err};
use crate::measurement::PyMeasurement;
use crate::navstate::PyNavState;
use crate::params::{PyBias, PyParams, bias_or_zero};
use nalgebra::{SVector, Vector3};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use preint::deskew::{DeltasAt, DeskewTarget};
use preint::truncation::TruncationEstimate;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The deltas from `t_i_ns` to each of `times_ns` (int64[K], non-decreasing, inside
/// `[t_i_ns, t_j_ns]`): those `preintegrate` gives over `[t_i_ns, t]` (equal to round-off),
/// in one pass over the samples.
/// Returns a dict of numpy arrays: `t_ns` int64[K], `delta_t` [s] float64[K], `delta_R`
/// float64[K, 3, 3] (body at t → body at t_i), `delta_v` [m/s] and `delta_p` [m] float64[K, 3]
/// (body frame i, gravity excluded).
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, t_i_ns, t_j_ns, times_ns, bias=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn deltas_at<'py>(
    py: Python<'py>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    t_i_ns: i64,
    t_j_ns: i64,
    times_ns: &Bound<'py, PyAny>,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<Bound<'py, PyDict>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let q = times("times_ns", times_ns)?;
    let (v, p, b, w) = (
        arrays.views(),
        &params.0,
        bias_or_zero(bias),
        (t_i_ns, t_j_ns),
    );
    let d = py
        .detach(|| {
            v.in_window(w, WINDOW_MARGIN, |s| {
                preint::deskew::deltas_at(p, &b, s, w, &q)
            })
        })
        .map_err(preint_err)?;
    let out = PyDict::new(py);
    put_deltas(py, &out, &d)?;
    Ok(out)
}

/// Fills `out` with the arrays of `d` (`t_ns`, `delta_t`, `delta_R`, `delta_v`, `delta_p`).
fn put_deltas<'py>(py: Python<'py>, out: &Bound<'py, PyDict>, d: &[DeltasAt]) -> PyResult<()> {
    let k = d.len();
    out.set_item(
        "t_ns",
        Array1::from_iter(d.iter().map(|x| x.t_ns)).into_pyarray(py),
    )?;
    out.set_item(
        "delta_t",
        Array1::from_iter(d.iter().map(|x| x.delta_t)).into_pyarray(py),
    )?;
    out.set_item(
        "delta_R",
        Array3::from_shape_fn((k, 3, 3), |(n, i, j)| d[n].delta_r.matrix()[(i, j)])
            .into_pyarray(py),
    )?;
    out.set_item(
        "delta_v",
        Array2::from_shape_fn((k, 3), |(n, i)| d[n].delta_v[i]).into_pyarray(py),
    )?;
    out.set_item(
        "delta_p",
        Array2::from_shape_fn((k, 3), |(n, i)| d[n].delta_p[i]).into_pyarray(py),
    )?;
    Ok(())
}

/// `(error, method, companion_cov)` as Python receives them.
type Estimate<'py> = (
    Bound<'py, PyArray1<f64>>,
    &'static str,
    Bound<'py, PyArray2<f64>>,
);

/// The estimated truncation (discretisation) error of `pim`, the window
/// `[pim.t_i_ns, pim.t_j_ns]` of the arrays preintegrated with `params` and `bias`:
/// `(error, method, companion_cov)` with `error` = scheme ⊖ exact deltas, float64[9] in
/// [δφ rad, δv m/s, δp m] (the chart of `PreintegratedImu.delta_error`), `method` "hermite4
/// companion" (euler, midpoint, galilean) or "richardson 2h" (hermite4), and `companion_cov`
/// float64[9, 9] the companion's covariance (for hermite4 `pim.cov`), which `inflate` weights
/// with. `bias` defaults to `pim.bias_hat`; another bias raises `PreintError` (the window must
/// be re-integrated with the bias `pim` was integrated with).
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, pim, bias=None))]
pub(crate) fn truncation_estimate<'py>(
    py: Python<'py>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    pim: PyRef<'_, PyMeasurement>,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<Estimate<'py>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let b = bias.map_or(pim.0.bias_hat, |b| b.0);
    if b != pim.0.bias_hat {
        return Err(crate::checks::invalid(format!(
            "bias: truncation_estimate re-integrates the window of pim, which was integrated at \
             {}, not {}; omit bias (or give pim.bias_hat)",
            crate::checks::show_bias(&pim.0.bias_hat),
            crate::checks::show_bias(&b)
        )));
    }
    let (v, p, m) = (arrays.views(), &params.0, &pim.0);
    // Twice the margin: the Richardson companion integrates every other sample, whose window
    // reads as many samples of its own beyond the edges; the other companion's interpolating
    // stencils read `CONTEXT_SAMPLES`.
    let margin = (2 * WINDOW_MARGIN).max(preint::truncation::CONTEXT_SAMPLES);
    let e = py
        .detach(|| {
            v.in_window((m.t_i_ns, m.t_j_ns), margin, |s| {
                preint::truncation::estimate(p, &b, s, m)
            })
        })
        .map_err(preint_err)?;
    let c = Array2::from_shape_fn((9, 9), |(i, j)| e.companion_cov[(i, j)]).into_pyarray(py);
    Ok((svec_py(py, &e.error), e.method, c))
}

/// `pim` weighted with a truncation-error estimate (Rust `truncation::inflate`): its 9×9
/// covariance becomes `companion_cov + u uᵀ` (the 9×9 block of its 15×15 one changes by the
/// same amount), with `u` the
/// estimate `error` (float64[9] in [δφ, δv, δp], `truncation_estimate`) as the factor of residual
/// mode `residual` sees it (Rust `truncation::offset_in_chart`): `error` itself for "component",
/// its exact image in the SE₂(3) chart for "logmap" (the default, as the factors'), and
/// `companion_cov` the companion's covariance `truncation_estimate` returns (default
/// `pim.cov`). A factor of that mode weighted by the result expects its discretisation error.
#[pyfunction]
#[pyo3(signature = (pim, error, residual="logmap", companion_cov=None))]
pub(crate) fn inflate(
    pim: PyRef<'_, PyMeasurement>,
    error: &Bound<'_, PyAny>,
    residual: &str,
    companion_cov: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMeasurement> {
    let mode = crate::factor::mode_from(residual)?;
    let e: Vec<f64> = error
        .extract()
        .map_err(|_| shape_err("error: expected nine numbers [dphi, dv, dp]"))?;
    if e.len() != 9 || !e.iter().all(|x| x.is_finite()) {
        return Err(shape_err(
            "error: expected nine finite numbers [dphi, dv, dp]",
        ));
    }
    let companion_cov = match companion_cov {
        None => pim.0.cov,
        Some(c) => symmetric9("companion_cov", c)?,
    };
    let est = TruncationEstimate {
        error: SVector::<f64, 9>::from_column_slice(&e),
        method: "given",
        companion_cov,
    };
    Ok(PyMeasurement(preint::truncation::inflate(
        &pim.0, &est, mode,
    )))
}

/// The argument `name` as a finite symmetric 9×9 matrix.
fn symmetric9(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<nalgebra::SMatrix<f64, 9, 9>> {
    let t: Vec<Vec<f64>> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected a 9×9 array")))?;
    if t.len() != 9 || t.iter().any(|r| r.len() != 9) {
        return Err(shape_err(format!("{name}: expected a 9×9 array")));
    }
    let m = nalgebra::SMatrix::<f64, 9, 9>::from_fn(|i, j| t[i][j]);
    if !m.iter().all(|x| x.is_finite()) || (m - m.transpose()).amax() > 1e-12 * m.amax() {
        return Err(shape_err(format!(
            "{name}: expected a finite symmetric 9×9 array"
        )));
    }
    Ok(m)
}

/// The second-order covariance term of `pim`'s SE₂(3) error (Rust `preint::second_order`),
/// float64[9, 9] in [δφ rad, δv m/s, δp m]: what the first-order covariance misses over long
/// windows with noisy gyroscopes. `pim` is the window `[pim.t_i_ns, pim.t_j_ns]` of the arrays
/// preintegrated with `params`; add the term with `add_covariance`. The mean χ² at the true
/// states it accounts for is `trace(inv(pim.cov) @ term)`.
#[pyfunction]
pub(crate) fn second_order_covariance<'py>(
    py: Python<'py>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    pim: PyRef<'_, PyMeasurement>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let (v, p, m) = (arrays.views(), &params.0, &pim.0);
    let c = py
        .detach(|| {
            v.in_window((m.t_i_ns, m.t_j_ns), WINDOW_MARGIN, |s| {
                preint::second_order::covariance(p, s, m)
            })
        })
        .map_err(preint_err)?;
    Ok(Array2::from_shape_fn((9, 9), |(i, j)| c[(i, j)]).into_pyarray(py))
}

/// `pim` with the symmetric float64[9, 9] `term` ([δφ, δv, δp], e.g. `second_order_covariance`)
/// added to its 9×9 covariance and to the 9×9 block of its 15×15 one.
#[pyfunction]
pub(crate) fn add_covariance(
    pim: PyRef<'_, PyMeasurement>,
    term: &Bound<'_, PyAny>,
) -> PyResult<PyMeasurement> {
    let m = symmetric9("term", term)?;
    Ok(PyMeasurement(preint::second_order::inflate(&pim.0, &m)))
}

/// The int64 query times argument `name` as a vector.
fn times(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<i64>> {
    let a = obj
        .cast::<PyArray1<i64>>()
        .map_err(|_| shape_err(format!("{name}: expected a 1-D numpy array of dtype int64")))?
        .readonly();
    Ok(a.as_array().to_vec())
}

/// The deltas and the predicted body state (world frame; gravity and `omega_coriolis`
/// applied as in `predict`) at each of `times_ns` (int64[K], non-decreasing, inside the
/// window), from `state_i`, the state at `t_i_ns`. Returns the dict of `deltas_at` plus
/// `rotation` float64[K, 3, 3] (body → world), `position` [m] and `velocity` [m/s]
/// float64[K, 3].
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, t_i_ns, t_j_ns, state_i, times_ns, bias=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn states_at<'py>(
    py: Python<'py>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    t_i_ns: i64,
    t_j_ns: i64,
    state_i: PyRef<'_, PyNavState>,
    times_ns: &Bound<'py, PyAny>,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<Bound<'py, PyDict>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let q = times("times_ns", times_ns)?;
    let (v, p, b, x, w) = (
        arrays.views(),
        &params.0,
        bias_or_zero(bias),
        state_i.0,
        (t_i_ns, t_j_ns),
    );
    let at = py
        .detach(|| {
            v.in_window(w, WINDOW_MARGIN, |s| {
                preint::deskew::states_at(p, &b, s, w, &x, &q)
            })
        })
        .map_err(preint_err)?;
    let k = at.len();
    let out = PyDict::new(py);
    let d: Vec<_> = at.iter().map(|a| a.deltas).collect();
    put_deltas(py, &out, &d)?;
    out.set_item(
        "rotation",
        Array3::from_shape_fn((k, 3, 3), |(n, i, j)| at[n].state.r.matrix()[(i, j)])
            .into_pyarray(py),
    )?;
    out.set_item(
        "position",
        Array2::from_shape_fn((k, 3), |(n, i)| at[n].state.p[i]).into_pyarray(py),
    )?;
    out.set_item(
        "velocity",
        Array2::from_shape_fn((k, 3), |(n, i)| at[n].state.v[i]).into_pyarray(py),
    )?;
    Ok(out)
}

/// Deskews a lidar sweep: each point `points[m]` [m], in the body frame at its own time
/// `points_t_ns[m]` (non-decreasing, inside the window), expressed in the body frame at
/// `t_i_ns` (`target="start"`) or `t_j_ns` (`target="end"`), with the states of `states_at`
/// from `state_i` (its attitude and velocity matter, its position does not). Returns
/// float64[M, 3] [m].
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, t_i_ns, t_j_ns, state_i, points_t_ns, points, target="start", bias=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn deskew_points<'py>(
    py: Python<'py>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    t_i_ns: i64,
    t_j_ns: i64,
    state_i: PyRef<'_, PyNavState>,
    points_t_ns: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    target: &str,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let tq = times("points_t_ns", points_t_ns)?;
    let pts = points
        .cast::<PyArray2<f64>>()
        .map_err(|_| shape_err("points: expected a numpy array of dtype float64 and shape (M, 3)"))?
        .readonly();
    if pts.shape()[1] != 3 || pts.shape()[0] != tq.len() {
        return Err(shape_err(format!(
            "points: expected shape ({}, 3), got ({}, {})",
            tq.len(),
            pts.shape()[0],
            pts.shape()[1]
        )));
    }
    let pts = pts.as_array();
    let pairs: Vec<(i64, Vector3<f64>)> = tq
        .iter()
        .enumerate()
        .map(|(m, &t)| (t, Vector3::new(pts[(m, 0)], pts[(m, 1)], pts[(m, 2)])))
        .collect();
    let target = match target {
        "start" => DeskewTarget::Start,
        "end" => DeskewTarget::End,
        _ => {
            return Err(shape_err(format!(
                "target {target:?}: use \"start\" or \"end\""
            )));
        }
    };
    let (v, p, b, x, w) = (
        arrays.views(),
        &params.0,
        bias_or_zero(bias),
        state_i.0,
        (t_i_ns, t_j_ns),
    );
    let out = py
        .detach(|| {
            v.in_window(w, WINDOW_MARGIN, |s| {
                preint::deskew::deskew_points(p, &b, s, w, &x, &pairs, target)
            })
        })
        .map_err(preint_err)?;
    Ok(Array2::from_shape_fn((out.len(), 3), |(n, i)| out[n][i]).into_pyarray(py))
}
