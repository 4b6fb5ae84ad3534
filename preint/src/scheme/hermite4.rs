//! The 4th-order Hermite–Magnus scheme ([`crate::Scheme::Hermite4`]): two-point Hermite
//! quadrature with end-point derivatives, 4th order in the step with one Exp per interval.
//!
//! Every node m carries, besides its sample `(ω_m, a_m)`, the derivatives `ω̇_m`, `ȧ_m` of the
//! quadratic through the three consecutive samples around it, `{m−1, m, m+1}` (one-sided,
//! `{m, m+1, m+2}` or `{m−2, m−1, m}`, at the ends of what is available; with two samples in all,
//! the difference quotient). An interval `[t_k, t_k+1]` of length `h` therefore reads the
//! samples `{k−1, …, k+2}`, the same stencil as a cubic, and the window edges use the context
//! samples just outside the window ([`preintegrate`](crate::preintegrate())). Each node's derivatives are computed
//! once, by the interval that ends there (by the first interval for node 0), and carried.
//!
//! With `u(t) = ΔR(t) a(t)` (frame i), `u̇ = ΔR (ω × a + ȧ)`, and the corrected trapezoidal
//! (two-point Hermite) rule `∫₀ʰ f = h/2 (f₀ + f₁) + h²/12 (ḟ₀ − ḟ₁)`, exact for cubics, applied
//! to ω, to `v̇ = u` and to `ṗ = v`:
//!
//! ```text
//! Ω       = h/2 (ω_k + ω_k+1) + h²/12 (ω̇_k − ω̇_k+1) + h²/12 ω_k × ω_k+1
//! ΔR_k+1  = ΔR_k Exp(Ω)
//! u_k+1   = ΔR_k+1 a_k+1,   u̇_k+1 = ΔR_k+1 (ω_k+1 × a_k+1 + ȧ_k+1)
//! Δv_k+1  = Δv_k + h/2 (u_k + u_k+1) + h²/12 (u̇_k − u̇_k+1)
//! Δp_k+1  = Δp_k + h/2 (Δv_k + Δv_k+1) + h²/12 (u_k − u_k+1)
//! ```
//!
//! `Ω` is 4th-order Magnus (Iserles & Nørsett 1999) for `Ṙ = R[ω]×`: its first term
//! integrates ω to O(h⁵), and on a uniform grid it *is* the integral of the cubic through
//! `ω_k−1 … ω_k+2`, `h/24 (−ω_k−1 + 13 ω_k + 13 ω_k+1 − ω_k+2)`; the commutator term
//! `κh² ω(c₁h) × ω(c₂h)` of the two-node Gauss form (`κ = √3/12`) equals `h²/12 ω_k × ω_k+1` to
//! O(h⁵). The local error of every delta is O(h⁵), the global error O(h⁴)
//! (`tests/tests/convergence.rs` measures the slopes). The quadratic's derivative is off by
//! `h² f‴/6` (uniform grid), but that error enters the velocity rule only as the difference of
//! two neighbouring nodes' errors (O(h³)) times h², so Δv is still exact for a cubic `a(t)`
//! without rotation, and ΔR for a cubic rate about a fixed axis (`preint/tests/schemes.rs`).
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`, `F = ΔR_k Jl(Ω) = ΔR_k+1 Jr(Ω)`,
//! `d^m_j`: the derivative weight of stencil sample j at node m): `ψ_k+1 = ψ_k + F δΩ`,
//! `δΩ = Σ_j [c_j I + [j=k] (−h²/12)[ω_k+1]× + [j=k+1] (h²/12)[ω_k]×] δω_j` with
//! `c_j = h/2 ([j=k] + [j=k+1]) + h²/12 (d^k_j − d^k+1_j)`; `δu_m = ΔR_m δa_m − [u_m]×ψ_m` and
//! `δu̇_m = ΔR_m (−[a_m]× δω_m + [ω_m]× δa_m + Σ_j d^m_j δa_j) − [u̇_m]×ψ_m`, and
//! `δp_k+1 = δp_k + h/2 (δv_k + δv_k+1) + h²/12 (δu_k − δu_k+1)`. The ψ_k terms give the
//! transition with `U1 = Δv_k+1 − Δv_k`, `U2 = Δp_k+1 − Δp_k − Δv_k h`; the stencil samples'
//! gains are the gain basis of the `scheme::linearisation` module with node terms:
//! `F_k = −h²/12 F[ω_k+1]×`, `E_k = [u_k]×ΔR_k·(−h²/12, −h³/24)`, `W_k = ΔR_k[ω_k]×·(h²/12,
//! h³/24)`, and `F_k+1 = h²/12 F[ω_k]×`, `E_k+1 = [u_k+1]×ΔR_k+1·(h²/12, h³/24)`,
//! `W_k+1 = ΔR_k+1[ω_k+1]×·(−h²/12, −h³/24)`.

use crate::propagation::linearisation::{GainBasis, GainCoef, GainForm, Linearisation, MAX_STENCIL, NodeTerms};
use super::{
    Deltas, IntervalScheme, Node, SchemeInfo, Stencil, TruncationCompanion, s_plus_hat_hat2,
};
use crate::choices::BiasCorrection;
use crate::noise::CellRule;
use crate::propagation::Shape;
use crate::sample::span_s;
use crate::propagation::blocks::{M3, V3, skew_mul};
use crate::propagation::transition::Transition;
use preint_lie::hat;
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// Hermite4's registry row ([`SchemeInfo`]).
pub(crate) const INFO: SchemeInfo = SchemeInfo {
    name: "hermite4",
    aliases: &["rk4", "high-order"],
    help: "Fourth order, Hermite–Magnus (uses the neighbouring samples).",
    order: 4,
    exact_on: "ΔR exact for a cubic rate about a fixed axis (a constant ω included); Δv for a cubic a without rotation; not exact on held input",
    exact_when_held: false,
    rank: 3,
    bias_correction: BiasCorrection::Additive,
    truncation: TruncationCompanion::Richardson,
    colour: "#009e73",
};

/// The documentation of [`Scheme::Hermite4`](super::Scheme::Hermite4).
macro_rules! variant_docs {
    () => {
        "4th-order Hermite–Magnus scheme (the command line also accepts `rk4`, the name users \
         look for, although it is not a Runge–Kutta method): each node's `ω̇`, `ȧ` from the \
         quadratic through it and its two neighbours; \
         `Ω = h/2(ω_k+ω_k+1) + h²/12(ω̇_k − ω̇_k+1 + ω_k×ω_k+1)` (4th-order Magnus); Δv by the \
         corrected trapezoid on `u = ΔR a` with `u̇ = ΔR(ω×a + ȧ)`, Δp by the corrected trapezoid \
         on `v`. One Exp per interval. Global error O(h⁴) on smooth input. ΔR exact for a cubic \
         rate about a fixed axis, Δv for a cubic `a` without rotation; not exact on held input, \
         whose steps its quadratics smooth over."
    };
}
pub(crate) use variant_docs;

/// The Hermite–Magnus scheme.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hermite4;

/// The weights of an interval's rules, functions of its length `h` \[s\] alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Rule {
    pub h: f64,
    /// `h/2` and `h²/12` (the trapezoid and its end correction).
    pub h_2: f64,
    pub h2_12: f64,
}

impl Rule {
    /// The rule of the interval `[t0_ns, t1_ns]`.
    pub(crate) fn new(t0_ns: i64, t1_ns: i64) -> Self {
        let h = span_s(t0_ns, t1_ns);
        Self {
            h,
            h_2: 0.5 * h,
            h2_12: h * h / 12.0,
        }
    }
}

/// The derivative at node `x_m` (m = 0, 1, 2) of the quadratic through three nodes at `t`
/// \[ns\], as `α (f₂ − f₁) + β (f₁ − f₀)`: returns `(α, β)` [1/s]. A function of the time stamps
/// alone, so every path that differentiates at the same node with the same nodes gets the
/// same weights. Uniform spacing h: `(1/2h, 1/2h)` centred, `(−1/2h, 3/2h)` forward,
/// `(3/2h, −1/2h)` backward.
pub(crate) fn slopes(t: [i64; 3], m: usize) -> (f64, f64) {
    let (h1, h2) = (span_s(t[0], t[1]), span_s(t[1], t[2]));
    let s = h1 + h2;
    match m {
        0 => (-h1 / (h2 * s), (h1 + s) / (h1 * s)),
        1 => (h1 / (h2 * s), h2 / (h1 * s)),
        _ => ((h2 + s) / (h2 * s), -h2 / (h1 * s)),
    }
}

/// The derivative weights of one node: `α (f_lo+2 − f_lo+1) + β (f_lo+1 − f_lo)` over the
/// stencil samples `lo, lo+1, lo+2`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Rates {
    lo: usize,
    alpha: f64,
    beta: f64,
}

impl Rates {
    /// The derivative at stencil position `m` of `st.nodes[..st.len]`: from the three
    /// consecutive samples around it (centred when both neighbours exist), or the difference
    /// quotient when `len = 2` (`α = 0`; the third node is then any node).
    fn at(st: &Stencil, m: usize) -> Self {
        let (nodes, n) = (&st.nodes, st.len);
        if n < 3 {
            return Self {
                lo: 0,
                alpha: 0.0,
                beta: 1.0 / span_s(nodes[0].t_ns, nodes[1].t_ns),
            };
        }
        let lo = m.saturating_sub(1).min(n - 3);
        let t = [nodes[lo].t_ns, nodes[lo + 1].t_ns, nodes[lo + 2].t_ns];
        let (alpha, beta) = slopes(t, m - lo);
        Self { lo, alpha, beta }
    }

    /// `(ω̇, ȧ)` at the node, from the stencil.
    #[inline(always)]
    pub(crate) fn of(&self, st: &Stencil) -> (V3, V3) {
        let x = [
            st.nodes[self.lo],
            st.nodes[self.lo + 1],
            st.nodes[self.lo + 2],
        ];
        (
            slope(
                &(x[2].w - x[1].w),
                &(x[1].w - x[0].w),
                self.alpha,
                self.beta,
            ),
            slope(
                &(x[2].a - x[1].a),
                &(x[1].a - x[0].a),
                self.alpha,
                self.beta,
            ),
        )
    }

    /// The weights by stencil position (of `f_j`, not of the differences).
    fn spread(&self) -> [f64; MAX_STENCIL] {
        let mut out = [0.0; MAX_STENCIL];
        out[self.lo] -= self.beta;
        out[self.lo + 1] += self.beta - self.alpha;
        out[self.lo + 2] += self.alpha;
        out
    }
}

/// `α d₁₂ + β d₀₁`: the derivative from the two differences (rounded as the deltas-only path
/// rounds it in lanes, so that the two agree).
#[inline(always)]
pub(crate) fn slope(d12: &V3, d01: &V3, alpha: f64, beta: f64) -> V3 {
    d12 * alpha + d01 * beta
}

/// The rule and the derivative weights of a stencil at the interval's two nodes, with the
/// stencil they belong to: every interior interval of a uniform stream has the same offsets,
/// so they are computed once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Weights {
    /// `(len, k, t_j − t_k [ns])` of the stencil (`len = 0`: none yet). The weights are a
    /// function of these alone, so a match reuses them exactly.
    key: (usize, usize, [i64; MAX_STENCIL]),
    pub rule: Rule,
    /// At node k and node k+1.
    pub d0: Rates,
    pub d1: Rates,
}

impl Weights {
    /// The weights for the stencil `st`.
    #[inline(always)]
    pub(crate) fn of(&mut self, st: &Stencil) -> &Self {
        let t0 = st.n0().t_ns;
        let mut off = [0i64; MAX_STENCIL];
        for (o, node) in off.iter_mut().zip(&st.nodes[..st.len]) {
            *o = node.t_ns.wrapping_sub(t0);
        }
        let key = (st.len, st.k, off);
        if key != self.key {
            *self = Self {
                key,
                rule: Rule::new(t0, st.n1().t_ns),
                d0: Rates::at(st, st.k),
                d1: Rates::at(st, st.k + 1),
            };
        }
        self
    }
}

/// Carried from one interval to the next: at node k, `u_k = ΔR_k a_k`, `u̇_k` and `ω̇_k`, and
/// the last stencil's weights.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HermiteCarry {
    u_last: V3,
    du_last: V3,
    dw_last: V3,
    weights: Weights,
}

/// What a Hermite step hands to its linearisation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HermiteStep {
    c: Rule,
    om: V3,
    k: RodriguesCoeffs,
    r0: M3,
    r1: M3,
    u0: V3,
    u1: V3,
    du1: V3,
    dv: V3,
    dp_rest: V3,
    d0: Rates,
    d1: Rates,
}

/// `Ω = h/2 (ω_k + ω_k+1) + h²/12 (ω̇_k − ω̇_k+1 + ω_k × ω_k+1)`.
#[inline(always)]
fn omega(c: &Rule, w0: &V3, w1: &V3, dw0: &V3, dw1: &V3) -> V3 {
    (w0 + w1) * c.h_2 + (dw0 - dw1 + w0.cross(w1)) * c.h2_12
}

/// The velocity and position steps from `u`, `u̇` at both nodes: `Δv_k+1` and
/// `Δp_k+1 − Δp_k = h/2 (Δv_k + Δv_k+1) + h²/12 (u_k − u_k+1)` (the corrected trapezoid for
/// `ṗ = v`, `v̇ = u`).
#[inline(always)]
fn advance(c: &Rule, v0: &V3, u0: &V3, du0: &V3, u1: &V3, du1: &V3) -> (V3, V3) {
    let v1 = v0 + ((u0 + u1) * c.h_2 + (du0 - du1) * c.h2_12);
    let dp = (v0 + v1) * c.h_2 + (u0 - u1) * c.h2_12;
    (v1, dp)
}

impl Hermite4 {
    /// Node k's `(ω̇_k, ȧ_k)` and node k+1's, with the interval's rule, for the stencil `st`
    /// (the weights cached in `cache`).
    #[inline(always)]
    pub(crate) fn node_rates(cache: &mut Weights, st: &Stencil) -> (Rule, Rates, Rates) {
        let w = cache.of(st);
        (w.rule, w.d0, w.d1)
    }
}

impl Shape for Hermite4 {
    const NODES_BEFORE: usize = 1;
    const NODES_AFTER: usize = 1;
    const END_NODE_NOISE: bool = true;
    const GAIN_FORM: GainForm = GainForm {
        psi_vp: true,
        acc_on_own_node: false,
    };
    type NodeTerms = [NodeTerms; 2];
}

impl IntervalScheme for Hermite4 {
    const CELL_RULE: CellRule = CellRule::Centered;
    type Carry = HermiteCarry;
    type Step = HermiteStep;

    fn start(c: &mut HermiteCarry, first: &Node) {
        c.u_last = first.a;
    }

    #[inline(always)]
    fn step(d: &mut Deltas, carry: &mut HermiteCarry, st: &Stencil) -> HermiteStep {
        let (n0, n1) = (st.n0(), st.n1());
        let (c, d0, d1) = Self::node_rates(&mut carry.weights, st);
        if st.first {
            // Node k's derivatives; `u_last = ΔR_k a_k` is already set.
            let (dw0, da0) = d0.of(st);
            carry.dw_last = dw0;
            carry.du_last = d.r * (n0.w.cross(&n0.a) + da0);
        }
        let (dw1, da1) = d1.of(st);
        let om = omega(&c, &n0.w, &n1.w, &carry.dw_last, &dw1);
        let s1 = n1.w.cross(&n1.a) + da1;
        let k = RodriguesCoeffs::new(&om);
        let r0 = d.r;
        let r1 = r0 * i_plus_hat_hat2(&om, k.a, k.b);
        let (u0, du0) = (carry.u_last, carry.du_last);
        let (u1, du1) = (r1 * n1.a, r1 * s1);
        let v0 = d.v;
        let (v1, dp) = advance(&c, &v0, &u0, &du0, &u1, &du1);
        d.p += dp;
        d.v = v1;
        d.r = r1;
        carry.u_last = u1;
        carry.du_last = du1;
        carry.dw_last = dw1;
        HermiteStep {
            c,
            om,
            k,
            r0,
            r1,
            u0,
            u1,
            du1,
            dv: v1 - v0,
            dp_rest: dp - v0 * c.h,
            d0,
            d1,
        }
    }

    #[inline(always)]
    fn linearise(s: &HermiteStep, st: &Stencil) -> Linearisation<[NodeTerms; 2]> {
        let (h_2, h12) = (s.c.h_2, s.c.h2_12);
        let (w0, w1) = (&st.n0().w, &st.n1().w);
        let f = s.r0 * s_plus_hat_hat2(&s.om, 1.0, s.k.b, s.k.c);
        // v and p rows of a ψ gain g: [x]× g and [y]× g.
        let x = s.u1 * (-h_2) + s.du1 * h12;
        let y = x * h_2 + s.u1 * h12;
        // The δω terms of u̇_k and u̇_k+1: v rows ∓h²/12 [u]×ΔR, p rows h/2 times those.
        let node = [
            NodeTerms {
                f: f * hat(w1) * (-h12),
                e: skew_mul(&s.u0, &s.r0),
                e_vp: (-h12, -h12 * h_2),
                w: s.r0 * hat(w0),
                w_vp: (h12, h12 * h_2),
            },
            NodeTerms {
                f: f * hat(w0) * h12,
                e: skew_mul(&s.u1, &s.r1),
                e_vp: (h12, h12 * h_2),
                w: s.r1 * hat(w1),
                w_vp: (-h12, -h12 * h_2),
            },
        ];
        let (sp0, sp1) = (s.d0.spread(), s.d1.spread());
        let mut coef = [GainCoef::default(); MAX_STENCIL];
        for (j, cj) in coef.iter_mut().enumerate().take(st.len) {
            let ek = f64::from(u8::from(j == st.k));
            let ek1 = f64::from(u8::from(j == st.k + 1));
            let (av, bv) = (h_2 * ek + h12 * sp0[j], h_2 * ek1 - h12 * sp1[j]);
            *cj = GainCoef {
                gyro: h_2 * (ek + ek1) + h12 * (sp0[j] - sp1[j]),
                a: (av, h_2 * av + h12 * ek),
                b: (bv, h_2 * bv - h12 * ek1),
            };
        }
        Linearisation {
            tr: Transition {
                h: s.c.h,
                u1: s.dv,
                u2: s.dp_rest,
            },
            basis: GainBasis {
                f,
                x,
                y,
                r0: s.r0,
                r1: s.r1,
            },
            coef,
            node,
        }
    }
}
