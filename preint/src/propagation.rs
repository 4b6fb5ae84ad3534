//! Error-state propagation in rotated coordinates, shared by every scheme.
//!
//! Chart (documented in [`crate::measurement`]): `ΔR = ΔR°·Exp(δφ)`, `Δv = Δv° + δv`,
//! `Δp = Δp° + δp`. Internally the rotation error is kept as `ψ = ΔR_k δφ` (the same error as a
//! left perturbation, in frame i). With that choice the rotation block of every transition is
//! the identity and `ΔR_k[a]×δφ = [u]×ψ` with `u = ΔR_k a` (PERFORMANCE.md, trick 2). Every
//! scheme's interval is linear in this error state and in the perturbations `n_j = [δω_j, δa_j]`
//! of the samples of its stencil:
//!
//! ```text
//! e_k+1 = A_k e_k + Σ_j Γ_kj n_j,   A_k = [[I, 0, 0], [−[U1]×, I, 0], [−[U2]×, h I, I]]
//! ```
//!
//! where `U1 = ∫ ΔR(t) a(t) dt` and `U2 = ∫ (h − s) ΔR(s) a(s) ds` over the interval (as the
//! scheme discretises them). A sample used by several intervals (midpoint: 2, rk4: up to 4)
//! keeps its cross-covariance `X_j = Cov(e, n_j)`; with `Z_j = A X_j` and
//! `W_j = Z_j + ½ Γ_j Q_j`:
//!
//! ```text
//! P ← A P Aᵀ + Σ_j (W_j Γ_jᵀ + Γ_j W_jᵀ),   X_j ← W_j + ½ Γ_j Q_j
//! ```
//!
//! which equals `A P Aᵀ + Σ_j (A X_j Γ_jᵀ + Γ_j X_jᵀ Aᵀ + Γ_j Q_j Γ_jᵀ)`. Bias Jacobians:
//! every sample sees `−δb`, so `J ← A J − Σ_j Γ_j`. Combined covariance (bias deviation `δb`
//! constant over an interval, then a random-walk step): `C = Cov(e, δb)`,
//! `V = A C + ½ Γ_Σ P_bb`, `P += V Γ_Σᵀ + Γ_Σ Vᵀ`, `C ← V + ½ Γ_Σ P_bb`, `P_bb += Σ_rw h`.

use nalgebra::{Matrix3, Vector3};

pub(crate) type M3 = Matrix3<f64>;
pub(crate) type V3 = Vector3<f64>;

/// A 9×6 matrix in 3×3 blocks, rows [ψ, v, p], columns [ω (or b_g), a (or b_a)]. The ψ–a block
/// is identically zero for every quantity propagated here (acceleration never moves ΔR).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Blk96 {
    pub rg: M3,
    pub vg: M3,
    pub pg: M3,
    pub va: M3,
    pub pa: M3,
}

impl Blk96 {
    #[inline(always)]
    fn add(&self, o: &Self) -> Self {
        Self {
            rg: self.rg + o.rg,
            vg: self.vg + o.vg,
            pg: self.pg + o.pg,
            va: self.va + o.va,
            pa: self.pa + o.pa,
        }
    }
    #[inline(always)]
    fn scale(&self, s: f64) -> Self {
        Self {
            rg: self.rg * s,
            vg: self.vg * s,
            pg: self.pg * s,
            va: self.va * s,
            pa: self.pa * s,
        }
    }
    /// `self · diag(Qg, Qa)`.
    #[inline(always)]
    fn mul_diag(&self, qg: &M3, qa: &M3) -> Self {
        Self {
            rg: self.rg * qg,
            vg: self.vg * qg,
            pg: self.pg * qg,
            va: self.va * qa,
            pa: self.pa * qa,
        }
    }
}

/// Symmetric 9×9 in its six distinct 3×3 blocks, order [ψ, v, p].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Sym9 {
    pub rr: M3,
    pub rv: M3,
    pub rp: M3,
    pub vv: M3,
    pub vp: M3,
    pub pp: M3,
}

/// `[u]× M` column by column (cross products, no 3×3 product).
#[inline(always)]
pub(crate) fn skew_mul(u: &V3, m: &M3) -> M3 {
    let c0 = u.cross(&m.column(0).into_owned());
    let c1 = u.cross(&m.column(1).into_owned());
    let c2 = u.cross(&m.column(2).into_owned());
    M3::from_columns(&[c0, c1, c2])
}

/// `M [u]×` = `−([u]× Mᵀ)ᵀ`.
#[inline(always)]
fn mul_skew(m: &M3, u: &V3) -> M3 {
    -skew_mul(u, &m.transpose()).transpose()
}

/// The transition of one interval: `h` [s], `U1` [m/s], `U2` [m] (see module doc).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Transition {
    pub h: f64,
    pub u1: V3,
    pub u2: V3,
}

impl Transition {
    /// `A X` for a 9×6 block matrix.
    #[inline(always)]
    fn apply(&self, x: &Blk96) -> Blk96 {
        Blk96 {
            rg: x.rg,
            vg: x.vg - skew_mul(&self.u1, &x.rg),
            pg: x.pg + x.vg * self.h - skew_mul(&self.u2, &x.rg),
            va: x.va,
            pa: x.pa + x.va * self.h,
        }
    }

    /// `A P Aᵀ` by blocks.
    #[inline(always)]
    fn conjugate(&self, p: &Sym9) -> Sym9 {
        let h = self.h;
        let (u1, u2) = (&self.u1, &self.u2);
        let p_vr = p.rv.transpose();
        let p_pr = p.rp.transpose();
        let p_pv = p.vp.transpose();
        // Rows of A P.
        let ap_vr = p_vr - skew_mul(u1, &p.rr);
        let ap_vv = p.vv - skew_mul(u1, &p.rv);
        let ap_vp = p.vp - skew_mul(u1, &p.rp);
        let ap_pr = p_pr + p_vr * h - skew_mul(u2, &p.rr);
        let ap_pv = p_pv + p.vv * h - skew_mul(u2, &p.rv);
        let ap_pp = p.pp + p.vp * h - skew_mul(u2, &p.rp);
        // (A P) Aᵀ; (−[U]×)ᵀ = [U]×.
        Sym9 {
            rr: p.rr,
            rv: p.rv + mul_skew(&p.rr, u1),
            rp: p.rp + p.rv * h + mul_skew(&p.rr, u2),
            vv: ap_vv + mul_skew(&ap_vr, u1),
            vp: ap_vp + ap_vv * h + mul_skew(&ap_vr, u2),
            pp: ap_pp + ap_pv * h + mul_skew(&ap_pr, u2),
        }
    }
}

/// `P += W Γᵀ + Γ Wᵀ` (both 9×6 with zero ψ–a block).
#[inline(always)]
fn add_sym(p: &mut Sym9, w: &Blk96, g: &Blk96) {
    let t = w.rg * g.rg.transpose();
    p.rr += t + t.transpose();
    p.rv += w.rg * g.vg.transpose() + g.rg * w.vg.transpose();
    p.rp += w.rg * g.pg.transpose() + g.rg * w.pg.transpose();
    let t = w.vg * g.vg.transpose() + w.va * g.va.transpose();
    p.vv += t + t.transpose();
    p.vp += w.vg * g.pg.transpose()
        + w.va * g.pa.transpose()
        + g.vg * w.pg.transpose()
        + g.va * w.pa.transpose();
    let t = w.pg * g.pg.transpose() + w.pa * g.pa.transpose();
    p.pp += t + t.transpose();
}

/// Per-sample white-noise covariance `Q_j = s_j · diag(Σ_g, Σ_a)`, `s_j` = 1 / (the sample's
/// time cell) [1/s]. Monomorphised once per noise shape.
pub(crate) trait NoiseQ: Copy {
    /// `Γ Q` for `Q = s · diag(Σ_g, Σ_a)`.
    fn gq(&self, g: &Blk96, s: f64) -> Blk96;
}

/// Isotropic `Σ_g = g I`, `Σ_a = a I`: scalar products only.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IsoQ {
    pub g: f64,
    pub a: f64,
}

impl NoiseQ for IsoQ {
    #[inline(always)]
    fn gq(&self, x: &Blk96, s: f64) -> Blk96 {
        let (g, a) = (self.g * s, self.a * s);
        Blk96 {
            rg: x.rg * g,
            vg: x.vg * g,
            pg: x.pg * g,
            va: x.va * a,
            pa: x.pa * a,
        }
    }
}

/// General (anisotropic) `Σ_g`, `Σ_a`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GenQ {
    pub g: M3,
    pub a: M3,
}

impl NoiseQ for GenQ {
    #[inline(always)]
    fn gq(&self, x: &Blk96, s: f64) -> Blk96 {
        x.mul_diag(&(self.g * s), &(self.a * s))
    }
}

/// Cross-covariance of the error with one still-used sample's noise.
#[derive(Clone, Copy, Debug)]
struct Pending {
    id: usize,
    x: Blk96,
}

/// Number of pending-sample slots (≥ the largest stencil).
const SLOTS: usize = 4;

/// One sample's contribution to an interval: its index, `s_j` [1/s] and its gain `Γ_j`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Input {
    pub id: usize,
    pub scale: f64,
    pub gain: Blk96,
}

/// The error state: covariance, bias Jacobians and the combined-covariance terms, all in
/// rotated coordinates.
#[derive(Clone, Debug)]
pub(crate) struct ErrorState {
    /// Covariance of the deltas from white measurement noise only (what `PreintegratedImu::cov`
    /// and the `ImuFactor` use, as GTSAM's `ImuFactor`).
    pub p: Sym9,
    /// The part of the deltas' covariance driven by the bias random walk during the window
    /// (combined level only); `p + p_walk` is the 9×9 block of the 15×15 covariance. Kept apart
    /// because propagation is linear, so the two parts evolve independently.
    pub p_walk: Sym9,
    pub j: Blk96,
    pub c: Blk96,
    pub pbb_g: M3,
    pub pbb_a: M3,
    pending: [Pending; SLOTS],
}

impl Default for ErrorState {
    fn default() -> Self {
        Self {
            p: Sym9::default(),
            p_walk: Sym9::default(),
            j: Blk96::default(),
            c: Blk96::default(),
            pbb_g: M3::zeros(),
            pbb_a: M3::zeros(),
            pending: [Pending {
                id: usize::MAX,
                x: Blk96::default(),
            }; SLOTS],
        }
    }
}

/// Bias random-walk densities and whether to propagate the combined terms.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BiasWalk {
    pub combined: bool,
    pub g: M3,
    pub a: M3,
}

impl ErrorState {
    /// Propagates through one interval (see module doc for the equations).
    #[inline(always)]
    pub(crate) fn step<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        inputs: &[Input],
        noise: &N,
        walk: &BiasWalk,
    ) {
        // X_j, C are untouched by the conjugation, so A X_j and A C can be formed afterwards.
        let v = if walk.combined {
            self.p_walk = tr.conjugate(&self.p_walk);
            Some(tr.apply(&self.c))
        } else {
            None
        };
        self.p = tr.conjugate(&self.p);
        let mut gsum = inputs[0].gain;
        for (k, inp) in inputs.iter().enumerate() {
            if k > 0 {
                gsum = gsum.add(&inp.gain);
            }
            let slot = &mut self.pending[inp.id % SLOTS];
            let half_gq = noise.gq(&inp.gain, inp.scale).scale(0.5);
            let wk = if slot.id == inp.id {
                tr.apply(&slot.x).add(&half_gq)
            } else {
                half_gq
            };
            add_sym(&mut self.p, &wk, &inp.gain);
            *slot = Pending {
                id: inp.id,
                x: wk.add(&half_gq),
            };
        }
        if let Some(v) = v {
            let half = gsum.mul_diag(&self.pbb_g, &self.pbb_a).scale(0.5);
            let v = v.add(&half);
            add_sym(&mut self.p_walk, &v, &gsum);
            self.c = v.add(&half);
        }
        self.pbb_g += walk.g * tr.h;
        self.pbb_a += walk.a * tr.h;
        let aj = tr.apply(&self.j);
        self.j = aj.add(&gsum.scale(-1.0));
    }
}
