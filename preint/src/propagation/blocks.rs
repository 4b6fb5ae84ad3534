//! Storage of the error-state quantities by blocks: 9×6 gains by columns ([`Gain96`]) and the
//! symmetric 9×9 covariance packed by columns ([`PackedSym9`]), both in the rotated error
//! coordinates `[ψ, v, p]` of the parent module. Updates are rank-3 outer products of columns,
//! the form that vectorises; no 9×9 matrix is ever formed.

use nalgebra::{Matrix3, SMatrix, Vector3};

pub(crate) type M3 = Matrix3<f64>;
pub(crate) type V3 = Vector3<f64>;

/// Three gyro-type columns (gyro noise or gyro bias), rows `[ψ, v, p]`.
pub(crate) type Cols9 = [[f64; 9]; 3];
/// Three accelerometer-type columns, rows `[v, p]` (the ψ rows are zero: acceleration never
/// moves ΔR).
pub(crate) type Cols6 = [[f64; 6]; 3];

/// `a × b` for a column stored as an array.
#[inline(always)]
pub(crate) fn cross(a: &V3, b: [f64; 3]) -> [f64; 3] {
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

/// The columns `(g_c, 0, 0)` of a gain with ψ rows only.
#[inline(always)]
pub(crate) fn psi_cols(g: &M3) -> Cols9 {
    let mut out = [[0.0; 9]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        col[..3].copy_from_slice(&[g[(0, c)], g[(1, c)], g[(2, c)]]);
    }
    out
}

/// The columns `(c_v R_c, c_p R_c)` of the (v, p)-rows gain `R·(c_v, c_p)`.
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
pub(crate) fn add_cols<const N: usize>(a: &mut [[f64; N]; 3], b: &[[f64; N]; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        for (u, w) in x.iter_mut().zip(y) {
            *u += w;
        }
    }
}

#[inline(always)]
pub(crate) fn sub_cols<const N: usize>(a: &mut [[f64; N]; 3], b: &[[f64; N]; 3]) {
    for (x, y) in a.iter_mut().zip(b) {
        for (u, w) in x.iter_mut().zip(y) {
            *u -= w;
        }
    }
}

#[inline(always)]
pub(crate) fn scale_cols<const N: usize>(a: &[[f64; N]; 3], s: f64) -> [[f64; N]; 3] {
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
pub(crate) fn mul_cols<const N: usize>(a: &[[f64; N]; 3], q: &M3) -> [[f64; N]; 3] {
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
/// here (a gain, a bias Jacobian, the delta–bias covariance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Gain96 {
    pub g: Cols9,
    pub a: Cols6,
}

impl Gain96 {
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
    pub(crate) fn mul_diag(&self, qg: &M3, qa: &M3) -> Self {
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

/// A symmetric 9×9 in the order [ψ, v, p], packed by columns (the upper triangle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PackedSym9(pub [f64; 50]);

impl Default for PackedSym9 {
    fn default() -> Self {
        Self([0.0; 50])
    }
}

impl PackedSym9 {
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

    /// [`PackedSym9::add_outer`] for columns with zero ψ rows (rows and columns [v, p] only).
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
    pub(crate) fn add_acc(&mut self, m: &M3, cv: f64, cp: f64) {
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
    pub(crate) fn add_sym(&mut self, w: &Gain96, g: &Gain96) {
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

/// A symmetric 9×9 in its six distinct 3×3 blocks, order [ψ, v, p].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SymBlocks9 {
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
pub(crate) fn mul_skew(m: &M3, u: &V3) -> M3 {
    -skew_mul(u, &m.transpose()).transpose()
}
