//! High-order scheme (`Scheme::Rk4`): 4th-order Magnus for ΔR, Simpson for Δv and Δp, with
//! ω(t) and a(t) given by the Lagrange polynomial through a stencil of up to four samples.
//!
//! Interval `[t_k, t_k+1]`, `h`, stencil `{k−1, k, k+1, k+2}` (cubic). The stencil runs over the
//! window's samples extended by one *context* sample on each side when there is one: the
//! window path ([`crate::window::preintegrate`]) passes the stream samples just outside the
//! window, so the edge intervals use the same centred stencils as an integration of the whole
//! stream would, and consecutive windows compose exactly (see [`crate::window`]). Without a
//! context sample (a stream end, or samples pushed into a [`crate::Preintegrator`] directly)
//! the stencil is one-sided, `{0, 1, 2, 3}` for the first interval and `{N−4, …, N−1}` for the
//! last, which keeps the interpolation error O(h⁴); fewer than four samples in all give a
//! linear or quadratic polynomial. A context sample only shapes the polynomial: its noise and
//! bias enter like any other stencil sample's, but no interval outside the window is
//! integrated.
//!
//! With Gauss–Legendre nodes `c₁,₂ = ½ ∓ √3/6` and `κ = √3/12`:
//! `Ω = h/2 (ω(c₁h) + ω(c₂h)) + κ h² ω(c₁h) × ω(c₂h)` (4th-order Magnus for the right-invariant
//! ODE `Ṙ = R[ω]×`), the half-step `Ω_m` likewise on `[0, h/2]`;
//! `R_m = ΔR_k Exp(Ω_m)`, `ΔR_k+1 = ΔR_k Exp(Ω)`; `u0 = ΔR_k a_k`, `u_m = R_m a(h/2)`,
//! `u1 = ΔR_k+1 a_k+1`; `Δv_k+1 = Δv_k + h/6 (u0 + 4u_m + u1)`,
//! `Δp_k+1 = Δp_k + Δv_k h + h²/6 (u0 + 2u_m)` (Simpson on `(h − s) u(s)`).
//!
//! Linearisation (rotated coordinates `ψ = ΔR δφ`): `ψ_end = ψ + ΔR_k+1 Jr(Ω) δΩ`,
//! `ψ_m = ψ + R_m Jr(Ω_m) δΩ_m`, `δΩ = D₁δω(c₁h) + D₂δω(c₂h)` with
//! `D₁ = h/2 I − κh²[ω₂]×`, `D₂ = h/2 I + κh²[ω₁]×` (and the half-step analogues), and
//! `δω(τ) = Σ_j ℓ_j(τ) δω_j`; `δu = R δa − [u]×ψ` at each Simpson node. Then
//! `U1 = h/6 (u0 + 4u_m + u1)`, `U2 = h²/6 (u0 + 2u_m)`.

use super::{Deltas, Node, span_s};
use crate::propagation::{Blk96, Input, M3, Transition, V3, skew_mul};
use lie::hat;
use lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

const SQRT3_6: f64 = 0.288_675_134_594_812_9; // √3/6
const KAPPA: f64 = 0.144_337_567_297_406_43; // √3/12

/// Lagrange basis weights `ℓ_j(τ)` of the nodes `x[..n]` (seconds), with `den[j] = Π(x_j − x_m)`.
#[inline(always)]
fn weights(x: &[f64; 4], den: &[f64; 4], n: usize, tau: f64) -> [f64; 4] {
    let mut l = [0.0; 4];
    for j in 0..n {
        let mut num = 1.0;
        for (m, xm) in x.iter().enumerate().take(n) {
            if m != j {
                num *= tau - xm;
            }
        }
        l[j] = num / den[j];
    }
    l
}

#[inline(always)]
fn combo(l: &[f64; 4], st: &[Node], f: impl Fn(&Node) -> V3) -> V3 {
    let mut s = V3::zeros();
    for (j, node) in st.iter().enumerate() {
        s += f(node) * l[j];
    }
    s
}

/// One interval `[st[kk].t, st[kk+1].t]` with stencil `st` (2–4 nodes, the first has index
/// `id0`). Uses and updates `d.u_last`. With `LIN`, writes the gains of the stencil samples
/// into `out[..st.len()]` and returns the transition.
#[inline(always)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    st: &[Node],
    kk: usize,
    id0: usize,
    out: &mut [Input; 4],
) -> Option<Transition> {
    let n = st.len();
    let t0 = st[kk].t_ns;
    let h = span_s(t0, st[kk + 1].t_ns);
    let mut x = [0.0; 4];
    for (j, node) in st.iter().enumerate() {
        x[j] = span_s(t0, node.t_ns);
    }
    let mut den = [1.0; 4];
    for j in 0..n {
        for m in 0..n {
            if m != j {
                den[j] *= x[j] - x[m];
            }
        }
    }
    let (c1, c2) = (0.5 - SQRT3_6, 0.5 + SQRT3_6);
    let l1 = weights(&x, &den, n, c1 * h);
    let l2 = weights(&x, &den, n, c2 * h);
    let lm1 = weights(&x, &den, n, 0.5 * c1 * h);
    let lm2 = weights(&x, &den, n, 0.5 * c2 * h);
    let lh = weights(&x, &den, n, 0.5 * h);
    let w1 = combo(&l1, st, |s| s.w);
    let w2 = combo(&l2, st, |s| s.w);
    let wm1 = combo(&lm1, st, |s| s.w);
    let wm2 = combo(&lm2, st, |s| s.w);
    let am = combo(&lh, st, |s| s.a);
    let om = (w1 + w2) * (0.5 * h) + w1.cross(&w2) * (KAPPA * h * h);
    let hm = 0.5 * h;
    let omm = (wm1 + wm2) * (0.5 * hm) + wm1.cross(&wm2) * (KAPPA * hm * hm);
    let k = RodriguesCoeffs::new(&om);
    let km = RodriguesCoeffs::new(&omm);
    let r0 = d.r;
    let re = r0 * i_plus_hat_hat2(&om, k.a, k.b);
    let rm = r0 * i_plus_hat_hat2(&omm, km.a, km.b);
    let u0 = d.u_last;
    let um = rm * am;
    let u1 = re * st[kk + 1].a;
    let h6 = h / 6.0;
    let hh6 = h * h / 6.0;
    d.p += d.v * h + (u0 + um * 2.0) * hh6;
    d.v += (u0 + um * 4.0 + u1) * h6;
    d.r = re;
    d.u_last = u1;
    if !LIN {
        return None;
    }
    let f = re * i_plus_hat_hat2(&om, -k.b, k.c);
    let fm = rm * i_plus_hat_hat2(&omm, -km.b, km.c);
    let i3 = M3::identity();
    let d1 = i3 * (0.5 * h) - hat(&w2) * (KAPPA * h * h);
    let d2 = i3 * (0.5 * h) + hat(&w1) * (KAPPA * h * h);
    let dm1 = i3 * (0.5 * hm) - hat(&wm2) * (KAPPA * hm * hm);
    let dm2 = i3 * (0.5 * hm) + hat(&wm1) * (KAPPA * hm * hm);
    let (fd1, fd2, fmd1, fmd2) = (f * d1, f * d2, fm * dm1, fm * dm2);
    let (he1, he2) = (skew_mul(&u1, &fd1), skew_mul(&u1, &fd2));
    let (hm1, hm2) = (skew_mul(&um, &fmd1), skew_mul(&um, &fmd2));
    for j in 0..n {
        let hmj = hm1 * lm1[j] + hm2 * lm2[j];
        let hej = he1 * l1[j] + he2 * l2[j];
        let mut va = rm * (4.0 * lh[j] * h6);
        let mut pa = rm * (2.0 * lh[j] * hh6);
        if j == kk {
            va += r0 * h6;
            pa += r0 * hh6;
        }
        if j == kk + 1 {
            va += re * h6;
        }
        out[j] = Input {
            id: id0 + j,
            gain: Blk96 {
                rg: fd1 * l1[j] + fd2 * l2[j],
                vg: (hmj * 4.0 + hej) * (-h6),
                pg: hmj * (-2.0 * hh6),
                va,
                pa,
            },
        };
    }
    Some(Transition {
        h,
        u1: (u0 + um * 4.0 + u1) * h6,
        u2: (u0 + um * 2.0) * hh6,
    })
}
