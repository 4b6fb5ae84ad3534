//! `PreintegratedImu`: the measurement between two keyframes, its arrays, bias correction and
//! pickle state.
//!
//! Tangent order of every matrix: **[δφ, δv, δp]** (9) and **[δφ, δv, δp, δb_g, δb_a]** (15);
//! bias order **[b_g, b_a]**; the rotation error is on the right (`ΔR = ΔR° Exp(δφ)`), Δv
//! [m/s] and Δp [m] are in body frame i and exclude gravity (Forster et al. 2017, eq. 33).

use crate::convert::{mat_py, svec_py, vec_py};
use crate::errors::preint_err;
use crate::params::{PyBias, coriolis_name};
use numpy::{PyArray1, PyArray2};
use preint::PreintegratedImu;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// A preintegrated IMU measurement between keyframes i and j (Rust `PreintegratedImu`).
/// Matrices are numpy arrays in tangent order [δφ, δv, δp] (`TANGENT_ORDER`), 15×15 ones in
/// [δφ, δv, δp, δb_g, δb_a] (`TANGENT_ORDER_15`); pickles exactly.
#[pyclass(name = "PreintegratedImu", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyMeasurement(pub PreintegratedImu);

#[pymethods]
impl PyMeasurement {
    /// Tangent order of `cov`, `delta_error` and the rows of `bias_jacobians`.
    #[classattr]
    const TANGENT_ORDER: (&'static str, &'static str, &'static str) = ("dphi", "dv", "dp");
    /// Tangent order of `cov15` and `residual_cov15()`.
    #[classattr]
    const TANGENT_ORDER_15: (
        &'static str,
        &'static str,
        &'static str,
        &'static str,
        &'static str,
    ) = ("dphi", "dv", "dp", "dbg", "dba");

    /// Keyframe i time [ns].
    #[getter]
    fn t_i_ns(&self) -> i64 {
        self.0.t_i_ns
    }
    /// Keyframe j time [ns].
    #[getter]
    fn t_j_ns(&self) -> i64 {
        self.0.t_j_ns
    }
    /// Δt = t_j − t_i [s].
    #[getter]
    fn delta_t(&self) -> f64 {
        self.0.delta_t
    }
    /// ΔR_ij (3×3 rotation matrix, body j → body i).
    #[getter(delta_R)]
    fn delta_r<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, self.0.delta_r.matrix())
    }
    /// Log(ΔR_ij) [rad] (rotation vector).
    #[getter]
    fn delta_rotvec<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.delta_r.log())
    }
    /// Δv_ij [m/s] in body frame i, gravity excluded.
    #[getter]
    fn delta_v<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.delta_v)
    }
    /// Δp_ij [m] in body frame i, gravity excluded.
    #[getter]
    fn delta_p<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.delta_p)
    }
    /// 9×9 covariance of [δφ, δv, δp] [rad², (m/s)², m²] (white noise, plus integration noise
    /// if set).
    #[getter]
    fn cov<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.cov)
    }
    /// 15×15 covariance of [δφ, δv, δp, δb_g, δb_a] with the bias random walk over the window
    /// (measured ⊖ true deltas; weight a factor residual with `residual_cov15()`).
    #[getter]
    fn cov15<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.cov15)
    }
    /// Covariance of the combined factor's residual at the true states: `cov15` with its
    /// delta–bias blocks negated.
    fn residual_cov15<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.residual_cov15())
    }
    /// 9×6 bias Jacobians `∂[ΔR, Δv, Δp]/∂[b_g, b_a]` at `bias_hat` (rows [δφ, δv, δp],
    /// columns [b_g, b_a]; the ΔR–b_a block is zero).
    #[getter]
    fn bias_jacobians<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.jac.as_matrix())
    }
    /// The bias estimate the samples were integrated with.
    #[getter]
    fn bias_hat(&self) -> PyBias {
        PyBias(self.0.bias_hat)
    }
    /// Gravity [m/s²] in the world frame.
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.gravity)
    }
    /// Navigation-frame rotation rate [rad/s] that prediction and factors use, or None.
    #[getter]
    fn omega_coriolis<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.0.omega_coriolis.as_ref().map(|w| vec_py(py, w))
    }
    /// Coriolis mode: "exact", "first" or "second".
    #[getter]
    fn coriolis(&self) -> &'static str {
        coriolis_name(self.0.coriolis)
    }
    /// How `corrected` (and so `predict` and the factors) applies a new bias: "additive"
    /// (Forster eq. 44) or "group" (right-applied on SE₂(3), GTSAM's Galilean backend).
    #[getter]
    fn bias_correction(&self) -> &'static str {
        self.0.bias_correction.name()
    }
    /// What was computed: "deltas", "covariance" or "combined".
    #[getter]
    fn level(&self) -> &'static str {
        match self.0.level {
            preint::Level::Deltas => "deltas",
            preint::Level::Covariance => "covariance",
            preint::Level::Combined => "combined",
        }
    }

    /// Deltas corrected to first order for the bias `bias`, additively (Forster eq. 44) or on
    /// the group (`bias_correction`): `(ΔR 3×3, Δv [m/s], Δp [m])`. At level "deltas" (no bias
    /// Jacobians) a `bias` other than `bias_hat` raises `PreintError` (kind `NoBiasJacobians`).
    #[allow(clippy::type_complexity)]
    fn corrected<'py>(
        &self,
        py: Python<'py>,
        bias: PyRef<'_, PyBias>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let (r, v, p) = self.0.try_corrected(&bias.0).map_err(preint_err)?;
        Ok((mat_py(py, r.matrix()), vec_py(py, &v), vec_py(py, &p)))
    }

    /// This measurement's deltas minus `reference`'s in [δφ, δv, δp]:
    /// `[Log(ΔR_refᵀ ΔR), Δv − Δv_ref, Δp − Δp_ref]` (the error `cov` describes when
    /// `reference` is the noise-free preintegration).
    fn delta_error<'py>(
        &self,
        py: Python<'py>,
        reference: PyRef<'_, Self>,
    ) -> Bound<'py, PyArray1<f64>> {
        svec_py(py, &self.0.delta_error(&reference.0))
    }

    fn __repr__(&self) -> String {
        let m = &self.0;
        let r = m.delta_r.log();
        format!(
            "PreintegratedImu(t_i_ns={}, t_j_ns={}, delta_rotvec=[{:?}, {:?}, {:?}] rad, delta_v=[{:?}, {:?}, {:?}] m/s, delta_p=[{:?}, {:?}, {:?}] m, level={:?}, tangent order [dphi, dv, dp])",
            m.t_i_ns,
            m.t_j_ns,
            r.x,
            r.y,
            r.z,
            m.delta_v.x,
            m.delta_v.y,
            m.delta_v.z,
            m.delta_p.x,
            m.delta_p.y,
            m.delta_p.z,
            self.level()
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Py<PyAny>, (Bound<'py, PyBytes>,))> {
        let ctor = py.get_type::<Self>().getattr("_from_state")?.unbind();
        Ok((
            ctor,
            (PyBytes::new(py, &crate::state::encode_measurement(&self.0)),),
        ))
    }

    /// Inverse of `__reduce__`'s state (pickle).
    #[staticmethod]
    fn _from_state(state: &[u8]) -> PyResult<Self> {
        crate::state::decode_measurement(state).map(Self)
    }
}
