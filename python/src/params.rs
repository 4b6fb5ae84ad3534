//! `Noise`, `ImuBias` and `Params`: the parameters of a preintegration.
//!
//! Units: noise densities as Kalibr gives them (gyro rad/s/√Hz, accelerometer m/s²/√Hz, random
//! walks rad/s²/√Hz and m/s³/√Hz); covariances continuous-time (GTSAM's
//! `gyroscopeCovariance` semantics, the densities squared); biases [rad/s], [m/s²]; gravity
//! [m/s²] in the world frame; times in integer nanoseconds.

use crate::checks;
use crate::convert::{cov3, mat_py, matrix, vec_py, vec3};
use crate::errors::shape_err;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use numpy::{PyArray1, PyArray2};
use preint::lie::SO3;
use preint::{
    BiasCorrection, CoriolisMode, ImuBias, ImuNoise, Level, LeverArm, PreintParams, Scheme,
    SensorPose,
};
use pyo3::prelude::*;

/// The constructor arguments of `Noise` (its pickle state).
type NoiseArgs = (f64, f64, f64, f64, f64);

/// Kalibr-style IMU noise densities (`Noise(gyro_noise_density, gyro_random_walk,
/// acc_noise_density, acc_random_walk, update_rate_hz=200.0)`): gyro [rad/s/√Hz], gyro bias
/// random walk [rad/s²/√Hz], accelerometer [m/s²/√Hz], accelerometer bias random walk
/// [m/s³/√Hz], rate [Hz]. White-noise densities and the rate must be finite and > 0, random
/// walks finite and ≥ 0 (`crate::checks`); otherwise `PreintError` (kind `InvalidParameter`).
#[pyclass(name = "Noise", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyNoise(pub ImuNoise);

#[pymethods]
impl PyNoise {
    #[new]
    #[pyo3(signature = (gyro_noise_density, gyro_random_walk, acc_noise_density, acc_random_walk, update_rate_hz=200.0))]
    fn new(
        gyro_noise_density: f64,
        gyro_random_walk: f64,
        acc_noise_density: f64,
        acc_random_walk: f64,
        update_rate_hz: f64,
    ) -> PyResult<Self> {
        let n = ImuNoise {
            gyro_noise_density,
            gyro_random_walk,
            acc_noise_density,
            acc_random_walk,
            update_rate_hz,
        };
        checks::noise("Noise", &n)?;
        Ok(Self(n))
    }

    /// The EuRoC MAV dataset's ADIS16448 densities (its `imu0.yaml`).
    #[staticmethod]
    fn euroc() -> Self {
        Self(ImuNoise::euroc())
    }

    /// Gyro white-noise density [rad/s/√Hz].
    #[getter]
    fn gyro_noise_density(&self) -> f64 {
        self.0.gyro_noise_density
    }
    /// Gyro bias random walk [rad/s²/√Hz].
    #[getter]
    fn gyro_random_walk(&self) -> f64 {
        self.0.gyro_random_walk
    }
    /// Accelerometer white-noise density [m/s²/√Hz].
    #[getter]
    fn acc_noise_density(&self) -> f64 {
        self.0.acc_noise_density
    }
    /// Accelerometer bias random walk [m/s³/√Hz].
    #[getter]
    fn acc_random_walk(&self) -> f64 {
        self.0.acc_random_walk
    }
    /// Sample rate [Hz].
    #[getter]
    fn update_rate_hz(&self) -> f64 {
        self.0.update_rate_hz
    }

    fn __repr__(&self) -> String {
        let n = &self.0;
        format!(
            "Noise(gyro_noise_density={:?}, gyro_random_walk={:?}, acc_noise_density={:?}, acc_random_walk={:?}, update_rate_hz={:?})",
            n.gyro_noise_density,
            n.gyro_random_walk,
            n.acc_noise_density,
            n.acc_random_walk,
            n.update_rate_hz
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __reduce__(&self, py: Python<'_>) -> PyResult<(Py<PyAny>, NoiseArgs)> {
        let n = &self.0;
        Ok((
            py.get_type::<Self>().into_any().unbind(),
            (
                n.gyro_noise_density,
                n.gyro_random_walk,
                n.acc_noise_density,
                n.acc_random_walk,
                n.update_rate_hz,
            ),
        ))
    }
}

/// An IMU bias estimate: gyro [rad/s] and accelerometer [m/s²], each in the sensor frame.
/// Vector order everywhere in preint: **[b_g, b_a]** (GTSAM's `ConstantBias` stores
/// [b_a, b_g]). Components must be finite.
#[pyclass(name = "ImuBias", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyBias(pub ImuBias);

#[pymethods]
impl PyBias {
    #[new]
    #[pyo3(signature = (gyro=None, acc=None))]
    fn new(gyro: Option<&Bound<'_, PyAny>>, acc: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let g = gyro.map(|g| vec3("gyro", g)).transpose()?;
        let a = acc.map(|a| vec3("acc", a)).transpose()?;
        let b = ImuBias::new(
            g.unwrap_or_else(Vector3::zeros),
            a.unwrap_or_else(Vector3::zeros),
        );
        checks::bias("ImuBias", &b)?;
        Ok(Self(b))
    }

    /// Gyro bias [rad/s].
    #[getter]
    fn gyro<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.gyro)
    }

    /// Accelerometer bias [m/s²].
    #[getter]
    fn acc<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.acc)
    }

    /// `[b_g, b_a]` as a 6-vector.
    fn vector<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let b = &self.0;
        numpy::PyArray1::from_vec(
            py,
            vec![b.gyro.x, b.gyro.y, b.gyro.z, b.acc.x, b.acc.y, b.acc.z],
        )
    }

    fn __repr__(&self) -> String {
        let b = &self.0;
        format!(
            "ImuBias(gyro=[{:?}, {:?}, {:?}], acc=[{:?}, {:?}, {:?}])",
            b.gyro.x, b.gyro.y, b.gyro.z, b.acc.x, b.acc.y, b.acc.z
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __reduce__(&self, py: Python<'_>) -> (Py<PyAny>, ([f64; 3], [f64; 3])) {
        let b = &self.0;
        (
            py.get_type::<Self>().into_any().unbind(),
            (b.gyro.into(), b.acc.into()),
        )
    }
}

/// An optional bias argument (`None`: zero).
pub(crate) fn bias_or_zero(b: Option<PyRef<'_, PyBias>>) -> ImuBias {
    b.map(|b| b.0).unwrap_or_else(ImuBias::zero)
}

/// The parameters of a preintegration (Rust `PreintParams`). `Params(noise=None)` starts from
/// `noise` (default `Noise.euroc()`): `Σ = density² I` for the four densities, gravity
/// `(0, 0, −9.81)` m/s², scheme `"midpoint"`, level `"combined"`; every field can then be set.
/// Every setter checks the new value (`crate::checks::params`: `PreintParams::validate`, gravity
/// within 100 m/s², `omega_coriolis` below 100 rad/s) and keeps the old one on error.
#[pyclass(name = "Params", module = "preint", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyParams(pub PreintParams);

pub(crate) fn scheme_from(name: &str) -> PyResult<Scheme> {
    Scheme::from_name(name).ok_or_else(|| {
        let names: Vec<_> = Scheme::ALL.iter().map(|s| s.name()).collect();
        shape_err(format!(
            "unknown scheme {name:?}: use one of {}",
            names.join(", ")
        ))
    })
}

fn level_name(l: Level) -> &'static str {
    match l {
        Level::Deltas => "deltas",
        Level::Covariance => "covariance",
        Level::Combined => "combined",
    }
}

pub(crate) fn level_from(name: &str) -> PyResult<Level> {
    match name {
        "deltas" => Ok(Level::Deltas),
        "covariance" => Ok(Level::Covariance),
        "combined" => Ok(Level::Combined),
        _ => Err(shape_err(format!(
            "unknown level {name:?}: use deltas, covariance or combined"
        ))),
    }
}

pub(crate) fn coriolis_name(m: CoriolisMode) -> &'static str {
    match m {
        CoriolisMode::FirstOrder => "first",
        CoriolisMode::SecondOrder => "second",
        CoriolisMode::Exact => "exact",
    }
}

fn coriolis_from(name: &str) -> PyResult<CoriolisMode> {
    match name {
        "first" => Ok(CoriolisMode::FirstOrder),
        "second" => Ok(CoriolisMode::SecondOrder),
        "exact" => Ok(CoriolisMode::Exact),
        _ => Err(shape_err(format!(
            "unknown Coriolis mode {name:?}: use first, second or exact"
        ))),
    }
}

/// A rotation from a 3×3 matrix or a unit quaternion `(w, x, y, z)`. Tolerance 1e-6: a matrix
/// with `‖RᵀR − I‖max ≤ 1e-6` and `det R > 0` is replaced by the nearest rotation
/// (`SO3::from_matrix`), a quaternion with `|‖q‖ − 1| ≤ 1e-6` is normalised; anything else
/// (NaN or infinite entries included) raises `ShapeError` naming `name`.
pub(crate) fn rotation(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<SO3> {
    if let Ok(q) = obj.extract::<Vec<f64>>()
        && q.len() == 4
    {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        if !n.is_finite() || (n - 1.0).abs() > 1e-6 {
            return Err(shape_err(format!(
                "{name}: quaternion (w, x, y, z) must have unit norm, got {n}"
            )));
        }
        let uq = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
        return Ok(SO3::from_matrix(&uq.to_rotation_matrix().into_inner()));
    }
    let m: Matrix3<f64> = matrix::<3, 3>(name, obj).map_err(|_| {
        shape_err(format!(
            "{name}: expected a 3×3 rotation matrix or a unit quaternion (w, x, y, z)"
        ))
    })?;
    let err = (m.transpose() * m - Matrix3::identity()).abs().max();
    if err.is_nan() || err > 1e-6 || m.determinant() <= 0.0 {
        return Err(shape_err(format!(
            "{name}: not a rotation matrix (‖RᵀR − I‖max = {err:e}, det = {})",
            m.determinant()
        )));
    }
    Ok(SO3::from_matrix(&m))
}

/// `(R_bs 3×3, t_bs [m])` as numpy arrays.
type PoseArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);

#[pymethods]
impl PyParams {
    #[new]
    #[pyo3(signature = (noise=None, *, scheme="midpoint", level="combined"))]
    fn new(noise: Option<PyRef<'_, PyNoise>>, scheme: &str, level: &str) -> PyResult<Self> {
        let n = noise.map(|n| n.0).unwrap_or_else(ImuNoise::euroc);
        checks::noise("noise", &n)?;
        let p = PreintParams::from_noise(&n)
            .with_scheme(scheme_from(scheme)?)
            .with_level(level_from(level)?);
        Ok(Self(p))
    }

    /// Gravity in the world frame [m/s²].
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_py(py, &self.0.gravity)
    }
    #[setter]
    fn set_gravity(&mut self, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let g = vec3("gravity", v)?;
        self.update(|p| p.gravity = g)
    }

    /// Gyro white-noise covariance Σ_g [rad²/s] (continuous-time; a number s means s·I).
    #[getter]
    fn gyroscope_covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.gyro_cov)
    }
    #[setter]
    fn set_gyroscope_covariance(&mut self, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = cov3("gyroscope_covariance", v)?;
        self.update(|p| p.gyro_cov = c)
    }
    /// Accelerometer white-noise covariance Σ_a [m²/s³] (continuous-time; a number s means s·I).
    #[getter]
    fn accelerometer_covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.acc_cov)
    }
    #[setter]
    fn set_accelerometer_covariance(&mut self, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = cov3("accelerometer_covariance", v)?;
        self.update(|p| p.acc_cov = c)
    }
    /// Gyro bias random-walk covariance [rad²/s³] (continuous-time).
    #[getter]
    fn bias_gyro_covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.gyro_bias_rw_cov)
    }
    #[setter]
    fn set_bias_gyro_covariance(&mut self, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = cov3("bias_gyro_covariance", v)?;
        self.update(|p| p.gyro_bias_rw_cov = c)
    }
    /// Accelerometer bias random-walk covariance [m²/s⁵] (continuous-time).
    #[getter]
    fn bias_acc_covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_py(py, &self.0.acc_bias_rw_cov)
    }
    #[setter]
    fn set_bias_acc_covariance(&mut self, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = cov3("bias_acc_covariance", v)?;
        self.update(|p| p.acc_bias_rw_cov = c)
    }

    /// Integration covariance [m²/s³] added to Δp per unit time (GTSAM's
    /// `integrationCovariance`), or None.
    #[getter]
    fn integration_covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.0.integration_cov.as_ref().map(|m| mat_py(py, m))
    }
    #[setter]
    fn set_integration_covariance(&mut self, v: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let c = v.map(|v| cov3("integration_covariance", v)).transpose()?;
        self.update(|p| p.integration_cov = c)
    }

    /// Integration scheme: `"euler"` (GTSAM's Manifold), `"midpoint"`, `"hermite4"` or `"galilean"`
    /// (GTSAM's `PreintegratedImuMeasurementsG`, exact for held input).
    #[getter]
    fn scheme(&self) -> &'static str {
        self.0.scheme.name()
    }
    #[setter]
    fn set_scheme(&mut self, v: &str) -> PyResult<()> {
        self.0.scheme = scheme_from(v)?;
        Ok(())
    }

    /// What is computed: `"deltas"`, `"covariance"` (9×9 and bias Jacobians) or `"combined"`
    /// (also the 15×15 covariance with bias random walk).
    #[getter]
    fn level(&self) -> &'static str {
        level_name(self.0.level)
    }
    #[setter]
    fn set_level(&mut self, v: &str) -> PyResult<()> {
        self.0.level = level_from(v)?;
        Ok(())
    }

    /// Gyro-bias change [rad/s] above which `measurement_for_bias` re-integrates.
    #[getter]
    fn reintegrate_gyro_threshold(&self) -> f64 {
        self.0.reintegrate_gyro_threshold
    }
    #[setter]
    fn set_reintegrate_gyro_threshold(&mut self, v: f64) -> PyResult<()> {
        self.update(|p| p.reintegrate_gyro_threshold = v)
    }

    /// Accelerometer-bias change [m/s²] above which `measurement_for_bias` re-integrates.
    #[getter]
    fn reintegrate_acc_threshold(&self) -> f64 {
        self.0.reintegrate_acc_threshold
    }
    #[setter]
    fn set_reintegrate_acc_threshold(&mut self, v: f64) -> PyResult<()> {
        self.update(|p| p.reintegrate_acc_threshold = v)
    }

    /// Largest allowed gap between samples [ns].
    #[getter]
    fn max_gap_ns(&self) -> i64 {
        self.0.max_gap_ns
    }
    #[setter]
    fn set_max_gap_ns(&mut self, v: i64) -> PyResult<()> {
        self.update(|p| p.max_gap_ns = v)
    }

    /// Whether a `Preintegrator` stores its samples (needed for re-integration).
    #[getter]
    fn keep_samples(&self) -> bool {
        self.0.keep_samples
    }
    #[setter]
    fn set_keep_samples(&mut self, v: bool) {
        self.0.keep_samples = v;
    }

    /// The IMU's pose in the body frame (GTSAM's `body_P_sensor`) as `(R_bs 3×3, t_bs [m])`,
    /// or None (IMU at the body origin).
    #[getter]
    fn body_p_sensor<'py>(&self, py: Python<'py>) -> Option<PoseArrays<'py>> {
        self.0
            .body_p_sensor
            .as_ref()
            .map(|s| (mat_py(py, s.rotation.matrix()), vec_py(py, &s.translation)))
    }

    /// Sets the IMU's pose in the body frame: `rotation` R_bs (3×3 matrix or unit quaternion
    /// (w, x, y, z)), `translation` [m] in the body frame; or clears it with `None`.
    #[pyo3(signature = (rotation, translation=None))]
    fn set_body_p_sensor(
        &mut self,
        rotation: Option<&Bound<'_, PyAny>>,
        translation: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let pose = match rotation {
            None => None,
            Some(r) => {
                let t = translation
                    .map(|t| vec3("translation", t))
                    .transpose()?
                    .unwrap_or_else(Vector3::zeros);
                checks::finite3("translation", &t, "m")?;
                Some(SensorPose::new(self::rotation("rotation", r)?, t))
            }
        };
        self.update(|p| p.body_p_sensor = pose)
    }

    /// Lever-arm model with `body_p_sensor`: `"exact"` (default) or `"centripetal"` (GTSAM's).
    #[getter]
    fn lever_arm(&self) -> &'static str {
        self.0.lever_arm.name()
    }
    #[setter]
    fn set_lever_arm(&mut self, v: &str) -> PyResult<()> {
        self.0.lever_arm = LeverArm::parse(v).ok_or_else(|| {
            shape_err(format!(
                "unknown lever-arm model {v:?}: use exact or centripetal"
            ))
        })?;
        Ok(())
    }

    /// How the deltas are corrected for a bias change: `"additive"` (Forster eq. 44, GTSAM's
    /// Manifold/Tangent backends), `"group"` (right-applied on the group, GTSAM's Galilean
    /// backend) or None (default: the scheme's, `"group"` for galilean, `"additive"` otherwise).
    #[getter]
    fn bias_correction(&self) -> Option<&'static str> {
        self.0.bias_correction.map(|c| c.name())
    }
    #[setter]
    fn set_bias_correction(&mut self, v: Option<&str>) -> PyResult<()> {
        self.0.bias_correction = v
            .map(|v| {
                BiasCorrection::parse(v).ok_or_else(|| {
                    shape_err(format!(
                        "unknown bias correction {v:?}: use additive or group"
                    ))
                })
            })
            .transpose()?;
        Ok(())
    }

    /// Rotation rate of the navigation frame [rad/s, navigation frame] (GTSAM's
    /// `omegaCoriolis`), or None.
    #[getter]
    fn omega_coriolis<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.0.omega_coriolis.as_ref().map(|w| vec_py(py, w))
    }
    #[setter]
    fn set_omega_coriolis(&mut self, v: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let w = v.map(|v| vec3("omega_coriolis", v)).transpose()?;
        self.update(|p| p.omega_coriolis = w)
    }

    /// How `omega_coriolis` enters prediction and factors: `"exact"` (default, GTSAM 4.3),
    /// `"first"` or `"second"` (GTSAM ≤ 4.2's orders).
    #[getter]
    fn coriolis(&self) -> &'static str {
        coriolis_name(self.0.coriolis)
    }
    #[setter]
    fn set_coriolis(&mut self, v: &str) -> PyResult<()> {
        self.0.coriolis = coriolis_from(v)?;
        Ok(())
    }

    /// Raises `PreintError` if a parameter is invalid (non-finite, not a covariance, …).
    fn validate(&self) -> PyResult<()> {
        checks::params(&self.0)
    }

    fn __repr__(&self) -> String {
        format!(
            "Params(scheme={:?}, level={:?}, gravity={:?})",
            self.0.scheme.name(),
            level_name(self.0.level),
            self.0.gravity.as_slice()
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.0 == other.0
    }

    fn __reduce__(&self, py: Python<'_>) -> PyResult<(Py<PyAny>, (Vec<u8>,))> {
        let ctor = py.get_type::<Self>().getattr("_from_state")?.unbind();
        Ok((ctor, (crate::state::encode_params(&self.0),)))
    }

    /// Inverse of `__reduce__`'s state (pickle).
    #[staticmethod]
    fn _from_state(state: &[u8]) -> PyResult<Self> {
        let p = crate::state::decode_params(state)?;
        checks::params(&p)?;
        Ok(Self(p))
    }
}

impl PyParams {
    /// Applies `f` to a copy of the parameters and keeps the copy if it passes
    /// [`checks::params`] (the error names the property; nothing changes on error).
    fn update(&mut self, f: impl FnOnce(&mut PreintParams)) -> PyResult<()> {
        let mut p = self.0.clone();
        f(&mut p);
        checks::params(&p)?;
        self.0 = p;
        Ok(())
    }
}
