//! Midpoint rule (design document; VINS-Mono's rule with the exact Exp):
//! `ω̄ = ½(ω_k + ω_k+1)`, `ΔR_k+1 = ΔR_k Exp(ω̄ h)`, `ā = ½(ΔR_k a_k + ΔR_k+1 a_k+1)`,
//! `Δv_k+1 = Δv_k + ā h`, `Δp_k+1 = Δp_k + Δv_k h + ½ ā h²`.
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`, `u0 = ΔR_k a_k`, `u1 = ΔR_k+1 a_k+1`):
//! `ψ_k+1 = ψ_k + G (δω_k + δω_k+1)` with `G = ΔR_k+1 Jr(ω̄h) h/2`;
//! `δu0 = ΔR_k δa_k − [u0]×ψ_k`, `δu1 = ΔR_k+1 δa_k+1 − [u1]×ψ_k+1`;
//! `δv_k+1 = δv_k + h/2 (δu0 + δu1)`, `δp_k+1 = δp_k + h δv_k + h²/4 (δu0 + δu1)`.
//! Hence `U1 = ā h`, `U2 = ½ ā h²`, and both samples share the gyro gains
//! `(G, −h/2 [u1]×G, −h²/4 [u1]×G)`; accelerometer gains `(h/2, h²/4)·ΔR_k` for sample k and
//! `(h/2, h²/4)·ΔR_k+1` for sample k+1. Sample k+1's noise also enters the next interval:
//! the internal `propagation` module keeps its gain pending and adds the sample's noise once,
//! through the merged gain `A_k+1 Γ_k,1 + Γ_k+1,0`, when interval k+1 is done (no
//! cross-covariance is kept).

use super::{Deltas, Node};
use crate::propagation::{MidGain, Transition, skew_mul};
use lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// One midpoint interval between nodes `n0` and `n1` of length `h` [s]. Uses
/// `d.u_last = ΔR_k a_k` and sets it to `ΔR_k+1 a_k+1`.
#[inline(always)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    n0: &Node,
    n1: &Node,
    h: f64,
) -> Option<(Transition, MidGain)> {
    let th = (n0.w + n1.w) * (0.5 * h);
    let k = RodriguesCoeffs::new(&th);
    let e = i_plus_hat_hat2(&th, k.a, k.b);
    let r0 = d.r;
    let r1 = r0 * e;
    let u0 = d.u_last;
    let u1 = r1 * n1.a;
    let abar = (u0 + u1) * 0.5;
    let hh = 0.5 * h * h;
    d.p += d.v * h + abar * hh;
    d.v += abar * h;
    d.r = r1;
    d.u_last = u1;
    if !LIN {
        return None;
    }
    let jr = i_plus_hat_hat2(&th, -k.b, k.c);
    let g = r1 * jr * (0.5 * h);
    let su = skew_mul(&u1, &g);
    Some((
        Transition {
            h,
            u1: abar * h,
            u2: abar * hh,
        },
        MidGain {
            rg: g,
            vg: su * (-0.5 * h),
            pg: su * (-0.25 * h * h),
            r0,
            r1,
            cv: 0.5 * h,
            cp: 0.25 * h * h,
        },
    ))
}
