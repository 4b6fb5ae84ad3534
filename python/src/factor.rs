//! `ImuFactor` and `CombinedImuFactor` (Rust `preint::ImuFactor`, `preint::CombinedImuFactor`):
//! residual, analytic Jacobians, whitening, χ² and prediction from numpy.
//!
//! Residual order **[r_φ, r_v, r_p]** (rad, m/s, m) and, for the combined factor,
//! **[r_φ, r_v, r_p, r_bg, r_ba]** (+ rad/s, m/s²), the order of the measurement's covariance.
//! Jacobians are a dict of one numpy block per variable: `"state_i"`, `"state_j"` (R×9, columns
//! in the `NavState` tangent order [δφ, δp, δv]), `"bias_i"` (and `"bias_j"` for the combined
//! factor; R×6, columns [δb_g, δb_a]).

use crate::convert::{mat_py, svec_py};
use crate::errors::{Class, new_err, raise, shape_err};
use crate::measurement::PyMeasurement;
use crate::navstate::{PyNavState, bias_or_hat, predict_checked};
use crate::params::PyBias;
use nalgebra::SVector;
use numpy::{PyArray1, PyArray2};
use preint::{CombinedImuFactor, FactorJacobians, ImuBias, ImuFactor, ResidualMode};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// The residual mode named `name` (Rust `ResidualMode::parse`: "logmap", "component").
pub(crate) fn mode_from(name: &str) -> PyResult<ResidualMode> {
    ResidualMode::parse(name).ok_or_else(|| {
        shape_err(format!(
            "unknown residual {name:?}: use \"logmap\" or \"component\""
        ))
    })
}

/// `(residual, {block name: Jacobian block})` as numpy.
type Evaluated<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>);
/// A state argument of a factor method.
type State<'a> = PyRef<'a, PyNavState>;
/// A bias argument of a factor method.
type Bias<'a> = PyRef<'a, PyBias>;

/// Pickle state of a factor: its residual mode's name (with [`DRIFT_SUFFIX`] for an
/// `ImuFactor` weighted with the in-window drift) and the measurement's bytes.
fn factor_state<'py>(
    py: Python<'py>,
    mode: &'static str,
    pim: &preint::PreintegratedImu,
) -> (&'static str, Bound<'py, PyBytes>) {
    (
        mode,
        PyBytes::new(py, &crate::state::encode_measurement(pim)),
    )
}

/// The suffix of a pickled residual mode whose `ImuFactor` weight includes the in-window
/// bias drift.
const DRIFT_SUFFIX: &str = "+in_window_drift";

/// The Python methods of both factor classes, written once for the pyclass `$py` wrapping the
/// Rust factor `$factor` (Python name `$name`), whose bias arguments after the two states are
/// `$bias…` (`bias_i`, or `bias_i, bias_j`): each defaults to `None`, `$py::biases` resolves
/// them, and each names its Jacobian block (`FactorJacobians::bias_i`, `bias_j`) and that
/// block's key in the dict `evaluate` returns. The docstrings that state a dimension or an
/// order are the class's own: the doc lines before each method's name in the invocation.
macro_rules! factor_pymethods {
    (
        $py:ident($factor:ident), $name:literal, biases($($bias:ident),+);
        RESIDUAL_ORDER: $order_ty:ty = $order:expr;
        $(#[doc = $sqrt_doc:tt])* sqrt_information;
        $(#[doc = $cov_doc:tt])* residual_covariance;
        $(#[doc = $res_doc:tt])* residual;
        $(#[doc = $eval_doc:tt])* evaluate;
        $(#[doc = $chi2_doc:tt])* chi2;
    ) => {
        impl $py {
            /// The factor of `pim` with the residual `mode` and, when `in_window_drift`, the
            /// drift-inclusive weight.
            fn build(
                pim: preint::PreintegratedImu,
                mode: &str,
                in_window_drift: bool,
            ) -> PyResult<Self> {
                Self::construct(pim, mode_from(mode)?, in_window_drift).map(Self)
            }

            /// `(residual, {"state_i", "state_j", bias blocks})` as numpy.
            fn evaluated<'py, const R: usize>(
                py: Python<'py>,
                (r, j): (SVector<f64, R>, FactorJacobians<R>),
            ) -> PyResult<Evaluated<'py>> {
                let d = PyDict::new(py);
                d.set_item("state_i", mat_py(py, &j.state_i()))?;
                d.set_item("state_j", mat_py(py, &j.state_j()))?;
                $(d.set_item(stringify!($bias), mat_py(py, &j.$bias()))?;)+
                Ok((svec_py(py, &r), d))
            }
        }

        #[pymethods]
        impl $py {
            /// Row order of the residual, `sqrt_information` and `residual_covariance`.
            #[classattr]
            const RESIDUAL_ORDER: $order_ty = $order;

            #[new]
            #[pyo3(signature = (pim, residual="logmap", *, in_window_drift=false))]
            fn new(
                pim: PyRef<'_, PyMeasurement>,
                residual: &str,
                in_window_drift: bool,
            ) -> PyResult<Self> {
                Self::build(pim.0.clone(), residual, in_window_drift)
            }

            /// The residual this factor evaluates: "logmap" or "component".
            #[getter]
            fn residual_mode(&self) -> &'static str {
                self.0.residual_mode().name()
            }

            /// Whether the weight includes the bias random walk within the window (an
            /// `ImuFactor` built with `in_window_drift=True`; a `CombinedImuFactor` always).
            #[getter]
            fn in_window_drift(&self) -> bool {
                self.drift()
            }

            /// The preintegrated measurement this factor reads (a copy).
            #[getter]
            fn pim(&self) -> PyMeasurement {
                PyMeasurement(self.0.preintegrated().clone())
            }

            $(#[doc = $sqrt_doc])*
            #[getter]
            fn sqrt_information<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
                mat_py(py, self.0.sqrt_information())
            }

            $(#[doc = $cov_doc])*
            #[getter]
            fn residual_covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
                mat_py(py, self.0.residual_covariance())
            }

            /// Predicted state at j (`preint.predict`) for the bias at i (default `pim.bias_hat`).
            #[pyo3(signature = (state_i, bias_i=None))]
            fn predict(&self, state_i: State<'_>, bias_i: Option<Bias<'_>>) -> PyResult<PyNavState> {
                let b = bias_or_hat(bias_i, self.0.preintegrated());
                predict_checked(self.0.preintegrated(), &state_i.0, &b)
            }

            $(#[doc = $res_doc])*
            #[pyo3(signature = (state_i, state_j, $($bias = None),+))]
            fn residual<'py>(&self, py: Python<'py>, state_i: State<'_>, state_j: State<'_>,
                $($bias: Option<Bias<'_>>),+) -> Bound<'py, PyArray1<f64>> {
                let ($($bias,)+) = self.biases($($bias),+);
                svec_py(py, &self.0.residual(&state_i.0, &state_j.0, $(&$bias),+))
            }

            $(#[doc = $eval_doc])*
            #[pyo3(signature = (state_i, state_j, $($bias = None),+))]
            fn evaluate<'py>(&self, py: Python<'py>, state_i: State<'_>, state_j: State<'_>,
                $($bias: Option<Bias<'_>>),+) -> PyResult<Evaluated<'py>> {
                let ($($bias,)+) = self.biases($($bias),+);
                Self::evaluated(py, self.0.evaluate(&state_i.0, &state_j.0, $(&$bias),+))
            }

            /// `evaluate` whitened: `(U r, {name: U J})` with U = `sqrt_information`.
            #[pyo3(signature = (state_i, state_j, $($bias = None),+))]
            fn evaluate_whitened<'py>(&self, py: Python<'py>, state_i: State<'_>, state_j: State<'_>,
                $($bias: Option<Bias<'_>>),+) -> PyResult<Evaluated<'py>> {
                let ($($bias,)+) = self.biases($($bias),+);
                let out = self.0.evaluate_whitened(&state_i.0, &state_j.0, $(&$bias),+);
                Self::evaluated(py, out)
            }

            $(#[doc = $chi2_doc])*
            #[pyo3(signature = (state_i, state_j, $($bias = None),+))]
            fn chi2(&self, state_i: State<'_>, state_j: State<'_>, $($bias: Option<Bias<'_>>),+)
                -> f64 {
                let ($($bias,)+) = self.biases($($bias),+);
                self.0.chi2(&state_i.0, &state_j.0, $(&$bias),+)
            }

            /// Least-squares cost `½ chi2` (GTSAM's `NonlinearFactor.error`).
            #[pyo3(signature = (state_i, state_j, $($bias = None),+))]
            fn cost(&self, state_i: State<'_>, state_j: State<'_>, $($bias: Option<Bias<'_>>),+)
                -> f64 {
                let ($($bias,)+) = self.biases($($bias),+);
                self.0.cost(&state_i.0, &state_j.0, $(&$bias),+)
            }

            fn __repr__(&self) -> String {
                let m = self.0.preintegrated();
                format!(
                    concat!($name, "(residual={:?}, t_i_ns={}, t_j_ns={})"),
                    self.residual_mode(),
                    m.t_i_ns,
                    m.t_j_ns
                )
            }

            fn __eq__(&self, other: &Self) -> bool {
                self.0 == other.0
            }

            #[allow(clippy::type_complexity)]
            fn __reduce__<'py>(
                &self,
                py: Python<'py>,
            ) -> PyResult<(Py<PyAny>, (&'static str, Bound<'py, PyBytes>))> {
                let ctor = py.get_type::<Self>().getattr("_from_state")?.unbind();
                Ok((
                    ctor,
                    factor_state(py, self.pickled_mode(), self.0.preintegrated()),
                ))
            }

            /// Inverse of `__reduce__`'s state (pickle).
            #[staticmethod]
            fn _from_state(mode: &str, state: &[u8]) -> PyResult<Self> {
                let (mode, drift) = match mode.strip_suffix(DRIFT_SUFFIX) {
                    Some(m) => (m, true),
                    None => (mode, false),
                };
                Self::build(crate::state::decode_measurement(state)?, mode, drift)
            }
        }
    };
}

/// Forster's IMU factor between `(state_i, state_j, bias_i)` (Rust `ImuFactor`):
/// `ImuFactor(pim, residual="logmap", *, in_window_drift=False)`, weighted by the
/// measurement's 9×9 covariance `cov` (GTSAM's weight) or, with `in_window_drift=True`, by the
/// [δφ, δv, δp] block of `cov15`, which adds the bias random walk within the window (Rust
/// `ImuFactor::with_in_window_drift`; needs level "combined"). Needs a
/// measurement preintegrated at level "covariance" or "combined"; raises `FactorError`
/// otherwise, or when the covariance is not positive definite (e.g. zero noise). Such a
/// measurement has bias Jacobians, so every `bias_i` is corrected for (a level "deltas"
/// measurement, which could not be, never reaches a factor).
///
/// Residual **[r_φ, r_v, r_p]** (rad, m/s, m), with `ΔR(b), Δv(b), Δp(b)` the deltas corrected
/// to first order for `bias_i` (Forster 2017 eq. 44), `g` gravity, `Δt` the window:
///
/// - `residual="component"` (GTSAM `ComponentWise`; Forster eq. 45):
///   `r_φ = Log(ΔR(b)ᵀ R_iᵀ R_j)`, `r_v = R_iᵀ(v_j − v_i − gΔt) − Δv(b)`,
///   `r_p = R_iᵀ(p_j − p_i − v_iΔt − ½gΔt²) − Δp(b)`; weighted by `cov`.
/// - `residual="logmap"` (default; GTSAM 4.3's `Logmap`): the SE₂(3) residual
///   `[r_φ, Jl(r_φ)⁻¹ΔR(b)ᵀ r_v, Jl(r_φ)⁻¹ΔR(b)ᵀ r_p]` = `Log(X̂_j⁻¹ X_j)`, weighted by
///   `T cov Tᵀ`, `T = diag(I, ΔRᵀ, ΔRᵀ)`.
///
/// Relation to GTSAM's `ImuFactor` error `e` (order [rot, pos, vel], bias [acc, gyro]):
/// Logmap `e = −P r` with `P` the reordering [φ, v, p] → [φ, p, v], Jacobians likewise;
/// component-wise (`M = R_jᵀR_i`) `e = [−r_φ, −M r_p, −M r_v]` (see the Rust `preint::ImuFactor`
/// docs for the Jacobians). `bias_i=None` means the measurement's `bias_hat`.
#[pyclass(name = "ImuFactor", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyImuFactor(pub ImuFactor);

impl PyImuFactor {
    fn biases(&self, bias_i: Option<PyRef<'_, PyBias>>) -> (ImuBias,) {
        (bias_or_hat(bias_i, self.0.preintegrated()),)
    }

    fn construct(
        pim: preint::PreintegratedImu,
        mode: ResidualMode,
        in_window_drift: bool,
    ) -> PyResult<ImuFactor> {
        if in_window_drift {
            ImuFactor::with_in_window_drift(pim, mode)
        } else {
            ImuFactor::with_mode(pim, mode)
        }
        .map_err(|e| raise(Class::Factor, e))
    }

    fn drift(&self) -> bool {
        self.0.in_window_drift()
    }

    fn pickled_mode(&self) -> &'static str {
        match (self.0.residual_mode(), self.0.in_window_drift()) {
            (ResidualMode::Logmap, true) => "logmap+in_window_drift",
            (ResidualMode::ComponentWise, true) => "component+in_window_drift",
            (m, false) => m.name(),
        }
    }
}

factor_pymethods! {
    PyImuFactor(ImuFactor), "ImuFactor", biases(bias_i);
    RESIDUAL_ORDER: (&'static str, &'static str, &'static str) = ("r_phi", "r_v", "r_p");
    /// Square-root information U (9×9, upper triangular, Σ⁻¹ = UᵀU, GTSAM's
    /// `noiseModel::Gaussian` convention) of `residual_covariance`, order [r_φ, r_v, r_p].
    sqrt_information;
    /// The 9×9 covariance Σ weighting the residual, order [r_φ, r_v, r_p] [rad², (m/s)², m²]:
    /// `pim.cov` (component) or `T cov Tᵀ` (logmap). GTSAM's `residualCovariance()` is
    /// `P Σ Pᵀ` in its order [rot, pos, vel] (logmap mode).
    residual_covariance;
    /// Residual [r_φ, r_v, r_p] (9, rad, m/s, m) in this factor's mode.
    residual;
    /// `(residual, jacobians)`: the residual (9) and the analytic Jacobians as
    /// `{"state_i": 9×9, "state_j": 9×9, "bias_i": 9×6}`; rows [r_φ, r_v, r_p], state columns
    /// [δφ, δp, δv] (`NavState.retract` perturbations), bias columns [δb_g, δb_a] (additive).
    evaluate;
    /// Squared Mahalanobis norm `rᵀ Σ⁻¹ r = ‖U r‖²` (χ² with 9 dof).
    chi2;
}

/// The combined IMU factor between `(state_i, state_j, bias_i, bias_j)` (Rust
/// `CombinedImuFactor`): `CombinedImuFactor(pim, residual="logmap")`. Needs a measurement
/// preintegrated at level "combined" with a non-zero bias random walk; raises `FactorError`
/// otherwise.
///
/// Residual **[r_φ, r_v, r_p, r_bg, r_ba]** (rad, m/s, m, rad/s, m/s²): the first nine as in
/// `ImuFactor` (same mode) evaluated with `bias_i`, then `b_g,j − b_g,i`, `b_a,j − b_a,i`;
/// weighted by `pim.residual_cov15()` (component) or `diag(T, I₆) residual_cov15()
/// diag(T, I₆)ᵀ` (logmap), GTSAM 4.3's `CombinedImuFactor` weighting. GTSAM's error is
/// `[e_9, b_i − b_j]` in its orders ([rot, pos, vel], bias [acc, gyro]). `bias_i=None` means
/// `pim.bias_hat`; `bias_j=None` means `bias_i`.
#[pyclass(name = "CombinedImuFactor", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyCombinedImuFactor(pub CombinedImuFactor);

impl PyCombinedImuFactor {
    fn biases(
        &self,
        bias_i: Option<PyRef<'_, PyBias>>,
        bias_j: Option<PyRef<'_, PyBias>>,
    ) -> (ImuBias, ImuBias) {
        let bi = bias_or_hat(bias_i, self.0.preintegrated());
        (bi, bias_j.map(|b| b.0).unwrap_or(bi))
    }

    /// `in_window_drift` is refused: this factor's weight always includes the random walk.
    fn construct(
        pim: preint::PreintegratedImu,
        mode: ResidualMode,
        in_window_drift: bool,
    ) -> PyResult<CombinedImuFactor> {
        if in_window_drift {
            return Err(new_err(
                Class::Factor,
                "InWindowDrift",
                "in_window_drift: CombinedImuFactor's weight always includes the bias random walk"
                    .into(),
            ));
        }
        CombinedImuFactor::with_mode(pim, mode).map_err(|e| raise(Class::Factor, e))
    }

    fn drift(&self) -> bool {
        true
    }

    fn pickled_mode(&self) -> &'static str {
        self.0.residual_mode().name()
    }
}

factor_pymethods! {
    PyCombinedImuFactor(CombinedImuFactor), "CombinedImuFactor", biases(bias_i, bias_j);
    RESIDUAL_ORDER: (
        &'static str,
        &'static str,
        &'static str,
        &'static str,
        &'static str,
    ) = ("r_phi", "r_v", "r_p", "r_bg", "r_ba");
    /// Square-root information U (15×15, upper triangular, Σ⁻¹ = UᵀU) of
    /// `residual_covariance`, order [r_φ, r_v, r_p, r_bg, r_ba].
    sqrt_information;
    /// The 15×15 covariance weighting the residual, order [r_φ, r_v, r_p, r_bg, r_ba]:
    /// `pim.residual_cov15()` (component) or `diag(T, I₆) residual_cov15() diag(T, I₆)ᵀ`
    /// (logmap).
    residual_covariance;
    /// Residual [r_φ, r_v, r_p, r_bg, r_ba] (15) in this factor's mode.
    residual;
    /// `(residual, jacobians)`: the residual (15) and the analytic Jacobians as
    /// `{"state_i": 15×9, "state_j": 15×9, "bias_i": 15×6, "bias_j": 15×6}`; rows
    /// [r_φ, r_v, r_p, r_bg, r_ba], state columns [δφ, δp, δv], bias columns [δb_g, δb_a].
    evaluate;
    /// `rᵀ Σ⁻¹ r = ‖U r‖²` (χ² with 15 dof).
    chi2;
}
