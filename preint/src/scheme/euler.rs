//! Forster 2017 / GTSAM `ManifoldPreintegration`: sample k held over interval k.
//!
//! `ΔR_k+1 = ΔR_k Exp(ω_k h)`, `Δp_k+1 = Δp_k + Δv_k h + ½ ΔR_k a_k h²`,
//! `Δv_k+1 = Δv_k + ΔR_k a_k h` (Forster eq. 35). Linearisation in rotated coordinates
//! `ψ = ΔR δφ` (Forster eq. 59 conjugated by ΔR): `U1 = u h`, `U2 = ½ u h²` with
//! `u = ΔR_k a_k`; gain of sample k: ψ ← `ΔR_k+1 Jr(ω_k h) h` (gyro), v ← `ΔR_k h`,
//! p ← `½ ΔR_k h²` (accelerometer). Sample k is used by interval k only; its cell is the
//! interval it is held over ([`crate::noise::CellRule::Held`]), so its noise is `Σ / h` (GTSAM).

use super::{Deltas, Node};
use crate::propagation::{Blk96, M3, Transition};
use lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// One Euler interval of length `h` [s] holding node `n0`; with `LIN`, its transition and the
/// gain of `n0`.
#[inline(always)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    n0: &Node,
    h: f64,
) -> Option<(Transition, Blk96)> {
    let th = n0.w * h;
    let k = RodriguesCoeffs::new(&th);
    let e = i_plus_hat_hat2(&th, k.a, k.b);
    let r0 = d.r;
    let u = r0 * n0.a;
    let h2 = 0.5 * h * h;
    d.p += d.v * h + u * h2;
    d.v += u * h;
    d.r = r0 * e;
    if !LIN {
        return None;
    }
    let jr = i_plus_hat_hat2(&th, -k.b, k.c);
    let gain = Blk96 {
        rg: d.r * jr * h,
        vg: M3::zeros(),
        pg: M3::zeros(),
        va: r0 * h,
        pa: r0 * h2,
    };
    Some((
        Transition {
            h,
            u1: u * h,
            u2: u * h2,
        },
        gain,
    ))
}
