//! Midpoint rule (design document; VINS-Mono's rule with the exact Exp):
//! `ω̄ = ½(ω_k + ω_k+1)`, `ΔR_k+1 = ΔR_k Exp(ω̄ h)`, `ā = ½(ΔR_k a_k + ΔR_k+1 a_k+1)`,
//! `Δv_k+1 = Δv_k + ā h`, `Δp_k+1 = Δp_k + Δv_k h + ½ ā h²`.
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`, `u0 = ΔR_k a_k`, `u1 = ΔR_k+1 a_k+1`):
//! `ψ_k+1 = ψ_k + G (δω_k + δω_k+1)` with `G = ΔR_k+1 Jr(ω̄h) h/2 = ΔR_k Jl(ω̄h) h/2`;
//! `δu0 = ΔR_k δa_k − [u0]×ψ_k`, `δu1 = ΔR_k+1 δa_k+1 − [u1]×ψ_k+1`;
//! `δv_k+1 = δv_k + h/2 (δu0 + δu1)`, `δp_k+1 = δp_k + h δv_k + h²/4 (δu0 + δu1)`.
//! Hence `U1 = ā h`, `U2 = ½ ā h²`, and both samples share the gyro gains
//! `(G, −h/2 [u1]×G, −h²/4 [u1]×G)`; accelerometer gains `(h/2, h²/4)·ΔR_k` for sample k and
//! `(h/2, h²/4)·ΔR_k+1` for sample k+1. Pulled back to the origin (internal
//! `propagation` module, `Φ_k+1⁻¹` with `(V, W, τ)`) the gyro columns are
//! `(G, x × G, y × G)` with `x = V − (h/2) u1`, `y = W − τV − c_p u1`, and the
//! accelerometer gains `(c_v, c_p)·ΔR` with `c_v = h/2`, `c_p = h²/4 − τ h/2`. Sample k+1's
//! noise also enters the next interval: the `propagation` module keeps its gain pending and
//! adds the sample's noise once, with the sum of both intervals' gains, when interval k+1 is
//! done (no cross-covariance is kept).

use super::{Deltas, Node, s_plus_hat_hat2};
use crate::propagation::{MidGain, Origin, Transition};
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// One midpoint interval between nodes `n0` and `n1` of length `h` \[s\]; gains are pulled back
/// to `o`. Uses `d.u_last = ΔR_k a_k` and sets it to `ΔR_k+1 a_k+1`. With `LIN`, returns the
/// transition and the pulled-back gains.
#[inline(always)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    n0: &Node,
    n1: &Node,
    h: f64,
    o: &mut Origin,
) -> Option<(Transition, MidGain)> {
    if !LIN {
        // Level::Deltas: ΔR as a unit quaternion (`Deltas`).
        let q1 = d.q.mul_exp_scaled(&(n0.w + n1.w), 0.5 * h);
        let u1 = q1.rotate(&n1.a);
        let abar = (d.u_last + u1) * 0.5;
        let hh = 0.5 * h * h;
        d.p += d.v * h + abar * hh;
        d.v += abar * h;
        d.q = q1;
        d.u_last = u1;
        return None;
    }
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
    let pb = o.pull_back(n1.t_ns, &d.v, &d.p);
    let cv = 0.5 * h;
    let cp = 0.5 * hh - pb.tau * cv;
    let g = r0 * s_plus_hat_hat2(&th, cv, cv * k.b, cv * k.c);
    Some((
        Transition {
            h,
            u1: abar * h,
            u2: abar * hh,
        },
        MidGain {
            pb,
            g,
            x: pb.dv - u1 * cv,
            y: pb.w - u1 * cp,
            r0,
            cv,
            cp,
        },
    ))
}
