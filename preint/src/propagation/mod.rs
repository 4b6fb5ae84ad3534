//! Error-state propagation, the same for every scheme: the covariance, the bias Jacobians and
//! the combined covariance from each interval's [`Linearisation`].
//!
//! Chart (documented in [`PreintegratedImu`](crate::PreintegratedImu)): `ΔR = ΔR°·Exp(δφ)`, `Δv = Δv° + δv`,
//! `Δp = Δp° + δp`. The rotation error is handled as `ψ = ΔR_k δφ` (the same error as a left
//! perturbation, in frame i), the *rotated* error `e_k = [ψ, δv, δp]`. With that choice the
//! rotation block of every transition is the identity and `ΔR_k[a]×δφ = [u]×ψ` with
//! `u = ΔR_k a`. Every scheme's interval is linear in this error state and in the
//! perturbations `n_j = [δω_j, δa_j]` of the samples of its stencil:
//!
//! ```text
//! e_k+1 = A_k e_k + Σ_j Γ_kj n_j,   A_k = [[I, 0, 0], [−[U1]×, I, 0], [−[U2]×, h I, I]]
//! ```
//!
//! where `U1 = ∫ ΔR(t) a(t) dt` and `U2 = ∫ (h − s) ΔR(s) a(s) ds` over the interval, as the
//! scheme discretises them (for every scheme here exactly the increments
//! `U1 = Δv_k+1 − Δv_k`, `U2 = Δp_k+1 − Δp_k − Δv_k h`).
//!
//! # Pulled-back error: no per-interval transition
//!
//! Products of such transitions keep the form ([`transition`]). Take node o = 1, the end of
//! the window's first interval, as the origin and let `Φ_k = Φ(o → k)`. The error is
//! propagated *pulled back* to the origin, `e'_k = Φ_k⁻¹ e_k`; since `Φ_k+1 = A_k Φ_k`,
//! `e'_k+1 = e'_k + Σ_j Γ'_kj n_j` with `Γ'_kj = Φ_k+1⁻¹ Γ_kj`: the transition disappears.
//! Covariance, bias Jacobians and the combined terms are then plain sums; they are pushed
//! forward once, `e = Φ_N e'`, when the measurement is read. With the origin at node 1 a
//! one-interval window needs no push-forward at all and keeps the exact zeros of its rotated
//! gains (Euler's gyro gain has no v and p rows), which merging such windows relies on.
//!
//! # Each sample's noise enters once
//!
//! A sample is read by every interval whose stencil holds it (Euler 1, midpoint 2, Hermite up
//! to 4), so its noise must not be added once per interval. Its total pulled-back gain is the
//! sum `G'_j = Σ_k Γ'_kj` over the intervals that read it; while a later interval may still
//! read it the sample is *pending*, and once none does it is *retired*:
//! `P' += G'_j Q_j G'_jᵀ`, `Q_j = diag(Σ_g, Σ_a)·white_scale(c_j)` ([`ImuNoise`](crate::ImuNoise)). The
//! result is the exact first-order covariance `Φ_N (Σ_j G'_j Q_j G'_jᵀ) Φ_Nᵀ`. A scheme whose
//! stencil is `{k, k+1}` retires sample k in interval k (its gain is then complete) and keeps
//! one pending sample (none when sample k+1's noise does not enter interval k; a held scheme
//! that gives sample k's whole gain, `HeldGain`, has it pulled back by [`PullBack::apply`] and
//! retired as general columns); a wider stencil keeps up to four, retired when the next
//! interval's stencil has moved past them (at the end of a window the stencil stops moving, so
//! that is only known then).
//!
//! # Bias Jacobians and the combined covariance
//!
//! Every sample sees `−δb` with its total gain, so `J' = −Σ_j G'_j`. Combined covariance (bias
//! deviation `δb` constant over an interval, then a random-walk step): `C = Cov(e, δb)`,
//! `V = A C + ½ Γ_Σ P_bb`, `P_walk ← A P_walk Aᵀ + V Γ_Σᵀ + Γ_Σ Vᵀ`, `C ← V + ½ Γ_Σ P_bb`,
//! `P_bb += Σ_rw·walk_scale(h)`, with `Γ_Σ = Σ_j Γ_kj` the interval's total gain. `P_walk` is
//! pulled back like `P` (`P'_walk += V' Γ'_Σᵀ + Γ'_Σ V'ᵀ`, `V' = Φ_k+1⁻¹ V`); the 9×6 `C` is kept
//! in rotated coordinates, where the blocks that vanish (Euler's gyro rows over the first
//! intervals) are exact zeros rather than round-off of a push-forward.
//!
//! # Storage
//!
//! Symmetric 9×9 matrices are packed ([`blocks::PackedSym9`]); 9×6 gains are stored by columns
//! ([`blocks::Gain96`]), the ψ rows of the accelerometer columns being identically zero.

pub(crate) mod blocks;
pub(crate) mod linearisation;
pub(crate) mod transition;

use blocks::{
    Cols6, Cols9, Gain96, M3, PackedSym9, V3, add_cols, mul_cols, rot_cols, scale_cols, sub_cols,
};
use linearisation::{
    BOTH, FIRST, GainBasis, GainCoef, GainForm, GyroColumns, Linearisation, MAX_STENCIL,
    NodeColumns, NodeTermsOf, OUTER, SECOND, add_acc, add_gyro,
};
use transition::{PullBack, Transition, rotated_sym};

/// The shape of a scheme's linearisation, which is all the propagator needs to know of the
/// scheme: which stencil samples an interval reads, whether the end node's noise enters it,
/// and which parts of the gain basis its gains use ([`linearisation`]). Every
/// [`IntervalScheme`](crate::scheme::IntervalScheme) has one.
pub(crate) trait Shape {
    /// Samples interval k reads before node k and after node k+1: its stencil is
    /// `k − NODES_BEFORE … k + 1 + NODES_AFTER`. A keyframe between samples gets a boundary
    /// sample interpolated through as many stream samples (linear for two, cubic Lagrange for
    /// four), and a wider stencil reads context samples beyond the window's edges
    /// ([`preintegrate`](crate::preintegrate())).
    const NODES_BEFORE: usize;
    /// See [`Shape::NODES_BEFORE`].
    const NODES_AFTER: usize;
    /// Whether sample k+1's noise enters interval k (false for a scheme that holds sample k
    /// over the interval).
    const END_NODE_NOISE: bool;
    /// Which parts of the gain basis the gains use.
    const GAIN_FORM: GainForm;
    /// The node terms of the gains: `()`, `[NodeTerms; 2]` for gains that depend on the
    /// rates' derivatives at the nodes, or a held sample's whole gain ([`linearisation`]).
    type NodeTerms: NodeTermsOf;

    /// Number of stencil samples.
    const STENCIL: usize = Self::NODES_BEFORE + 2 + Self::NODES_AFTER;
}

/// The rate coupling of an interval's stencil samples: `D_j = ∂a_j/∂ω_j`, how each node's
/// accelerometer input moves with its rate when the samples were transformed before the loop
/// (a lever arm corrected per sample, [`SensorPose`](crate::SensorPose)). The combined terms carry the gyro
/// bias through it.
pub(crate) type RateCoupling = [M3; MAX_STENCIL];

/// Per-sample white-noise covariance `Q_j = s_j · diag(Σ_g, Σ_a)` with
/// `s_j = white_scale(c_j)` [1/s] ([`ImuNoise`](crate::ImuNoise)), and the samples' rate coupling if they
/// have one ([`Coupled`]). Monomorphised once per noise shape.
pub(crate) trait NoiseCov: Copy {
    /// Whether the samples have a rate coupling ([`NoiseCov::coupling`]).
    const COUPLED: bool = false;
    /// `D(ω) = ∂a_node/∂ω_node` of a node whose rate is `w` (only called when
    /// [`NoiseCov::COUPLED`]).
    #[inline(always)]
    fn coupling(&self, _w: &V3) -> M3 {
        M3::zeros()
    }
    /// `P += Γ Q Γᵀ` for a gain with gyro columns `g` and accelerometer columns `R·(cv, cp)`
    /// (v and p rows), `R` a rotation.
    fn add_rot(&self, p: &mut PackedSym9, g: &Cols9, r: &M3, cv: f64, cp: f64, s: f64);
    /// `P += G Q Gᵀ` for a general gain.
    fn add_full(&self, p: &mut PackedSym9, g: &Gain96, s: f64);
}

/// Isotropic `Σ_g = g I`, `Σ_a = a I`: scalar products only.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IsotropicNoise {
    pub g: f64,
    pub a: f64,
}

impl NoiseCov for IsotropicNoise {
    #[inline(always)]
    fn add_rot(&self, p: &mut PackedSym9, g: &Cols9, _r: &M3, cv: f64, cp: f64, s: f64) {
        p.add_outer(g, g, self.g * s);
        // R Σ_a Rᵀ = a I: the accelerometer noise adds to diagonals only.
        let a = self.a * s;
        p.add_diag_vp(a * (cv * cv), a * (cv * cp), a * (cp * cp));
    }

    #[inline(always)]
    fn add_full(&self, p: &mut PackedSym9, g: &Gain96, s: f64) {
        p.add_outer(&g.g, &g.g, self.g * s);
        p.add_outer_vp(&g.a, &g.a, self.a * s);
    }
}

/// How a transform of the samples before the loop makes a node's accelerometer input depend on
/// its rate (a lever arm taken off each specific force, [`SensorPose`](crate::SensorPose)).
pub(crate) trait RateMap: Copy {
    /// `D(ω) = ∂a_node/∂ω_node` at the rate `w` [rad/s].
    fn d(&self, w: &V3) -> M3;
}

/// The noise `N` of samples transformed by `C` before the loop: the same white noise on the
/// raw readings, which the transform couples (`δa_node = δa + D(ω) δω`), so the raw gyroscope
/// noise and bias also move the specific force. The loop carries `D` in every gain it retires
/// and in the combined terms (`G_g + G_a D`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coupled<N, C> {
    pub noise: N,
    pub map: C,
}

impl<N: NoiseCov, C: RateMap> NoiseCov for Coupled<N, C> {
    const COUPLED: bool = true;
    #[inline(always)]
    fn coupling(&self, w: &V3) -> M3 {
        self.map.d(w)
    }
    #[inline(always)]
    fn add_rot(&self, p: &mut PackedSym9, g: &Cols9, r: &M3, cv: f64, cp: f64, s: f64) {
        self.noise.add_rot(p, g, r, cv, cp, s);
    }
    #[inline(always)]
    fn add_full(&self, p: &mut PackedSym9, g: &Gain96, s: f64) {
        self.noise.add_full(p, g, s);
    }
}

/// General (anisotropic) `Σ_g`, `Σ_a`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AnisotropicNoise {
    pub g: M3,
    pub a: M3,
}

impl NoiseCov for AnisotropicNoise {
    #[inline(always)]
    fn add_rot(&self, p: &mut PackedSym9, g: &Cols9, r: &M3, cv: f64, cp: f64, s: f64) {
        p.add_outer(&mul_cols(g, &self.g), g, s);
        p.add_acc(&rotated_sym(r, &(self.a * s)), cv, cp);
    }

    #[inline(always)]
    fn add_full(&self, p: &mut PackedSym9, g: &Gain96, s: f64) {
        p.add_outer(&mul_cols(&g.g, &self.g), &g.g, s);
        p.add_outer_vp(&mul_cols(&g.a, &self.a), &g.a, s);
    }
}

/// A sample's accelerometer gain: its node's `ΔR·(c_v, c_p)`, or general columns.
#[derive(Clone, Copy, Debug)]
pub(crate) enum AccGain<'a> {
    Rot { r: &'a M3, cv: f64, cp: f64 },
    Full(&'a Cols6),
}

/// A retired sample's total pulled-back gain.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleGain<'a> {
    pub g: &'a Cols9,
    pub acc: AccGain<'a>,
}

impl SampleGain<'_> {
    /// As a general 9×6 gain.
    #[inline]
    pub(crate) fn full(&self) -> Gain96 {
        Gain96 {
            g: *self.g,
            a: match self.acc {
                AccGain::Rot { r, cv, cp } => rot_cols(r, cv, cp),
                AccGain::Full(a) => *a,
            },
        }
    }

    /// `P += G Q Gᵀ` with `Q = diag(Σ_g, Σ_a)·s`.
    #[inline(always)]
    pub(crate) fn add_noise<N: NoiseCov>(&self, p: &mut PackedSym9, noise: &N, s: f64) {
        match self.acc {
            AccGain::Rot { r, cv, cp } => noise.add_rot(p, self.g, r, cv, cp, s),
            AccGain::Full(a) => noise.add_full(p, &Gain96 { g: *self.g, a: *a }, s),
        }
    }
}

/// A pending sample: its index and the sum of its pulled-back gains so far (accelerometer part
/// as scalars of its node's ΔR for schemes with `acc_on_own_node`, else as columns).
#[derive(Clone, Copy, Debug)]
struct Pending {
    id: usize,
    g: Cols9,
    a: Cols6,
    cv: f64,
    cp: f64,
}

/// No sample in a pending slot.
const NO_ID: usize = usize::MAX;

impl Default for Pending {
    fn default() -> Self {
        Self {
            id: NO_ID,
            g: [[0.0; 9]; 3],
            a: [[0.0; 6]; 3],
            cv: 0.0,
            cp: 0.0,
        }
    }
}

/// Bias random-walk densities and whether to propagate the combined terms.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BiasWalk {
    pub combined: bool,
    pub g: M3,
    pub a: M3,
    /// `(σ_g², σ_a²)` when both densities are isotropic (`Σ = σ² I`): `Γ P_bb` is then a
    /// scaling.
    pub iso: Option<(f64, f64)>,
}

/// Hands a retired sample (index, total gain) to the caller, with the covariance to add its
/// noise to.
pub(crate) trait Retire: FnMut(&mut PackedSym9, usize, &SampleGain) {}
impl<F: FnMut(&mut PackedSym9, usize, &SampleGain)> Retire for F {}

/// The error state: covariance, bias Jacobians and the combined-covariance terms, pulled back
/// to the origin except `C` (module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct ErrorState {
    /// Covariance of the deltas from the white measurement noise of the retired samples.
    pub p: PackedSym9,
    /// The part of the deltas' covariance driven by the bias random walk during the window
    /// (combined level only); `p + p_walk` is the 9×9 block of the 15×15 covariance. Kept apart
    /// because propagation is linear, so the two parts evolve independently.
    pub p_walk: PackedSym9,
    /// Bias Jacobian `J'`.
    pub j: Gain96,
    /// `C = Cov(e, δb)` in rotated coordinates (combined level only).
    pub c: Gain96,
    /// `Σ walk_scale(h)` over the intervals: `P_bb = diag(Σ_bg, Σ_ba)·walk_t`.
    pub walk_t: f64,
    /// Pending samples of a wide stencil, in slot `id % 4`; for a `{k, k+1}` stencil, slot 0
    /// holds sample k+1.
    pending: [Pending; 4],
}

impl ErrorState {
    /// Propagates one interval of scheme `S` whose stencil samples have indices
    /// `first_id + j` (stencil position `j < len`, node k at `k_pos`), pulled back by `pb`.
    /// Samples whose gain this interval completes are handed to `retire` after entering the
    /// bias Jacobian.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn interval<S: Shape>(
        &mut self,
        lin: &Linearisation<S::NodeTerms>,
        pb: &PullBack,
        first_id: usize,
        k_pos: usize,
        len: usize,
        walk: &BiasWalk,
        coupling: Option<&RateCoupling>,
        retire: impl Retire,
    ) {
        if S::NodeTerms::HELD {
            self.held::<S>(lin, pb, first_id, walk, coupling, retire);
            return;
        }
        let form = S::GAIN_FORM;
        let f = lin.basis.gyro_columns(form, Some(pb));
        let node = S::NodeTerms::PRESENT
            .then(|| lin.basis.node_columns(&lin.node.terms(), form, Some(pb)));
        if S::NODES_BEFORE + S::NODES_AFTER == 0 {
            self.two_point::<S>(lin, &f, pb, first_id, retire);
        } else {
            self.wide::<S>(lin, &f, node.as_ref(), pb, first_id, k_pos, len);
        }
        if walk.combined {
            self.walk_step::<S>(lin, &f, node.as_ref(), pb, (k_pos, len), walk, coupling);
        }
        self.walk_t += crate::noise::walk_scale(lin.tr.h);
    }

    /// A held scheme's interval ([`NodeTermsOf::HELD`]): sample k's whole gain, pulled back,
    /// is complete and retired now (the interval reads no other sample's noise); with the
    /// combined terms, it is also the interval's total gain `Γ_Σ`.
    #[inline(always)]
    fn held<S: Shape>(
        &mut self,
        lin: &Linearisation<S::NodeTerms>,
        pb: &PullBack,
        id: usize,
        walk: &BiasWalk,
        coupling: Option<&RateCoupling>,
        mut retire: impl Retire,
    ) {
        // A whole gain is sample k's only: no end-node noise, no wider stencil.
        const {
            assert!(
                !S::NodeTerms::HELD
                    || (!S::END_NODE_NOISE && S::NODES_BEFORE + S::NODES_AFTER == 0)
            )
        };
        let rot = lin.node.held();
        let g = pb.apply(rot);
        sub_cols(&mut self.j.g, &g.g);
        sub_cols(&mut self.j.a, &g.a);
        retire(
            &mut self.p,
            id,
            &SampleGain {
                g: &g.g,
                acc: AccGain::Full(&g.a),
            },
        );
        if walk.combined {
            let (mut gsum, mut rot) = (g, *rot);
            if let Some(d) = coupling {
                // `Γ_a,k D_k`: sample k's accelerometer gain through its rate coupling.
                let mut extra = Gain96::default();
                add_acc_through(&mut extra.g, &g.a, &d[0]);
                let fwd = pb.forward().apply(&extra);
                add_cols(&mut gsum.g, &extra.g);
                add_cols(&mut rot.g, &fwd.g);
            }
            self.walk_tail(&lin.tr, pb, &gsum, &rot, walk);
        }
        self.walk_t += crate::noise::walk_scale(lin.tr.h);
    }

    /// A stencil `{k, k+1}`: sample k's gain is complete (the pending part from interval k−1
    /// plus this interval's), so it is retired now; sample k+1's part becomes pending.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // parallel arrays
    fn two_point<S: Shape>(
        &mut self,
        lin: &Linearisation<S::NodeTerms>,
        f: &GyroColumns,
        pb: &PullBack,
        id: usize,
        mut retire: impl Retire,
    ) {
        let (c0, c1) = (&lin.coef[0], &lin.coef[1]);
        let next = &mut self.pending[0];
        // Sample k's gyro columns: its pending part plus `c_k B(F)` (no copy when that is all);
        // sample k+1's pending part starts as `c_k+1 B(F)`. One pass, which also takes sample
        // k's gain off the bias Jacobian.
        let owned;
        let g: &Cols9 = if S::END_NODE_NOISE {
            let mut sum = [[0.0; 9]; 3];
            for c in 0..3 {
                for i in 0..9 {
                    let fi = f[c][i];
                    let x = next.g[c][i] + fi * c0.gyro;
                    sum[c][i] = x;
                    self.j.g[c][i] -= x;
                    next.g[c][i] = fi * c1.gyro;
                }
            }
            owned = sum;
            &owned
        } else {
            let g = if c0.gyro == 1.0 {
                f
            } else {
                owned = scale_cols(f, c0.gyro);
                &owned
            };
            sub_cols(&mut self.j.g, g);
            g
        };
        let (av, ap) = pb.vp(c0.a.0, c0.a.1);
        let r0 = &lin.basis.r0;
        let a;
        let acc = if S::GAIN_FORM.acc_on_own_node {
            let (cv, cp) = if S::END_NODE_NOISE {
                (next.cv + av, next.cp + ap)
            } else {
                (av, ap)
            };
            sub_rot(&mut self.j.a, r0, cv, cp);
            AccGain::Rot { r: r0, cv, cp }
        } else {
            let mut full = rot_cols(r0, av, ap);
            if S::END_NODE_NOISE {
                for (x, y) in full.iter_mut().zip(&next.a) {
                    for (u, w) in x.iter_mut().zip(y) {
                        *u += w;
                    }
                }
            }
            sub_cols(&mut self.j.a, &full);
            a = full;
            AccGain::Full(&a)
        };
        if S::END_NODE_NOISE {
            let (bv, bp) = pb.vp(c1.b.0, c1.b.1);
            if S::GAIN_FORM.acc_on_own_node {
                (next.cv, next.cp) = (bv, bp);
            } else {
                next.a = rot_cols(&lin.basis.r1, bv, bp);
            }
        }
        retire(&mut self.p, id, &SampleGain { g, acc });
    }

    /// A wide stencil: every stencil sample's gain is added to its pending sum (retired later,
    /// [`ErrorState::retire_below`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn wide<S: Shape>(
        &mut self,
        lin: &Linearisation<S::NodeTerms>,
        f: &GyroColumns,
        node: Option<&NodeColumns>,
        pb: &PullBack,
        first_id: usize,
        k_pos: usize,
        len: usize,
    ) {
        let acc = lin.basis.acc_columns(pb.tau);
        for j in 0..len {
            let slot = self.slot(first_id + j);
            let c = &lin.coef[j];
            if j == k_pos {
                add_gyro::<FIRST>(&mut slot.g, f, node, c);
                add_acc::<FIRST, true>(&mut slot.a, &acc, node, c);
            } else if j == k_pos + 1 {
                add_gyro::<SECOND>(&mut slot.g, f, node, c);
                add_acc::<SECOND, true>(&mut slot.a, &acc, node, c);
            } else {
                add_gyro::<OUTER>(&mut slot.g, f, node, c);
                add_acc::<OUTER, true>(&mut slot.a, &acc, node, c);
            }
        }
    }

    /// The pending gain of sample `id`, which interval gains are added to (a sample first
    /// read starts at zero). Samples no longer read must have been retired first.
    #[inline(always)]
    fn slot(&mut self, id: usize) -> &mut Pending {
        let slot = &mut self.pending[id % 4];
        if slot.id != id {
            debug_assert_eq!(slot.id, NO_ID, "pending sample not retired");
            *slot = Pending {
                id,
                ..Pending::default()
            };
        }
        slot
    }

    /// Wide stencils: retires the pending samples with index below `below` (their total gain
    /// enters the bias Jacobian: every sample sees `−δb`).
    #[inline(always)]
    pub(crate) fn retire_below(&mut self, below: usize, mut retire: impl Retire) {
        for slot in 0..self.pending.len() {
            let id = self.pending[slot].id;
            if id == NO_ID || id >= below {
                continue;
            }
            let pd = std::mem::take(&mut self.pending[slot]);
            sub_cols(&mut self.j.g, &pd.g);
            sub_cols(&mut self.j.a, &pd.a);
            let gain = SampleGain {
                g: &pd.g,
                acc: AccGain::Full(&pd.a),
            };
            retire(&mut self.p, id, &gain);
        }
    }

    /// Stencils `{k, k+1}`, end of the window: retires the last sample `id`, whose pending
    /// gain is complete (`r`: its node's ΔR).
    #[inline]
    pub(crate) fn retire_last<S: Shape>(&mut self, id: usize, r: &M3, mut retire: impl Retire) {
        if !S::END_NODE_NOISE {
            return;
        }
        let pd = std::mem::take(&mut self.pending[0]);
        sub_cols(&mut self.j.g, &pd.g);
        let acc = if S::GAIN_FORM.acc_on_own_node {
            sub_rot(&mut self.j.a, r, pd.cv, pd.cp);
            AccGain::Rot {
                r,
                cv: pd.cv,
                cp: pd.cp,
            }
        } else {
            sub_cols(&mut self.j.a, &pd.a);
            AccGain::Full(&pd.a)
        };
        retire(&mut self.p, id, &SampleGain { g: &pd.g, acc });
    }

    /// The combined terms of an interval (module docs): its total gain `Γ_Σ` pulled back
    /// (`f`, `node`, `pb`) and in rotated coordinates.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn walk_step<S: Shape>(
        &mut self,
        lin: &Linearisation<S::NodeTerms>,
        f: &GyroColumns,
        node: Option<&NodeColumns>,
        pb: &PullBack,
        (k_pos, len): (usize, usize),
        walk: &BiasWalk,
        coupling: Option<&RateCoupling>,
    ) {
        let form = S::GAIN_FORM;
        let mut sum = GainCoef::default();
        let n = if S::NODES_BEFORE + S::NODES_AFTER == 0 {
            S::STENCIL
        } else {
            len
        };
        for c in &lin.coef[..n] {
            sum = sum.add(c);
        }
        let (gsum, rot) = if S::NodeTerms::PRESENT {
            // The sum pulled back, and pushed forward again (`Φ_k+1 Γ'_Σ`): cheaper than
            // building the node terms' columns a second time.
            let mut g = Gain96::default();
            add_gyro::<BOTH>(&mut g.g, f, node, &sum);
            add_acc::<BOTH, true>(&mut g.a, &lin.basis.acc_columns(pb.tau), node, &sum);
            (g, pb.forward().apply(&g))
        } else {
            // Without node terms: `B(Σc F)` and `ΔR_k·(Σα) + ΔR_k+1·(Σβ)` directly.
            let basis = GainBasis {
                f: lin.basis.f * sum.gyro,
                ..lin.basis
            };
            let total = |g: GyroColumns, tau: f64| {
                let (av, ap) = (sum.a.0, sum.a.1 - tau * sum.a.0);
                let mut a = rot_cols(&lin.basis.r0, av, ap);
                if S::END_NODE_NOISE {
                    let (bv, bp) = (sum.b.0, sum.b.1 - tau * sum.b.0);
                    add_cols(&mut a, &rot_cols(&lin.basis.r1, bv, bp));
                }
                Gain96 { g, a }
            };
            (
                total(basis.gyro_columns(form, Some(pb)), pb.tau),
                total(basis.gyro_columns(form, None), 0.0),
            )
        };
        let (gsum, rot) = match coupling {
            Some(d) => {
                let extra = self.coupled_walk::<S>(lin, node, pb, (k_pos, len), d);
                let fwd = pb.forward().apply(&extra);
                let (mut gsum, mut rot) = (gsum, rot);
                add_cols(&mut gsum.g, &extra.g);
                add_cols(&mut rot.g, &fwd.g);
                (gsum, rot)
            }
            None => (gsum, rot),
        };
        self.walk_tail(&lin.tr, pb, &gsum, &rot, walk);
    }

    /// The combined terms of an interval with transition `tr` from its total gain `Γ_Σ`,
    /// pulled back (`gsum`) and in rotated coordinates at node k+1 (`rot`).
    #[inline(always)]
    fn walk_tail(
        &mut self,
        tr: &Transition,
        pb: &PullBack,
        gsum: &Gain96,
        rot: &Gain96,
        walk: &BiasWalk,
    ) {
        // `C` is kept in rotated coordinates, where its zero blocks (e.g. Euler's first
        // intervals) are exact: `V = A C + ½ Γ_Σ P_bb`, `C ← V + ½ Γ_Σ P_bb`; `P_walk` is
        // pulled back, `P'_walk += V' Γ'_Σᵀ + Γ'_Σ V'ᵀ` with `V' = Φ_k+1⁻¹ V`.
        let t = 0.5 * self.walk_t;
        let half = match walk.iso {
            Some((g, a)) => Gain96 {
                g: scale_cols(&rot.g, g * t),
                a: scale_cols(&rot.a, a * t),
            },
            None => rot.mul_diag(&(walk.g * t), &(walk.a * t)),
        };
        let v = tr.apply(&self.c).add(&half);
        self.p_walk.add_sym(&pb.apply(&v), gsum);
        self.c = v.add(&half);
    }
}

impl ErrorState {
    /// The gyro columns a rate coupling adds to an interval's total gain: `Σ_j Γ_a,kj D_j`,
    /// pulled back (each stencil sample's accelerometer gain through its `D_j`).
    #[inline(never)]
    fn coupled_walk<S: Shape>(
        &self,
        lin: &Linearisation<S::NodeTerms>,
        node: Option<&NodeColumns>,
        pb: &PullBack,
        (k_pos, len): (usize, usize),
        d: &RateCoupling,
    ) -> Gain96 {
        let acc = lin.basis.acc_columns(pb.tau);
        let n = if S::NODES_BEFORE + S::NODES_AFTER == 0 {
            S::STENCIL
        } else {
            len
        };
        let mut extra = Gain96::default();
        for (j, (c, dj)) in lin.coef.iter().zip(d).take(n).enumerate() {
            // A sample without an accelerometer gain in this interval (Euler's k+1).
            if !S::NodeTerms::PRESENT && c.a == (0.0, 0.0) && c.b == (0.0, 0.0) {
                continue;
            }
            let mut a = [[0.0; 6]; 3];
            if j == k_pos {
                add_acc::<FIRST, true>(&mut a, &acc, node, c);
            } else if j == k_pos + 1 {
                add_acc::<SECOND, true>(&mut a, &acc, node, c);
            } else {
                add_acc::<OUTER, true>(&mut a, &acc, node, c);
            }
            add_acc_through(&mut extra.g, &a, dj);
        }
        extra
    }
}

/// `g += a·D` on the v and p rows: an accelerometer gain `a` carried into gyro columns through
/// a rate coupling `D = ∂a_node/∂ω_node` ([`RateCoupling`]).
#[inline]
pub(crate) fn add_acc_through(g: &mut Cols9, a: &Cols6, d: &M3) {
    for (c, col) in g.iter_mut().enumerate() {
        for (m, am) in a.iter().enumerate() {
            let w = d[(m, c)];
            for i in 0..6 {
                col[3 + i] += am[i] * w;
            }
        }
    }
}

/// `J'_a −= r·(cv, cp)` (v and p rows).
#[inline(always)]
fn sub_rot(j: &mut Cols6, r: &M3, cv: f64, cp: f64) {
    for (c, col) in j.iter_mut().enumerate() {
        for i in 0..3 {
            col[i] -= cv * r[(i, c)];
            col[3 + i] -= cp * r[(i, c)];
        }
    }
}
