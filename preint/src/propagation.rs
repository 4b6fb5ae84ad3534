//! Error-state propagation, shared by every scheme: every gain is pulled back to one origin
//! near the window start, where gains simply add.
//!
//! Chart (documented in [`crate::measurement`]): `ΔR = ΔR°·Exp(δφ)`, `Δv = Δv° + δv`,
//! `Δp = Δp° + δp`. The rotation error is handled as `ψ = ΔR_k δφ` (the same error as a left
//! perturbation, in frame i), the *rotated* error `e_k = [ψ, δv, δp]`. With that choice the
//! rotation block of every transition is the identity and `ΔR_k[a]×δφ = [u]×ψ` with
//! `u = ΔR_k a` (PERFORMANCE.md, trick 2). Every scheme's interval is linear in this error
//! state and in the perturbations `n_j = [δω_j, δa_j]` of the samples of its stencil:
//!
//! ```text
//! e_k+1 = A_k e_k + Σ_j Γ_kj n_j,   A_k = [[I, 0, 0], [−[U1]×, I, 0], [−[U2]×, h I, I]]
//! ```
//!
//! where `U1 = ∫ ΔR(t) a(t) dt` and `U2 = ∫ (h − s) ΔR(s) a(s) ds` over the interval, as the
//! scheme discretises them; for every scheme here they are exactly the increments
//! `U1 = Δv_k+1 − Δv_k`, `U2 = Δp_k+1 − Δp_k − Δv_k h`.
//!
//! # Transition between any two nodes
//!
//! Products of such transitions keep the form: from node k to node m,
//! `Φ = [[I, 0, 0], [−[V]×, I, 0], [−[W]×, T I, I]]` with `T = t_m − t_k`, `V = Δv_m − Δv_k`,
//! `W = Δp_m − Δp_k − Δv_k T` (compose two steps and use the increments above);
//! [`Transition`] holds `(T, V, W)`.
//!
//! # Pulled-back error: no per-interval transition
//!
//! Take node o = 1, the end of the window's first interval, as the origin and let
//! `Φ_k = Φ(o → k)`: `T = τ_k = t_k − t_o`, `V = Δv_k − Δv_o`, `W = Δp_k − Δp_o − Δv_o τ_k`, so
//!
//! ```text
//! Φ_k⁻¹ = [[I, 0, 0], [[V]×, I, 0], [[W − τ_k V]×, −τ_k I, I]],   W − τ_k V = Δp_k − Δp_o − τ_k Δv_k.
//! ```
//!
//! The error is propagated *pulled back* to the origin, `e'_k = Φ_k⁻¹ e_k`. Since
//! `Φ_k+1 = A_k Φ_k`, `e'_k+1 = e'_k + Σ_j Γ'_kj n_j` with `Γ'_kj = Φ_k+1⁻¹ Γ_kj`: the
//! transition disappears (the first interval's gains enter at the origin itself, `Φ_1 = I`). A
//! gain column `(r, v, p)` (ψ, v and p rows) entering at node k is pulled back ([`PullBack`]) as
//!
//! ```text
//! r' = r,   v' = v + V × r,   p' = p − τ_k v + (W − τ_k V) × r
//! ```
//!
//! so a rotation-row gain `g` whose v and p rows are `[x]× g` and `[y]× g` stays of that form
//! (`x' = x + V`, `y' = y − τ_k x + W − τ_k V`), and an accelerometer gain `R·(c_v, c_p)` (v and
//! p rows) becomes `R·(c_v, c_p − τ_k c_v)`. Covariance, bias Jacobians and the combined terms
//! are then plain sums; they are pushed forward once, `e = Φ_N e'` ([`Transition::push_forward`],
//! [`Transition::apply`]), when the measurement is read. With the origin at node 1 a
//! one-interval window needs no push-forward at all and keeps the exact zeros of its rotated
//! gains (Euler's gyro gain has no v and p rows), which merging such windows relies on.
//!
//! # Each sample's noise enters once
//!
//! A sample is used by every interval whose stencil holds it (Euler 1, midpoint 2, rk4 up to 4),
//! so its noise must not be added once per interval. Its total pulled-back gain is the sum
//! `G'_j = Σ_k Γ'_kj` over the intervals that use it; while a later interval still uses it the
//! sample is *pending* and that sum is being collected, and once no later interval uses it the
//! sample is *retired*: `P' += G'_j Q_j G'_jᵀ`, with `Q_j = diag(Σ_g, Σ_a)·white_scale(c_j)`
//! ([`crate::noise`]). At the end every pending sample is retired. No cross-covariance is kept;
//! the result is the exact first-order covariance `Φ_N (Σ_j G'_j Q_j G'_jᵀ) Φ_Nᵀ`. Euler has
//! no pending sample; midpoint has one (sample k+1, whose total gain is complete when interval
//! k+1 is done, see [`ErrorState::step_mid`]); rk4 has up to four ([`ErrorState::pending`]).
//!
//! # Bias Jacobians and the combined covariance
//!
//! Every sample sees `−δb` with its total gain, so `J' = −Σ_j G'_j`: Euler subtracts each
//! interval's gain `Γ'_Σ = Σ_j Γ'_kj` (its one sample), midpoint and rk4 each sample's total
//! gain when it is retired. Combined covariance (bias deviation `δb` constant over an
//! interval, then a random-walk step): `C = Cov(e, δb)`,
//! `V = A C + ½ Γ_Σ P_bb`, `P_walk ← A P_walk Aᵀ + V Γ_Σᵀ + Γ_Σ Vᵀ`, `C ← V + ½ Γ_Σ P_bb`,
//! `P_bb += Σ_rw·walk_scale(h)`. `P_walk` is pulled back like `P`
//! (`P'_walk += V' Γ'_Σᵀ + Γ'_Σ V'ᵀ`, `V' = Φ_k+1⁻¹ V`); the 9×6 `C` is kept in rotated
//! coordinates, where the blocks that vanish (Euler's gyro rows over the first intervals) are
//! exact zeros rather than round-off of a push-forward.
//!
//! # Storage
//!
//! Symmetric 9×9 matrices are packed ([`Sym9`]); 9×6 gains are stored by columns ([`Blk96`]),
//! the ψ rows of the accelerometer columns being identically zero (acceleration never moves
//! ΔR). Updates are rank-3 outer products of columns, the form that vectorises.

use crate::scheme::span_s;
use nalgebra::{Matrix3, SMatrix, Vector3};

pub(crate) type M3 = Matrix3<f64>;
pub(crate) type V3 = Vector3<f64>;

/// Three gyro-type columns (gyro noise or gyro bias), rows `[ψ, v, p]`.
pub(crate) type Cols9 = [[f64; 9]; 3];
/// Three accelerometer-type columns, rows `[v, p]` (the ψ rows are zero).
pub(crate) type Cols6 = [[f64; 6]; 3];

#[inline(always)]
fn cross(a: &V3, b: [f64; 3]) -> [f64; 3] {
    [
        a.y * b[2] - a.z * b[1],
        a.z * b[0] - a.x * b[2],
        a.x * b[1] - a.y * b[0],
    ]
}

/// The columns `(g_c, x × g_c, y × g_c)` of the gain whose ψ rows are `g` and whose v and p
/// rows are `[x]× g` and `[y]× g`.
#[inline(always)]
pub(crate) fn skew_cols(g: &M3, x: &V3, y: &V3) -> Cols9 {
    let mut out = [[0.0; 9]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        let r = [g[(0, c)], g[(1, c)], g[(2, c)]];
        let v = cross(x, r);
        let p = cross(y, r);
        *col = [r[0], r[1], r[2], v[0], v[1], v[2], p[0], p[1], p[2]];
    }
    out
}

/// The columns `(c_v R_c, c_p R_c)` of the accelerometer gain `R·(c_v, c_p)`.
#[inline(always)]
pub(crate) fn rot_cols(r: &M3, cv: f64, cp: f64) -> Cols6 {
    let mut out = [[0.0; 6]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        let x = [r[(0, c)], r[(1, c)], r[(2, c)]];
        *col = [
            cv * x[0],
            cv * x[1],
            cv * x[2],
            cp * x[0],
            cp * x[1],
            cp * x[2],
        ];
    }
    out
}

#[inline(always)]
fn add_cols<const N: usize>(a: &mut [[f64; N]; 3], b: &[[f64; N]; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        for (u, w) in x.iter_mut().zip(y) {
            *u += w;
        }
    }
}

#[inline(always)]
fn sub_cols<const N: usize>(a: &mut [[f64; N]; 3], b: &[[f64; N]; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        for (u, w) in x.iter_mut().zip(y) {
            *u -= w;
        }
    }
}

#[inline(always)]
fn scale_cols<const N: usize>(a: &[[f64; N]; 3], s: f64) -> [[f64; N]; 3] {
    let mut out = *a;
    for x in out.iter_mut() {
        for u in x.iter_mut() {
            *u *= s;
        }
    }
    out
}

/// `A·Q` for columns `A` and a 3×3 `Q`: column c is `Σ_d A_d Q[d][c]`.
#[inline(always)]
fn mul_cols<const N: usize>(a: &[[f64; N]; 3], q: &M3) -> [[f64; N]; 3] {
    let mut out = [[0.0; N]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        for i in 0..N {
            col[i] = a[0][i] * q[(0, c)] + a[1][i] * q[(1, c)] + a[2][i] * q[(2, c)];
        }
    }
    out
}

/// A 9×6 matrix by columns: gyro (or b_g) columns with rows [ψ, v, p], accelerometer (or b_a)
/// columns with rows [v, p]; its ψ–a block is identically zero for every quantity propagated
/// here.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Blk96 {
    pub g: Cols9,
    pub a: Cols6,
}

impl Blk96 {
    #[inline(always)]
    pub(crate) fn add(&self, o: &Self) -> Self {
        let mut out = *self;
        out.add_assign(o);
        out
    }
    #[inline(always)]
    pub(crate) fn add_assign(&mut self, o: &Self) {
        add_cols(&mut self.g, &o.g);
        add_cols(&mut self.a, &o.a);
    }
    #[inline(always)]
    pub(crate) fn scale(&self, s: f64) -> Self {
        Self {
            g: scale_cols(&self.g, s),
            a: scale_cols(&self.a, s),
        }
    }
    /// `self · diag(Qg, Qa)`.
    #[inline(always)]
    fn mul_diag(&self, qg: &M3, qa: &M3) -> Self {
        Self {
            g: mul_cols(&self.g, qg),
            a: mul_cols(&self.a, qa),
        }
    }
    /// The 3×3 block of the gyro columns at row block `row` (0 ψ, 1 v, 2 p).
    pub(crate) fn gyro_block(&self, row: usize) -> M3 {
        M3::from_fn(|i, c| self.g[c][3 * row + i])
    }
    /// The 3×3 block of the accelerometer columns at row block `row` (1 v, 2 p).
    pub(crate) fn acc_block(&self, row: usize) -> M3 {
        M3::from_fn(|i, c| self.a[c][3 * (row - 1) + i])
    }
    /// The dense 9×6 matrix with the ψ rows premultiplied by `rt` (rotated coordinates → the
    /// chart `δφ = ΔRᵀ ψ` when `rt = ΔRᵀ`).
    pub(crate) fn chart(&self, rt: &M3) -> SMatrix<f64, 9, 6> {
        let mut m = SMatrix::<f64, 9, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(rt * self.gyro_block(0)));
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.gyro_block(1));
        m.fixed_view_mut::<3, 3>(6, 0)
            .copy_from(&self.gyro_block(2));
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.acc_block(1));
        m.fixed_view_mut::<3, 3>(6, 3).copy_from(&self.acc_block(2));
        m
    }
}

/// Start of column j of a packed symmetric 9×9: the upper triangle by columns, each column
/// padded to an even length (entries `i ≤ j` used), so that updates run on aligned pairs.
const COL: [usize; 10] = [0, 2, 4, 8, 12, 18, 24, 32, 40, 50];

/// Index of entry `(i, j)`, `i ≤ j`, of a packed symmetric 9×9.
#[inline(always)]
const fn packed(i: usize, j: usize) -> usize {
    COL[j] + i
}

/// `x[i] += Σ_c w_c[i] b_c` for `i < N`: one column of a rank-3 update (rows of length `R`).
#[inline(always)]
fn axpy<const R: usize, const N: usize>(x: &mut [f64], w: &[[f64; R]; 3], b: [f64; 3]) {
    let x: &mut [f64; N] = (&mut x[..N]).try_into().expect("constant column range");
    for i in 0..N {
        x[i] += w[0][i] * b[0] + w[1][i] * b[1] + w[2][i] * b[2];
    }
}

/// Symmetric 9×9, order [ψ, v, p], packed (see `COL`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sym9(pub [f64; 50]);

impl Default for Sym9 {
    fn default() -> Self {
        Self([0.0; 50])
    }
}

impl Sym9 {
    /// Entry `(i, j)` (either triangle).
    #[inline(always)]
    pub(crate) fn at(&self, i: usize, j: usize) -> f64 {
        self.0[packed(i.min(j), i.max(j))]
    }

    /// The 3×3 block at row block `r`, column block `c` (0 ψ, 1 v, 2 p).
    pub(crate) fn block(&self, r: usize, c: usize) -> M3 {
        M3::from_fn(|i, j| self.at(3 * r + i, 3 * c + j))
    }

    /// `P += s Σ_c w_c g_cᵀ` (upper triangle; symmetric when `W = G·Q` with `Q` symmetric).
    /// Column j is written for `i ≤ j` rounded up to even (the padding entry is never read), so
    /// that every column is a run of aligned pairs. Out of line: on its own the compiler keeps
    /// the columns in memory and pairs the rows (inlined into a large step it does not).
    #[inline(never)]
    pub(crate) fn add_outer(&mut self, w: &Cols9, g: &Cols9, s: f64) {
        let b = |j: usize| [g[0][j] * s, g[1][j] * s, g[2][j] * s];
        let p = &mut self.0;
        axpy::<9, 2>(&mut p[COL[0]..], w, b(0));
        axpy::<9, 2>(&mut p[COL[1]..], w, b(1));
        axpy::<9, 4>(&mut p[COL[2]..], w, b(2));
        axpy::<9, 4>(&mut p[COL[3]..], w, b(3));
        axpy::<9, 6>(&mut p[COL[4]..], w, b(4));
        axpy::<9, 6>(&mut p[COL[5]..], w, b(5));
        axpy::<9, 8>(&mut p[COL[6]..], w, b(6));
        axpy::<9, 8>(&mut p[COL[7]..], w, b(7));
        axpy::<9, 9>(&mut p[COL[8]..], w, b(8));
    }

    /// [`Sym9::add_outer`] for columns with zero ψ rows (rows and columns [v, p] only).
    #[inline(never)]
    pub(crate) fn add_outer_vp(&mut self, w: &Cols6, g: &Cols6, s: f64) {
        let b = |j: usize| [g[0][j] * s, g[1][j] * s, g[2][j] * s];
        let p = &mut self.0;
        axpy::<6, 1>(&mut p[COL[3] + 3..], w, b(0));
        axpy::<6, 2>(&mut p[COL[4] + 3..], w, b(1));
        axpy::<6, 3>(&mut p[COL[5] + 3..], w, b(2));
        axpy::<6, 4>(&mut p[COL[6] + 3..], w, b(3));
        axpy::<6, 5>(&mut p[COL[7] + 3..], w, b(4));
        axpy::<6, 6>(&mut p[COL[8] + 3..], w, b(5));
    }

    /// Adds `(dv, dvp, dp)` to the diagonals of the v–v, v–p and p–p blocks.
    #[inline(always)]
    pub(crate) fn add_diag_vp(&mut self, dv: f64, dvp: f64, dp: f64) {
        for i in 0..3 {
            self.0[packed(3 + i, 3 + i)] += dv;
            self.0[packed(3 + i, 6 + i)] += dvp;
            self.0[packed(6 + i, 6 + i)] += dp;
        }
    }

    /// Adds `m·(cv², cv·cp, cp²)` (`m` symmetric) to the v–v, v–p and p–p blocks.
    #[inline(always)]
    fn add_acc(&mut self, m: &M3, cv: f64, cp: f64) {
        let (vv, vp, pp) = (cv * cv, cv * cp, cp * cp);
        for j in 0..3 {
            for i in 0..3 {
                if i <= j {
                    self.0[packed(3 + i, 3 + j)] += m[(i, j)] * vv;
                    self.0[packed(6 + i, 6 + j)] += m[(i, j)] * pp;
                }
                self.0[packed(3 + i, 6 + j)] += m[(i, j)] * vp;
            }
        }
    }

    /// Adds the symmetric `m` to the p–p block.
    #[inline(always)]
    pub(crate) fn add_pp(&mut self, m: &M3) {
        for j in 0..3 {
            for i in 0..=j {
                self.0[packed(6 + i, 6 + j)] += m[(i, j)];
            }
        }
    }

    /// Adds `x` to the diagonal of the p–p block.
    #[inline(always)]
    pub(crate) fn add_pp_diag(&mut self, x: f64) {
        for i in 0..3 {
            self.0[packed(6 + i, 6 + i)] += x;
        }
    }

    /// `P += W Γᵀ + Γ Wᵀ` (both 9×6 with zero ψ–a block).
    #[inline(always)]
    fn add_sym(&mut self, w: &Blk96, g: &Blk96) {
        self.add_outer(&w.g, &g.g, 1.0);
        self.add_outer(&g.g, &w.g, 1.0);
        self.add_outer_vp(&w.a, &g.a, 1.0);
        self.add_outer_vp(&g.a, &w.a, 1.0);
    }

    pub(crate) fn add_assign(&mut self, o: &Self) {
        for (a, b) in self.0.iter_mut().zip(&o.0) {
            *a += b;
        }
    }
}

/// Rotated covariance in its six distinct 3×3 blocks, order [ψ, v, p].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Blocks9 {
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

/// The transition `Φ` between two nodes (see module doc): duration `h` \[s\], `U1` [m/s],
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
    pub(crate) fn apply(&self, x: &Blk96) -> Blk96 {
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
    pub(crate) fn push_forward(&self, s: &Sym9) -> Blocks9 {
        let p = Blocks9 {
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
        Blocks9 {
            rr: p.rr,
            rv: p.rv + mul_skew(&p.rr, u1),
            rp: p.rp + p.rv * h + mul_skew(&p.rr, u2),
            vv: ap_vv + mul_skew(&ap_vr, u1),
            vp: ap_vp + ap_vv * h + mul_skew(&ap_vr, u2),
            pp: ap_pp + ap_pv * h + mul_skew(&ap_pr, u2),
        }
    }
}

/// The origin of the pulled-back error (module doc): node 1, the end of the window's first
/// interval.
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

/// `Φ_k⁻¹` at node k (module doc): a gain entering there is pulled back to the origin.
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
    pub(crate) fn apply(&self, x: &Blk96) -> Blk96 {
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

/// Per-sample white-noise covariance `Q_j = s_j · diag(Σ_g, Σ_a)` with
/// `s_j = white_scale(c_j)` [1/s] ([`crate::noise`]). Monomorphised once per noise shape.
pub(crate) trait NoiseQ: Copy {
    /// `P += Γ Q Γᵀ` for a gain with gyro columns `g` and accelerometer columns `R·(cv, cp)`
    /// (v and p rows), `R` a rotation: every sample's gain in Euler and midpoint.
    fn add_rot(&self, p: &mut Sym9, g: &Cols9, r: &M3, cv: f64, cp: f64, s: f64);
    /// `P += G Q Gᵀ` for a general gain.
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64);
}

/// Isotropic `Σ_g = g I`, `Σ_a = a I`: scalar products only.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IsoQ {
    pub g: f64,
    pub a: f64,
}

impl NoiseQ for IsoQ {
    #[inline(always)]
    fn add_rot(&self, p: &mut Sym9, g: &Cols9, _r: &M3, cv: f64, cp: f64, s: f64) {
        p.add_outer(g, g, self.g * s);
        // R Σ_a Rᵀ = a I: the accelerometer noise adds to diagonals only.
        let a = self.a * s;
        p.add_diag_vp(a * (cv * cv), a * (cv * cp), a * (cp * cp));
    }

    #[inline(always)]
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64) {
        p.add_outer(&g.g, &g.g, self.g * s);
        p.add_outer_vp(&g.a, &g.a, self.a * s);
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
    fn add_rot(&self, p: &mut Sym9, g: &Cols9, r: &M3, cv: f64, cp: f64, s: f64) {
        p.add_outer(&mul_cols(g, &self.g), g, s);
        let ra = r * (self.a * s) * r.transpose();
        p.add_acc(&((ra + ra.transpose()) * 0.5), cv, cp);
    }

    #[inline(always)]
    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64) {
        p.add_outer(&mul_cols(&g.g, &self.g), &g.g, s);
        p.add_outer_vp(&mul_cols(&g.a, &self.a), &g.a, s);
    }
}

/// A pending sample (module doc): its index and the sum of its pulled-back gains so far.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pending {
    pub id: usize,
    pub g: Blk96,
}

/// No sample in a pending slot.
pub(crate) const NO_ID: usize = usize::MAX;
/// Number of pending-sample slots (≥ the largest stencil); sample `id` lives in `id % SLOTS`.
pub(crate) const SLOTS: usize = 4;

/// Midpoint: the pulled-back gain of the last interval's end sample, which the next interval
/// completes. Its accelerometer columns are `ΔR_k+1·(cv, cp)`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MidPending {
    pub g: Cols9,
    pub cv: f64,
    pub cp: f64,
}

/// The error state: covariance, bias Jacobians and the combined-covariance terms, pulled back
/// to the origin except `C` (module doc).
#[derive(Clone, Debug)]
pub(crate) struct ErrorState {
    /// Covariance of the deltas from the white measurement noise of the retired samples
    /// (`Φ_N P' Φ_Nᵀ` is what `PreintegratedImu::cov` holds once every sample is retired, as
    /// GTSAM's `ImuFactor`).
    pub p: Sym9,
    /// The part of the deltas' covariance driven by the bias random walk during the window
    /// (combined level only); `p + p_walk` is the 9×9 block of the 15×15 covariance. Kept apart
    /// because propagation is linear, so the two parts evolve independently.
    pub p_walk: Sym9,
    /// Bias Jacobian `J'`.
    pub j: Blk96,
    /// `C = Cov(e, δb)` in rotated coordinates (combined level only).
    pub c: Blk96,
    /// `Σ walk_scale(h)` over the intervals: `P_bb = diag(Σ_bg, Σ_ba)·walk_t`.
    pub walk_t: f64,
    /// rk4: pending samples.
    pub pend: [Pending; SLOTS],
    /// Midpoint: the end sample of the last interval.
    mid: MidPending,
}

impl Default for ErrorState {
    fn default() -> Self {
        Self {
            p: Sym9::default(),
            p_walk: Sym9::default(),
            j: Blk96::default(),
            c: Blk96::default(),
            walk_t: 0.0,
            pend: [Pending {
                id: NO_ID,
                g: Blk96::default(),
            }; SLOTS],
            mid: MidPending::default(),
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

/// A midpoint interval's pulled-back gains: both samples share the gyro gain
/// `(G, x × G, y × G)` (ψ, v, p rows; [`skew_cols`]); the accelerometer gains are `ΔR_k·(cv, cp)`
/// (sample k) and `ΔR_k+1·(cv, cp)` (sample k+1).
#[derive(Clone, Copy, Debug)]
pub(crate) struct MidGain {
    /// The pull-back used, `Φ_k+1⁻¹`.
    pub pb: PullBack,
    pub g: M3,
    pub x: V3,
    pub y: V3,
    /// `ΔR_k`.
    pub r0: M3,
    pub cv: f64,
    pub cp: f64,
}

impl ErrorState {
    /// Combined terms and bias-walk step for interval `tr` ending at node k+1
    /// (`pb = Φ_k+1⁻¹`); `gsum` gives the interval's total pulled-back gain, `rotated` the
    /// same gain in rotated coordinates (both used at the combined level only).
    #[inline(always)]
    fn walk_step(
        &mut self,
        tr: &Transition,
        pb: &PullBack,
        gsum: impl FnOnce(&Self) -> Blk96,
        rotated: impl FnOnce(&Blk96) -> Blk96,
        walk: &BiasWalk,
    ) {
        if walk.combined {
            // `C` is kept in rotated coordinates, where its zero blocks (e.g. Euler's first
            // intervals) are exact: `V = A C + ½ Γ_Σ P_bb`, `C ← V + ½ Γ_Σ P_bb`; `P_walk` is
            // pulled back, `P'_walk += V' Γ'_Σᵀ + Γ'_Σ V'ᵀ` with `V' = Φ_k+1⁻¹ V`.
            let gsum = gsum(self);
            let rot = rotated(&gsum);
            let t = 0.5 * self.walk_t;
            let half = match walk.iso {
                Some((g, a)) => Blk96 {
                    g: scale_cols(&rot.g, g * t),
                    a: scale_cols(&rot.a, a * t),
                },
                None => rot.mul_diag(&(walk.g * t), &(walk.a * t)),
            };
            let v = tr.apply(&self.c).add(&half);
            self.p_walk.add_sym(&pb.apply(&v), &gsum);
            self.c = v.add(&half);
        }
        self.walk_t += crate::noise::walk_scale(tr.h);
    }

    /// `J'_a −= r·(cv, cp)` (v and p rows).
    #[inline(always)]
    fn sub_acc_jac(&mut self, r: &M3, cv: f64, cp: f64) {
        for (c, col) in self.j.a.iter_mut().enumerate() {
            for i in 0..3 {
                col[i] -= cv * r[(i, c)];
                col[3 + i] -= cp * r[(i, c)];
            }
        }
    }

    /// Euler interval `tr`: sample k (pulled-back gyro columns `g`, accelerometer columns
    /// `r0·(cv, cp)`) is used once, so it is retired at once with noise scale `scale` [1/s]
    /// (0 when the caller collects its gain instead). `cp0` is `c_p` in rotated coordinates
    /// (`½h²`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step_euler<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        pb: &PullBack,
        g: &Cols9,
        r0: &M3,
        (cv, cp, cp0): (f64, f64, f64),
        scale: f64,
        noise: &N,
        walk: &BiasWalk,
    ) {
        if scale != 0.0 {
            noise.add_rot(&mut self.p, g, r0, cv, cp, scale);
        }
        sub_cols(&mut self.j.g, g);
        self.sub_acc_jac(r0, cv, cp);
        let gsum = |_: &Self| Blk96 {
            g: *g,
            a: rot_cols(r0, cv, cp),
        };
        // Rotated: the gyro gain has ψ rows only.
        let rotated = |_: &Blk96| {
            let mut rg = [[0.0; 9]; 3];
            for (o, col) in rg.iter_mut().zip(g) {
                o[..3].copy_from_slice(&col[..3]);
            }
            Blk96 {
                g: rg,
                a: rot_cols(r0, cv, cp0),
            }
        };
        self.walk_step(tr, pb, gsum, rotated, walk);
    }

    /// Midpoint interval `tr` from `ΔR_k` (`g.r0`) to `r1 = ΔR_k+1` ending at node k+1
    /// (`g.pb = Φ_k+1⁻¹`). Sample k's gain is now complete (the pending part from interval k−1 plus
    /// this interval's): it is retired with noise scale `s0` [1/s] (0 when the caller collects
    /// the gain instead), enters the bias Jacobian (`J' −= G'_k`: every sample sees `−δb`), and
    /// is returned (gyro columns, `(cv, cp)` of its accelerometer gain `r0·(cv, cp)`). Sample
    /// k+1 becomes pending.
    #[inline(always)]
    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)] // parallel arrays
    pub(crate) fn step_mid<N: NoiseQ>(
        &mut self,
        tr: &Transition,
        g: &MidGain,
        r1: &M3,
        s0: f64,
        noise: &N,
        walk: &BiasWalk,
    ) -> MidPending {
        // done = pending + this interval's gain; this interval's gain becomes pending.
        let mut done = MidPending {
            g: [[0.0; 9]; 3],
            cv: self.mid.cv + g.cv,
            cp: self.mid.cp + g.cp,
        };
        for c in 0..3 {
            let r = [g.g[(0, c)], g.g[(1, c)], g.g[(2, c)]];
            let (v, p) = (cross(&g.x, r), cross(&g.y, r));
            let col = [r[0], r[1], r[2], v[0], v[1], v[2], p[0], p[1], p[2]];
            for i in 0..9 {
                let x = self.mid.g[c][i] + col[i];
                done.g[c][i] = x;
                self.j.g[c][i] -= x;
                self.mid.g[c][i] = col[i];
            }
        }
        (self.mid.cv, self.mid.cp) = (g.cv, g.cp);
        if s0 != 0.0 {
            noise.add_rot(&mut self.p, &done.g, &g.r0, done.cv, done.cp, s0);
        }
        self.sub_acc_jac(&g.r0, done.cv, done.cp);
        // The interval's total gain: the gyro columns count twice (one per sample).
        let gsum = |e: &Self| Blk96 {
            g: scale_cols(&e.mid.g, 2.0),
            a: rot_cols(&(g.r0 + r1), g.cv, g.cp),
        };
        self.walk_step(tr, &g.pb, gsum, |x| g.pb.forward().apply(x), walk);
        done
    }

    /// Midpoint, end of the window: removes and returns the last sample's pending gain (its
    /// accelerometer columns are `r·(cv, cp)`), which enters the bias Jacobian.
    #[inline]
    pub(crate) fn take_mid(&mut self, r: &M3) -> MidPending {
        let m = std::mem::take(&mut self.mid);
        sub_cols(&mut self.j.g, &m.g);
        self.sub_acc_jac(r, m.cv, m.cp);
        m
    }

    /// rk4: the pending gain of sample `id`, which interval gains are added to (a sample
    /// first used starts at zero). Samples no longer used must have been retired
    /// ([`ErrorState::take_pending`]) first.
    #[inline(always)]
    pub(crate) fn pending(pend: &mut [Pending; SLOTS], id: usize) -> &mut Blk96 {
        let slot = &mut pend[id % SLOTS];
        if slot.id != id {
            debug_assert_eq!(slot.id, NO_ID, "pending sample not retired");
            *slot = Pending {
                id,
                g: Blk96::default(),
            };
        }
        &mut slot.g
    }

    /// rk4 interval `tr` ending at node k+1 (`pb = Φ_k+1⁻¹`), whose gains were added to the
    /// pending samples ([`ErrorState::pending`]); `gsum` is their sum (combined level only).
    #[inline(always)]
    pub(crate) fn step_multi(
        &mut self,
        tr: &Transition,
        pb: &PullBack,
        gsum: &Blk96,
        walk: &BiasWalk,
    ) {
        self.walk_step(tr, pb, |_| *gsum, |x| pb.forward().apply(x), walk);
    }

    /// Removes the pending sample of slot `slot` and returns it; its total gain enters the
    /// bias Jacobian (`J' −= G'_j`: every sample sees `−δb`).
    #[inline(always)]
    pub(crate) fn take_pending(&mut self, slot: usize) -> Pending {
        let pd = std::mem::replace(
            &mut self.pend[slot],
            Pending {
                id: NO_ID,
                g: Blk96::default(),
            },
        );
        sub_cols(&mut self.j.g, &pd.g.g);
        sub_cols(&mut self.j.a, &pd.g.a);
        pd
    }

    /// Retires a sample: `P' += G' Q G'ᵀ` with `Q = diag(Σ_g, Σ_a)·s`.
    #[inline(always)]
    pub(crate) fn add_noise<N: NoiseQ>(&mut self, g: &Blk96, s: f64, noise: &N) {
        noise.add_full(&mut self.p, g, s);
    }
}
