//! The preintegrated measurement ([`PreintegratedImu`], whose documentation gives its chart
//! and bias Jacobians) and its blocks.

use crate::choices::BiasCorrection;
use crate::choices::CoriolisMode;
use crate::choices::Level;
use crate::edges::EdgeNoise;
use crate::error::PreintError;
use crate::sample::ImuBias;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use preint_lie::SO3;

/// 9×9 covariance of the preintegration error, order [δφ, δv, δp].
pub type Cov9 = SMatrix<f64, 9, 9>;
/// 15×15 covariance, order [δφ, δv, δp, δb_g, δb_a].
pub type Cov15 = SMatrix<f64, 15, 15>;

/// `D M D` with `D = diag(−I₉, I₆)`: the 9×6 and 6×9 blocks of `m` negated, the 9×9 and 6×6
/// blocks kept. Maps the covariance of `[δ, δb]` to that of `[−δ, δb]` and back.
pub fn negate_delta_bias_blocks(m: &Cov15) -> Cov15 {
    let mut out = *m;
    for r in 0..9 {
        for c in 9..15 {
            out[(r, c)] = -m[(r, c)];
            out[(c, r)] = -m[(c, r)];
        }
    }
    out
}

/// The five bias Jacobians of the preintegrated deltas (Forster eq. 44), evaluated at
/// `bias_hat`. Units: ∂ΔR/∂b_g [rad/(rad/s)] = \[s\], ∂Δv/∂b_g [m/s/(rad/s)], ∂Δv/∂b_a \[s\],
/// ∂Δp/∂b_g [m/(rad/s)], ∂Δp/∂b_a \[s²\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasJacobians {
    /// ∂ΔR/∂b_g (right perturbation of ΔR).
    pub d_r_d_bg: Matrix3<f64>,
    /// ∂Δv/∂b_g.
    pub d_v_d_bg: Matrix3<f64>,
    /// ∂Δv/∂b_a.
    pub d_v_d_ba: Matrix3<f64>,
    /// ∂Δp/∂b_g.
    pub d_p_d_bg: Matrix3<f64>,
    /// ∂Δp/∂b_a.
    pub d_p_d_ba: Matrix3<f64>,
}

impl BiasJacobians {
    /// The five blocks as one 9×6 matrix: rows [δφ, δv, δp] (the chart of this module),
    /// columns [b_g, b_a]; the rotation rows' accelerometer block is zero.
    pub fn as_matrix(&self) -> SMatrix<f64, 9, 6> {
        let mut m = SMatrix::<f64, 9, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.d_r_d_bg);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.d_v_d_bg);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.d_v_d_ba);
        m.fixed_view_mut::<3, 3>(6, 0).copy_from(&self.d_p_d_bg);
        m.fixed_view_mut::<3, 3>(6, 3).copy_from(&self.d_p_d_ba);
        m
    }

    /// The blocks of a 9×6 matrix laid out as [`as_matrix`](Self::as_matrix)'s (its rotation
    /// rows' accelerometer block is not read).
    pub fn from_matrix(m: &SMatrix<f64, 9, 6>) -> Self {
        let b = |i, j| -> Matrix3<f64> { m.fixed_view::<3, 3>(i, j).into_owned() };
        Self {
            d_r_d_bg: b(0, 0),
            d_v_d_bg: b(3, 0),
            d_v_d_ba: b(3, 3),
            d_p_d_bg: b(6, 0),
            d_p_d_ba: b(6, 3),
        }
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        [
            &self.d_r_d_bg,
            &self.d_v_d_bg,
            &self.d_v_d_ba,
            &self.d_p_d_bg,
            &self.d_p_d_ba,
        ]
        .iter()
        .all(|m| m.iter().all(|x| x.is_finite()))
    }
}

impl Default for BiasJacobians {
    fn default() -> Self {
        let z = Matrix3::zeros();
        Self {
            d_r_d_bg: z,
            d_v_d_bg: z,
            d_v_d_ba: z,
            d_p_d_bg: z,
            d_p_d_ba: z,
        }
    }
}

/// A preintegrated IMU measurement between keyframes i and j (times `t_i_ns`, `t_j_ns`).
///
/// `delta_v` and `delta_p` are in body frame i and exclude gravity (Forster eq. 33):
/// `R_j = R_i ΔR`, `v_j = v_i + gΔt + R_i Δv`, `p_j = p_i + v_iΔt + ½gΔt² + R_i Δp` in a
/// non-rotating world frame; with `omega_coriolis` set, [`crate::earth`] gives the prediction.
///
/// # Chart
///
/// Forster et al. 2017, eqs. 38–44: with `ΔR, Δv, Δp` the values integrated from noisy
/// samples and `ΔR°, Δv°, Δp°` those of noise-free samples (same bias estimate),
/// `ΔR = ΔR°·Exp(δφ)`, `Δv = Δv° + δv`, `Δp = Δp° + δp`, all expressed in body frame *i*.
/// The covariance is that of **[δφ, δv, δp]** (rad, m/s, m), in this order.
///
/// Bias Jacobians are w.r.t. the bias estimate `bias_hat` used during integration, bias order
/// **[b_g, b_a]**: for a new bias `b = bias_hat + δb`,
/// `ΔR(b) ≈ ΔR·Exp(∂ΔR/∂b_g·δb_g)`, `Δv(b) ≈ Δv + ∂Δv/∂b_g·δb_g + ∂Δv/∂b_a·δb_a`, and
/// `Δp(b)` likewise (Forster eq. 44).
#[derive(Clone, Debug, PartialEq)]
pub struct PreintegratedImu {
    /// Keyframe i time \[ns\].
    pub t_i_ns: i64,
    /// Keyframe j time \[ns\].
    pub t_j_ns: i64,
    /// Δt = t_j − t_i \[s\].
    pub delta_t: f64,
    /// ΔR_ij (rotation from body j to body i).
    pub delta_r: SO3,
    /// Δv_ij [m/s], frame i.
    pub delta_v: Vector3<f64>,
    /// Δp_ij \[m\], frame i.
    pub delta_p: Vector3<f64>,
    /// Covariance of [δφ, δv, δp] (white measurement noise, plus integration noise if set).
    pub cov: Cov9,
    /// Covariance of the error state `[δφ, δv, δp, δb_g, δb_a]` including the bias random walk
    /// over the window: `[δφ, δv, δp]` = measured ⊖ true deltas (the chart of this module, as
    /// `cov`) and `δb = b_j − b_i` [rad/s, m/s²]. A gyro bias that drifts up makes the
    /// measured rotation run ahead, so the delta–bias blocks are those of this error, **not**
    /// of a factor residual (which is true ⊖ measured for the deltas): weight a residual with
    /// [`residual_cov15`](Self::residual_cov15). This is what [`merge`](crate::merge()) composes, and equals
    /// GTSAM 4.3's `PreintegratedCombinedMeasurements::preintMeasCov()` after reordering to
    /// [rot, pos, vel, b_a, b_g] and rotating the pos and vel blocks by `ΔRᵀ` (GTSAM's
    /// `NavState` chart; `preint/tests/combined_gtsam.rs`).
    pub cov15: Cov15,
    /// Bias Jacobians at `bias_hat`.
    pub jac: BiasJacobians,
    /// `∂[δφ, δv, δp]/∂t_d` [rad/s, m/s², m/s]: the deltas' derivative with respect to the
    /// IMU–keyframe time offset, both window ends moving (`t_imu = t_cam + t_d`;
    /// [`crate::time_offset`]), at the offset the window was integrated with. Zero when
    /// unknown (at [`Level::Deltas`], with a lever arm removed in closed form, hand-made).
    pub jac_td: SVector<f64, 9>,
    /// Bias estimate used for integration.
    pub bias_hat: ImuBias,
    /// Gravity vector in the world frame [m/s²] (default (0, 0, −9.81)).
    pub gravity: Vector3<f64>,
    /// Rotation rate of the navigation frame ω_ie [rad/s, navigation frame] that prediction
    /// and the factors account for (`None`: a non-rotating frame). See [`crate::earth`].
    pub omega_coriolis: Option<Vector3<f64>>,
    /// How `omega_coriolis` enters prediction and the factors (ignored when it is `None`).
    pub coriolis: CoriolisMode,
    /// What was computed: [`Level::Deltas`] (covariances and Jacobians zero),
    /// [`Level::Covariance`] (`cov`, `jac`; `cov15` is `diag(cov, Σ_bg Δt, Σ_ba Δt)` without
    /// the random walk's effect on the deltas, so it must not weight a combined factor) or
    /// [`Level::Combined`] (everything).
    pub level: Level,
    /// The noise sources near the window edges and their gains (for exact merging).
    pub edge_noise: EdgeNoise,
    /// How [`corrected`](Self::corrected) (and so [`predict`](crate::predict) and the factors)
    /// applies the first-order bias correction: the resolved
    /// [`PreintParams::bias_correction`](crate::PreintParams::bias_correction).
    pub bias_correction: BiasCorrection,
}

impl PreintegratedImu {
    /// This measurement's deltas minus `reference`'s, in the covariance's tangent order
    /// [δφ, δv, δp]: `[Log(ΔR_refᵀ ΔR), Δv − Δv_ref [m/s], Δp − Δp_ref [m]]` (right
    /// perturbation of ΔR, as `cov`). With `reference` the noise-free preintegration of the same
    /// window, this is the error whose covariance `cov` predicts.
    pub fn delta_error(&self, reference: &PreintegratedImu) -> SVector<f64, 9> {
        let r = self.delta_r.minus(&reference.delta_r);
        let v = self.delta_v - reference.delta_v;
        let p = self.delta_p - reference.delta_p;
        SVector::<f64, 9>::from_column_slice(&[r.x, r.y, r.z, v.x, v.y, v.z, p.x, p.y, p.z])
    }

    /// Covariance of the residual of [`CombinedImuFactor`](crate::CombinedImuFactor),
    /// `r = [r_φ, r_v, r_p, b_g,j − b_g,i, b_a,j − b_a,i]`, at the true states.
    ///
    /// To first order `[r_φ, r_v, r_p] = −[δφ, δv, δp]` (the factor compares the true relative
    /// motion with the measured one: `r_φ = Log(ΔRᵀ R_iᵀR_j) = Log(Exp(−δφ))`) while the bias
    /// rows are `+δb`, so with `D = diag(−I₉, I₆)` this is `D·cov15·D`: `cov15` with its 9×6
    /// and 6×9 delta–bias blocks negated. The 9×9 block is `cov15`'s (the sign of a whole
    /// vector does not change its covariance), and `cov` is likewise the covariance of
    /// [`ImuFactor`](crate::ImuFactor)'s residual. GTSAM 4.3's combined factor residual is
    /// `[e, b_i − b_j]` with `e ≈ +δ` in its chart: its `residualCovariance()` is this matrix
    /// after the reordering and rotation described at [`cov15`](Self::cov15).
    pub fn residual_cov15(&self) -> Cov15 {
        negate_delta_bias_blocks(&self.cov15)
    }

    /// Whether the deltas can be corrected to `bias`: always for a measurement with bias
    /// Jacobians ([`Level::Covariance`], [`Level::Combined`]); at [`Level::Deltas`], whose
    /// Jacobians are zero, only for `bias == bias_hat` exactly (δb = 0, no correction), and
    /// otherwise [`PreintError::NoBiasJacobians`]: a first-order correction with zero
    /// Jacobians would return the deltas of `bias_hat` as if they were those of `bias`.
    /// Costs one comparison of the level for a measurement with Jacobians.
    ///
    /// Every function that corrects for a bias checks it: [`corrected`](Self::corrected),
    /// [`corrected_with_time_offset`](Self::corrected_with_time_offset) and
    /// [`predict`](crate::predict) panic, [`try_corrected`](Self::try_corrected) and
    /// [`try_predict`](crate::try_predict) return the error,
    /// [`Preintegrator::measurement_for_bias`](crate::Preintegrator::measurement_for_bias)
    /// re-integrates (or returns the error without stored samples). The factors need a
    /// covariance, so they refuse a [`Level::Deltas`] measurement when they are built
    /// ([`FactorError::LevelTooLow`](crate::FactorError::LevelTooLow)) and always have
    /// Jacobians.
    #[inline]
    pub fn check_bias(&self, bias: &ImuBias) -> Result<(), PreintError> {
        if self.level == Level::Deltas && *bias != self.bias_hat {
            return Err(self.no_bias_jacobians(bias));
        }
        Ok(())
    }

    #[cold]
    fn no_bias_jacobians(&self, bias: &ImuBias) -> PreintError {
        PreintError::NoBiasJacobians {
            bias: *bias,
            bias_hat: self.bias_hat,
        }
    }

    /// Panics with the message of [`check_bias`](Self::check_bias)'s error.
    #[inline]
    pub(crate) fn assert_bias(&self, bias: &ImuBias) {
        if let Err(e) = self.check_bias(bias) {
            panic!("{e}");
        }
    }
}
