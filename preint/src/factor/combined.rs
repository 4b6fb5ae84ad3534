//! [`CombinedImuFactor`]: the 15-dim factor with the bias change over the window.

use super::{CombinedImuFactorJacobians, FactorError, ResidualMode, Weighted};
use crate::choices::Level;
use crate::measurement::PreintegratedImu;
use crate::navstate::NavState;
use crate::sample::ImuBias;
use nalgebra::{Matrix3, SMatrix, SVector};

/// The combined IMU factor between `(NavState_i, NavState_j, b_i, b_j)`: residual
/// `[r_φ, r_v, r_p, b_g,j − b_g,i, b_a,j − b_a,i]` (15-dim; the first nine as in [`ImuFactor`](super::ImuFactor),
/// evaluated with `b_i`), weighted by the covariance of that residual,
/// [`PreintegratedImu::residual_cov15`]: the bias random walk over the window and its
/// correlation with the deltas, with the sign of the residual (the deltas' rows are
/// true ⊖ measured, the bias rows `b_j − b_i`; `cov15` itself is the error state's
/// covariance, measured ⊖ true, and has the opposite delta–bias blocks). GTSAM
/// `CombinedImuFactor` semantics, as weighted by GTSAM 4.3's `residualCovariance()`.
///
/// Jacobians: the first nine rows as in [`ImuFactor`](super::ImuFactor); the bias rows are `−I` w.r.t. `δb_i`
/// and `+I` w.r.t. `δb_j` (additive bias perturbations, order [b_g, b_a]).
#[derive(Clone, Debug, PartialEq)]
pub struct CombinedImuFactor(Weighted<15>);

impl CombinedImuFactor {
    /// Builds the factor; computes the square-root information of
    /// [`pim.residual_cov15()`](PreintegratedImu::residual_cov15).
    ///
    /// Errors: [`FactorError::LevelTooLow`] unless `pim.level` is [`Level::Combined`]; else as
    /// [`ImuFactor::new`](super::ImuFactor::new); a zero bias random walk makes `cov15`
    /// singular ([`FactorError::CovarianceNotPositiveDefinite`] with `dim = 15`).
    pub fn new(pim: PreintegratedImu) -> Result<Self, FactorError> {
        Self::with_mode(pim, ResidualMode::default())
    }

    /// Builds the factor with the given [`ResidualMode`]: the first nine rows of the residual
    /// are those of [`ImuFactor`](super::ImuFactor) in that mode, the bias rows unchanged;
    /// [`ResidualMode::Logmap`] weights with `diag(T, I₆) residual_cov15() diag(T, I₆)ᵀ`
    /// ([`ResidualMode::Logmap`](crate::ResidualMode::Logmap)). Errors as [`new`](Self::new).
    pub fn with_mode(pim: PreintegratedImu, mode: ResidualMode) -> Result<Self, FactorError> {
        let cov = pim.residual_cov15();
        Weighted::new(pim, Level::Combined, "cov15", cov, mode).map(Self)
    }

    /// The residual this factor evaluates.
    pub fn residual_mode(&self) -> ResidualMode {
        self.0.mode
    }

    /// The preintegrated measurement this factor reads.
    pub fn preintegrated(&self) -> &PreintegratedImu {
        &self.0.pim
    }

    /// Square-root information `U` of the residual covariance `Σ_r =`
    /// [`residual_cov15`](PreintegratedImu::residual_cov15) (upper triangular, `Σ_r⁻¹ = UᵀU`),
    /// order [r_φ, r_v, r_p, r_bg, r_ba].
    pub fn sqrt_information(&self) -> &SMatrix<f64, 15, 15> {
        &self.0.sqrt_info
    }

    /// The covariance `Σ_r` that weights the residual: `residual_cov15()` (component-wise) or
    /// `diag(T, I₆) residual_cov15() diag(T, I₆)ᵀ` (Logmap), order [φ, v, p, b_g, b_a].
    pub fn residual_covariance(&self) -> &SMatrix<f64, 15, 15> {
        &self.0.cov
    }

    /// Residual `[r_φ, r_v, r_p, r_bg, r_ba]` (rad, m/s, m, rad/s, m/s²); in
    /// [`ResidualMode::Logmap`] the first nine rows are the SE₂(3) residual.
    pub fn residual(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
    ) -> SVector<f64, 15> {
        self.evaluate(state_i, state_j, bias_i, bias_j).0
    }

    /// Residual and analytic Jacobians (the bias-at-j blocks are filled here).
    pub fn evaluate(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
    ) -> (SVector<f64, 15>, CombinedImuFactorJacobians) {
        let (r9, j9) = self.0.residual9_mode(state_i, state_j, bias_i);
        extend15((r9, j9), bias_i, bias_j)
    }

    /// Residual, Jacobians and `∂r/∂δt_d` [per s] at a time-offset change `dtd_s` \[s\]
    /// relative to the offset the measurement was integrated with (as
    /// [`ImuFactor::evaluate_with_time_offset`](crate::ImuFactor::evaluate_with_time_offset); the
    /// bias rows do not depend on it). With `dtd_s = 0` the residual and blocks are
    /// [`evaluate`](Self::evaluate)'s.
    pub fn evaluate_with_time_offset(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
        dtd_s: f64,
    ) -> (
        SVector<f64, 15>,
        CombinedImuFactorJacobians,
        SVector<f64, 15>,
    ) {
        let (r9, j9, c9) = self.0.residual9_mode_td(state_i, state_j, bias_i, dtd_s);
        let (r, j) = extend15((r9, j9), bias_i, bias_j);
        let mut col = SVector::<f64, 15>::zeros();
        col.fixed_rows_mut::<9>(0).copy_from(&c9);
        (r, j, col)
    }

    /// Whitened residual `U r` and Jacobians `U J`.
    pub fn evaluate_whitened(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
    ) -> (SVector<f64, 15>, CombinedImuFactorJacobians) {
        self.0
            .whiten(self.evaluate(state_i, state_j, bias_i, bias_j))
    }

    /// `rᵀ Σ_r⁻¹ r` with `Σ_r` = [`residual_cov15`](PreintegratedImu::residual_cov15) (χ² with
    /// 15 dof).
    pub fn chi2(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
    ) -> f64 {
        self.0
            .chi2(&self.residual(state_i, state_j, bias_i, bias_j))
    }

    /// `½ chi2`.
    pub fn cost(
        &self,
        state_i: &NavState,
        state_j: &NavState,
        bias_i: &ImuBias,
        bias_j: &ImuBias,
    ) -> f64 {
        0.5 * self.chi2(state_i, state_j, bias_i, bias_j)
    }
}

/// The 15-dim residual and Jacobians from the 9-dim ones: bias rows `b_j − b_i`.
fn extend15(
    (r9, j9): (SVector<f64, 9>, crate::ImuFactorJacobians),
    bias_i: &ImuBias,
    bias_j: &ImuBias,
) -> (SVector<f64, 15>, CombinedImuFactorJacobians) {
    let mut r = SVector::<f64, 15>::zeros();
    r.fixed_rows_mut::<9>(0).copy_from(&r9);
    r.fixed_rows_mut::<3>(9)
        .copy_from(&(bias_j.gyro - bias_i.gyro));
    r.fixed_rows_mut::<3>(12)
        .copy_from(&(bias_j.acc - bias_i.acc));
    let ext = |m: &SMatrix<f64, 9, 3>| {
        let mut o = SMatrix::<f64, 15, 3>::zeros();
        o.fixed_rows_mut::<9>(0).copy_from(m);
        o
    };
    let id = Matrix3::identity();
    let mut j = CombinedImuFactorJacobians {
        phi_i: ext(&j9.phi_i),
        p_i: ext(&j9.p_i),
        v_i: ext(&j9.v_i),
        phi_j: ext(&j9.phi_j),
        p_j: ext(&j9.p_j),
        v_j: ext(&j9.v_j),
        bg_i: ext(&j9.bg_i),
        ba_i: ext(&j9.ba_i),
        bg_j: SMatrix::zeros(),
        ba_j: SMatrix::zeros(),
    };
    j.bg_i.fixed_view_mut::<3, 3>(9, 0).copy_from(&(-id));
    j.ba_i.fixed_view_mut::<3, 3>(12, 0).copy_from(&(-id));
    j.bg_j.fixed_view_mut::<3, 3>(9, 0).copy_from(&id);
    j.ba_j.fixed_view_mut::<3, 3>(12, 0).copy_from(&id);
    (r, j)
}
