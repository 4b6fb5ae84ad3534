//! The one shape in which every scheme gives its linearisation: the interval's transition and
//! the gain of each stencil sample, in rotated coordinates at the interval's end node (the
//! `propagation` module's chart, `ψ = ΔR δφ`).
//!
//! Every interval is linear in the rotated error and in the perturbations `n_j = [δω_j, δa_j]`
//! of its stencil samples: `e_k+1 = A_k e_k + Σ_j Γ_kj n_j` with
//! `A_k = [[I, 0, 0], [−[U1]×, I, 0], [−[U2]×, h I, I]]` ([`Transition`]). The gains of all
//! the schemes here are built from a few 3×3 blocks that the interval shares
//! ([`GainBasis`]), weighted per sample by five scalars ([`GainCoef`]):
//!
//! ```text
//! gyro columns of Γ_kj  = c_j B(F) + [j = k] (B(F_k) + E_k·(e_v, e_p)) + [j = k+1] (B(F_k+1) + E_k+1·(e'_v, e'_p))
//! accel columns of Γ_kj = ΔR_k·(α_v, α_p) + ΔR_k+1·(β_v, β_p) + [j = k] W_k·(w_v, w_p) + [j = k+1] W_k+1·(w'_v, w'_p)
//! ```
//!
//! where `B(G) = (G, [x]× G, [y]× G)` is a ψ gain with the v and p rows the rotation error
//! drags along, and `M·(c_v, c_p)` a gain with v and p rows only. The node terms (`F_k`, `E_k`,
//! `W_k`, …) exist for schemes that read the rates' derivatives at the nodes (the Hermite
//! scheme); [`GainForm`] says which parts a scheme has, so the propagator never multiplies an
//! exact zero.
//!
//! A scheme that holds sample k over interval k and whose gain has no such structure (the
//! Galilean scheme: its v and p rows are general 3×3 matrices) hands sample k's whole 9×6 gain
//! instead ([`HeldGain`] as its node terms, [`NodeTermsOf::HELD`]); the basis and scalars are
//! then unused.

use crate::propagation::blocks::{Cols6, Cols9, Gain96, M3, V3, psi_cols, rot_cols, skew_cols};
use crate::propagation::transition::{PullBack, Transition};

/// Which parts of the [`GainBasis`] a scheme uses (the others are exact zeros).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GainForm {
    /// The ψ gain `F` drags v and p rows along (`x`, `y` non-zero in rotated coordinates).
    pub psi_vp: bool,
    /// Sample k's accelerometer gain is `ΔR_k·(α_v, α_p)`, sample k+1's `ΔR_k+1·(β_v, β_p)`, and
    /// no other sample has one: every sample's accelerometer gain is then its own node's ΔR
    /// times two scalars, over every interval that reads it.
    pub acc_on_own_node: bool,
}

/// The terms of one node (k or k+1) of an interval with node terms (module docs).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NodeTerms {
    /// `F_k`: a ψ gain, with the interval's `x`, `y`.
    pub f: M3,
    /// `E_k` and its scalars `(e_v, e_p)`: v and p rows of the gyro columns.
    pub e: M3,
    pub e_vp: (f64, f64),
    /// `W_k` and its scalars: accelerometer columns.
    pub w: M3,
    pub w_vp: (f64, f64),
}

/// The blocks an interval's gains are built of (module docs), in rotated coordinates at node
/// k+1; the node terms are in [`Linearisation::node`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GainBasis {
    /// The shared ψ gain `F` and its skew rows `x`, `y`.
    pub f: M3,
    pub x: V3,
    pub y: V3,
    /// `ΔR_k`, `ΔR_k+1`.
    pub r0: M3,
    pub r1: M3,
}

/// The node terms of an interval: `[NodeTerms; 2]` (nodes k and k+1) for schemes that have
/// them, `()` for the others, [`HeldGain`] for a held scheme that gives its whole gain.
pub(crate) trait NodeTermsOf: Copy + std::fmt::Debug {
    /// Whether there are node terms.
    const PRESENT: bool;
    /// Whether the interval's gain is [`NodeTermsOf::held`]: the whole 9×6 gain of its only
    /// noise source, sample k (a scheme with a stencil `{k, k+1}` and no end-node noise).
    const HELD: bool = false;
    /// The terms of nodes k and k+1 (only called when [`NodeTermsOf::PRESENT`]).
    fn terms(&self) -> [NodeTerms; 2];
    /// Sample k's whole gain, rotated coordinates at node k+1 (only called when
    /// [`NodeTermsOf::HELD`]).
    #[inline(always)]
    fn held(&self) -> &Gain96 {
        &ZERO_GAIN
    }
}

const ZERO_GAIN: Gain96 = Gain96 {
    g: [[0.0; 9]; 3],
    a: [[0.0; 6]; 3],
};

/// Sample k's whole 9×6 gain over interval k, in rotated coordinates at node k+1: gyro
/// columns rows `[ψ, v, p]`, accelerometer columns rows `[v, p]` (module docs).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HeldGain(pub Gain96);

impl NodeTermsOf for HeldGain {
    const PRESENT: bool = false;
    const HELD: bool = true;
    fn terms(&self) -> [NodeTerms; 2] {
        [NodeTerms::default(); 2]
    }
    #[inline(always)]
    fn held(&self) -> &Gain96 {
        &self.0
    }
}

impl NodeTermsOf for () {
    const PRESENT: bool = false;
    fn terms(&self) -> [NodeTerms; 2] {
        [NodeTerms::default(); 2]
    }
}

impl NodeTermsOf for [NodeTerms; 2] {
    const PRESENT: bool = true;
    #[inline(always)]
    fn terms(&self) -> [NodeTerms; 2] {
        *self
    }
}

/// One stencil sample's scalars: `c_j` (gyro), `(α_v, α_p)` with `ΔR_k` and `(β_v, β_p)` with
/// `ΔR_k+1` (accelerometer).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct GainCoef {
    pub gyro: f64,
    pub a: (f64, f64),
    pub b: (f64, f64),
}

impl GainCoef {
    /// The sum of two samples' scalars (the basis is linear in them).
    #[inline(always)]
    pub(crate) fn add(&self, o: &Self) -> Self {
        Self {
            gyro: self.gyro + o.gyro,
            a: (self.a.0 + o.a.0, self.a.1 + o.a.1),
            b: (self.b.0 + o.b.0, self.b.1 + o.b.1),
        }
    }
}

/// Maximum number of stencil samples of an interval.
pub(crate) const MAX_STENCIL: usize = 4;

/// The linearisation of one interval: its transition and the gains of its stencil samples
/// (`coef[j]` for stencil position `j`; positions beyond the stencil are zero), with the node
/// terms `T` ([`NodeTermsOf`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Linearisation<T = ()> {
    pub tr: Transition,
    pub basis: GainBasis,
    pub coef: [GainCoef; MAX_STENCIL],
    pub node: T,
}

/// The roles of a stencil sample in [`add_gyro`] and [`add_acc`]: neither node of the interval,
/// its first node (k), its second (k+1), and the sum over the whole stencil (both).
pub(crate) const OUTER: u8 = 0;
pub(crate) const FIRST: u8 = 1;
pub(crate) const SECOND: u8 = 2;
pub(crate) const BOTH: u8 = FIRST | SECOND;

/// The gyro columns `B(F)` of a [`GainBasis`] in the coordinates the gains are wanted in
/// (pulled back to the origin, or rotated at node k+1).
pub(crate) type GyroColumns = Cols9;

/// The accelerometer columns of a [`GainBasis`]: `ΔR_k·(1, −τ)` and `ΔR_k+1·(1, −τ)` (scaled
/// per sample by `(α_v, α_p)` and `(β_v, β_p)`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct AccColumns {
    pub r0: Cols6,
    pub r1: Cols6,
}

/// The node terms as columns: gyro `B(F_k) + E_k·(…)`, `B(F_k+1) + E_k+1·(…)`, accelerometer
/// `W_k·(…)`, `W_k+1·(…)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodeColumns {
    pub gk: Cols9,
    pub gk1: Cols9,
    pub ak: Cols6,
    pub ak1: Cols6,
}

/// The skew rows `(x, y)` and `τ` of the coordinates wanted: pulled back by `pb`, or (with
/// `None`) rotated at node k+1.
#[inline(always)]
fn skew_rows(b: &GainBasis, form: GainForm, pb: Option<&PullBack>) -> (V3, V3, f64) {
    match pb {
        Some(pb) if form.psi_vp => {
            let (x, y) = pb.skew(&b.x, &b.y);
            (x, y, pb.tau)
        }
        Some(pb) => (pb.dv, pb.w, pb.tau),
        None => (b.x, b.y, 0.0),
    }
}

impl GainBasis {
    /// The gyro columns `B(F)` pulled back by `pb` (or, with `pb = None`, in rotated
    /// coordinates at node k+1).
    #[inline(always)]
    pub(crate) fn gyro_columns(&self, form: GainForm, pb: Option<&PullBack>) -> GyroColumns {
        if form.psi_vp || pb.is_some() {
            let (x, y, _) = skew_rows(self, form, pb);
            skew_cols(&self.f, &x, &y)
        } else {
            psi_cols(&self.f)
        }
    }

    /// The accelerometer columns for a pull-back of `τ` \[s\] (0: rotated coordinates).
    #[inline(always)]
    pub(crate) fn acc_columns(&self, tau: f64) -> AccColumns {
        AccColumns {
            r0: rot_cols(&self.r0, 1.0, -tau),
            r1: rot_cols(&self.r1, 1.0, -tau),
        }
    }

    /// The node terms `node` as columns, pulled back by `pb` (or rotated, with `None`).
    #[inline(always)]
    pub(crate) fn node_columns(
        &self,
        node: &[NodeTerms; 2],
        form: GainForm,
        pb: Option<&PullBack>,
    ) -> NodeColumns {
        let (x, y, tau) = skew_rows(self, form, pb);
        let vp = |m: &M3, (cv, cp): (f64, f64)| rot_cols(m, cv, cp - tau * cv);
        let with_e = |n: &NodeTerms| {
            let mut c = skew_cols(&n.f, &x, &y);
            let e = vp(&n.e, n.e_vp);
            for (col, ec) in c.iter_mut().zip(&e) {
                for i in 0..6 {
                    col[3 + i] += ec[i];
                }
            }
            c
        };
        NodeColumns {
            gk: with_e(&node[0]),
            gk1: with_e(&node[1]),
            ak: vp(&node[0].w, node[0].w_vp),
            ak1: vp(&node[1].w, node[1].w_vp),
        }
    }
}

/// Adds the gyro columns of a stencil sample with scalars `c` and role `ROLE` (`OUTER`,
/// `FIRST`, `SECOND`, `BOTH`) to `g`: `c_j B(F)` plus its node terms.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // parallel arrays
pub(crate) fn add_gyro<const ROLE: u8>(
    g: &mut Cols9,
    f: &GyroColumns,
    node: Option<&NodeColumns>,
    c: &GainCoef,
) {
    let (k0, k1) = (ROLE & FIRST != 0, ROLE & SECOND != 0);
    for col in 0..3 {
        for i in 0..9 {
            let mut x = f[col][i] * c.gyro;
            if let Some(n) = node {
                if k0 {
                    x += n.gk[col][i];
                }
                if k1 {
                    x += n.gk1[col][i];
                }
            }
            g[col][i] += x;
        }
    }
}

/// Adds the accelerometer columns of a stencil sample with scalars `c` and role `ROLE` to
/// `a`; `END`: the `ΔR_k+1` terms exist.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // parallel arrays
pub(crate) fn add_acc<const ROLE: u8, const END: bool>(
    a: &mut Cols6,
    acc: &AccColumns,
    node: Option<&NodeColumns>,
    c: &GainCoef,
) {
    let (k0, k1) = (ROLE & FIRST != 0, ROLE & SECOND != 0);
    let ((av, ap), (bv, bp)) = (c.a, c.b);
    for col in 0..3 {
        for i in 0..3 {
            // v rows: r·α_v; p rows: r·(α_p − τα_v) = (r·1)·α_p + (r·(−τ))·α_v.
            let mut v = acc.r0[col][i] * av;
            let mut p = acc.r0[col][i] * ap + acc.r0[col][3 + i] * av;
            if END {
                v += acc.r1[col][i] * bv;
                p += acc.r1[col][i] * bp;
                p += acc.r1[col][3 + i] * bv;
            }
            if let Some(n) = node {
                if k0 {
                    v += n.ak[col][i];
                    p += n.ak[col][3 + i];
                }
                if k1 {
                    v += n.ak1[col][i];
                    p += n.ak1[col][3 + i];
                }
            }
            a[col][i] += v;
            a[col][3 + i] += p;
        }
    }
}
