//! `gimbal-lock`: the body passes exactly through ZYX pitch ±90° while also turning in the
//! direction that ZYX Euler rates cannot represent there.

use crate::scene::{Scene, SceneState};
use lie::SO3;
use nalgebra::Vector3;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_8, SQRT_2};

/// `gimbal-lock`: the body pitches through the vertical while rolling about the world x axis.
///
/// ```text
/// R_wb(t) = Rx(α(t))·Ry(β(t))
/// β(t) = A sin(πt/8),  A = π/√2 ≈ 2.221 rad (127°)   so β = ±π/2 exactly at t = 2, 6, 10, 14 s
/// α(t) = −0.5 cos(πt/4)                              so α = 0 at the same instants
/// ω_b = Ry(β)ᵀ(α̇, 0, 0) + (0, β̇, 0) = (α̇ cos β, β̇, α̇ sin β)
/// ω̇_b = (α̈ cos β − α̇β̇ sin β, β̈, α̈ sin β + α̇β̇ cos β)
/// p(t) = (2 sin 0.5t, 2 cos 0.5t, 0.3 sin t) m
/// ```
///
/// The ZYX pitch of this attitude is `asin(cos α · sin β)`: it reaches exactly ±90° at
/// t = 2, 6, 10, 14 s (period 16 s), and only there. At those instants the body rate has the
/// component `α̇ sin β = ±π/8 rad/s` along `(0, sin φ, cos φ)`, the direction outside the range
/// of the Euler-rate→body-rate matrix `W(φ, ±π/2)`: the canonical ZYX roll and yaw jump by π
/// there. Quaternion and matrix integrators notice nothing special. What an Euler-angle
/// integrator (`E = W⁻¹`) does, measured in `tests/deadreckon.rs` (noise-free, 1 kHz):
/// - passing through the lock, its roll/yaw state jumps by ≈ π in one step and the midpoint
///   rule loses its second order (max rotation error ≈ 2e-3 rad vs ≈ 1.3e-7 rad for the matrix
///   Exp); the rotation itself does *not* diverge, because at the lock the broken direction
///   (roll + yaw) does not change R, and after it the fast Euler-angle dynamics relaxes back;
/// - started exactly at the lock (t = 2 s, `tan θ ≈ 1.6e16`), the Euler rule ends with an
///   O(1) rad error (0.38 rad at 100 Hz, 1.13 rad at 1 kHz) that does not shrink with rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GimbalLockScene;

impl GimbalLockScene {
    /// Pitch sweep amplitude `A = π/√2` \[rad\].
    pub const BETA_AMPLITUDE: f64 = FRAC_PI_2 * SQRT_2;
    /// The instants \[s\] (within the first period) at which the ZYX pitch is exactly ±90°.
    pub const LOCK_TIMES_S: [f64; 4] = [2.0, 6.0, 10.0, 14.0];
}

impl Scene for GimbalLockScene {
    fn name(&self) -> &str {
        "gimbal-lock"
    }

    fn state(&self, t: f64) -> SceneState {
        let a = Self::BETA_AMPLITUDE;
        let (sb8, cb8) = (FRAC_PI_8 * t).sin_cos();
        let (beta, beta_d, beta_dd) = (
            a * sb8,
            a * FRAC_PI_8 * cb8,
            -a * FRAC_PI_8 * FRAC_PI_8 * sb8,
        );
        let (sa4, ca4) = (FRAC_PI_4 * t).sin_cos();
        let (alpha, alpha_d, alpha_dd) = (
            -0.5 * ca4,
            0.5 * FRAC_PI_4 * sa4,
            0.5 * FRAC_PI_4 * FRAC_PI_4 * ca4,
        );
        let (sb, cb) = beta.sin_cos();
        let r_wb =
            SO3::exp(&Vector3::new(alpha, 0.0, 0.0)) * SO3::exp(&Vector3::new(0.0, beta, 0.0));
        let omega_b = Vector3::new(alpha_d * cb, beta_d, alpha_d * sb);
        let omega_dot_b = Vector3::new(
            alpha_dd * cb - alpha_d * beta_d * sb,
            beta_dd,
            alpha_dd * sb + alpha_d * beta_d * cb,
        );
        let (s, c) = (0.5 * t).sin_cos();
        let (s1, c1) = t.sin_cos();
        SceneState {
            p: Vector3::new(2.0 * s, 2.0 * c, 0.3 * s1),
            v: Vector3::new(c, -s, 0.3 * c1),
            a: Vector3::new(-0.5 * s, -0.5 * c, -0.3 * s1),
            r_wb,
            omega_b,
            omega_dot_b,
        }
    }
}
