//! Integration schemes: one interval `[t_k, t_k+1]` of the deltas and, when asked, its
//! linearisation (transition and per-sample gains, see the internal `propagation` module).
//!
//! Every scheme works on bias-corrected samples `ω = ω_m − b̂_g`, `a = a_m − b̂_a` and updates
//! `ΔR_k+1 = ΔR_k Exp(Ω_k)`, `Δv`, `Δp` in frame i (gravity excluded, Forster eq. 33).

pub mod euler;
pub mod midpoint;
pub mod rk4;

use crate::propagation::{M3, V3};

/// A bias-corrected sample: time [ns], `ω` [rad/s], `a` [m/s²].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Node {
    pub t_ns: i64,
    pub w: V3,
    pub a: V3,
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
