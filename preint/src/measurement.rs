//! The preintegrated measurement: what a preintegrator produces and what a factor reads.
//!
//! Chart (Forster et al. 2017, eqs. 38–44): with `ΔR, Δv, Δp` the values integrated from noisy
//! samples and `ΔR°, Δv°, Δp°` those of noise-free samples (same bias estimate),
//! `ΔR = ΔR°·Exp(δφ)`, `Δv = Δv° + δv`, `Δp = Δp° + δp`, all expressed in body frame *i*.
//! The covariance is that of **[δφ, δv, δp]** (rad, m/s, m), in this order.
//!
//! Bias Jacobians are w.r.t. the bias estimate `bias_hat` used during integration, bias order
//! **[b_g, b_a]**: for a new bias `b = bias_hat + δb`,
//! `ΔR(b) ≈ ΔR·Exp(∂ΔR/∂b_g·δb_g)`, `Δv(b) ≈ Δv + ∂Δv/∂b_g·δb_g + ∂Δv/∂b_a·δb_a`, and
//! `Δp(b)` likewise (Forster eq. 44).

use crate::sample::ImuBias;
use lie::SO3;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// 9×9 covariance of the preintegration error, order [δφ, δv, δp].
pub type Cov9 = SMatrix<f64, 9, 9>;
/// 15×15 covariance, order [δφ, δv, δp, δb_g, δb_a].
pub type Cov15 = SMatrix<f64, 15, 15>;

/// The five bias Jacobians of the preintegrated deltas (Forster eq. 44), evaluated at
/// `bias_hat`. Units: ∂ΔR/∂b_g [rad/(rad/s)] = [s], ∂Δv/∂b_g [m/s/(rad/s)], ∂Δv/∂b_a [s],
/// ∂Δp/∂b_g [m/(rad/s)], ∂Δp/∂b_a [s²].
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
/// `R_j = R_i ΔR`, `v_j = v_i + gΔt + R_i Δv`, `p_j = p_i + v_iΔt + ½gΔt² + R_i Δp`.
#[derive(Clone, Debug, PartialEq)]
pub struct PreintegratedImu {
    /// Keyframe i time [ns].
    pub t_i_ns: i64,
    /// Keyframe j time [ns].
    pub t_j_ns: i64,
    /// Δt = t_j − t_i [s].
    pub delta_t: f64,
    /// ΔR_ij (rotation from body j to body i).
    pub delta_r: SO3,
    /// Δv_ij [m/s], frame i.
    pub delta_v: Vector3<f64>,
    /// Δp_ij [m], frame i.
    pub delta_p: Vector3<f64>,
    /// Covariance of [δφ, δv, δp] (white measurement noise, plus integration noise if set).
    pub cov: Cov9,
    /// Covariance of [δφ, δv, δp, δb_g, δb_a] including the bias random walk over the window
    /// (`δb = b_j − b_i`), for a combined factor.
    pub cov15: Cov15,
    /// Bias Jacobians at `bias_hat`.
    pub jac: BiasJacobians,
    /// Bias estimate used for integration.
    pub bias_hat: ImuBias,
    /// Gravity vector in the world frame [m/s²] (default (0, 0, −9.81)).
    pub gravity: Vector3<f64>,
}

impl PreintegratedImu {
    /// Deltas corrected to first order for a new bias estimate `bias` (Forster eq. 44):
    /// `ΔR·Exp(∂ΔR/∂b_g δb_g)`, `Δv + ∂Δv/∂b_g δb_g + ∂Δv/∂b_a δb_a`, `Δp + …`, with
    /// `δb = bias − bias_hat`. Returns `(ΔR(b), Δv(b) [m/s], Δp(b) [m])`.
    pub fn corrected(&self, bias: &ImuBias) -> (SO3, Vector3<f64>, Vector3<f64>) {
        let dbg = bias.gyro - self.bias_hat.gyro;
        let dba = bias.acc - self.bias_hat.acc;
        let j = &self.jac;
        (
            self.delta_r.plus(&(j.d_r_d_bg * dbg)),
            self.delta_v + j.d_v_d_bg * dbg + j.d_v_d_ba * dba,
            self.delta_p + j.d_p_d_bg * dbg + j.d_p_d_ba * dba,
        )
    }
}
