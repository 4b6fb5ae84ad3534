//! Forster 2017 / GTSAM `ManifoldPreintegration`: sample k held over interval k.
//!
//! `ΔR_k+1 = ΔR_k Exp(ω_k h)`, `Δp_k+1 = Δp_k + Δv_k h + ½ ΔR_k a_k h²`,
//! `Δv_k+1 = Δv_k + ΔR_k a_k h` (Forster eq. 35). Linearisation in rotated coordinates
//! `ψ = ΔR δφ` (Forster eq. 59 conjugated by ΔR): `U1 = u h`, `U2 = ½ u h²` with
//! `u = ΔR_k a_k`; gain of sample k: ψ ← `ΔR_k+1 Jr(ω_k h) h = ΔR_k Jl(ω_k h) h` (gyro),
//! v ← `ΔR_k h`, p ← `½ ΔR_k h²` (accelerometer). Sample k is used by interval k only; its cell
//! is the interval it is held over ([`crate::noise::CellRule::Held`]), so its noise is `Σ / h`
//! (GTSAM). The gain is returned pulled back (internal `propagation` module, `Φ_k+1⁻¹` with
//! `(V, W, τ)`): gyro columns `(g, V × g, (W − τV) × g)`, accelerometer `ΔR_k·(h, ½h² − τ h)`.

use super::{Deltas, Node, s_plus_hat_hat2};
use crate::propagation::{Cols9, M3, Origin, PullBack, Transition, skew_cols};
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// Sample k's pulled-back gain: gyro columns `g`, accelerometer columns `r0·(cv, cp)`
/// (`cp0`: `c_p` in rotated coordinates), and the pull-back `pb = Φ_k+1⁻¹` used.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EulerGain {
    pub pb: PullBack,
    pub g: Cols9,
    pub r0: M3,
    pub cv: f64,
    pub cp: f64,
    pub cp0: f64,
}

/// One Euler interval of length `h` \[s\] holding node `n0` and ending at `t1_ns`; with `LIN`,
/// its transition and the gain of `n0` pulled back to `o`.
#[inline(always)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    n0: &Node,
    h: f64,
    t1_ns: i64,
    o: &mut Origin,
) -> Option<(Transition, EulerGain)> {
    if !LIN {
        // Level::Deltas: ΔR as a unit quaternion (`Deltas`).
        let u = d.q.rotate(&n0.a);
        let h2 = 0.5 * h * h;
        d.p += d.v * h + u * h2;
        d.v += u * h;
        d.q = d.q.mul_exp_scaled(&n0.w, h);
        return None;
    }
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
    // ΔR_k+1 Jr(θ) h = ΔR_k Jl(θ) h (Exp(θ) Jr(θ) = Jl(θ)).
    let rg = r0 * s_plus_hat_hat2(&th, h, h * k.b, h * k.c);
    let pb = o.pull_back(t1_ns, &d.v, &d.p);
    Some((
        Transition {
            h,
            u1: u * h,
            u2: u * h2,
        },
        EulerGain {
            g: skew_cols(&rg, &pb.dv, &pb.w),
            pb,
            r0,
            cv: h,
            cp: h2 - pb.tau * h,
            cp0: h2,
        },
    ))
}
