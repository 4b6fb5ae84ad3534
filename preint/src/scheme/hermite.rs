//! High-order scheme (`Scheme::Hermite4`): two-point Hermite quadrature with exact end-point
//! derivatives, 4th order in the step with one Exp per interval.
//!
//! Every node m carries, besides its sample `(ω_m, a_m)`, the derivatives `ω̇_m`, `ȧ_m` of the
//! quadratic through the three consecutive samples around it, `{m−1, m, m+1}` (one-sided,
//! `{m, m+1, m+2}` or `{m−2, m−1, m}`, at the ends of what is available; with two samples in all,
//! the difference quotient). An interval `[t_k, t_k+1]` of length `h` therefore reads the
//! samples `{k−1, …, k+2}`, the same stencil as a cubic, and the window edges use the context
//! samples just outside the window exactly as described for the window path
//! ([`crate::window`]). Each node's derivatives are computed once, by the interval that ends
//! there (by the first interval for node 0), and carried to the next interval.
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
//! `Ω` is 4th-order Magnus (Iserles–Nørsett) for `Ṙ = R[ω]×`: its first term integrates ω to
//! O(h⁵), and on a uniform grid it *is* the integral of the cubic through `ω_k−1 … ω_k+2`,
//! `h/24 (−ω_k−1 + 13 ω_k + 13 ω_k+1 − ω_k+2)`; the commutator term `κh² ω(c₁h) × ω(c₂h)` of the
//! two-node Gauss form (`κ = √3/12`) equals `h²/12 ω_k × ω_k+1` to O(h⁵). The local error of
//! every delta is O(h⁵), the global error O(h⁴) (`tests/tests/convergence.rs` measures the
//! slopes). The quadratic's derivative is off by `h² f‴/6` (uniform grid), but that error
//! enters the velocity rule only as the difference of two neighbouring nodes' errors (O(h³))
//! times h², so Δv is still exact for a cubic `a(t)` without rotation, and ΔR for a cubic rate
//! about a fixed axis (`preint/tests/schemes.rs`). Cost: one Exp, two rotations and three
//! cross products per sample, where Gauss–Legendre Magnus with Simpson's rule (this scheme's
//! predecessor) needs two Exp, three rotations and ω at four interpolated points.
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`, `F = ΔR_k Jl(Ω) = ΔR_k+1 Jr(Ω)`,
//! `d^m_j`: the derivative weight of stencil sample j at node m): `ψ_k+1 = ψ_k + F δΩ`,
//! `δΩ = Σ_j [c_j I + [j=k] (−h²/12)[ω_k+1]× + [j=k+1] (h²/12)[ω_k]×] δω_j` with
//! `c_j = h/2 ([j=k] + [j=k+1]) + h²/12 (d^k_j − d^k+1_j)`; `δu_m = ΔR_m δa_m − [u_m]×ψ_m` and
//! `δu̇_m = ΔR_m (−[a_m]× δω_m + [ω_m]× δa_m + Σ_j d^m_j δa_j) − [u̇_m]×ψ_m`, and
//! `δp_k+1 = δp_k + h/2 (δv_k + δv_k+1) + h²/12 (δu_k − δu_k+1)`. The ψ_k terms give
//! the transition with `U1 = Δv_k+1 − Δv_k`, `U2 = Δp_k+1 − Δp_k − Δv_k h` (internal
//! `propagation` module); the gains of the stencil samples follow from the rules above
//! (`GainBasis`), are pulled back to the origin and added to their pending gains, so each
//! sample's noise enters once with the sum of its gains over every interval that reads it.
//!
//! At [`crate::Level::Deltas`] the same rules are rearranged so that everything but one
//! quaternion product and two rotations is independent of ΔR (the `deltas` submodule).

pub(crate) mod deltas;

use super::{Deltas, Node, s_plus_hat_hat2, span_s};
use crate::propagation::{
    Blk96, Cols6, Cols9, ErrorState, M3, Origin, Pending, PullBack, SLOTS, Transition, V3,
    rot_cols, skew_cols, skew_mul,
};
use preint_lie::hat;
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// The weights of an interval's rules, functions of its length `h` \[s\] alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Rule {
    pub h: f64,
    /// `h/2` and `h²/12` (the trapezoid and its end correction).
    h_2: f64,
    h2_12: f64,
}

impl Rule {
    /// The rule of the interval `[t0_ns, t1_ns]`.
    fn new(t0_ns: i64, t1_ns: i64) -> Self {
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
fn slopes(t: [i64; 3], m: usize) -> (f64, f64) {
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
struct Rates {
    lo: usize,
    alpha: f64,
    beta: f64,
}

impl Rates {
    /// The derivative at stencil position `m` of `st[..n]`: from the three consecutive samples
    /// around it (centred when both neighbours exist), or the difference quotient when
    /// `n = 2` (`α = 0`; `st[2]` is then any node).
    fn at(st: &[&Node; 4], n: usize, m: usize) -> Self {
        if n < 3 {
            return Self {
                lo: 0,
                alpha: 0.0,
                beta: 1.0 / span_s(st[0].t_ns, st[1].t_ns),
            };
        }
        let lo = m.saturating_sub(1).min(n - 3);
        let (alpha, beta) = slopes([st[lo].t_ns, st[lo + 1].t_ns, st[lo + 2].t_ns], m - lo);
        Self { lo, alpha, beta }
    }

    /// `(ω̇, ȧ)` at the node, from the stencil `st`.
    #[inline(always)]
    fn of(&self, st: &[&Node; 4]) -> (V3, V3) {
        rates(
            [st[self.lo], st[self.lo + 1], st[self.lo + 2]],
            self.alpha,
            self.beta,
        )
    }

    /// The weights by stencil position (of `f_j`, not of the differences).
    fn spread(&self) -> [f64; 4] {
        let mut out = [0.0; 4];
        out[self.lo] -= self.beta;
        out[self.lo + 1] += self.beta - self.alpha;
        out[self.lo + 2] += self.alpha;
        out
    }
}

/// `(ω̇, ȧ) = α (f₂ − f₁) + β (f₁ − f₀)` for `f = ω, a` over three consecutive nodes.
#[inline(always)]
fn rates(x: [&Node; 3], alpha: f64, beta: f64) -> (V3, V3) {
    (
        slope(&(x[2].w - x[1].w), &(x[1].w - x[0].w), alpha, beta),
        slope(&(x[2].a - x[1].a), &(x[1].a - x[0].a), alpha, beta),
    )
}

/// `α d₁₂ + β d₀₁`: the derivative from the two differences (rounded as `deltas` rounds it in
/// lanes, so that the slice path and [`step`] agree).
#[inline(always)]
fn slope(d12: &V3, d01: &V3, alpha: f64, beta: f64) -> V3 {
    d12 * alpha + d01 * beta
}

/// The rule and the derivative weights of a stencil at the interval's two nodes, with the
/// stencil they belong to: every interior interval of a uniform stream has the same offsets,
/// so they are computed once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Weights {
    /// `(n, kk, t_j − t_kk [ns])` of the stencil (`n = 0`: none yet). The weights are a
    /// function of these alone, so a match reuses them exactly.
    key: (usize, usize, [i64; 4]),
    rule: Rule,
    /// At node k (`st[kk]`) and node k+1 (`st[kk + 1]`).
    d0: Rates,
    d1: Rates,
}

impl Weights {
    /// The weights for stencil `st[..n]` and interval `[st[kk].t, st[kk+1].t]`.
    #[inline(always)]
    fn of(&mut self, st: &[&Node; 4], n: usize, kk: usize) -> &Self {
        let t0 = st[kk].t_ns;
        let mut off = [0i64; 4];
        for (o, node) in off.iter_mut().zip(&st[..n]) {
            *o = node.t_ns.wrapping_sub(t0);
        }
        let key = (n, kk, off);
        if key != self.key {
            *self = Self {
                key,
                rule: Rule::new(st[kk].t_ns, st[kk + 1].t_ns),
                d0: Rates::at(st, n, kk),
                d1: Rates::at(st, n, kk + 1),
            };
        }
        self
    }
}

/// The steady state's weights ([`Weights`] for the centred stencil `{k, k+1, k+2}` of node
/// k+1), keyed by the two intervals \[ns\]: what the slice path needs per sample.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SteadyWeights {
    key: (i64, i64),
    rule: Rule,
    alpha: f64,
    beta: f64,
}

impl SteadyWeights {
    /// The weights for the nodes at `t` \[ns\] (the default key (0, 0) matches no stream).
    #[inline(always)]
    fn of(&mut self, t: [i64; 3]) -> &Self {
        let key = (t[1].wrapping_sub(t[0]), t[2].wrapping_sub(t[1]));
        if key != self.key {
            let (alpha, beta) = slopes(t, 1);
            *self = Self {
                key,
                rule: Rule::new(t[0], t[1]),
                alpha,
                beta,
            };
        }
        self
    }
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

/// One interval `[st[kk].t, st[kk+1].t]` with stencil `st[..n]` (2–4 nodes, unused entries
/// may be any node: their weights are zero; the first has index `id0`); `first`: the window's
/// first interval, which also computes node k's derivatives (later intervals take them from
/// `d`). Gains are pulled back to `o`; `cache` keeps the last stencil's weights. Uses and
/// updates `d.u_last`, `d.du_last`, `d.dw_last`. With `LIN`, adds the pulled-back gain of each
/// stencil sample `id0 + j` to its pending gain in `pend` (and all of them to `sum`, if given)
/// and returns the transition and the pull-back used (`Φ_k+1⁻¹`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    st: &[&Node; 4],
    n: usize,
    kk: usize,
    first: bool,
    id0: usize,
    o: &mut Origin,
    cache: &mut Weights,
    pend: &mut [Pending; SLOTS],
    sum: Option<&mut Blk96>,
) -> Option<(Transition, PullBack)> {
    let (n0, n1) = (st[kk], st[kk + 1]);
    let Weights {
        rule: c, d0, d1, ..
    } = *cache.of(st, n, kk);
    if first {
        // Node k's derivatives; `u_last = ΔR_k a_k` is already set.
        let (dw0, da0) = d0.of(st);
        d.dw_last = dw0;
        if LIN {
            d.du_last = d.r * (n0.w.cross(&n0.a) + da0);
        } else {
            d.s_last = deltas::s_of(&n0.w, &n0.a, &da0);
        }
    }
    let (dw1, da1) = d1.of(st);
    if !LIN {
        deltas::step(d, &c, n0, n1, &dw1, &da1);
        return None;
    }
    let om = omega(&c, &n0.w, &n1.w, &d.dw_last, &dw1);
    let s1 = n1.w.cross(&n1.a) + da1;
    let k = RodriguesCoeffs::new(&om);
    let r0 = d.r;
    let r1 = r0 * i_plus_hat_hat2(&om, k.a, k.b);
    let (u0, du0) = (d.u_last, d.du_last);
    let (u1, du1) = (r1 * n1.a, r1 * s1);
    let v0 = d.v;
    let (v1, dp) = advance(&c, &v0, &u0, &du0, &u1, &du1);
    d.p += dp;
    d.v = v1;
    d.r = r1;
    d.u_last = u1;
    d.du_last = du1;
    d.dw_last = dw1;
    let (h_2, h12) = (c.h_2, c.h2_12);
    // ψ gains: F = ΔR_k Jl(Ω); sample k adds F·(−h²/12)[ω_k+1]×, sample k+1 F·(h²/12)[ω_k]×.
    let f = r0 * s_plus_hat_hat2(&om, 1.0, k.b, k.c);
    let fk = f * hat(&n1.w) * (-h12);
    let fk1 = f * hat(&n0.w) * h12;
    let pb = o.pull_back(n1.t_ns, &d.v, &d.p);
    let tau = pb.tau;
    // v and p rows of a ψ gain g: [x_v]× g and [x_p]× g (x_p = h/2 x_v + h²/12 u_k+1),
    // pulled back (propagation module).
    let xv = u1 * (-h_2) + du1 * h12;
    let xp = xv * h_2 + u1 * h12;
    let x = pb.dv + xv;
    let y = pb.w + xp - xv * tau;
    // The δω terms of u̇_k and u̇_k+1: v rows ∓h²/12 [u]×ΔR, p rows h/2 times those.
    let pv = h_2 - tau;
    let e0 = skew_mul(&u0, &r0);
    let e1 = skew_mul(&u1, &r1);
    let basis = GainBasis {
        f: skew_cols(&f, &x, &y),
        fk: add_vp(&skew_cols(&fk, &x, &y), &e0, -h12, -h12 * pv),
        fk1: add_vp(&skew_cols(&fk1, &x, &y), &e1, h12, h12 * pv),
        r0: rot_cols(&r0, 1.0, -tau),
        r1: rot_cols(&r1, 1.0, -tau),
        wk: rot_cols(&(r0 * hat(&n0.w)), h12, h12 * pv),
        wk1: rot_cols(&(r1 * hat(&n1.w)), -h12, -h12 * pv),
    };
    let (w0, w1) = (d0.spread(), d1.spread());
    let coef = |j: usize| -> [f64; 5] {
        let (ek, ek1) = (
            f64::from(u8::from(j == kk)),
            f64::from(u8::from(j == kk + 1)),
        );
        let (av, bv) = (h_2 * ek + h12 * w0[j], h_2 * ek1 - h12 * w1[j]);
        [
            h_2 * (ek + ek1) + h12 * (w0[j] - w1[j]),
            av,
            h_2 * av + h12 * ek,
            bv,
            h_2 * bv - h12 * ek1,
        ]
    };
    for j in 0..n {
        let (g, c) = (ErrorState::pending(pend, id0 + j), coef(j));
        if j == kk {
            basis.add_to::<FIRST>(g, &c);
        } else if j == kk + 1 {
            basis.add_to::<SECOND>(g, &c);
        } else {
            basis.add_to::<OUTER>(g, &c);
        }
    }
    if let Some(s) = sum {
        // Σ_j of the gains above: the basis is linear in the scalars, and samples k and k+1
        // add their own terms once each.
        let mut cs = [0.0; 5];
        for j in 0..n {
            for (a, b) in cs.iter_mut().zip(coef(j)) {
                *a += b;
            }
        }
        basis.add_to::<BOTH>(s, &cs);
    }
    let u2 = dp - v0 * c.h;
    Some((
        Transition {
            h: c.h,
            u1: v1 - v0,
            u2,
        },
        pb,
    ))
}

/// `b` with `e·(cv, cp)` added to its v and p rows.
#[inline(always)]
fn add_vp(b: &Cols9, e: &M3, cv: f64, cp: f64) -> Cols9 {
    let mut out = *b;
    for (c, col) in out.iter_mut().enumerate() {
        for i in 0..3 {
            col[3 + i] += cv * e[(i, c)];
            col[6 + i] += cp * e[(i, c)];
        }
    }
    out
}

/// What the pulled-back gains of one interval's stencil samples are made of (see [`step`]):
/// sample j's gyro columns are `c_j B(F) [+ B(F_k) + E_k if j = k] [+ B(F_k+1) + E_k+1 if
/// j = k+1]`, `B(g) = (g, [x]× g, [y]× g)`; its accelerometer columns are
/// `ΔR_k·(α_v, α_p − τα_v) + ΔR_k+1·(β_v, β_p − τβ_v)` with the scalars of `coef`, plus
/// `ΔR_k[ω_k]×·(h²/12, h³/20 − τh²/12)` if j = k and `ΔR_k+1[ω_k+1]×·(−h²/12, −h³/30 + τh²/12)`
/// if j = k+1.
struct GainBasis {
    f: Cols9,
    fk: Cols9,
    fk1: Cols9,
    /// `ΔR_k·(1, −τ)` and `ΔR_k+1·(1, −τ)`: scaled per sample by `(α_v, α_p)` and `(β_v, β_p)`.
    r0: Cols6,
    r1: Cols6,
    wk: Cols6,
    wk1: Cols6,
}

/// [`GainBasis::add_to`]'s roles: a stencil sample that is neither node of the interval, its
/// first node (k), its second (k+1), and the sum over the whole stencil.
const OUTER: u8 = 0;
const FIRST: u8 = 1;
const SECOND: u8 = 2;
const BOTH: u8 = FIRST | SECOND;

impl GainBasis {
    /// Adds the gain of a stencil sample with scalars `c = [c_j, α_v, α_p, β_v, β_p]` to `g`;
    /// `ROLE` says which node terms it has (`FIRST`: k's, `SECOND`: k+1's), so that the terms
    /// a sample does not have cost nothing.
    #[inline(always)]
    fn add_to<const ROLE: u8>(&self, g: &mut Blk96, c: &[f64; 5]) {
        let (k0, k1) = (ROLE & FIRST != 0, ROLE & SECOND != 0);
        for col in 0..3 {
            for i in 0..9 {
                let mut x = self.f[col][i] * c[0];
                if k0 {
                    x += self.fk[col][i];
                }
                if k1 {
                    x += self.fk1[col][i];
                }
                g.g[col][i] += x;
            }
        }
        for col in 0..3 {
            for i in 0..3 {
                // v rows: r·α_v; p rows: r·(α_p − τα_v) = (r·1)·α_p + (r·(−τ))·α_v.
                let mut v = self.r0[col][i] * c[1] + self.r1[col][i] * c[3];
                let mut p = self.r0[col][i] * c[2]
                    + self.r0[col][3 + i] * c[1]
                    + self.r1[col][i] * c[4]
                    + self.r1[col][3 + i] * c[3];
                if k0 {
                    v += self.wk[col][i];
                    p += self.wk[col][3 + i];
                }
                if k1 {
                    v += self.wk1[col][i];
                    p += self.wk1[col][3 + i];
                }
                g.a[col][i] += v;
                g.a[col][3 + i] += p;
            }
        }
    }
}
