//! Integration schemes: one interval `[t_k, t_k+1]` of the deltas and, when asked, its
//! linearisation (transition and per-sample gains, see the internal `propagation` module).
//!
//! Every scheme works on bias-corrected samples `ω = ω_m − b̂_g`, `a = a_m − b̂_a` and updates
//! `ΔR_k+1 = ΔR_k Exp(Ω_k)`, `Δv`, `Δp` in frame i (gravity excluded, Forster eq. 33).

pub mod euler;
pub mod midpoint;
pub mod rk4;

use crate::propagation::{M3, V3};
use lie::so3::{RodriguesCoeffs, exp_coeffs};
use nalgebra::Matrix3;

/// A bias-corrected sample: time [ns], `ω` [rad/s], `a` [m/s²].
///
/// Aligned so that `w` and `a` each start a 16-byte pair: the vector stores that write a node
/// and the loads that read it soon after then cover the same bytes (a load spanning two
/// pending stores cannot be forwarded and stalls).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct Node {
    pub w: V3,
    _pad_w: f64,
    pub a: V3,
    pub t_ns: i64,
}

impl Node {
    #[inline(always)]
    pub(crate) fn new(t_ns: i64, w: V3, a: V3) -> Self {
        Self {
            w,
            _pad_w: 0.0,
            a,
            t_ns,
        }
    }
}

/// Running deltas: `ΔR_k`, `Δv_k` [m/s], `Δp_k` [m]; `u_last = ΔR_k a_k` cached by the
/// schemes that evaluate the acceleration at both ends of an interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Deltas {
    pub r: M3,
    pub v: V3,
    pub p: V3,
    pub u_last: V3,
}

impl Default for Deltas {
    fn default() -> Self {
        Self {
            r: M3::identity(),
            v: V3::zeros(),
            p: V3::zeros(),
            u_last: V3::zeros(),
        }
    }
}

/// `(t1 − t0)·1e-9` [s] computed in i128, so any pair of i64 timestamps is safe.
#[inline(always)]
pub(crate) fn span_s(t0_ns: i64, t1_ns: i64) -> f64 {
    // Same integer, same rounding: the i64 → f64 conversion is a single instruction, the
    // i128 one a library call.
    match t1_ns.checked_sub(t0_ns) {
        Some(d) => d as f64 * 1e-9,
        None => (t1_ns as i128 - t0_ns as i128) as f64 * 1e-9,
    }
}

/// `s I + α[φ]× + β[φ]×²`, built entry-wise from `[φ]×² = φφᵀ − θ²I` (no 3×3 products): with
/// Rodrigues' coefficients `(b, c)` ([`lie::so3::RodriguesCoeffs`]), `s·Jl(φ)` is
/// `(s, s b, s c)` and `s·Jr(φ)` is `(s, −s b, s c)`.
#[inline(always)]
pub(crate) fn s_plus_hat_hat2(phi: &V3, s: f64, alpha: f64, beta: f64) -> M3 {
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (bxy, bxz, byz) = (beta * x * y, beta * x * z, beta * y * z);
    let (ax, ay, az) = (alpha * x, alpha * y, alpha * z);
    Matrix3::new(
        s - beta * (yy + zz),
        bxy - az,
        bxz + ay,
        bxy + az,
        s - beta * (xx + zz),
        byz - ax,
        bxz - ay,
        byz + ax,
        s - beta * (xx + yy),
    )
}

/// Rodrigues' coefficients of `phi` ([`RodriguesCoeffs`]); without `LIN` only `a` and `b`
/// (what Exp needs) are computed and `c` is 0.
#[inline(always)]
pub(crate) fn coeffs<const LIN: bool>(phi: &V3) -> RodriguesCoeffs {
    if LIN {
        RodriguesCoeffs::new(phi)
    } else {
        let (a, b) = exp_coeffs(phi.norm_squared());
        RodriguesCoeffs { a, b, c: 0.0 }
    }
}
