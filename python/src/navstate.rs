//! `NavState` (attitude, position, velocity) and `predict` (Rust `preint::NavState`,
//! `preint::predict`).
//!
//! Frames: `R` rotates body → world (`x_w = R x_b`); position [m] and velocity [m/s] of the body
//! origin in the world frame (z up). Tangent order of a state **[δφ, δp, δv]** (rad, m, m/s):
//! `R ← R Exp(δφ)` (right, body frame), `p ← p + R δp` (body frame), `v ← v + δv` (world
//! frame). This is GTSAM's `NavState` order (pose first), **not** the [δφ, δv, δp] order of
//! residuals and covariances.

use crate::checks;
use crate::convert::{mat_py, vec_py, vec3};
use crate::errors::shape_err;
use crate::measurement::PyMeasurement;
use crate::params::{PyBias, rotation};
use nalgebra::{Matrix3, Vector3};
use numpy::{PyArray1, PyArray2};
use preint::lie::SO3;
use preint::{ImuBias, NavState, NavTangent};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// A navigation state (Rust `NavState`): `NavState(rotation, position, velocity)` with
/// `rotation` R_wb (body → world; a 3×3 rotation matrix or a unit quaternion (w, x, y, z),
/// within 1e-6: `crate::params::rotation`), `position` [m] and `velocity` [m/s] of the body
/// origin in the world frame (z up), all finite.
///
/// Tangent order **[δφ, δp, δv]** (`TANGENT_ORDER`; rad, m, m/s) with
/// `R ← R·Exp(δφ)` (right, body frame), `p ← p + R·δp` (body frame), `v ← v + δv` (world
/// frame): Forster et al. 2017 Sec. VI-B, and to first order GTSAM's `Pose3` retract with
/// the `ImuFactor`'s world-frame velocity. Pickles exactly.
#[pyclass(name = "NavState", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyNavState(pub NavState);

/// A 9-vector from any sequence of nine numbers.
fn vec9(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<NavTangent> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected nine numbers")))?;
    if v.len() != 9 {
        return Err(shape_err(format!(
            "{name}: expected nine numbers [dphi, dp, dv], got {}",
            v.len()
        )));
    }
    Ok(NavTangent::from_column_slice(&v))
}

#[pymethods]
impl PyNavState {
    /// Tangent order of `retract`, `local` and the factors' `state_i` / `state_j` Jacobian
    /// columns.
    #[classattr]
    const TANGENT_ORDER: (&'static str, &'static str, &'static str) = ("dphi", "dp", "dv");

    #[new]
    #[pyo3(signature = (rotation=None, position=None, velocity=None))]
    fn new(
        rotation: Option<&Bound<'_, PyAny>>,
        position: Option<&Bound<'_, PyAny>>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let r = rotation
            .map(|r| self::rotation("rotation", r))
            .transpose()?
            .unwrap_or_else(SO3::identity);
        let p = position.map(|p| vec3("position", p)).transpose()?;
        let v = velocity.map(|v| vec3("velocity", v)).transpose()?;
        let (p, v) = (
            p.unwrap_or_else(Vector3::zeros),
            v.unwrap_or_else(Vector3::zeros),
        );
        checks::finite3("position", &p, "m")?;
        checks::finite3("velocity", &v, "m/s")?;
        Ok(Self(NavState::new(r, p, v)))
    }

    /// Identity attitude, zero position and velocity.
    #[staticmethod]
    fn identity() -> Self {
        Self(NavState::identity())
    }

    /// Attitude R_wb (3×3, body → world).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, self.0.r.matrix())
    }
    /// Position of the body origin in the world frame [m].
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.p)
    }
    /// Velocity of the body origin in the world frame [m/s].
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.v)
    }

    /// `self ⊕ delta` for `delta = [δφ, δp, δv]` (rad, m, m/s):
    /// `(R Exp(δφ), p + R δp, v + δv)`.
    fn retract(&self, delta: &Bound<'_, PyAny>) -> PyResult<Self> {
        let d = vec9("delta", delta)?;
        if let Some(i) = d.iter().position(|x| !x.is_finite()) {
            return Err(checks::invalid(format!(
                "delta[{i}] must be finite (order [dphi rad, dp m, dv m/s]), got {:?}",
                d[i]
            )));
        }
        Ok(Self(self.0.retract(&d)))
    }

    /// `other ⊖ self = [Log(Rᵀ R_o), Rᵀ (p_o − p), v_o − v]` in [δφ, δp, δv], the inverse of
    /// `retract`: `self.retract(self.local(o))` equals `o` to round-off.
    fn local<'py>(&self, py: Python<'py>, other: PyRef<'_, Self>) -> Bound<'py, PyArray1<f64>> {
        crate::convert::svec_py(py, &self.0.local(&other.0))
    }

    fn __repr__(&self) -> String {
        let (r, p, v) = (self.0.r.log(), self.0.p, self.0.v);
        format!(
            "NavState(rotvec=[{:?}, {:?}, {:?}] rad, position=[{:?}, {:?}, {:?}] m, velocity=[{:?}, {:?}, {:?}] m/s)",
            r.x, r.y, r.z, p.x, p.y, p.z, v.x, v.y, v.z
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Py<PyAny>, (Bound<'py, PyBytes>,))> {
        let ctor = py.get_type::<Self>().getattr("_from_state")?.unbind();
        Ok((ctor, (PyBytes::new(py, &encode_state(&self.0)),)))
    }

    /// Inverse of `__reduce__`'s state (pickle).
    #[staticmethod]
    fn _from_state(state: &[u8]) -> PyResult<Self> {
        let s = decode_state(state)?;
        if !s.is_finite() {
            return Err(checks::invalid(
                "NavState pickle state: non-finite rotation, position or velocity",
            ));
        }
        Ok(Self(s))
    }
}

/// The 15 numbers of `s` (R column-major, p, v) as little-endian bytes.
pub(crate) fn encode_state(s: &NavState) -> Vec<u8> {
    s.r.matrix()
        .iter()
        .chain(s.p.iter())
        .chain(s.v.iter())
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// The state written by [`encode_state`].
pub(crate) fn decode_state(b: &[u8]) -> PyResult<NavState> {
    if b.len() != 15 * 8 {
        return Err(shape_err(
            "pickle state: truncated or not written by this version of preint",
        ));
    }
    let x: Vec<f64> = b
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    Ok(NavState::new(
        SO3::from_matrix_unchecked(Matrix3::from_column_slice(&x[0..9])),
        Vector3::from_column_slice(&x[9..12]),
        Vector3::from_column_slice(&x[12..15]),
    ))
}

/// The bias argument of prediction and factors: `None` means the measurement's own estimate
/// `bias_hat` (no bias correction).
pub(crate) fn bias_or_hat(b: Option<PyRef<'_, PyBias>>, pim: &preint::PreintegratedImu) -> ImuBias {
    b.map(|b| b.0).unwrap_or(pim.bias_hat)
}

/// The state at keyframe j predicted from `state_i` and the bias at i (Rust `preint::predict`;
/// Forster et al. 2017 eq. 33 with the first-order bias correction of eq. 44):
///
/// `R_j = R_i ΔR(b)`, `v_j = v_i + g Δt + R_i Δv(b)`, `p_j = p_i + v_i Δt + ½ g Δt² + R_i Δp(b)`
///
/// with `g = pim.gravity` [m/s², world] and `Δt = pim.delta_t` [s]. `bias_i` (order [b_g, b_a])
/// defaults to `pim.bias_hat`. With `pim.omega_coriolis` set the navigation frame rotates and
/// the prediction follows `pim.coriolis` ("exact": GTSAM 4.3; "first"/"second": GTSAM ≤ 4.2).
/// Equals GTSAM's `PreintegratedImuMeasurements.predict(state_i, bias_i)`. A measurement of
/// level "deltas" has no bias Jacobians: a `bias_i` other than its `bias_hat` raises
/// `PreintError` (kind `NoBiasJacobians`) instead of being ignored.
#[pyfunction]
#[pyo3(signature = (pim, state_i, bias_i=None))]
pub(crate) fn predict(
    pim: PyRef<'_, PyMeasurement>,
    state_i: PyRef<'_, PyNavState>,
    bias_i: Option<PyRef<'_, PyBias>>,
) -> PyResult<PyNavState> {
    let b = bias_or_hat(bias_i, &pim.0);
    predict_checked(&pim.0, &state_i.0, &b)
}

/// `preint::try_predict`, its refusal as `PreintError`.
pub(crate) fn predict_checked(
    pim: &preint::PreintegratedImu,
    state_i: &NavState,
    bias: &ImuBias,
) -> PyResult<PyNavState> {
    preint::try_predict(pim, state_i, bias)
        .map(PyNavState)
        .map_err(crate::errors::preint_err)
}
