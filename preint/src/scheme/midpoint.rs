//! The midpoint rule (VINS-Mono's rule, with the exact Exp and a unit rotation):
//!
//! ```text
//! ω̄ = ½(ω_k + ω_k+1),   ΔR_k+1 = ΔR_k Exp(ω̄ h),   ā = ½(ΔR_k a_k + ΔR_k+1 a_k+1)
//! Δv_k+1 = Δv_k + ā h,   Δp_k+1 = Δp_k + Δv_k h + ½ ā h²
//! ```
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`, `u0 = ΔR_k a_k`, `u1 = ΔR_k+1 a_k+1`):
//! `ψ_k+1 = ψ_k + G (δω_k + δω_k+1)` with `G = ΔR_k+1 Jr(ω̄h) h/2 = ΔR_k Jl(ω̄h) h/2`;
//! `δu0 = ΔR_k δa_k − [u0]×ψ_k`, `δu1 = ΔR_k+1 δa_k+1 − [u1]×ψ_k+1`;
//! `δv_k+1 = δv_k + h/2 (δu0 + δu1)`, `δp_k+1 = δp_k + h δv_k + h²/4 (δu0 + δu1)`.
//! Hence `U1 = ā h`, `U2 = ½ ā h²`; both samples share the gyro gain
//! `(G, −h/2 [u1]×G, −h²/4 [u1]×G)`; the accelerometer gains are `(h/2, h²/4)·ΔR_k` for sample
//! k and `(h/2, h²/4)·ΔR_k+1` for sample k+1. Sample k+1's noise also enters the next
//! interval, with the same `ΔR_k+1`; the propagator adds it once, with the sum of both gains.

use crate::propagation::linearisation::{GainBasis, GainCoef, GainForm, Linearisation, MAX_STENCIL};
use super::{Deltas, IntervalScheme, Node, SchemeInfo, Stencil, TruncationCompanion, s_plus_hat_hat2};
use crate::choices::BiasCorrection;
use crate::noise::CellRule;
use crate::propagation::Shape;
use crate::propagation::blocks::{M3, V3};
use crate::propagation::transition::Transition;
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// Midpoint's registry row ([`SchemeInfo`]).
pub(crate) const INFO: SchemeInfo = SchemeInfo {
    name: "midpoint",
    aliases: &[],
    help: "Second order (the mean of the samples at both ends of each interval).",
    order: 2,
    exact_on: "ΔR exact when ω is linear between samples about a fixed axis; Δv when nothing rotates and a is linear between samples, Δp when a is also constant; not exact on held input (it averages across a step)",
    exact_when_held: false,
    rank: 1,
    bias_correction: BiasCorrection::Additive,
    truncation: TruncationCompanion::Hermite4Upsampled,
    colour: "#0072b2",
};

/// The documentation of [`Scheme::Midpoint`](super::Scheme::Midpoint).
macro_rules! variant_docs {
    () => {
        "`ω̄ = ½(ω_k + ω_k+1)`, `ΔR_k+1 = ΔR_k Exp(ω̄ h)`, `ā = ½(ΔR_k a_k + ΔR_k+1 a_k+1)`, \
         `Δv_k+1 = Δv_k + ā h`, `Δp_k+1 = Δp_k + Δv_k h + ½ ā h²`. Global error O(h²). ΔR \
         exact for a rate linear between samples about a fixed axis; Δv without rotation for \
         `a` linear between samples, Δp only for `a` constant; not exact on held input (its \
         mean rate straddles each step)."
    };
}
pub(crate) use variant_docs;

/// The midpoint scheme ([`crate::Scheme::Midpoint`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Midpoint;

/// Carried from one interval to the next: `ΔR_k a_k` [m/s²], frame i.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MidpointCarry {
    u_last: V3,
}

/// What a midpoint step hands to its linearisation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MidpointStep {
    th: V3,
    k: RodriguesCoeffs,
    r0: M3,
    r1: M3,
    u1: V3,
    abar: V3,
    h: f64,
    hh: f64,
}

impl Shape for Midpoint {
    const NODES_BEFORE: usize = 0;
    const NODES_AFTER: usize = 0;
    const END_NODE_NOISE: bool = true;
    const GAIN_FORM: GainForm = GainForm {
        psi_vp: true,
        acc_on_own_node: true,
    };
    type NodeTerms = ();
}

impl IntervalScheme for Midpoint {
    const CELL_RULE: CellRule = CellRule::Centered;
    type Carry = MidpointCarry;
    type Step = MidpointStep;

    fn start(c: &mut MidpointCarry, first: &Node) {
        // ΔR_0 a_0 = a_0.
        c.u_last = first.a;
    }

    #[inline(always)]
    fn step(d: &mut Deltas, c: &mut MidpointCarry, st: &Stencil) -> MidpointStep {
        let (n0, n1, h) = (st.n0(), st.n1(), st.h());
        let th = (n0.w + n1.w) * (0.5 * h);
        let k = RodriguesCoeffs::new(&th);
        let e = i_plus_hat_hat2(&th, k.a, k.b);
        let r0 = d.r;
        let r1 = r0 * e;
        let u1 = r1 * n1.a;
        let abar = (c.u_last + u1) * 0.5;
        let hh = 0.5 * h * h;
        d.p += d.v * h + abar * hh;
        d.v += abar * h;
        d.r = r1;
        c.u_last = u1;
        MidpointStep {
            th,
            k,
            r0,
            r1,
            u1,
            abar,
            h,
            hh,
        }
    }

    #[inline(always)]
    fn linearise(s: &MidpointStep, _: &Stencil) -> Linearisation {
        let cv = 0.5 * s.h;
        let cp = 0.5 * s.hh;
        let mut coef = [GainCoef::default(); MAX_STENCIL];
        coef[0] = GainCoef {
            gyro: 1.0,
            a: (cv, cp),
            b: (0.0, 0.0),
        };
        coef[1] = GainCoef {
            gyro: 1.0,
            a: (0.0, 0.0),
            b: (cv, cp),
        };
        Linearisation {
            tr: Transition {
                h: s.h,
                u1: s.abar * s.h,
                u2: s.abar * s.hh,
            },
            basis: GainBasis {
                f: s.r0 * s_plus_hat_hat2(&s.th, cv, cv * s.k.b, cv * s.k.c),
                x: s.u1 * -cv,
                y: s.u1 * -cp,
                r0: s.r0,
                r1: s.r1,
            },
            coef,
            node: (),
        }
    }
}
