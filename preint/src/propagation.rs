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
    /// `P += Γ Q Γᵀ` for one sample's gain in [`NGain`] form; with `GV = false` the gyro
    /// rows of v and p are taken as zero.
    fn add_gqg<const GV: bool>(&self, p: &mut Sym9, g: &NGain, s: f64);
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
    fn gq(&self, x: &Blk96, s: f64) -> Blk96 {
        x.mul_diag(&(self.g * s), &(self.a * s))
    }

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
    /// Midpoint: gain of the last interval's end sample (its noise is not yet in `p`, which
    /// holds the covariance of `e − Γ n_end`; [`ErrorState::finish_mid`] adds it).
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
            pending: [Pending {
                id: usize::MAX,
                x: Blk96::default(),
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
    /// Propagates through an interval with a single input whose noise gain is `ng` (white
    /// noise added once, no cross-covariance kept); `gsum` is the total gain for the bias
    /// Jacobians and the combined terms.
    #[inline(always)]
    fn step_one<N: NoiseQ, const GV: bool>(
        &mut self,
        tr: &Transition,
        ng: &NGain,
        scale: f64,
        gsum: &Blk96,
        noise: &N,
        walk: &BiasWalk,
    ) {
        let v = if walk.combined {
            self.p_walk = tr.conjugate(&self.p_walk);
            Some(tr.apply(&self.c))
        } else {
            None
        };
        self.p = tr.conjugate(&self.p);
        noise.add_gqg::<GV>(&mut self.p, ng, scale);
        if let Some(v) = v {
            let half = gsum.mul_diag(&self.pbb_g, &self.pbb_a).scale(0.5);
            let v = v.add(&half);
            add_sym(&mut self.p_walk, &v, gsum);
            self.c = v.add(&half);
        }
        self.pbb_g += walk.g * tr.h;
        self.pbb_a += walk.a * tr.h;
        let aj = tr.apply(&self.j);
        self.j = aj.add(&gsum.scale(-1.0));
    }

    /// Euler interval: one input with zero gyro gains in the v and p rows and accelerometer
    /// gains `r0·(h, ½h²)` (`gain.va = r0 h`, `gain.pa = r0 ½h²`).
    #[inline(always)]
    pub(crate) fn step_euler<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        inp: &Input,
        r0: &M3,
        cp: f64,
        noise: &N,
        walk: &BiasWalk,
    ) {
        let ng = NGain {
            rg: inp.gain.rg,
            vg: M3::zeros(),
            pg: M3::zeros(),
            r: *r0,
            cv: tr.h,
            cp,
        };
        self.step_one::<N, false>(tr, &ng, inp.scale, &inp.gain, noise, walk);
    }

    /// Midpoint interval. With `f_k = e_k − Γ_k−1,1 n_k` (independent of `n_k`),
    /// `f_k+1 = A f_k + (A Γ_k−1,1 + Γ_k,0) n_k`: each sample's noise enters once, through
    /// the merged gain; `s0` is sample k's noise scale.
    #[inline(always)]
    pub(crate) fn step_mid<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        g: &MidGain,
        s0: f64,
        noise: &N,
        walk: &BiasWalk,
    ) {
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
        self.step_one::<N, true>(tr, &ng, s0, &gsum, noise, walk);
    }

    /// Midpoint, end of the window: adds the last sample's noise (scale `s` [1/s]).
    #[inline]
    pub(crate) fn finish_mid<N: NoiseQ>(&mut self, noise: &N, s: f64) {
        let m = self.mid;
        noise.add_gqg::<true>(&mut self.p, &m, s);
        self.mid = NGain::default();
    }

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
