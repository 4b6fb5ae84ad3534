//! [`ImuFactor`]: the 9-dim factor between two navigation states and the bias at i.

use super::{FactorError, ImuFactorJacobians, ResidualMode, Weighted};
use crate::choices::Level;
use crate::measurement::PreintegratedImu;
use crate::navstate::{NavState, predict};
use crate::sample::ImuBias;
use nalgebra::{SMatrix, SVector};

/// Forster's IMU factor between `(NavState_i, NavState_j, bias_i)` (module docs for the
/// residual [r_φ, r_v, r_p], perturbations and Jacobians). It reads only a
/// [`PreintegratedImu`] and weights the residual with its 9×9 covariance `cov` (the residual
/// is `−[δφ, δv, δp]` to first order, whose covariance is `cov`); in
/// [`ResidualMode::Logmap`] (the default) the residual is its SE₂(3) form and the weight
/// `T cov Tᵀ` ([`logmap`](super::logmap)). The bias is held constant
/// over the window: on data whose bias drifts noticeably within a window, use
/// [`CombinedImuFactor`](super::CombinedImuFactor), whose covariance includes the random walk.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuFactor(Weighted<9>);

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
    /// residual by `T cov Tᵀ` ([`logmap`](super::logmap) module docs). Errors as [`new`](Self::new).
    pub fn with_mode(pim: PreintegratedImu, mode: ResidualMode) -> Result<Self, FactorError> {
        let cov = pim.cov;
        Weighted::new(pim, Level::Covariance, "cov", cov, mode).map(Self)
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

    /// Residual and its analytic Jacobians (blocks and perturbations in the module docs).
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
    /// [`crate::time_offset`], and the module docs): the deltas corrected by
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
