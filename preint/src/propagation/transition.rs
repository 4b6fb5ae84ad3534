//! Transitions of the rotated error `e = [ψ, v, p]` between nodes, and the pull-back to the
//! window's origin (parent module docs).
//!
//! Every transition has the form
//! `Φ = [[I, 0, 0], [−[V]×, I, 0], [−[W]×, T I, I]]`: an interval's with `T = h`,
//! `V = U1 = Δv_k+1 − Δv_k`, `W = U2 = Δp_k+1 − Δp_k − Δv_k h`, and products of such
//! transitions keep it ([`Transition`]). The origin is node 1; `Φ_k = Φ(o → k)` and its inverse
//! [`PullBack`] carry a gain between node k and the origin.

use super::blocks::{Gain96, M3, PackedSym9, SymBlocks9, V3, cross, mul_skew, skew_mul};
use crate::sample::span_s;

/// The transition `Φ` between two nodes (module docs): duration `h` \[s\], `U1` [m/s],
/// `U2` \[m\].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Transition {
    pub h: f64,
    pub u1: V3,
    pub u2: V3,
}

impl Transition {
    /// `Φ X` for a 9×6 block matrix.
    #[inline(always)]
    pub(crate) fn apply(&self, x: &Gain96) -> Gain96 {
        let mut out = *x;
        for (o, col) in out.g.iter_mut().zip(&x.g) {
            let r = [col[0], col[1], col[2]];
            let (a, b) = (cross(&self.u1, r), cross(&self.u2, r));
            for i in 0..3 {
                o[3 + i] = col[3 + i] - a[i];
                o[6 + i] = col[6 + i] + col[3 + i] * self.h - b[i];
            }
        }
        for (o, col) in out.a.iter_mut().zip(&x.a) {
            for i in 0..3 {
                o[3 + i] = col[3 + i] + col[i] * self.h;
            }
        }
        out
    }

    /// `Φ P Φᵀ` by blocks.
    pub(crate) fn push_forward(&self, s: &PackedSym9) -> SymBlocks9 {
        let p = SymBlocks9 {
            rr: s.block(0, 0),
            rv: s.block(0, 1),
            rp: s.block(0, 2),
            vv: s.block(1, 1),
            vp: s.block(1, 2),
            pp: s.block(2, 2),
        };
        let h = self.h;
        let (u1, u2) = (&self.u1, &self.u2);
        let p_vr = p.rv.transpose();
        let p_pr = p.rp.transpose();
        let p_pv = p.vp.transpose();
        // Rows of Φ P.
        let ap_vr = p_vr - skew_mul(u1, &p.rr);
        let ap_vv = p.vv - skew_mul(u1, &p.rv);
        let ap_vp = p.vp - skew_mul(u1, &p.rp);
        let ap_pr = p_pr + p_vr * h - skew_mul(u2, &p.rr);
        let ap_pv = p_pv + p.vv * h - skew_mul(u2, &p.rv);
        let ap_pp = p.pp + p.vp * h - skew_mul(u2, &p.rp);
        // (Φ P) Φᵀ; (−[U]×)ᵀ = [U]×.
        SymBlocks9 {
            rr: p.rr,
            rv: p.rv + mul_skew(&p.rr, u1),
            rp: p.rp + p.rv * h + mul_skew(&p.rr, u2),
            vv: ap_vv + mul_skew(&ap_vr, u1),
            vp: ap_vp + ap_vv * h + mul_skew(&ap_vr, u2),
            pp: ap_pp + ap_pv * h + mul_skew(&ap_pr, u2),
        }
    }
}

/// The origin of the pulled-back error (parent module docs): node 1, the end of the window's
/// first interval.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Origin {
    pub t_ns: i64,
    pub v: V3,
    pub p: V3,
    pub set: bool,
}

impl Origin {
    /// `Φ_k⁻¹` for node k at `t_ns` \[ns\] with deltas `(v, p)`; the first call (node 1) fixes
    /// the origin there.
    #[inline(always)]
    pub(crate) fn pull_back(&mut self, t_ns: i64, v: &V3, p: &V3) -> PullBack {
        if !self.set {
            *self = Self {
                t_ns,
                v: *v,
                p: *p,
                set: true,
            };
        }
        let tau = span_s(self.t_ns, t_ns);
        PullBack {
            dv: v - self.v,
            w: p - self.p - v * tau,
            tau,
        }
    }

    /// `Φ_k` for node k at `t_ns` \[ns\] with deltas `(v, p)`: what pushes a pulled-back
    /// quantity forward to that node.
    pub(crate) fn push_to(&self, t_ns: i64, v: &V3, p: &V3) -> Transition {
        let tau = span_s(self.t_ns, t_ns);
        Transition {
            h: tau,
            u1: v - self.v,
            u2: p - self.p - self.v * tau,
        }
    }
}

/// `Φ_k⁻¹` at node k (parent module docs): a gain entering there is pulled back to the
/// origin. A gain column `(r, v, p)` becomes `(r, v + V × r, p − τ v + (W − τV) × r)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PullBack {
    /// `V = Δv_k − Δv_o` [m/s].
    pub dv: V3,
    /// `W − τ V = Δp_k − Δp_o − τ Δv_k` \[m\].
    pub w: V3,
    /// `τ = t_k − t_o` \[s\].
    pub tau: f64,
}

impl PullBack {
    /// The skew rows `(x, y)` of a ψ gain `g` (v and p rows `[x]× g`, `[y]× g`) pulled back:
    /// `(x + V, y − τ x + W − τV)`.
    #[inline(always)]
    pub(crate) fn skew(&self, x: &V3, y: &V3) -> (V3, V3) {
        (x + self.dv, self.w + y - x * self.tau)
    }

    /// The scalars `(c_v, c_p)` of a (v, p)-rows gain `M·(c_v, c_p)` pulled back:
    /// `(c_v, c_p − τ c_v)`.
    #[inline(always)]
    pub(crate) fn vp(&self, cv: f64, cp: f64) -> (f64, f64) {
        (cv, cp - self.tau * cv)
    }

    /// `Φ_k`, the inverse.
    #[inline(always)]
    pub(crate) fn forward(&self) -> Transition {
        Transition {
            h: self.tau,
            u1: self.dv,
            u2: self.w + self.dv * self.tau,
        }
    }

    /// `Φ_k⁻¹ X` for a 9×6 block matrix in rotated coordinates at node k.
    #[inline(always)]
    pub(crate) fn apply(&self, x: &Gain96) -> Gain96 {
        let mut out = *x;
        for (o, col) in out.g.iter_mut().zip(&x.g) {
            let r = [col[0], col[1], col[2]];
            let (a, b) = (cross(&self.dv, r), cross(&self.w, r));
            for i in 0..3 {
                o[3 + i] = col[3 + i] + a[i];
                o[6 + i] = col[6 + i] - col[3 + i] * self.tau + b[i];
            }
        }
        for (o, col) in out.a.iter_mut().zip(&x.a) {
            for i in 0..3 {
                o[3 + i] = col[3 + i] - col[i] * self.tau;
            }
        }
        out
    }
}

/// `M` with a rotation: `R M Rᵀ`, symmetrised.
#[inline(always)]
pub(crate) fn rotated_sym(r: &M3, m: &M3) -> M3 {
    let x = r * m * r.transpose();
    (x + x.transpose()) * 0.5
}
