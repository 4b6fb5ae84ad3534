//! Preintegration parameters: gravity, continuous-time noise covariances, integration scheme,
//! what to compute, bias re-integration thresholds and the largest allowed sample gap.

use crate::choices::{BiasCorrection, CoriolisMode, Level, LeverArm};
use crate::error::PreintError;
use crate::noise::ImuNoise;
use crate::scheme::Scheme;
use nalgebra::{Matrix3, Vector3};
use preint_lie::SO3;

/// Pose of the IMU in the body frame, GTSAM's `body_P_sensor`: an IMU that is not at the body
/// origin, and the exact map from the sensor's preintegrated deltas to the body's.
///
/// # Model
///
/// The IMU (frame s) is rigidly mounted at `body_P_sensor = (R, r)`: `R = R_bs` rotates sensor
/// vectors into the body frame and `r` \[m\] is the sensor origin in body coordinates. Biases and
/// noise are the sensor's, in the sensor frame (as in GTSAM's `body_P_sensor`). The sensor reads
/// the body rate `ω_s = Rᵀ ω_b` and the specific force of the point it sits on,
///
/// ```text
/// f_s = Rᵀ (f_b + ω̇_b × r + ω_b × (ω_b × r)),
/// ```
///
/// where `f_b` is the specific force at the body origin: the lever arm adds the tangential
/// (`ω̇ × r`) and centripetal (`ω × (ω × r)`) accelerations of the sensor's point.
///
/// # The body deltas from the sensor's, exactly
///
/// Preintegrating the sensor's samples gives the deltas of the sensor's point in frame s at
/// keyframe i (`ΔR_s`, `Δv_s`, `Δp_s`, Forster et al. 2017, eq. 33). Writing the sensor's
/// position and velocity through the body's (`p_s = p_b + R_wb r`, `v_s = v_b + R_wb (ω_b × r)`)
/// gives the body's deltas without approximation:
///
/// ```text
/// ΔR = R ΔR_s Rᵀ
/// Δv = R Δv_s + ω_i × r − ΔR (ω_j × r)
/// Δp = R Δp_s + Δt (ω_i × r) + r − ΔR r
/// ```
///
/// with `ω_i = R ω_s,i`, `ω_j = R ω_s,j` the bias-corrected body rates at the window's first
/// and last sample. This is the lever-arm correction of the specific force,
/// `f_b = R f_s − ω̇ × r − ω × (ω × r)`, integrated in closed form: by parts,
/// `∫ ΔR (ω̇ × r) dt = ΔR_j (ω_j × r) − ω_i × r − ∫ ΔR (ω × (ω × r)) dt`, so both terms together
/// integrate to the end-point values above. No estimate of `ω̇` is needed and no term is
/// dropped: the body deltas carry exactly the integration error the scheme makes on the
/// sensor's own samples, whatever the scheme. (A per-sample correction needs `ω̇` from
/// differences of neighbouring samples and carries that estimate's error; subtracting only the
/// centripetal term, as GTSAM's `correctMeasurementsBySensorPose` does, leaves out
/// `∫ ΔR (ω̇ × r) dt` entirely.)
///
/// # Linearisation (chart of [`PreintegratedImu`](crate::PreintegratedImu), order [δφ, δv, δp])
///
/// With `ΔR_s = ΔR°_s Exp(δφ_s)`, the body error is `e = A e_s + B_i δω_i + B_j δω_j` for the
/// sensor error `e_s` and perturbations `δω = R δω_s` of the end rates:
///
/// ```text
/// A = [[R, 0, 0], [ΔR [ω_j × r]× R, R, 0], [ΔR [r]× R, 0, R]]
/// B_i = [0; −[r]×; −Δt [r]×],   B_j = [0; ΔR [r]×; 0]
/// ```
///
/// The end rates are the bias-corrected readings of the first and last sample (for a window
/// whose boundary sample is interpolated, the same combination of stream samples), so their
/// noise is that of those samples, which also entered `e_s`: the covariance uses the gains the
/// measurement keeps for its edge samples ([`EdgeNoise`](crate::edges::EdgeNoise)) and is the exact first-order
/// covariance of the body deltas, gyroscope noise moved into the velocity and position rows
/// included. Bias Jacobians: `J = A J_s − (B_i + B_j) R` on the gyro columns (every sample sees
/// `−δb_g`), `A J_s` on the accelerometer columns. Combined covariance: the gyro bias at the
/// window's end, `b_g,i + δb_g`, is what `ω_j` should have been corrected with, so
/// `e = A e_s + B_j R δb_g + …` and `[e; δb]` maps by `[[A, B_j R S_g], [0, I]]`
/// (`S_g` selects `δb_g`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorPose {
    /// `R_bs`: rotates sensor vectors into the body frame (`x_b = R_bs x_s`).
    pub rotation: SO3,
    /// The sensor origin in body coordinates \[m\] (the lever arm).
    pub translation: Vector3<f64>,
}

impl SensorPose {
    /// The pose from `R_bs` (sensor → body) and the sensor origin in the body frame \[m\].
    pub fn new(rotation: SO3, translation: Vector3<f64>) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// True if every entry is finite and the rotation is orthonormal to 1e-9.
    pub fn is_valid(&self) -> bool {
        let m = self.rotation.matrix();
        m.iter().all(|x| x.is_finite())
            && self.translation.iter().all(|x| x.is_finite())
            && (m.transpose() * m - Matrix3::identity()).amax() < 1e-9
            && m.determinant() > 0.0
    }
}

/// Shape of a 3×3 covariance, decided once when the preintegrator is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum CovShape {
    /// `s·I`.
    Isotropic(f64),
    /// A general symmetric positive semi-definite matrix.
    General(Matrix3<f64>),
}

impl CovShape {
    /// `Isotropic(s)` if `m` is exactly `s·I`, else `General(m)`.
    pub(crate) fn of(m: &Matrix3<f64>) -> Self {
        let s = m[(0, 0)];
        let off = [
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 0)],
            m[(1, 2)],
            m[(2, 0)],
            m[(2, 1)],
        ];
        if off.iter().all(|&x| x == 0.0) && m[(1, 1)] == s && m[(2, 2)] == s {
            CovShape::Isotropic(s)
        } else {
            CovShape::General(*m)
        }
    }
}

/// Parameters of a preintegration.
///
/// Noise covariances are **continuous-time** (power spectral densities, the square of the Kalibr
/// densities, GTSAM's `gyroscopeCovariance`/`accelerometerCovariance` semantics): a sample
/// whose time cell is `c` carries white noise of covariance `Σ/c`, and a random walk adds
/// `Σ_rw h` over a step `h`; the conversion and the cell rule are in [`ImuNoise`](crate::ImuNoise). An
/// exactly isotropic matrix `s·I` selects a closed-form fast path, decided once when the
/// preintegrator is built.
#[derive(Clone, Debug, PartialEq)]
pub struct PreintParams {
    /// Gravity in the world frame [m/s²]; default `(0, 0, −9.81)` (z up).
    pub gravity: Vector3<f64>,
    /// Gyro white-noise covariance density Σ_g [rad²/s] (= σ_g² I for Kalibr σ_g).
    pub gyro_cov: Matrix3<f64>,
    /// Accelerometer white-noise covariance density Σ_a [m²/s³] (= σ_a² I).
    pub acc_cov: Matrix3<f64>,
    /// Gyro bias random-walk density Σ_bg [rad²/s³] (= σ_bg² I); a step Δt adds `Σ_bg Δt`.
    pub gyro_bias_rw_cov: Matrix3<f64>,
    /// Accelerometer bias random-walk density Σ_ba [m²/s⁵] (= σ_ba² I).
    pub acc_bias_rw_cov: Matrix3<f64>,
    /// Optional integration covariance Σ_int [m²/s] (GTSAM semantics): after each interval of
    /// length h, `ΔR_k+1 Σ_int ΔR_k+1ᵀ h` is added to the δp block. `None` = 0.
    pub integration_cov: Option<Matrix3<f64>>,
    /// Integration scheme; default [`Scheme::Midpoint`].
    pub scheme: Scheme,
    /// What to compute; default [`Level::Combined`].
    pub level: Level,
    /// Re-integrate from the stored samples when ‖δb_g‖ exceeds this [rad/s]; default
    /// [`DEFAULT_REINTEGRATE_GYRO`].
    pub reintegrate_gyro_threshold: f64,
    /// Re-integrate when ‖δb_a‖ exceeds this [m/s²]; default [`DEFAULT_REINTEGRATE_ACC`].
    pub reintegrate_acc_threshold: f64,
    /// Largest allowed gap between consecutive samples \[ns\]; default [`DEFAULT_MAX_GAP_NS`].
    pub max_gap_ns: i64,
    /// Keep the samples for re-integration after a bias change; default `true`. Without them
    /// [`Preintegrator::measurement_for_bias`](crate::Preintegrator::measurement_for_bias)
    /// always returns the first-order correction and
    /// [`Preintegrator::reintegrate`](crate::Preintegrator::reintegrate) is an error
    /// ([`PreintError::SamplesNotKept`]).
    pub keep_samples: bool,
    /// Pose of the IMU in the body frame (GTSAM's `body_P_sensor`): with it the measurement is
    /// the body's, lever arm and rotation included ([`SensorPose`](crate::SensorPose)); biases and noise
    /// stay the sensor's. `None`: the IMU frame is the body frame. Default `None`.
    pub body_p_sensor: Option<SensorPose>,
    /// How the lever arm of `body_p_sensor` is removed; default [`LeverArm::Exact`].
    pub lever_arm: LeverArm,
    /// Rotation rate of the navigation frame ω_ie [rad/s, navigation frame] (Earth rotation,
    /// e.g. [`earth_rate_enu`](crate::earth::earth_rate_enu)); `None` (the default) = a
    /// non-rotating frame. Used by prediction and the factors, not by the per-sample loop.
    pub omega_coriolis: Option<Vector3<f64>>,
    /// How `omega_coriolis` enters prediction and the factors; default
    /// [`CoriolisMode::Exact`].
    pub coriolis: CoriolisMode,
    /// How the measurement's deltas are corrected for a new bias estimate
    /// ([`PreintegratedImu::corrected`](crate::PreintegratedImu::corrected), used by
    /// [`predict`](crate::predict) and both factors). `None` (the default) = the scheme's:
    /// [`BiasCorrection::Group`] for [`Scheme::Galilean`], as its reference GTSAM 4.3
    /// `GalileanPreintegration` does (its bias-corrected deltas then equal GTSAM's, and the
    /// correction is more accurate at large bias changes, `docs/EVIDENCE.md`),
    /// [`BiasCorrection::Additive`] (Forster eq. 44, GTSAM's Manifold/Tangent backends)
    /// otherwise: the scheme's
    /// [`SchemeInfo::bias_correction`](crate::SchemeInfo::bias_correction).
    pub bias_correction: Option<BiasCorrection>,
    /// IMU intrinsics applied to every raw sample before integration, and whether the deltas'
    /// Jacobians with respect to them are accumulated ([`crate::intrinsics`]; the bias
    /// estimate and the noise densities are then those of the corrected samples). `None` (the
    /// default): samples are integrated as read.
    pub intrinsics: Option<crate::intrinsics::AppliedIntrinsics>,
    /// Time-offset change \[s\] above which
    /// [`time_offset::measurement_for_time_offset`](crate::time_offset::measurement_for_time_offset)
    /// re-integrates instead of correcting to first order; default
    /// [`DEFAULT_REINTEGRATE_TIME_OFFSET`].
    pub reintegrate_time_offset_threshold: f64,
}

/// Default gyro-bias change [rad/s] above which the first-order correction is replaced by
/// re-integration. Measured (`tests/reintegration.rs`, EuRoC noise, 200 Hz, 1 s window of a
/// smooth scene at |ω| ≈ 1–2 rad/s, all three schemes): the first-order error against exact
/// re-integration grows as ‖δb_g‖² (`n(2δb)/n(δb) = 4.00`) and its Mahalanobis norm
/// `n = √(eᵀΣ⁻¹e)` (9 dof, Σ the white-noise covariance) reaches 1 at ‖δb_g‖ = 0.0307 rad/s
/// (the velocity block alone reaches its σ at ≈ 0.05 rad/s); at the default 0.01 rad/s it is
/// 0.106. The default keeps a margin of 10 in n (≈ 3 in δb) for longer windows and faster
/// motion, where the curvature is larger.
pub const DEFAULT_REINTEGRATE_GYRO: f64 = 0.01;
/// Default accelerometer-bias change [m/s²] above which samples are re-integrated. The deltas
/// are affine in b_a for a fixed b_g, so the first-order correction is exact in b_a alone;
/// the error comes from the (b_g, b_a) cross terms, `n ≈ |e_gg δb_g² + e_ga δb_g δb_a|`.
/// Measured (same setting as [`DEFAULT_REINTEGRATE_GYRO`]): with ‖δb_g‖ at the gyro default
/// 0.01 rad/s, n reaches 1 at ‖δb_a‖ = 0.40 m/s² and is 0.50 at this default; with
/// ‖δb_g‖ = 0.003 rad/s the crossing is 1.34 m/s².
pub const DEFAULT_REINTEGRATE_ACC: f64 = 0.2;
/// Default time-offset change \[s\] above which the first-order time-offset correction
/// ([`crate::time_offset`]) is replaced by re-integration. Measured (`tests/tests/time_offset.rs`:
/// `aggressive` scene, 200 Hz, ten 1 s windows, EuRoC densities, largest value over windows and
/// signs): the first-order error against re-integration grows as δt_d² for midpoint and hermite4
/// (`n(2 ms)/n(1 ms) = 4.0`) and its Mahalanobis norm `n = √(eᵀΣ⁻¹e)` (9 dof) reaches 1 at
/// δt_d = 2.26 ms; at this default it is 0.049 (a margin of 20 in n, 4.5 in δt_d, for faster
/// motion and longer windows). Euler and galilean reach 1 at 0.95 and 0.88 ms (0.48 and 0.52
/// here): their discrete deltas' derivative with respect to a window end differs from the end
/// sample at first order in the sample period, which the correction does not model. Not
/// correcting at all costs n = 3.4 already at 0.1 ms.
pub const DEFAULT_REINTEGRATE_TIME_OFFSET: f64 = 5e-4;
/// Default largest sample gap: 250 ms.
pub const DEFAULT_MAX_GAP_NS: i64 = 250_000_000;

impl PreintParams {
    /// Parameters from Kalibr densities: `Σ_g = σ_g² I`, `Σ_a = σ_a² I`, `Σ_bg = σ_bg² I`,
    /// `Σ_ba = σ_ba² I`; gravity `(0, 0, −9.81)`, midpoint, combined covariance, default
    /// thresholds, no integration covariance.
    pub fn from_noise(noise: &ImuNoise) -> Self {
        let i = Matrix3::identity();
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            gyro_cov: i * noise.gyro_noise_density.powi(2),
            acc_cov: i * noise.acc_noise_density.powi(2),
            gyro_bias_rw_cov: i * noise.gyro_random_walk.powi(2),
            acc_bias_rw_cov: i * noise.acc_random_walk.powi(2),
            integration_cov: None,
            scheme: Scheme::Midpoint,
            level: Level::Combined,
            reintegrate_gyro_threshold: DEFAULT_REINTEGRATE_GYRO,
            reintegrate_acc_threshold: DEFAULT_REINTEGRATE_ACC,
            max_gap_ns: DEFAULT_MAX_GAP_NS,
            keep_samples: true,
            body_p_sensor: None,
            lever_arm: LeverArm::Exact,
            omega_coriolis: None,
            coriolis: CoriolisMode::Exact,
            bias_correction: None,
            intrinsics: None,
            reintegrate_time_offset_threshold: DEFAULT_REINTEGRATE_TIME_OFFSET,
        }
    }

    /// Same parameters with another scheme.
    pub fn with_scheme(mut self, scheme: Scheme) -> Self {
        self.scheme = scheme;
        self
    }

    /// Same parameters with another computation level.
    pub fn with_level(mut self, level: Level) -> Self {
        self.level = level;
        self
    }

    /// Same parameters with another gravity vector [m/s², world frame].
    pub fn with_gravity(mut self, gravity: Vector3<f64>) -> Self {
        self.gravity = gravity;
        self
    }

    /// Same parameters with the IMU at `pose` in the body frame ([`SensorPose`](crate::SensorPose)).
    pub fn with_body_p_sensor(mut self, pose: SensorPose) -> Self {
        self.body_p_sensor = Some(pose);
        self
    }

    /// Same parameters with a navigation-frame rotation rate ω_ie [rad/s, navigation frame].
    pub fn with_omega_coriolis(mut self, omega: Vector3<f64>) -> Self {
        self.omega_coriolis = Some(omega);
        self
    }

    /// Same parameters with the bias correction `correction` (`None`: the scheme's default).
    pub fn with_bias_correction(mut self, correction: Option<BiasCorrection>) -> Self {
        self.bias_correction = correction;
        self
    }

    /// The bias correction the measurements carry: `bias_correction`, or the scheme's default
    /// ([`SchemeInfo::bias_correction`](crate::SchemeInfo::bias_correction)).
    pub fn resolved_bias_correction(&self) -> BiasCorrection {
        self.bias_correction
            .unwrap_or(self.scheme.info().bias_correction)
    }

    /// Same parameters with another [`CoriolisMode`].
    pub fn with_coriolis(mut self, mode: CoriolisMode) -> Self {
        self.coriolis = mode;
        self
    }

    /// Checks every field: finite values, symmetric covariances with non-negative diagonals,
    /// positive thresholds and gap.
    pub fn validate(&self) -> Result<(), PreintError> {
        let bad = |name, reason| Err(PreintError::InvalidParameter { name, reason });
        if !self.gravity.iter().all(|x| x.is_finite()) {
            return bad("gravity", "non-finite component");
        }
        if let Some(w) = &self.omega_coriolis
            && !w.iter().all(|x| x.is_finite())
        {
            return bad("omega_coriolis", "non-finite component");
        }
        let covs = [
            ("gyro_cov", Some(&self.gyro_cov)),
            ("acc_cov", Some(&self.acc_cov)),
            ("gyro_bias_rw_cov", Some(&self.gyro_bias_rw_cov)),
            ("acc_bias_rw_cov", Some(&self.acc_bias_rw_cov)),
            ("integration_cov", self.integration_cov.as_ref()),
        ];
        for (name, m) in covs {
            let Some(m) = m else { continue };
            if !m.iter().all(|x| x.is_finite()) {
                return bad(name, "non-finite entry");
            }
            if (0..3).any(|i| m[(i, i)] < 0.0) {
                return bad(name, "negative variance on the diagonal");
            }
            let scale = m.amax().max(f64::MIN_POSITIVE);
            if (m - m.transpose()).amax() > 1e-12 * scale {
                return bad(name, "not symmetric");
            }
        }
        if self.reintegrate_gyro_threshold.is_nan() || self.reintegrate_gyro_threshold <= 0.0 {
            return bad("reintegrate_gyro_threshold", "must be positive");
        }
        if self.reintegrate_acc_threshold.is_nan() || self.reintegrate_acc_threshold <= 0.0 {
            return bad("reintegrate_acc_threshold", "must be positive");
        }
        let td = self.reintegrate_time_offset_threshold;
        if td.is_nan() || td <= 0.0 {
            return bad("reintegrate_time_offset_threshold", "must be positive");
        }
        if let Some(pose) = &self.body_p_sensor
            && !pose.is_valid()
        {
            return bad(
                "body_p_sensor",
                "non-finite entry or rotation not orthonormal",
            );
        }
        if let Some(x) = &self.intrinsics {
            x.model.validate()?;
            if x.jacobians && self.body_p_sensor.is_some() {
                return bad(
                    "intrinsics",
                    "Jacobians with respect to the intrinsics are not supported with body_p_sensor",
                );
            }
        }
        if self.max_gap_ns <= 0 {
            return bad("max_gap_ns", "must be positive");
        }
        Ok(())
    }
}

impl Default for PreintParams {
    /// [`PreintParams::from_noise`] with the EuRoC densities ([`ImuNoise::euroc`]).
    fn default() -> Self {
        Self::from_noise(&ImuNoise::euroc())
    }
}
