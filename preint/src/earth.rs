//! Earth rotation: prediction in a navigation frame that rotates at a constant rate ω_ie.
//!
//! # Model
//!
//! The navigation (world) frame `n` rotates with respect to an inertial frame at the constant
//! rate `ω = ω_ie` [rad/s], expressed in `n` (e.g. an Earth-fixed local-level frame:
//! [`earth_rate_enu`]). Gravity `g` [m/s²] is fixed in `n` (it is the local plumb-bob
//! gravity; the centrifugal acceleration is *not* folded into it). The gyroscope measures the
//! body's inertial rate and the accelerometer the inertial specific force, so with `R`
//! body → n, `p`, `v` position and velocity in `n`, and `ω_m`, `f` the bias-free measurements:
//!
//! ```text
//! Ṙ = R [ω_m]× − [ω]× R
//! v̇ = R f + g − 2 ω×v − ω×(ω×p)
//! ṗ = v
//! ```
//!
//! The preintegrated deltas `ΔR, Δv, Δp` (body frame i) do not depend on ω: Earth rotation
//! enters only the prediction and the factors, never the per-sample loop.
//!
//! # Modes ([`CoriolisMode`])
//!
//! **Exact.** Freeze the navigation frame at `t_i` (frame `I`, `Q(t) = Exp(ω (t − t_i))`
//! takes `n(t)` vectors to `I`). In `I` the motion is inertial with a rotating gravity
//! `Q(t) g`, and `v̄ = v + ω×p` is the velocity seen from `I`; integrating twice gives, with
//! `T = t_j − t_i`, `w = −ω T` and `A = Exp(w)` (Brossard, Barrau, Bonnabel, T-RO 2022,
//! eqs. 80–84; GTSAM 4.3's `NavState::correctPIM` with `omegaCoriolis`):
//!
//! ```text
//! R_j = A R_i ΔR
//! p_j = A (p_i + T v̄_i + R_i Δp) + T² Γ_P(w) g
//! v̄_j = A (v̄_i + R_i Δv) + T J_l(w) g,          v_j = v̄_j − ω×p_j
//! J_l(w) = ∫₀¹ Exp(s w) ds,   Γ_P(w) = ∫₀¹ s Exp(s w) ds = ½ I + ⅓[w]× + ⅛[w]×² + …
//! ```
//!
//! This is exact whenever the deltas are: the transition of two consecutive windows composes
//! to that of the merged window.
//!
//! **FirstOrder / SecondOrder.** The additive Coriolis correction of strapdown navigation
//! that GTSAM's implementation of Forster et al.'s factor (T-RO 2017) applies up to 4.2
//! (`NavState::coriolis`, `use2ndOrderCoriolis` selecting the centrifugal terms), with
//! `c = ω×(ω×p_i)` for SecondOrder and `c = 0` for FirstOrder:
//!
//! ```text
//! R_j = R_i Exp(Log ΔR − T R_iᵀ ω)
//! p_j = p_i + T v_i + ½ g T² + R_i Δp − T² ω×v_i − ½ T² c
//! v_j = v_i + g T + R_i Δv − 2 T ω×v_i − T c
//! ```
//!
//! Their error grows as `|ω| T` times the motion (reported in `docs/EVIDENCE.md`).

use crate::choices::CoriolisMode;
use nalgebra::{Matrix3, Vector3};
use preint_lie::{SO3, hat, jl};

/// Earth's rotation rate Ω_E [rad/s] (WGS-84).
pub const EARTH_RATE_RAD_S: f64 = 7.292_115e-5;

/// The Earth rate ω_ie [rad/s] in a local-level **east-north-up** world frame (x east,
/// y north, z up, the crate's z-up convention) at geodetic latitude `latitude_deg` \[deg\]:
/// `Ω_E (0, cos φ, sin φ)`. For a frame whose x axis points north instead, swap the first
/// two components.
///
/// ```
/// let w = preint::earth::earth_rate_enu(90.0);
/// assert!((w.z - preint::earth::EARTH_RATE_RAD_S).abs() < 1e-20 && w.y.abs() < 1e-20);
/// ```
pub fn earth_rate_enu(latitude_deg: f64) -> Vector3<f64> {
    let phi = latitude_deg.to_radians();
    Vector3::new(0.0, phi.cos(), phi.sin()) * EARTH_RATE_RAD_S
}

/// `J_l(w) = ∫₀¹ Exp(s w) ds` (the SO(3) left Jacobian).
pub fn gamma_v(w: &Vector3<f64>) -> Matrix3<f64> {
    jl(w)
}

/// `Γ_P(w) = ∫₀¹ s Exp(s w) ds = ½ I + a [w]× + b [w]×²` with, for θ = ‖w‖,
/// `a = (sin θ − θ cos θ)/θ³`, `b = (½ − (cos θ + θ sin θ − 1)/θ²)/θ²` (series
/// `a = ⅓ − θ²/30 + θ⁴/840 − …`, `b = ⅛ − θ²/144 + θ⁴/5760 − …` below θ = 0.1).
pub fn gamma_p(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let (a, b) = if t2 < 1e-2 {
        (
            1.0 / 3.0 - t2 / 30.0 + t2 * t2 / 840.0 - t2 * t2 * t2 / 45_360.0,
            0.125 - t2 / 144.0 + t2 * t2 / 5_760.0 - t2 * t2 * t2 / 403_200.0,
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        ((s - t * c) / (t2 * t), (0.5 - (c + t * s - 1.0) / t2) / t2)
    };
    let k = hat(w);
    Matrix3::identity() * 0.5 + k * a + k * k * b
}

/// What the exact transition over `T` needs: `A = Exp(−ωT)` and the gravity terms
/// `T J_l(−ωT) g` [m/s] and `T² Γ_P(−ωT) g` \[m\].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Transport {
    pub a: SO3,
    pub vg: Vector3<f64>,
    pub pg: Vector3<f64>,
}

impl Transport {
    pub(crate) fn new(omega: &Vector3<f64>, dt: f64, g: &Vector3<f64>) -> Self {
        let w = -omega * dt;
        Self {
            a: SO3::exp(&w),
            vg: gamma_v(&w) * g * dt,
            pg: gamma_p(&w) * g * (dt * dt),
        }
    }
}

/// `ω×(ω×p)` for [`CoriolisMode::SecondOrder`], zero otherwise.
pub(crate) fn centrifugal(
    omega: &Vector3<f64>,
    p: &Vector3<f64>,
    mode: CoriolisMode,
) -> Vector3<f64> {
    if mode == CoriolisMode::SecondOrder {
        omega.cross(&omega.cross(p))
    } else {
        Vector3::zeros()
    }
}
