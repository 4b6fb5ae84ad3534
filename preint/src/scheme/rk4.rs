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
//! `U1 = h/6 (u0 + 4u_m + u1)`, `U2 = h²/6 (u0 + 2u_m)`. The stencil samples' gains are
//! pulled back (internal `propagation` module) and added to their pending gains. On a uniform
//! grid every interior stencil has the same offsets, so its Lagrange weights are computed once
//! (`Weights`).

use super::{Deltas, Node, s_plus_hat_hat2, span_s};
use crate::propagation::{
    Blk96, Cols6, Cols9, ErrorState, M3, Origin, Pending, PullBack, SLOTS, Transition, V3,
    rot_cols, skew_mul,
};
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

/// The Lagrange weights of a stencil at the five points the scheme evaluates (the Gauss nodes
/// of the interval and of its first half, and its midpoint), with the stencil they belong to:
/// every interior interval of a uniform stream has the same offsets, so they are computed once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Weights {
    /// `(n, kk, t_j − t_kk [ns])` of the stencil (`n = 0`: none yet). The weights are a
    /// function of these alone, so a match reuses them exactly.
    key: (usize, usize, [i64; 4]),
    l1: [f64; 4],
    l2: [f64; 4],
    lm1: [f64; 4],
    lm2: [f64; 4],
    lh: [f64; 4],
}

impl Weights {
    /// The weights for stencil `st[..n]` and interval `[st[kk].t, st[kk+1].t]` (zero for the
    /// unused nodes `j ≥ n`).
    #[inline(always)]
    fn of(&mut self, st: &[&Node; 4], n: usize, kk: usize) -> &Self {
        let t0 = st[kk].t_ns;
        let mut off = [0i64; 4];
        for (o, node) in off.iter_mut().zip(&st[..n]) {
            *o = node.t_ns.wrapping_sub(t0);
        }
        let key = (n, kk, off);
        if key != self.key {
            self.compute(st, kk, key);
        }
        self
    }

    #[inline(never)]
    fn compute(&mut self, st: &[&Node; 4], kk: usize, key: (usize, usize, [i64; 4])) {
        let n = key.0;
        let t0 = st[kk].t_ns;
        let h = span_s(t0, st[kk + 1].t_ns);
        let mut x = [0.0; 4];
        for (j, node) in st[..n].iter().enumerate() {
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
        *self = Self {
            key,
            l1: weights(&x, &den, n, c1 * h),
            l2: weights(&x, &den, n, c2 * h),
            lm1: weights(&x, &den, n, 0.5 * c1 * h),
            lm2: weights(&x, &den, n, 0.5 * c2 * h),
            lh: weights(&x, &den, n, 0.5 * h),
        };
    }
}

/// One interval `[st[kk].t, st[kk+1].t]` with stencil `st[..n]` (2–4 nodes, the first has
/// index `id0`; `cache` keeps the last stencil's Lagrange weights); gains are pulled back to
/// `o`. Uses and updates `d.u_last`. With `LIN`, adds the pulled-back gain of each stencil
/// sample `id0 + j` to its pending gain in `pend` (and all of them to `sum`, if given) and returns the
/// transition and the pull-back used (`Φ_k+1⁻¹`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn step<const LIN: bool>(
    d: &mut Deltas,
    st: &[&Node; 4],
    n: usize,
    kk: usize,
    id0: usize,
    o: &mut Origin,
    cache: &mut Weights,
    pend: &mut [Pending; SLOTS],
    sum: Option<&mut Blk96>,
) -> Option<(Transition, PullBack)> {
    let h = span_s(st[kk].t_ns, st[kk + 1].t_ns);
    let Weights {
        l1,
        l2,
        lm1,
        lm2,
        lh,
        ..
    } = *cache.of(st, n, kk);
    // ω at the four Gauss nodes and a at the midpoint (the weights of unused nodes are 0).
    let (mut w1, mut w2, mut wm1, mut wm2, mut am) = (
        V3::zeros(),
        V3::zeros(),
        V3::zeros(),
        V3::zeros(),
        V3::zeros(),
    );
    for (j, node) in st.iter().enumerate() {
        w1 += node.w * l1[j];
        w2 += node.w * l2[j];
        wm1 += node.w * lm1[j];
        wm2 += node.w * lm2[j];
        am += node.a * lh[j];
    }
    let om = (w1 + w2) * (0.5 * h) + w1.cross(&w2) * (KAPPA * h * h);
    let hm = 0.5 * h;
    let omm = (wm1 + wm2) * (0.5 * hm) + wm1.cross(&wm2) * (KAPPA * hm * hm);
    let h6 = h / 6.0;
    let hh6 = h * h / 6.0;
    if !LIN {
        // Level::Deltas: ΔR as a unit quaternion (`Deltas`).
        let q1 = d.q.mul_exp(&om, om.norm_squared());
        let um = d.q.mul_exp(&omm, omm.norm_squared()).rotate(&am);
        let u1 = q1.rotate(&st[kk + 1].a);
        let u0 = d.u_last;
        d.p += d.v * h + (u0 + um * 2.0) * hh6;
        d.v += (u0 + um * 4.0 + u1) * h6;
        d.q = q1;
        d.u_last = u1;
        return None;
    }
    let k = RodriguesCoeffs::new(&om);
    let km = RodriguesCoeffs::new(&omm);
    let r0 = d.r;
    let re = r0 * i_plus_hat_hat2(&om, k.a, k.b);
    let rm = r0 * i_plus_hat_hat2(&omm, km.a, km.b);
    let u0 = d.u_last;
    let um = rm * am;
    let u1 = re * st[kk + 1].a;
    d.p += d.v * h + (u0 + um * 2.0) * hh6;
    d.v += (u0 + um * 4.0 + u1) * h6;
    d.r = re;
    d.u_last = u1;
    // ΔR_k+1 Jr(Ω) = ΔR_k Jl(Ω) and R_m Jr(Ω_m) = ΔR_k Jl(Ω_m) (Exp(φ) Jr(φ) = Jl(φ)).
    let f = r0 * s_plus_hat_hat2(&om, 1.0, k.b, k.c);
    let fm = r0 * s_plus_hat_hat2(&omm, 1.0, km.b, km.c);
    let i3 = M3::identity();
    let d1 = i3 * (0.5 * h) - hat(&w2) * (KAPPA * h * h);
    let d2 = i3 * (0.5 * h) + hat(&w1) * (KAPPA * h * h);
    let dm1 = i3 * (0.5 * hm) - hat(&wm2) * (KAPPA * hm * hm);
    let dm2 = i3 * (0.5 * hm) + hat(&wm1) * (KAPPA * hm * hm);
    let (fd1, fd2, fmd1, fmd2) = (f * d1, f * d2, fm * dm1, fm * dm2);
    // Rotated gains of sample j: ψ ← r_j = fd1 ℓ₁ + fd2 ℓ₂, v ← −h/6 (4 [u_m]× m_j + [u1]× r_j),
    // p ← −h²/3 [u_m]× m_j with m_j = fmd1 ℓm₁ + fmd2 ℓm₂. Pulled back (propagation module):
    // v' = [x]× r_j − 4h/6 [u_m]× m_j, p' = [y]× r_j + (4τh/6 − h²/3) [u_m]× m_j.
    let pb = o.pull_back(st[kk + 1].t_ns, &d.v, &d.p);
    let tau1 = pb.tau;
    let x = pb.dv - u1 * h6;
    let y = pb.w + u1 * (tau1 * h6);
    let (xr1, xr2) = (skew_mul(&x, &fd1), skew_mul(&x, &fd2));
    let (yr1, yr2) = (skew_mul(&y, &fd1), skew_mul(&y, &fd2));
    let (hm1, hm2) = (skew_mul(&um, &fmd1), skew_mul(&um, &fmd2));
    let cm = 4.0 * tau1 * h6 - 2.0 * hh6;
    let basis = GainBasis::new(
        [fd1, fd2],
        [xr1, xr2],
        [yr1, yr2],
        [hm1 * (-4.0 * h6), hm2 * (-4.0 * h6)],
        [hm1 * cm, hm2 * cm],
        [&r0, &rm, &re],
        [h6, hh6, tau1],
    );
    let wj = |j: usize| [l1[j], l2[j], lm1[j], lm2[j], lh[j]];
    for j in 0..n {
        basis.add_to(
            ErrorState::pending(pend, id0 + j),
            wj(j),
            j == kk,
            j == kk + 1,
        );
    }
    if let Some(s) = sum {
        for j in 0..n {
            basis.add_to(s, wj(j), j == kk, j == kk + 1);
        }
    }
    Some((
        Transition {
            h,
            u1: (u0 + um * 4.0 + u1) * h6,
            u2: (u0 + um * 2.0) * hh6,
        },
        pb,
    ))
}

/// What the gains of one interval's stencil samples are made of (see [`step`]), by columns:
/// sample j's pulled-back gain is `Σ_i w_i B_i` with `w = [ℓ₁, ℓ₂, ℓm₁, ℓm₂]` for the gyro
/// columns (`B_i` stacks `fd_i`, `xr_i`, `yr_i` for i = 1, 2 and `0`, `−(4h/6) hm_i`,
/// `c_m hm_i` for the half-step terms), and `ℓh A_m [+ A_0 if j = kk] [+ A_1 if j = kk+1]` for
/// the accelerometer columns, with `A_m = R_m·(4h/6, h²/3 − 4τh/6)`,
/// `A_0 = ΔR_k·(h/6, h²/6 − τh/6)`, `A_1 = ΔR_k+1·(h/6, −τh/6)` (v and p rows, `p' = p − τ v`).
struct GainBasis {
    g: [Cols9; 4],
    a: [Cols6; 3],
}

impl GainBasis {
    #[inline(always)]
    fn new(
        fd: [M3; 2],
        xr: [M3; 2],
        yr: [M3; 2],
        hv: [M3; 2],
        hp: [M3; 2],
        [r0, rm, re]: [&M3; 3],
        [h6, hh6, tau]: [f64; 3],
    ) -> Self {
        let z = M3::zeros();
        let stack = |a: &M3, b: &M3, c: &M3| {
            let mut out = [[0.0; 9]; 3];
            for (k, col) in out.iter_mut().enumerate() {
                for i in 0..3 {
                    col[i] = a[(i, k)];
                    col[3 + i] = b[(i, k)];
                    col[6 + i] = c[(i, k)];
                }
            }
            out
        };
        let vm = 4.0 * h6;
        Self {
            g: [
                stack(&fd[0], &xr[0], &yr[0]),
                stack(&fd[1], &xr[1], &yr[1]),
                stack(&z, &hv[0], &hp[0]),
                stack(&z, &hv[1], &hp[1]),
            ],
            a: [
                rot_cols(rm, vm, 2.0 * hh6 - tau * vm),
                rot_cols(r0, h6, hh6 - tau * h6),
                rot_cols(re, h6, -tau * h6),
            ],
        }
    }

    /// Adds the gain of the stencil sample with weights `w = [ℓ₁, ℓ₂, ℓm₁, ℓm₂, ℓh]` to `g`;
    /// `first`/`second`: it is the interval's first/second node.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // parallel arrays, indexed alike
    fn add_to(&self, g: &mut Blk96, w: [f64; 5], first: bool, second: bool) {
        let b = &self.g;
        for c in 0..3 {
            for i in 0..9 {
                g.g[c][i] +=
                    b[0][c][i] * w[0] + b[1][c][i] * w[1] + b[2][c][i] * w[2] + b[3][c][i] * w[3];
            }
        }
        let (w0, w1) = (f64::from(u8::from(first)), f64::from(u8::from(second)));
        for c in 0..3 {
            for i in 0..6 {
                g.a[c][i] += self.a[0][c][i] * w[4] + self.a[1][c][i] * w0 + self.a[2][c][i] * w1;
            }
        }
    }
}
