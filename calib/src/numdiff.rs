//! Numeric differentiation of functions between manifolds, with the semantics of Ceres'
//! `NumericDiffCostFunction` (methods `FORWARD`, `CENTRAL`, `RIDDERS`, defaults of
//! `NumericDiffOptions`).
//!
//! For `f: X → Y`, column `j` of the Jacobian is the derivative of `f(x ⊕ h e_j) ⊖ f(x)`
//! at `h = 0`: the input is perturbed through [`Manifold::retract`] (right perturbation
//! `X·Exp(h e_j)` for Lie groups) and the output is differenced through [`Manifold::local`]
//! taken at `f(x)`. The result is a `dim Y × dim X` matrix in the tangent coordinates of the
//! [`preint_lie`] conventions (right perturbations on both sides).
//!
//! # Step sizes
//! Ceres uses `h_j = max(relative_step·|x_j|, min_step)`. A tangent coordinate of a Lie group
//! has no magnitude (the perturbation is taken at the identity of the tangent space), so
//! `|x_j|` is taken from [`NumDiffOptions::magnitudes`] when given (set it for vector
//! parameters whose entries are far from 1) and is 0 otherwise, so that the step is the
//! absolute floor [`NumDiffOptions::min_step`] (Ceres: `√ε ≈ 1.49e-8`).
//! For Ridders the base step is `max(ridders_relative_initial_step·|x_j|,
//! ridders_min_initial_step)` (Ceres: `max(√ε, 1e-2)`) and, as in Ceres, the tableau starts at
//! `base·shrink^(max_extrapolations/2)` (0.32 with the defaults) and shrinks by `shrink` per
//! row. Functions with a branch cut close to `x` (e.g. `Log` at θ = π − 1e-3) need a base step
//! below the distance to the cut.

use nalgebra::{DMatrix, DVector};
use preint_lie::Manifold;

/// Differencing scheme (Ceres `NumericDiffMethodType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// `(f(x⊕h) ⊖ f(x)) / h`: error O(h), one extra evaluation per column.
    Forward,
    /// `(f(x⊕h) ⊖ f(x) − (f(x⊕−h) ⊖ f(x))) / 2h`: error O(h²), two evaluations per column.
    Central,
    /// Central differences at geometrically shrinking steps, extrapolated to h → 0 by
    /// Richardson's method (Ridders 1982; Press et al., *Numerical Recipes* §5.7 `dfridr`).
    Ridders,
}

/// Options, with the defaults of Ceres' `NumericDiffOptions`.
#[derive(Clone, Debug, PartialEq)]
pub struct NumDiffOptions {
    /// Relative step for forward/central differences (Ceres `relative_step_size`, 1e-6).
    pub relative_step: f64,
    /// Absolute floor of the forward/central step, in tangent units (Ceres: `√ε`).
    pub min_step: f64,
    /// Relative base step for Ridders (Ceres `ridders_relative_initial_step_size`, 1e-2).
    pub ridders_relative_initial_step: f64,
    /// Absolute floor of the Ridders base step, in tangent units (Ceres: `max(√ε, 1e-2)`).
    pub ridders_min_initial_step: f64,
    /// Step shrink factor between tableau rows (Ceres `ridders_step_shrink_factor`, 2).
    pub ridders_shrink: f64,
    /// Maximum number of tableau rows (Ceres `max_num_ridders_extrapolations`, 10).
    pub ridders_max_extrapolations: usize,
    /// Stop once the Ridders error estimate (2-norm of a column) is below this (Ceres
    /// `ridders_epsilon`, 1e-12).
    pub ridders_epsilon: f64,
    /// Optional magnitudes `|x_j|` per tangent coordinate, used by the relative steps (see the
    /// module docs). `None`: all zero, i.e. absolute steps.
    pub magnitudes: Option<Vec<f64>>,
}

impl Default for NumDiffOptions {
    fn default() -> Self {
        Self {
            relative_step: 1e-6,
            min_step: f64::EPSILON.sqrt(),
            ridders_relative_initial_step: 1e-2,
            ridders_min_initial_step: 1e-2,
            ridders_shrink: 2.0,
            ridders_max_extrapolations: 10,
            ridders_epsilon: 1e-12,
            magnitudes: None,
        }
    }
}

impl NumDiffOptions {
    /// Defaults with a different Ridders base step `h` [tangent units] (both the relative and
    /// the absolute one), e.g. `1e-5` next to a branch cut.
    pub fn with_ridders_step(h: f64) -> Self {
        Self {
            ridders_relative_initial_step: h,
            ridders_min_initial_step: h,
            ..Self::default()
        }
    }
}

/// Errors of numeric differentiation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NumDiffError {
    /// The function returned a value whose tangent dimension differs from `f(x)`'s.
    #[error("f(x ⊕ δ) has tangent dimension {got}, f(x) has {expected} (column {column})")]
    OutputDimension {
        /// Dimension of `f(x)`.
        expected: usize,
        /// Dimension of the perturbed output.
        got: usize,
        /// Perturbed column.
        column: usize,
    },
    /// A difference was NaN or infinite.
    #[error("non-finite difference in Jacobian column {column} (step {step:e})")]
    NonFinite {
        /// Perturbed column.
        column: usize,
        /// Step used.
        step: f64,
    },
    /// An option is out of its domain.
    #[error("invalid numeric-differentiation option: {0}")]
    InvalidOption(&'static str),
    /// `magnitudes` has the wrong length.
    #[error("magnitudes has {got} entries, the input tangent has {expected}")]
    MagnitudesLength {
        /// `dim X`.
        expected: usize,
        /// Given length.
        got: usize,
    },
}

/// A Ridders Jacobian and its per-column error estimates.
#[derive(Clone, Debug, PartialEq)]
pub struct RiddersJacobian {
    /// `dim Y × dim X` Jacobian.
    pub jacobian: DMatrix<f64>,
    /// Ridders' error estimate per column (2-norm over the column's entries): the larger
    /// difference between the chosen extrapolant and its two parents in the tableau.
    pub error: DVector<f64>,
}

/// Checks the options' domains and the length of `magnitudes` against `dim X = n`.
fn validate(opts: &NumDiffOptions, n: usize) -> Result<(), NumDiffError> {
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    let pos = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(opts.relative_step) && pos(opts.min_step)) {
        return Err(NumDiffError::InvalidOption(
            "relative_step must be ≥ 0 and min_step > 0",
        ));
    }
    if !(ok(opts.ridders_relative_initial_step) && pos(opts.ridders_min_initial_step)) {
        return Err(NumDiffError::InvalidOption(
            "ridders_relative_initial_step must be ≥ 0 and ridders_min_initial_step > 0",
        ));
    }
    if !(opts.ridders_shrink.is_finite() && opts.ridders_shrink > 1.0) {
        return Err(NumDiffError::InvalidOption("ridders_shrink must be > 1"));
    }
    if opts.ridders_max_extrapolations == 0 {
        return Err(NumDiffError::InvalidOption(
            "ridders_max_extrapolations must be ≥ 1",
        ));
    }
    if let Some(m) = &opts.magnitudes
        && m.len() != n
    {
        return Err(NumDiffError::MagnitudesLength {
            expected: n,
            got: m.len(),
        });
    }
    Ok(())
}

/// `|x_j|` for the relative steps (0 without [`NumDiffOptions::magnitudes`]).
fn magnitude(opts: &NumDiffOptions, j: usize) -> f64 {
    opts.magnitudes.as_ref().map_or(0.0, |m| m[j].abs())
}

/// Evaluates `f(x ⊕ h e_j) ⊖ y0` into `out` (`delta` is scratch of length dim X).
fn perturbed<X: Manifold, Y: Manifold>(
    f: &impl Fn(&X) -> Y,
    x: &X,
    y0: &Y,
    j: usize,
    h: f64,
    delta: &mut [f64],
    out: &mut [f64],
) -> Result<(), NumDiffError> {
    delta.fill(0.0);
    delta[j] = h;
    let y = f(&x.retract(delta));
    let m = y.dim();
    if m != out.len() {
        return Err(NumDiffError::OutputDimension {
            expected: out.len(),
            got: m,
            column: j,
        });
    }
    y0.local(&y, out);
    Ok(())
}

/// One difference quotient for column `j` at step `h` (forward or central).
#[allow(clippy::too_many_arguments)]
fn column<X: Manifold, Y: Manifold>(
    f: &impl Fn(&X) -> Y,
    x: &X,
    y0: &Y,
    j: usize,
    h: f64,
    central: bool,
    delta: &mut [f64],
    out: &mut DVector<f64>,
) -> Result<(), NumDiffError> {
    let m = out.len();
    perturbed(f, x, y0, j, h, delta, out.as_mut_slice())?;
    if central {
        let mut back = DVector::zeros(m);
        perturbed(f, x, y0, j, -h, delta, back.as_mut_slice())?;
        *out -= back;
        *out /= 2.0 * h;
    } else {
        *out /= h;
    }
    if out.iter().any(|v| !v.is_finite()) {
        return Err(NumDiffError::NonFinite { column: j, step: h });
    }
    Ok(())
}

/// Jacobian of `f` at `x` by forward or central differences (Ceres `FORWARD` / `CENTRAL`).
///
/// Step per column: `h_j = max(relative_step·|x_j|, min_step)` (see the module docs).
/// For [`Method::Ridders`] this calls [`ridders`] and drops the error estimate.
///
/// ```
/// use nalgebra::{DMatrix, Vector3};
/// use preint_calib::numdiff::{Method, NumDiffOptions, jacobian, ridders};
/// use preint_lie::{SO3, hat};
///
/// // f(R) = R·v: with R ← R·Exp(δ), ∂f/∂δ = −R [v]×.
/// let r = SO3::exp(&Vector3::new(0.3, -0.2, 0.5));
/// let v = Vector3::new(1.0, 2.0, 3.0);
/// let f = |r: &SO3| r.act(&v);
/// let exact = DMatrix::from_column_slice(3, 3, (-r.matrix() * hat(&v)).as_slice());
/// let central = jacobian(f, &r, Method::Central, &NumDiffOptions::default()).unwrap();
/// assert!((central - &exact).amax() < 1e-7);
/// let rid = ridders(f, &r, &NumDiffOptions::default()).unwrap();
/// assert!((rid.jacobian - exact).amax() < 1e-10);
/// ```
pub fn jacobian<X: Manifold, Y: Manifold>(
    f: impl Fn(&X) -> Y,
    x: &X,
    method: Method,
    opts: &NumDiffOptions,
) -> Result<DMatrix<f64>, NumDiffError> {
    if method == Method::Ridders {
        return ridders(f, x, opts).map(|r| r.jacobian);
    }
    let n = x.dim();
    validate(opts, n)?;
    let y0 = f(x);
    let m = y0.dim();
    let mut jac = DMatrix::zeros(m, n);
    let mut delta = vec![0.0; n];
    let mut col = DVector::zeros(m);
    for j in 0..n {
        let h = (opts.relative_step * magnitude(opts, j)).max(opts.min_step);
        column(
            &f,
            x,
            &y0,
            j,
            h,
            method == Method::Central,
            &mut delta,
            &mut col,
        )?;
        jac.set_column(j, &col);
    }
    Ok(jac)
}

/// Jacobian of `f` at `x` by Ridders' method with Richardson extrapolation, following Ceres'
/// `EvaluateRiddersJacobianColumn`: row `i` of the tableau holds the central difference at
/// `h_i = h₀/s^i` and its extrapolations `D_{i,k} = (s^{2k} D_{i,k−1} − D_{i−1,k−1}) /
/// (s^{2k} − 1)`; the candidate with the smallest `max(‖D_{i,k} − D_{i,k−1}‖,
/// ‖D_{i,k} − D_{i−1,k−1}‖)` is kept; the loop stops when that error is below
/// `ridders_epsilon`, or when the newest lowest-order entry drifts from the previous row by
/// more than twice the best error (round-off takes over).
pub fn ridders<X: Manifold, Y: Manifold>(
    f: impl Fn(&X) -> Y,
    x: &X,
    opts: &NumDiffOptions,
) -> Result<RiddersJacobian, NumDiffError> {
    let n = x.dim();
    validate(opts, n)?;
    let y0 = f(x);
    let m = y0.dim();
    let mut jac = DMatrix::zeros(m, n);
    let mut err = DVector::zeros(n);
    let mut delta = vec![0.0; n];
    for j in 0..n {
        let (col, e) = ridders_column(&f, x, &y0, j, opts, &mut delta)?;
        jac.set_column(j, &col);
        err[j] = e;
    }
    Ok(RiddersJacobian {
        jacobian: jac,
        error: err,
    })
}

/// Column `j` of the Ridders Jacobian and its error estimate (see [`ridders`]).
fn ridders_column<X: Manifold, Y: Manifold>(
    f: &impl Fn(&X) -> Y,
    x: &X,
    y0: &Y,
    j: usize,
    opts: &NumDiffOptions,
    delta: &mut [f64],
) -> Result<(DVector<f64>, f64), NumDiffError> {
    let m = y0.dim();
    let rows = opts.ridders_max_extrapolations;
    let s = opts.ridders_shrink;
    let base = (opts.ridders_relative_initial_step * magnitude(opts, j))
        .max(opts.ridders_min_initial_step);
    let mut h = base * s.powi((rows / 2) as i32);
    let mut prev: Vec<DVector<f64>> = Vec::with_capacity(rows);
    let mut best = DVector::zeros(m);
    let mut best_err = f64::MAX;
    for i in 0..rows {
        let mut cur: Vec<DVector<f64>> = Vec::with_capacity(i + 1);
        let mut d0 = DVector::zeros(m);
        column(f, x, y0, j, h, true, delta, &mut d0)?;
        if i == 0 {
            best = d0.clone();
        }
        cur.push(d0);
        h /= s;
        let mut fac = s * s;
        for k in 1..=i {
            let cand = (&cur[k - 1] * fac - &prev[k - 1]) / (fac - 1.0);
            fac *= s * s;
            let e = (&cand - &cur[k - 1])
                .norm()
                .max((&cand - &prev[k - 1]).norm());
            let done = e <= best_err;
            if done {
                best_err = e;
                best = cand.clone();
            }
            cur.push(cand);
            if done && best_err < opts.ridders_epsilon {
                break;
            }
        }
        if best_err < opts.ridders_epsilon {
            break;
        }
        if i > 0 && (&cur[i] - &prev[i - 1]).norm() >= 2.0 * best_err {
            break;
        }
        prev = cur;
    }
    Ok((best, best_err))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};
    use preint_lie::SO3;

    fn poly(x: &Vector2<f64>) -> Vector3<f64> {
        Vector3::new(x[0] * x[0] * x[1], x[0].sin(), (x[1]).exp())
    }
    fn poly_jac(x: &Vector2<f64>) -> DMatrix<f64> {
        DMatrix::from_row_slice(
            3,
            2,
            &[
                2.0 * x[0] * x[1],
                x[0] * x[0],
                x[0].cos(),
                0.0,
                0.0,
                x[1].exp(),
            ],
        )
    }

    #[test]
    fn methods_reach_their_expected_accuracy_on_vectors() {
        let x = Vector2::new(0.7, -1.3);
        let exact = poly_jac(&x);
        let o = NumDiffOptions::default();
        let fw = jacobian(poly, &x, Method::Forward, &o).unwrap();
        let ce = jacobian(poly, &x, Method::Central, &o).unwrap();
        let ri = ridders(poly, &x, &o).unwrap();
        let e = |a: &DMatrix<f64>| (a - &exact).amax();
        // Forward with h ≈ 1.5e-8: truncation ~h, round-off ~ε/h ≈ 1.5e-8.
        assert!(e(&fw) < 1e-6 && e(&fw) > 1e-12, "forward {}", e(&fw));
        assert!(e(&ce) < 1e-7, "central {}", e(&ce));
        assert!(e(&ri.jacobian) < 1e-11, "ridders {}", e(&ri.jacobian));
        // The estimate bounds the true error up to a small factor.
        for j in 0..2 {
            let true_err = (ri.jacobian.column(j) - exact.column(j)).norm();
            assert!(true_err <= 10.0 * ri.error[j] + 1e-13, "col {j}");
        }
    }

    #[test]
    fn relative_steps_use_magnitudes() {
        // f(x) = x², at x = 1e6 an absolute 1.5e-8 step loses everything to round-off
        // (f ≈ 1e12, ulp ≈ 1.2e-4); a relative step keeps ~8 digits.
        let f = |x: &f64| x * x;
        let x = 1e6;
        let abs = jacobian(f, &x, Method::Central, &NumDiffOptions::default()).unwrap();
        let rel = jacobian(
            f,
            &x,
            Method::Central,
            &NumDiffOptions {
                magnitudes: Some(vec![x]),
                ..NumDiffOptions::default()
            },
        )
        .unwrap();
        assert!(((rel[(0, 0)] - 2e6) / 2e6).abs() < 1e-8);
        assert!(((abs[(0, 0)] - 2e6) / 2e6).abs() > 1e-6);
    }

    #[test]
    fn differentiates_through_manifold_retract_and_local() {
        // f(R) = R·R: right perturbation gives d(RR)/dR = Rᵀ + I (compose Jacobians summed).
        let r = SO3::exp(&Vector3::new(0.3, -0.2, 0.5));
        let j = ridders(|a: &SO3| a.compose(a), &r, &NumDiffOptions::default()).unwrap();
        let expected = r.matrix().transpose() + nalgebra::Matrix3::identity();
        let diff = (j.jacobian - DMatrix::from_column_slice(3, 3, expected.as_slice())).amax();
        assert!(diff < 1e-10, "{diff}");
    }

    #[test]
    fn bad_inputs_give_typed_errors() {
        let x = Vector2::new(1.0, 2.0);
        let bad = NumDiffOptions {
            ridders_shrink: 1.0,
            ..NumDiffOptions::default()
        };
        assert!(matches!(
            ridders(poly, &x, &bad),
            Err(NumDiffError::InvalidOption(_))
        ));
        let wrong_len = NumDiffOptions {
            magnitudes: Some(vec![1.0]),
            ..NumDiffOptions::default()
        };
        assert_eq!(
            jacobian(poly, &x, Method::Forward, &wrong_len),
            Err(NumDiffError::MagnitudesLength {
                expected: 2,
                got: 1
            })
        );
        let nan = |x: &f64| if *x == 1.0 { 0.0 } else { f64::NAN };
        assert!(matches!(
            jacobian(nan, &1.0, Method::Central, &NumDiffOptions::default()),
            Err(NumDiffError::NonFinite { column: 0, .. })
        ));
        let grow = |x: &f64| DVector::from_element(if *x == 1.0 { 2 } else { 3 }, *x);
        assert!(matches!(
            jacobian(grow, &1.0, Method::Forward, &NumDiffOptions::default()),
            Err(NumDiffError::OutputDimension {
                expected: 2,
                got: 3,
                column: 0
            })
        ));
    }
}
