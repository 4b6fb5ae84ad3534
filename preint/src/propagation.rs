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
//! where `U1 = ∫ ΔR(t) a(t) dt` and `U2 = ∫ (h − s) ΔR(s) a(s) ds` over the interval, as the
//! scheme discretises them; for every scheme here they are exactly the increments
//! `U1 = Δv_k+1 − Δv_k`, `U2 = Δp_k+1 − Δp_k − Δv_k h`.
//!
//! # Pending gains: each sample's noise enters once
//!
//! A sample is used by every interval whose stencil holds it (Euler 1, midpoint 2, rk4 up to 4),
//! so its noise must not be added once per interval. Write the error after interval k as
//! `e = f + Σ_{j pending} G_j n_j`, the pending samples being those a later interval still
//! uses, `G_j` their accumulated gains and `f` independent of them. Then per interval
//!
//! ```text
//! P_f ← A P_f Aᵀ,   G_j ← A G_j + Γ_kj   (a sample first used here starts at G_j = Γ_kj),
//! ```
//!
//! and a sample no later interval uses is *retired*: `P_f += G_j Q_j G_jᵀ`, with
//! `Q_j = diag(Σ_g, Σ_a)·white_scale(c_j)` ([`crate::noise`]). At the end every pending sample
//! is retired. No cross-covariance is kept; the result is the exact first-order covariance
//! `Σ_j G_j Q_j G_jᵀ`. Euler has no pending sample; midpoint has one (sample k+1, whose
//! *merged gain* `A Γ_k,1 + Γ_k+1,0` is added when interval k+1 is done, see
//! [`ErrorState::step_mid`]); rk4 has up to four ([`ErrorState::step_multi`]).
//!
//! # Transition between any two nodes
//!
//! Products of such transitions keep the form: from node k to node m,
//! `Φ = [[I, 0, 0], [−[V]×, I, 0], [−[W]×, T I, I]]` with `T = t_m − t_k`, `V = Δv_m − Δv_k`,
//! `W = Δp_m − Δp_k − Δv_k T` (compose two steps and use the increments above). So a gain
//! known at node k is carried to the end of the window from the deltas alone
//! ([`Transition::between`]), which is how the gains of the samples near the window edges are
//! collected without per-interval work.
//!
//! # Bias Jacobians and the combined covariance
//!
//! Every sample sees `−δb`, so `J ← A J − Σ_j Γ_kj`. Combined covariance (bias deviation `δb`
//! constant over an interval, then a random-walk step): `C = Cov(e, δb)`,
//! `V = A C + ½ Γ_Σ P_bb`, `P += V Γ_Σᵀ + Γ_Σ Vᵀ`, `C ← V + ½ Γ_Σ P_bb`,
//! `P_bb += Σ_rw·walk_scale(h)`, with `Γ_Σ = Σ_j Γ_kj`.

use crate::noise::walk_scale;
use nalgebra::{Matrix3, SMatrix, Vector3};

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
    pub(crate) fn add(&self, o: &Self) -> Self {
        Self {
            rg: self.rg + o.rg,
            vg: self.vg + o.vg,
            pg: self.pg + o.pg,
            va: self.va + o.va,
            pa: self.pa + o.pa,
        }
    }
    #[inline(always)]
    pub(crate) fn scale(&self, s: f64) -> Self {
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
    /// The dense 9×6 matrix with the ψ rows premultiplied by `rt` (rotated coordinates → the
    /// chart `δφ = ΔRᵀ ψ` when `rt = ΔRᵀ`).
    pub(crate) fn chart(&self, rt: &M3) -> SMatrix<f64, 9, 6> {
        let mut m = SMatrix::<f64, 9, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&(rt * self.rg));
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.vg);
        m.fixed_view_mut::<3, 3>(6, 0).copy_from(&self.pg);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.va);
        m.fixed_view_mut::<3, 3>(6, 3).copy_from(&self.pa);
        m
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

/// The transition of one interval, or of several (see module doc): duration `h` [s], `U1`
/// [m/s], `U2` [m].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Transition {
    pub h: f64,
    pub u1: V3,
    pub u2: V3,
}

impl Transition {
    /// `Φ` from a node with deltas `(v0, p0)` to a later node `h` [s] after it with deltas
    /// `(v1, p1)` (module doc, "Transition between any two nodes").
    #[inline]
    pub(crate) fn between(h: f64, v0: &V3, p0: &V3, v1: &V3, p1: &V3) -> Self {
        Self {
            h,
            u1: v1 - v0,
            u2: p1 - p0 - v0 * h,
        }
    }

    /// `A X` for a 9×6 block matrix.
    #[inline(always)]
    pub(crate) fn apply(&self, x: &Blk96) -> Blk96 {
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

/// Per-sample white-noise covariance `Q_j = s_j · diag(Σ_g, Σ_a)` with
/// `s_j = white_scale(c_j)` [1/s] ([`crate::noise`]). Monomorphised once per noise shape.
pub(crate) trait NoiseQ: Copy {
    /// `P += Γ Q Γᵀ` for one sample's gain in [`NGain`] form; with `GV = false` the gyro
    /// rows of v and p are taken as zero.
    fn add_gqg<const GV: bool>(&self, p: &mut Sym9, g: &NGain, s: f64);
    /// `P += G Q Gᵀ` for a general gain.
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64);
}

/// One sample's noise gain whose accelerometer blocks are `R·cv` (v row) and `R·cp` (p row),
/// `R` a rotation, so that `Γ_a Q_a Γ_aᵀ = (cv, cp)² · R Σ_a Rᵀ s`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NGain {
    pub rg: M3,
    pub vg: M3,
    pub pg: M3,
    pub r: M3,
    pub cv: f64,
    pub cp: f64,
}

impl NGain {
    /// The same gain as a general 9×6 block matrix.
    #[inline]
    pub(crate) fn blk(&self) -> Blk96 {
        Blk96 {
            rg: self.rg,
            vg: self.vg,
            pg: self.pg,
            va: self.r * self.cv,
            pa: self.r * self.cp,
        }
    }
}

/// Adds `m·(cv², cv·cp, cp²)` to the v–v, v–p and p–p blocks.
#[inline(always)]
fn add_acc(p: &mut Sym9, m: &M3, cv: f64, cp: f64) {
    p.vv += m * (cv * cv);
    p.vp += m * (cv * cp);
    p.pp += m * (cp * cp);
}

/// Isotropic `Σ_g = g I`, `Σ_a = a I`: scalar products only.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IsoQ {
    pub g: f64,
    pub a: f64,
}

impl NoiseQ for IsoQ {
    #[inline(always)]
    fn add_gqg<const GV: bool>(&self, p: &mut Sym9, g: &NGain, s: f64) {
        // ΔR Σ_a ΔRᵀ = a I: the accelerometer noise adds to diagonals only.
        let gs = self.g * s;
        p.rr += (g.rg * g.rg.transpose()) * gs;
        if GV {
            p.rv += (g.rg * g.vg.transpose()) * gs;
            p.rp += (g.rg * g.pg.transpose()) * gs;
            p.vv += (g.vg * g.vg.transpose()) * gs;
            p.vp += (g.vg * g.pg.transpose()) * gs;
            p.pp += (g.pg * g.pg.transpose()) * gs;
        }
        let as_ = self.a * s;
        let (dv, dvp, dp) = (
            as_ * (g.cv * g.cv),
            as_ * (g.cv * g.cp),
            as_ * (g.cp * g.cp),
        );
        for i in 0..3 {
            p.vv[(i, i)] += dv;
            p.vp[(i, i)] += dvp;
            p.pp[(i, i)] += dp;
        }
    }

    #[inline(always)]
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64) {
        let (gs, as_) = (self.g * s, self.a * s);
        p.rr += (g.rg * g.rg.transpose()) * gs;
        p.rv += (g.rg * g.vg.transpose()) * gs;
        p.rp += (g.rg * g.pg.transpose()) * gs;
        p.vv += (g.vg * g.vg.transpose()) * gs + (g.va * g.va.transpose()) * as_;
        p.vp += (g.vg * g.pg.transpose()) * gs + (g.va * g.pa.transpose()) * as_;
        p.pp += (g.pg * g.pg.transpose()) * gs + (g.pa * g.pa.transpose()) * as_;
    }
}

/// `½(m + mᵀ)`.
#[inline(always)]
fn sym(m: M3) -> M3 {
    (m + m.transpose()) * 0.5
}

/// General (anisotropic) `Σ_g`, `Σ_a`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GenQ {
    pub g: M3,
    pub a: M3,
}

impl NoiseQ for GenQ {
    #[inline(always)]
    fn add_gqg<const GV: bool>(&self, p: &mut Sym9, g: &NGain, s: f64) {
        let qs = self.g * s;
        let wr = g.rg * qs;
        p.rr += sym(wr * g.rg.transpose());
        if GV {
            let wv = g.vg * qs;
            p.rv += wr * g.vg.transpose();
            p.rp += wr * g.pg.transpose();
            p.vv += sym(wv * g.vg.transpose());
            p.vp += wv * g.pg.transpose();
            p.pp += sym((g.pg * qs) * g.pg.transpose());
        }
        let ra = sym(g.r * (self.a * s) * g.r.transpose());
        add_acc(p, &ra, g.cv, g.cp);
    }

    #[inline(always)]
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64) {
        let (qg, qa) = (self.g * s, self.a * s);
        let (wr, wv, wp) = (g.rg * qg, g.vg * qg, g.pg * qg);
        let (xv, xp) = (g.va * qa, g.pa * qa);
        p.rr += sym(wr * g.rg.transpose());
        p.rv += wr * g.vg.transpose();
        p.rp += wr * g.pg.transpose();
        p.vv += sym(wv * g.vg.transpose() + xv * g.va.transpose());
        p.vp += wv * g.pg.transpose() + xv * g.pa.transpose();
        p.pp += sym(wp * g.pg.transpose() + xp * g.pa.transpose());
    }
}

/// A pending sample (module doc): its index and accumulated gain.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pending {
    pub id: usize,
    pub g: Blk96,
}

/// No sample in a pending slot.
pub(crate) const NO_ID: usize = usize::MAX;
/// Number of pending-sample slots (≥ the largest stencil); sample `id` lives in `id % SLOTS`.
pub(crate) const SLOTS: usize = 4;

/// One sample's contribution to an interval: its index and its gain `Γ_kj`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Input {
    pub id: usize,
    pub gain: Blk96,
}

/// The error state: covariance, bias Jacobians and the combined-covariance terms, all in
/// rotated coordinates.
#[derive(Clone, Debug)]
pub(crate) struct ErrorState {
    /// Covariance of the deltas from the white measurement noise of the retired samples
    /// (`P_f` of the module doc; what `PreintegratedImu::cov` holds once every sample is
    /// retired, as GTSAM's `ImuFactor`).
    pub p: Sym9,
    /// The part of the deltas' covariance driven by the bias random walk during the window
    /// (combined level only); `p + p_walk` is the 9×9 block of the 15×15 covariance. Kept apart
    /// because propagation is linear, so the two parts evolve independently.
    pub p_walk: Sym9,
    pub j: Blk96,
    pub c: Blk96,
    pub pbb_g: M3,
    pub pbb_a: M3,
    /// rk4: pending samples.
    pub pend: [Pending; SLOTS],
    /// Midpoint: gain of the last interval's end sample (its noise is not yet in `p`).
    mid: NGain,
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
            pend: [Pending {
                id: NO_ID,
                g: Blk96::default(),
            }; SLOTS],
            mid: NGain::default(),
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

/// A midpoint interval's gains: both samples share the gyro gains `(rg, vg, pg)`; the
/// accelerometer gains are `r0·(cv, cp)` (sample k) and `r1·(cv, cp)` (sample k+1).
#[derive(Clone, Copy, Debug)]
pub(crate) struct MidGain {
    pub rg: M3,
    pub vg: M3,
    pub pg: M3,
    pub r0: M3,
    pub r1: M3,
    pub cv: f64,
    pub cp: f64,
}

impl ErrorState {
    /// `A C` before the conjugation (C is untouched by it), and `p_walk ← A p_walk Aᵀ`.
    #[inline(always)]
    fn walk_pre(&mut self, tr: &Transition, walk: &BiasWalk) -> Option<Blk96> {
        if walk.combined {
            self.p_walk = tr.conjugate(&self.p_walk);
            Some(tr.apply(&self.c))
        } else {
            None
        }
    }

    /// Combined terms, bias-walk step and bias Jacobians for an interval of total gain `gsum`.
    #[inline(always)]
    fn tail(&mut self, tr: &Transition, ac: Option<Blk96>, gsum: &Blk96, walk: &BiasWalk) {
        if let Some(v) = ac {
            let half = gsum.mul_diag(&self.pbb_g, &self.pbb_a).scale(0.5);
            let v = v.add(&half);
            add_sym(&mut self.p_walk, &v, gsum);
            self.c = v.add(&half);
        }
        let ws = walk_scale(tr.h);
        self.pbb_g += walk.g * ws;
        self.pbb_a += walk.a * ws;
        let aj = tr.apply(&self.j);
        self.j = aj.add(&gsum.scale(-1.0));
    }

    /// Euler interval: sample k (gain `gain`: `rg`, `va = r0 h`, `pa = r0 ½h²`, zero gyro
    /// gains in the v and p rows) is used once, so it is retired at once with noise scale
    /// `scale` [1/s] (0 when the caller collects its gain instead).
    #[inline(always)]
    pub(crate) fn step_euler<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        gain: &Blk96,
        r0: &M3,
        scale: f64,
        noise: &N,
        walk: &BiasWalk,
    ) {
        let ng = NGain {
            rg: gain.rg,
            vg: M3::zeros(),
            pg: M3::zeros(),
            r: *r0,
            cv: tr.h,
            cp: 0.5 * tr.h * tr.h,
        };
        let ac = self.walk_pre(tr, walk);
        self.p = tr.conjugate(&self.p);
        noise.add_gqg::<false>(&mut self.p, &ng, scale);
        self.tail(tr, ac, gain, walk);
    }

    /// Midpoint interval. With `f_k = e_k − Γ_k−1,1 n_k` (independent of `n_k`),
    /// `f_k+1 = A f_k + (A Γ_k−1,1 + Γ_k,0) n_k`: sample k is retired here through its merged
    /// gain, with noise scale `s0` [1/s] (0 when the caller collects the gain instead).
    /// Returns that merged gain (on the error after this interval).
    #[inline(always)]
    pub(crate) fn step_mid<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        g: &MidGain,
        s0: f64,
        noise: &N,
        walk: &BiasWalk,
    ) -> NGain {
        let m = &self.mid;
        let h = tr.h;
        let ng = NGain {
            rg: m.rg + g.rg,
            vg: m.vg - skew_mul(&tr.u1, &m.rg) + g.vg,
            pg: m.pg + m.vg * h - skew_mul(&tr.u2, &m.rg) + g.pg,
            r: g.r0,
            cv: m.cv + g.cv,
            cp: m.cp + h * m.cv + g.cp,
        };
        let gsum = Blk96 {
            rg: g.rg + g.rg,
            vg: g.vg + g.vg,
            pg: g.pg + g.pg,
            va: g.r0 * g.cv + g.r1 * g.cv,
            pa: g.r0 * g.cp + g.r1 * g.cp,
        };
        self.mid = NGain {
            rg: g.rg,
            vg: g.vg,
            pg: g.pg,
            r: g.r1,
            cv: g.cv,
            cp: g.cp,
        };
        let ac = self.walk_pre(tr, walk);
        self.p = tr.conjugate(&self.p);
        noise.add_gqg::<true>(&mut self.p, &ng, s0);
        self.tail(tr, ac, &gsum, walk);
        ng
    }

    /// Midpoint, end of the window: removes and returns the last sample's pending gain.
    #[inline]
    pub(crate) fn take_mid(&mut self) -> NGain {
        std::mem::take(&mut self.mid)
    }

    /// Interval with several samples that may be pending (rk4): `P ← A P Aᵀ`, every pending
    /// gain `G ← A G`, then `G_j += Γ_kj` for the inputs (new samples start at `Γ_kj`).
    /// Samples no longer used must have been retired ([`ErrorState::take_pending`]) first.
    #[inline(always)]
    pub(crate) fn step_multi(&mut self, tr: &Transition, inputs: &[Input], walk: &BiasWalk) {
        let ac = self.walk_pre(tr, walk);
        self.p = tr.conjugate(&self.p);
        for slot in self.pend.iter_mut() {
            if slot.id != NO_ID {
                slot.g = tr.apply(&slot.g);
            }
        }
        let mut gsum = Blk96::default();
        for inp in inputs {
            gsum = gsum.add(&inp.gain);
            let slot = &mut self.pend[inp.id % SLOTS];
            if slot.id == inp.id {
                slot.g = slot.g.add(&inp.gain);
            } else {
                debug_assert_eq!(slot.id, NO_ID, "pending sample not retired");
                *slot = Pending {
                    id: inp.id,
                    g: inp.gain,
                };
            }
        }
        self.tail(tr, ac, &gsum, walk);
    }

    /// Removes the pending sample of slot `slot` and returns it (its gain is on the current
    /// error).
    #[inline(always)]
    pub(crate) fn take_pending(&mut self, slot: usize) -> Pending {
        std::mem::replace(
            &mut self.pend[slot],
            Pending {
                id: NO_ID,
                g: Blk96::default(),
            },
        )
    }

    /// Retires a sample: `P += G Q Gᵀ` with `Q = diag(Σ_g, Σ_a)·s`.
    #[inline(always)]
    pub(crate) fn add_noise<N: NoiseQ>(&mut self, g: &Blk96, s: f64, noise: &N) {
        noise.add_full(&mut self.p, g, s);
    }
}
