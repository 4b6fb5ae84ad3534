//! [`ImuFactor`]: the 9-dim factor between two navigation states and the bias at i.

use super::{FactorError, ImuFactorJacobians, ResidualMode, Weighted};
use crate::choices::Level;
use crate::measurement::PreintegratedImu;
use crate::navstate::{NavState, predict};
use crate::sample::ImuBias;
use nalgebra::{SMatrix, SVector};

/// Forster's IMU factor between `(NavState_i, NavState_j, bias_i)` (below: the residual
/// [r_φ, r_v, r_p], its perturbations and Jacobians). It reads only a
/// [`PreintegratedImu`] and weights the residual with its 9×9 covariance `cov` (the residual
/// is `−[δφ, δv, δp]` to first order, whose covariance is `cov`); in
/// [`ResidualMode::Logmap`] (the default) the residual is its SE₂(3) form and the weight
/// `T cov Tᵀ` ([`ResidualMode::Logmap`](crate::ResidualMode::Logmap)). The bias is held constant
/// over the window: on data whose bias drifts noticeably within a window, use
/// [`CombinedImuFactor`](super::CombinedImuFactor), whose covariance includes the random walk.
///
/// Each factor evaluates one of two residuals ([`ResidualMode`], set when it is built): the
/// SE₂(3) **Logmap** residual ([`ResidualMode::Logmap`](crate::ResidualMode::Logmap), the default, as in GTSAM 4.3, chosen on NEES
/// evidence) or Forster's **component-wise** residual below. The Logmap one is computed from the
/// component-wise residual and Jacobians described here.
///
/// # Residual (Forster et al. 2017, T-RO, eq. 45)
///
/// With `ΔR(b), Δv(b), Δp(b)` the deltas corrected to first order for the bias `b` at keyframe i
/// ([`PreintegratedImu::corrected`]: eq. 44, or on the group for
/// [`BiasCorrection::Group`](crate::BiasCorrection::Group)), `g` the world gravity and
/// `Δt = t_j − t_i`:
///
/// ```text
/// r_φ = Log(ΔR(b)ᵀ R_iᵀ R_j)                                   [rad]
/// r_v = R_iᵀ (v_j − v_i − g Δt) − Δv(b)                        [m/s]
/// r_p = R_iᵀ (p_j − p_i − v_i Δt − ½ g Δt²) − Δp(b)            [m]
/// ```
///
/// in the order **[r_φ, r_v, r_p]**, the order of the preintegration covariance
/// [δφ, δv, δp] (see [`PreintegratedImu`](crate::PreintegratedImu)), so `rᵀ Σ⁻¹ r` is the Mahalanobis cost.
///
/// # Perturbations (one per Jacobian block)
///
/// Each block `∂r/∂δx` is the derivative at `δx = 0` of `r(x ⊕ δx)`, with ([`NavState`](crate::NavState)):
///
/// | block | perturbation |
/// |---|---|
/// | `phi_i`, `phi_j` | `R ← R·Exp(δφ)` (right, body frame) \[rad\] |
/// | `p_i`, `p_j` | `p ← p + R·δp` (body frame — to first order GTSAM's `Pose3` retract `[dw, dt]`, `dt` in body) \[m\] |
/// | `v_i`, `v_j` | `v ← v + δv` (world frame, GTSAM's `ImuFactor` velocity) [m/s] |
/// | `bg_i`, `ba_i` | `b_g,i ← b_g,i + δb_g` [rad/s], `b_a,i ← b_a,i + δb_a` [m/s²] |
/// | `bg_j`, `ba_j` | same for the bias at j (combined factor only; zero in [`ImuFactor`]) |
///
/// Analytic blocks (Forster 2017, supplementary material, Sec. "Jacobians of the residual"),
/// with `E = Exp(r_φ)`, `Jr⁻¹ = Jr⁻¹(r_φ)`, `δb_g = b_g − b̂_g` (w.r.t. the integration bias
/// `bias_hat`) and `J_R^g = ∂ΔR/∂b_g` etc.:
///
/// ```text
/// ∂r_φ/∂δφ_i = −Jr⁻¹ R_jᵀ R_i          ∂r_φ/∂δφ_j = Jr⁻¹
/// ∂r_φ/∂δb_g = −Jr⁻¹ Eᵀ Jr(J_R^g δb_g) J_R^g
/// ∂r_v/∂δφ_i = [R_iᵀ (v_j − v_i − g Δt)]×
/// ∂r_v/∂δv_i = −R_iᵀ   ∂r_v/∂δv_j = R_iᵀ   ∂r_v/∂δb_g = −J_v^g   ∂r_v/∂δb_a = −J_v^a
/// ∂r_p/∂δφ_i = [R_iᵀ (p_j − p_i − v_i Δt − ½ g Δt²)]×
/// ∂r_p/∂δp_i = −I   ∂r_p/∂δv_i = −R_iᵀ Δt   ∂r_p/∂δp_j = R_iᵀ R_j
/// ∂r_p/∂δb_g = −J_p^g   ∂r_p/∂δb_a = −J_p^a
/// ```
///
/// (with [`BiasCorrection::Group`](crate::BiasCorrection::Group), `J_v`, `J_p` in the velocity
/// and position rows are the derivatives of the group-corrected `Δv(b)`, `Δp(b)`,
/// [`BiasCorrection`](crate::BiasCorrection)); all other blocks are zero. Every block is checked against central differences on the
/// manifold in `preint/tests/factor.rs` (both bias corrections). With an Earth rate (`pim.omega_coriolis`) the residual
/// compares the deltas the states imply in the rotating frame instead (`rotating.rs`, each
/// [`CoriolisMode`](crate::CoriolisMode); Jacobians checked in `preint/tests/earth.rs`); its
/// covariance is the same.
///
/// # Time offset
///
/// `evaluate_with_time_offset` (both factors) evaluates the residual at a change `δt_d` \[s\]
/// of the IMU–keyframe time offset relative to the one the measurement was integrated with
/// ([`crate::time_offset`]): the deltas corrected by `J_b δb + J_td δt_d` in the measurement's
/// bias correction, every Jacobian block at that point, and the column `∂r/∂δt_d`
/// (`[−Jr⁻¹(r_φ) Eᵀ Jr(c_φ) j_φ, −∂Δv(b)/∂t_d, −∂Δp(b)/∂t_d]`, mapped to the Logmap chart as the
/// gyro-bias columns are). At `δt_d = 0` the residual and blocks are those of `evaluate`.
/// Checked against central differences in `preint/tests/time_offset_factor.rs`.
///
/// # Whitening
///
/// The square-root information `U` is the **upper** Cholesky factor of `Σ⁻¹` (`Σ⁻¹ = UᵀU`,
/// positive diagonal; GTSAM's `noiseModel::Gaussian` convention). It is computed without
/// forming `Σ⁻¹`: with `P` the order-reversing permutation, `P Σ P = L Lᵀ` and `U = P L⁻¹ P`.
/// Whitened residual `U r`, whitened Jacobians `U J`, and `chi2 = ‖U r‖² = rᵀ Σ⁻¹ r`.
///
/// # Relation to GTSAM (`ImuFactor`, `ImuFactorErrorMode::ComponentWise`)
///
/// GTSAM's error is `e = [Log(R_jᵀ R̂_j), R_jᵀ(p̂_j − p_j), R_jᵀ(v̂_j − v_j)]` in the order
/// [rot, pos, vel] with `(R̂_j, p̂_j, v̂_j)` = [`predict`](crate::predict). Hence, with `M = R_jᵀ R_i`,
/// `e_rot = −r_φ`, `e_pos = −M r_p`, `e_vel = −M r_v`, i.e.
/// `r = −diag(I, Mᵀ, Mᵀ) e` after reordering. Jacobians map as
/// `∂e/∂x = −diag(I, M, M)·∂r/∂x` except for the rotations, which also move `M`:
/// `∂e_{pos,vel}/∂δφ_i += M [r_{p,v}]×` and `∂e_{pos,vel}/∂δφ_j −= [M r_{p,v}]×`; GTSAM's bias
/// order is [b_a, b_g]. Tested against GTSAM 4.3 fixtures in `preint/tests/factor_gtsam.rs`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuFactor(Weighted<9>, bool);

impl ImuFactor {
    /// Builds the factor; computes the square-root information of `pim.cov`.
    ///
    /// Errors: [`FactorError::LevelTooLow`] for a [`Level::Deltas`] measurement,
    /// [`FactorError::NonFinite`], [`FactorError::NonPositiveDeltaT`],
    /// [`FactorError::CovarianceNotPositiveDefinite`] (e.g. a noise-free preintegration).
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use preint::{ImuBias, ImuFactor, ImuSample, NavState, PreintParams, Preintegrator};
    /// let mut pi = Preintegrator::new(PreintParams::default(), ImuBias::zero()).unwrap();
    /// for k in 0..201i64 {
    ///     let s = ImuSample::new(k * 5_000_000, Vector3::new(0.0, 0.0, 0.2), Vector3::new(0.0, 0.0, 9.81));
    ///     pi.integrate(&s).unwrap();
    /// }
    /// let factor = ImuFactor::new(pi.finish().unwrap()).unwrap();
    /// // At the state the measurement predicts, the residual is zero.
    /// let xi = NavState::identity();
    /// let xj = factor.predict(&xi, &ImuBias::zero());
    /// assert!(factor.residual(&xi, &xj, &ImuBias::zero()).amax() < 1e-12);
    /// // A 1 cm error in the position at j costs χ² = (0.01 / σ_p)² along that axis.
    /// let mut off = xj;
    /// off.p.x += 0.01;
    /// assert!(factor.chi2(&xi, &off, &ImuBias::zero()) > 1.0);
    /// ```
    pub fn new(pim: PreintegratedImu) -> Result<Self, FactorError> {
        Self::with_mode(pim, ResidualMode::default())
    }

    /// Builds the factor with the given [`ResidualMode`]: [`ResidualMode::ComponentWise`]
    /// weights `[r_φ, r_v, r_p]` by `pim.cov`, [`ResidualMode::Logmap`] weights the SE₂(3)
    /// residual by `T cov Tᵀ` ([`ResidualMode::Logmap`](crate::ResidualMode::Logmap)). Errors as [`new`](Self::new).
    pub fn with_mode(pim: PreintegratedImu, mode: ResidualMode) -> Result<Self, FactorError> {
        let cov = pim.cov;
        Weighted::new(pim, Level::Covariance, "cov", cov, mode).map(|w| Self(w, false))
    }

    /// Builds the factor weighted by the covariance of its residual when the true bias drifts
    /// within the window as the parameters' bias random walk says, while the factor holds it at
    /// its value at i: the [δφ, δv, δp] block of `pim.cov15` (`cov` plus the drift's effect on
    /// the deltas, the 9×9 marginal of the combined propagation of Forster et al. 2017, App. C).
    /// [`new`](Self::new) weights by `cov` alone, as GTSAM's `ImuFactor` does, which is
    /// optimistic by that drift on windows of seconds. Needs a [`Level::Combined`] measurement;
    /// otherwise errors as [`new`](Self::new).
    pub fn with_in_window_drift(
        pim: PreintegratedImu,
        mode: ResidualMode,
    ) -> Result<Self, FactorError> {
        let cov = pim.cov15.fixed_view::<9, 9>(0, 0).into_owned();
        Weighted::new(pim, Level::Combined, "cov15", cov, mode).map(|w| Self(w, true))
    }

    /// Whether the weight includes the in-window bias drift
    /// ([`with_in_window_drift`](Self::with_in_window_drift)).
    pub fn in_window_drift(&self) -> bool {
        self.1
    }

    /// The residual this factor evaluates.
    pub fn residual_mode(&self) -> ResidualMode {
        self.0.mode
    }

    /// The preintegrated measurement this factor reads.
    pub fn preintegrated(&self) -> &PreintegratedImu {
        &self.0.pim
    }

    /// Square-root information `U` (upper triangular, `Σ⁻¹ = UᵀU`), order [δφ, δv, δp], of
    /// `Σ = cov` (component-wise) or `T cov Tᵀ` (Logmap).
    pub fn sqrt_information(&self) -> &SMatrix<f64, 9, 9> {
        &self.0.sqrt_info
    }

    /// The covariance `Σ` that weights the residual: `cov` (component-wise) or `T cov Tᵀ`
    /// (Logmap), order [φ, v, p].
    pub fn residual_covariance(&self) -> &SMatrix<f64, 9, 9> {
        &self.0.cov
    }

    /// Predicted state at j ([`predict`], Forster eq. 33) for the bias `bias_i`.
    pub fn predict(&self, state_i: &NavState, bias_i: &ImuBias) -> NavState {
        predict(&self.0.pim, state_i, bias_i)
    }

    /// Residual `r = [r_φ [rad], r_v [m/s], r_p [m]]` (Forster eq. 45 with eq. 44 bias
    /// correction), or its SE₂(3) form `Log(D(b)⁻¹ Y)` for [`ResidualMode::Logmap`].
    /// Non-finite states give non-finite residuals (no panic).
    pub fn residual(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
    ) -> SVector<f64, 9> {
        self.evaluate(state_i, state_j, bias_i).0
    }

    /// Residual and its analytic Jacobians (blocks and perturbations in [`ImuFactor`]'s
    /// documentation).
    pub fn evaluate(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
    ) -> (SVector<f64, 9>, ImuFactorJacobians) {
        self.0.residual9_mode(state_i, state_j, bias_i)
    }

    /// Residual, Jacobians and `∂r/∂δt_d` [per s] at a time-offset change `dtd_s` \[s\] relative
    /// to the offset the measurement was integrated with (`t_imu = t_cam + t_d`;
    /// [`crate::time_offset`], and [`ImuFactor`]'s documentation): the deltas corrected by
    /// `J_b δb + J_td δt_d` ([`PreintegratedImu::corrected_with_time_offset`]). With
    /// `dtd_s = 0` the residual and blocks are [`evaluate`](Self::evaluate)'s.
    pub fn evaluate_with_time_offset(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        dtd_s: f64,
    ) -> (SVector<f64, 9>, ImuFactorJacobians, SVector<f64, 9>) {
        self.0.residual9_mode_td(state_i, state_j, bias_i, dtd_s)
    }

    /// Whitened residual `U r` and Jacobians `U J` (`U` = [`sqrt_information`](Self::sqrt_information)).
    pub fn evaluate_whitened(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
    ) -> (SVector<f64, 9>, ImuFactorJacobians) {
        self.0.whiten(self.evaluate(state_i, state_j, bias_i))
    }

    /// Squared Mahalanobis norm `rᵀ Σ⁻¹ r = ‖U r‖²` (dimensionless; χ² with 9 dof).
    pub fn chi2(&self, state_i: &NavState, state_j: &NavState, bias_i: &ImuBias) -> f64 {
        self.0.chi2(&self.residual(state_i, state_j, bias_i))
    }

    /// Least-squares cost `½ chi2` (GTSAM's `NonlinearFactor::error`).
    pub fn cost(&self, state_i: &NavState, state_j: &NavState, bias_i: &ImuBias) -> f64 {
        0.5 * self.chi2(state_i, state_j, bias_i)
    }
}
