//! The preintegrator fed from numpy arrays (one call, no per-sample Python loop) or sample by
//! sample, the one-call window functions and `merge`.
//!
//! Arrays: `t_ns` int64[N] (nanoseconds), `gyro` float64[N, 3] [rad/s], `acc` float64[N, 3]
//! [m/s²], sensor frame. The GIL is released while Rust integrates.

use crate::convert::{SampleArrays, SampleViews, WINDOW_MARGIN, vec3, with_scratch};
use crate::errors::{Class, preint_err, raise, shape_err};
use crate::measurement::PyMeasurement;
use crate::params::{PyBias, PyParams, bias_or_zero};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use preint::{ImuBias, ImuSample, PreintError, PreintParams, PreintegratedImu, Preintegrator};
use pyo3::prelude::*;

/// Accumulates samples into a measurement (Rust `Preintegrator`):
/// `Preintegrator(params, bias=None, capacity=0)`; `integrate(t_ns, gyro, acc)` adds one
/// sample, `integrate_arrays(t_ns, gyro, acc)` many in one call; `finish()` returns the
/// `PreintegratedImu` over [first sample, last sample]. A rejected sample raises
/// `PreintError` naming it and leaves the preintegrator unchanged. `capacity` (samples stored
/// without reallocating) is at most the readers' bound of 50 million samples.
#[pyclass(name = "Preintegrator", module = "preint")]
pub(crate) struct PyPreintegrator(Preintegrator);

#[pymethods]
impl PyPreintegrator {
    #[new]
    #[pyo3(signature = (params, bias=None, capacity=0))]
    fn new(
        params: PyRef<'_, PyParams>,
        bias: Option<PyRef<'_, PyBias>>,
        capacity: usize,
    ) -> PyResult<Self> {
        let most = preint_io::reader::DEFAULT_MAX_SAMPLES;
        if capacity > most {
            return Err(crate::checks::invalid(format!(
                "capacity must be at most {most} samples (the readers' bound), got {capacity}; \
                 the stored samples grow as needed beyond it"
            )));
        }
        Preintegrator::with_capacity(params.0.clone(), bias_or_zero(bias), capacity)
            .map(Self)
            .map_err(preint_err)
    }

    /// Adds one sample: time [ns], gyro [rad/s] and accelerometer [m/s²] (three numbers each).
    fn integrate(
        &mut self,
        t_ns: i64,
        gyro: &Bound<'_, PyAny>,
        acc: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let s = ImuSample::new(t_ns, vec3("gyro", gyro)?, vec3("acc", acc)?);
        self.0.integrate(&s).map_err(preint_err)
    }

    /// Adds the samples of the arrays in order (see the module docs); stops at the first
    /// invalid one, raising `PreintError` with its index, the samples before it integrated.
    fn integrate_arrays(
        &mut self,
        py: Python<'_>,
        t_ns: &Bound<'_, PyAny>,
        gyro: &Bound<'_, PyAny>,
        acc: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let arrays = SampleArrays::new(t_ns, gyro, acc)?;
        let (v, inner) = (arrays.views(), &mut self.0);
        // Converted in cache-sized chunks: no copy of the whole stream is made.
        py.detach(|| {
            with_scratch(|buf| {
                let mut start = 0;
                while start < v.len() {
                    let end = (start + CHUNK).min(v.len());
                    buf.clear();
                    v.fill(start..end, buf);
                    inner.integrate_slice(buf)?;
                    start = end;
                }
                Ok(())
            })
        })
        .map_err(preint_err)
    }

    /// The measurement over [first sample, last sample] (more samples may be added after).
    fn finish(&self, py: Python<'_>) -> PyResult<PyMeasurement> {
        let inner = &self.0;
        py.detach(|| inner.finish())
            .map(PyMeasurement)
            .map_err(preint_err)
    }

    /// The measurement for a new bias estimate: first-order corrected, or re-integrated from
    /// the stored samples when the change exceeds the thresholds. Returns
    /// `(PreintegratedImu, reintegrated: bool)`. At level "deltas" (no bias Jacobians) any
    /// change re-integrates, and without `keep_samples` raises `PreintError` (kind
    /// `NoBiasJacobians`).
    fn measurement_for_bias(
        &self,
        py: Python<'_>,
        bias: PyRef<'_, PyBias>,
    ) -> PyResult<(PyMeasurement, bool)> {
        let (inner, b) = (&self.0, bias.0);
        let u = py
            .detach(|| inner.measurement_for_bias(&b))
            .map_err(preint_err)?;
        Ok((PyMeasurement(u.measurement), u.reintegrated))
    }

    /// Re-integrates the stored samples with the bias estimate `bias`.
    fn reintegrate(&mut self, py: Python<'_>, bias: PyRef<'_, PyBias>) -> PyResult<()> {
        let (inner, b) = (&mut self.0, bias.0);
        py.detach(|| inner.reintegrate(&b)).map_err(preint_err)
    }

    /// The parameters (a copy).
    #[getter]
    fn params(&self) -> PyParams {
        PyParams(self.0.params().clone())
    }

    /// The bias estimate samples are integrated with.
    #[getter]
    fn bias_hat(&self) -> PyBias {
        PyBias(*self.0.bias_hat())
    }

    fn __len__(&self) -> usize {
        self.0.len()
    }
}

/// Samples converted per `integrate_slice` call of `integrate_arrays` (229 KiB).
const CHUNK: usize = 4096;

/// The window `[t_i_ns, t_j_ns]` of the arrays: `preint::preintegrate` on its samples
/// ([`SampleViews::in_window`]).
fn window(
    p: &PreintParams,
    b: &ImuBias,
    v: &SampleViews<'_>,
    (t_i_ns, t_j_ns): (i64, i64),
) -> Result<PreintegratedImu, PreintError> {
    v.in_window((t_i_ns, t_j_ns), WINDOW_MARGIN, |s| {
        preint::preintegrate(p, b, s, t_i_ns, t_j_ns)
    })
}

/// The measurement over the keyframe window `[t_i_ns, t_j_ns]` of a time-ordered stream
/// (boundary samples interpolated when a keyframe falls between samples).
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, t_i_ns, t_j_ns, bias=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn preintegrate(
    py: Python<'_>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'_, PyAny>,
    gyro: &Bound<'_, PyAny>,
    acc: &Bound<'_, PyAny>,
    t_i_ns: i64,
    t_j_ns: i64,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<PyMeasurement> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let (v, p, b) = (arrays.views(), &params.0, bias_or_zero(bias));
    py.detach(|| window(p, &b, &v, (t_i_ns, t_j_ns)))
        .map(PyMeasurement)
        .map_err(preint_err)
}

/// One measurement per pair of consecutive keyframes `keyframes_ns` (int64[K], increasing)
/// over one stream, in one call: a list of K − 1 `PreintegratedImu`.
#[pyfunction]
#[pyo3(signature = (params, t_ns, gyro, acc, keyframes_ns, bias=None))]
pub(crate) fn preintegrate_windows(
    py: Python<'_>,
    params: PyRef<'_, PyParams>,
    t_ns: &Bound<'_, PyAny>,
    gyro: &Bound<'_, PyAny>,
    acc: &Bound<'_, PyAny>,
    keyframes_ns: &Bound<'_, PyAny>,
    bias: Option<PyRef<'_, PyBias>>,
) -> PyResult<Vec<PyMeasurement>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let k = keyframes_ns
        .cast::<PyArray1<i64>>()
        .map_err(|_| shape_err("keyframes_ns: expected a 1-D numpy array of dtype int64"))?
        .readonly();
    if k.len() < 2 {
        return Err(shape_err("keyframes_ns: at least two keyframes are needed"));
    }
    let k = k.as_array().to_vec();
    let (v, p, b) = (arrays.views(), &params.0, bias_or_zero(bias));
    // Each window converts only its own samples, into one reused buffer.
    let out = py.detach(|| {
        k.windows(2)
            .map(|w| window(p, &b, &v, (w[0], w[1])))
            .collect::<Result<Vec<_>, _>>()
    });
    Ok(out
        .map_err(preint_err)?
        .into_iter()
        .map(PyMeasurement)
        .collect())
}

/// The measurement over `[a.t_i, b.t_j]` from two consecutive measurements (exact when both
/// come from one stream, including the noise of the samples they share).
#[pyfunction]
pub(crate) fn merge(
    a: PyRef<'_, PyMeasurement>,
    b: PyRef<'_, PyMeasurement>,
) -> PyResult<PyMeasurement> {
    preint::merge(&a.0, &b.0)
        .map(PyMeasurement)
        .map_err(|e| raise(Class::Merge, e))
}
