//! `gimbal-lock`: the body passes exactly through ZYX pitch ±90°, where the Euler-angle
//! kinematics `Θ̇ = E(Θ)ω` are singular, while it also rolls.

use crate::scene::{Scene, SceneState};
use nalgebra::Vector3;
use preint_lie::SO3;
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
/// t = 2, 6, 10, 14 s (period 16 s), and only there. At those instants the canonical ZYX roll
/// and yaw ([`crate::euler_zyx_of`], pitch ∈ [−90°, 90°]) jump by π while pitch touches 90° and
/// turns back: a branch flip of the angles, not of R. The exact Euler-angle path itself is
/// smooth (unwrapped, pitch passes beyond 90°) and its rates stay bounded (≤ 0.81 rad/s on
/// [0, 3] s): at t = 2 s, `ω_b = (0, π²/16, π/8)` lies in the range of the Euler-rate→body-rate
/// matrix `W(φ, π/2)` for exactly the roll the trajectory has there, `tan φ = −2/π`. What is
/// singular is the integrator's ODE `Θ̇ = E(Θ)ω`: `E` has `1/cos θ` entries that vary on the
/// time scale `|t − t_lock|`, so near the lock no step size is small enough, and the result
/// depends on where the samples fall relative to the lock. Quaternion and matrix integrators
/// notice nothing special. Measured in `tests/deadreckon.rs` (noise-free):
/// - midpoint rule through the lock (3 s, 250 Hz … 16 kHz, the lock placed 0 … 1e-3 s from a
///   sample): the Euler-angle error varies ≥ 10× with that placement, its worst case is
///   ≥ 1000× the matrix error (2.5e3× at 250 Hz, 1.5e5× at 16 kHz), and it does not converge at
///   second order (worst·rate² grows 57×), while quaternion and matrix stay at
///   e ≈ 0.190 Δt² and 0.127 Δt² (rad, Δt in s) whatever the placement;
/// - Euler rule through the lock: the rule's own first-order error dominates, so the
///   rotation error stays within 2.3× the matrix error and converges at first order; but at
///   every rate and placement the angle state jumps by ≥ 0.15 rad (up to 1.3 rad) in one
///   step: an implied Euler rate ∝ 1/Δt (≥ 47 rad/s at 250 Hz, ≥ 3900 rad/s at 16 kHz);
/// - started exactly at the lock (t = 2 s, pitch = fl(π/2), `|E(Θ₀)ω₀| ≈ 5e15` rad/s): the
///   first Euler-rule step moves the angles by ~1e12–1e14 rad and the error over the
///   following 14 s is 0.3–1.1 rad at 100 Hz … 2 kHz, not shrinking with the rate; the
///   midpoint rule's error is ≥ 1000× the matrix error (measured).
///
/// So "fails" means: loses its order and its accuracy depends on the sample placement (midpoint),
/// produces non-physical angle jumps (Euler rule), or is wrong by O(1) rad at every rate
/// (started at the lock). It never panics; no NaN appeared in these runs. The raw angle states
/// are available from [`crate::euler_zyx_angles`].
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
