//! A Jacobian checker in the spirit of Ceres' `GradientChecker`: compares analytic Jacobian
//! blocks with Ridders' numeric Jacobian ([`crate::numdiff::ridders`]) and reports the worst
//! relative error, with its block and entry.
//!
//! The input may be a product manifold (a tuple such as `(SO3, Vector3<f64>)`); its tangent is
//! the concatenation of the components' tangents, and the analytic Jacobian is given as one
//! block per component, in order (block widths must add up to `dim X`). A single matrix is a
//! single block.
//!
//! Relative error of an entry (analytic `a`, numeric `n`):
//! `|a − n| / max(|a|, |n|, floor_rel·max_block|n|, floor_abs)`. The floors make entries that
//! are analytically zero (where Ridders returns round-off) compare on the scale of their
//! block instead of their own, like Ceres' `IsClose`, which switches to the absolute error when
//! one side is zero.

use crate::numdiff::{NumDiffError, NumDiffOptions, ridders};
use nalgebra::{DMatrix, DVector, Dim, Matrix, RawStorage};
use preint_lie::Manifold;

/// Options of [`check_jacobian`].
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Largest accepted relative error (default 1e-8).
    pub tolerance: f64,
    /// Denominator floor relative to the largest numeric entry of the block (default 1e-3).
    pub floor_rel: f64,
    /// Absolute denominator floor (default 1e-12).
    pub floor_abs: f64,
    /// Options of the Ridders differentiation.
    pub numdiff: NumDiffOptions,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-8,
            floor_rel: 1e-3,
            floor_abs: 1e-12,
            numdiff: NumDiffOptions::default(),
        }
    }
}

/// Outcome of a check: the worst entry over all blocks.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Worst relative error (see the module docs).
    pub worst_rel_error: f64,
    /// Index of the block holding it.
    pub block: usize,
    /// Row of the entry (output tangent coordinate).
    pub row: usize,
    /// Column of the entry within its block (tangent coordinate of that input component).
    pub col: usize,
    /// Analytic value there.
    pub analytic: f64,
    /// Numeric value there.
    pub numeric: f64,
    /// Ridders' error estimate of the numeric column holding the entry.
    pub numeric_error_estimate: f64,
    /// The whole numeric Jacobian (`dim Y × dim X`).
    pub numeric_jacobian: DMatrix<f64>,
}

impl std::fmt::Display for CheckReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "worst relative error {:.3e} in block {} entry ({}, {}): analytic {:.17e}, numeric {:.17e} (Ridders error estimate {:.1e})",
            self.worst_rel_error,
            self.block,
            self.row,
            self.col,
            self.analytic,
            self.numeric,
            self.numeric_error_estimate
        )
    }
}

/// Errors of [`check_jacobian`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckError {
    /// The worst relative error exceeds the tolerance.
    #[error("Jacobian check failed (tolerance {tolerance:e}): {report}")]
    Mismatch {
        /// Tolerance used.
        tolerance: f64,
        /// The worst entry.
        report: Box<CheckReport>,
    },
    /// Block shapes do not match `dim Y × dim X`.
    #[error("block {block} is {rows}×{cols}: {msg}")]
    Shape {
        /// Offending block (or the number of blocks when widths do not add up).
        block: usize,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
        /// What was expected.
        msg: String,
    },
    /// An analytic entry is NaN or infinite.
    #[error("analytic block {block} entry ({row}, {col}) is not finite")]
    NonFiniteAnalytic {
        /// Block.
        block: usize,
        /// Row.
        row: usize,
        /// Column within the block.
        col: usize,
    },
    /// Numeric differentiation failed.
    #[error(transparent)]
    NumDiff(#[from] NumDiffError),
}

/// Copies any nalgebra matrix (fixed or dynamic, owned or a view) into a `DMatrix`.
pub fn to_dmatrix<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
    m: &Matrix<f64, R, C, S>,
) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// Compares the analytic Jacobian blocks of `f` at `x` with Ridders' numeric Jacobian.
///
/// `blocks[b]` is `∂f/∂x_b` (`dim Y × dim x_b`) w.r.t. the right-perturbation tangent of
/// component `b` of `x`; the widths must add up to `dim X`. Returns the report of the worst
/// entry, or [`CheckError::Mismatch`] when its relative error exceeds `opts.tolerance`.
///
/// ```
/// use nalgebra::Vector3;
/// use preint_calib::{CheckOptions, check_jacobian, to_dmatrix};
/// use preint_lie::{SO3, hat};
///
/// // f(R, t) = R·v + t on SO3 × R³: ∂f/∂δR = −R [v]×, ∂f/∂t = I.
/// let v = Vector3::new(1.0, -2.0, 0.5);
/// let x = (SO3::exp(&Vector3::new(0.1, 0.2, -0.3)), Vector3::new(1.0, 2.0, 3.0));
/// let f = |x: &(SO3, Vector3<f64>)| x.0.act(&v) + x.1;
/// let d_rot = -x.0.matrix() * hat(&v);
/// let blocks = [to_dmatrix(&d_rot), to_dmatrix(&nalgebra::Matrix3::<f64>::identity())];
/// let report = check_jacobian(f, &x, &blocks, &CheckOptions::default()).unwrap();
/// assert!(report.worst_rel_error < 1e-8);
/// ```
pub fn check_jacobian<X: Manifold, Y: Manifold>(
    f: impl Fn(&X) -> Y,
    x: &X,
    blocks: &[DMatrix<f64>],
    opts: &CheckOptions,
) -> Result<CheckReport, CheckError> {
    check_shapes(blocks, f(x).dim(), x.dim())?;
    let num = ridders(f, x, &opts.numdiff)?;
    let report = worst_entry(blocks, num.jacobian, &num.error, opts);
    if report.worst_rel_error > opts.tolerance {
        return Err(CheckError::Mismatch {
            tolerance: opts.tolerance,
            report: Box::new(report),
        });
    }
    Ok(report)
}

/// Block widths adding up to `n = dim X`, `m = dim Y` rows each, finite entries.
fn check_shapes(blocks: &[DMatrix<f64>], m: usize, n: usize) -> Result<(), CheckError> {
    let total: usize = blocks.iter().map(|b| b.ncols()).sum();
    if total != n || blocks.is_empty() {
        return Err(CheckError::Shape {
            block: blocks.len(),
            rows: m,
            cols: total,
            msg: format!("block widths add up to {total}, the input tangent has dimension {n}"),
        });
    }
    for (b, blk) in blocks.iter().enumerate() {
        if blk.nrows() != m {
            return Err(CheckError::Shape {
                block: b,
                rows: blk.nrows(),
                cols: blk.ncols(),
                msg: format!("expected {m} rows (output tangent dimension)"),
            });
        }
        if let Some(k) = blk.iter().position(|v| !v.is_finite()) {
            return Err(CheckError::NonFiniteAnalytic {
                block: b,
                row: k % m,
                col: k / m,
            });
        }
    }
    Ok(())
}

/// The entry of the largest relative error (module docs) of `blocks` against the numeric
/// Jacobian `numeric` with per-column error estimates `error`.
fn worst_entry(
    blocks: &[DMatrix<f64>],
    numeric: DMatrix<f64>,
    error: &DVector<f64>,
    opts: &CheckOptions,
) -> CheckReport {
    let m = numeric.nrows();
    let mut report = CheckReport {
        worst_rel_error: -1.0,
        block: 0,
        row: 0,
        col: 0,
        analytic: 0.0,
        numeric: 0.0,
        numeric_error_estimate: 0.0,
        numeric_jacobian: DMatrix::zeros(0, 0),
    };
    let mut c0 = 0;
    for (b, blk) in blocks.iter().enumerate() {
        let w = blk.ncols();
        let nb = numeric.columns(c0, w);
        let floor = (opts.floor_rel * nb.amax()).max(opts.floor_abs);
        for c in 0..w {
            for r in 0..m {
                let a = blk[(r, c)];
                let v = nb[(r, c)];
                let e = (a - v).abs() / a.abs().max(v.abs()).max(floor);
                if e > report.worst_rel_error {
                    report.worst_rel_error = e;
                    report.block = b;
                    report.row = r;
                    report.col = c;
                    report.analytic = a;
                    report.numeric = v;
                    report.numeric_error_estimate = error[c0 + c];
                }
            }
        }
        c0 += w;
    }
    report.worst_rel_error = report.worst_rel_error.max(0.0);
    report.numeric_jacobian = numeric;
    report
}
