//! Small dense Gauss-Newton / Levenberg-Marquardt on manifolds, run by argmin's
//! [`Executor`](argmin::core::Executor).
//!
//! # Problem
//! Minimise `F(x) = ½‖r(x)‖²` over `x ∈ X`, `X: Manifold` (products of `SO3`, vectors, …).
//! A [`LeastSquares`] problem returns the residual `r(x)` (m) and its Jacobian
//! `J = ∂r(x ⊕ δ)/∂δ |_{δ=0}` (m × n) w.r.t. the **right-perturbation tangent** of the
//! [`preint_lie`] conventions. Residuals are expected to be **whitened** (divided by their
//! standard deviation, or multiplied by a square-root information), so that `JᵀJ` is the Fisher
//! information and its inverse the covariance of the estimate's tangent error.
//!
//! # Iteration
//! With `H = JᵀJ`, `g = Jᵀr`:
//!
//! 1. **Factorisation and rank test.** `H` is factored by Cholesky, `H = LLᵀ`. The rank test
//!    estimates `λ_max(H)` by power iteration and `λ_min(H)` by inverse iteration through `L`
//!    (30 iterations each, O(n²) per iteration, from a fixed pseudo-random start vector); the
//!    system counts as well conditioned when `λ_min > 100·rank_threshold·λ_max` (the factor 100
//!    covers the estimates' error: inverse iteration over-estimates `λ_min` only while the start
//!    vector's components along the smallest eigenvectors have not yet dominated). Only when
//!    Cholesky fails or the test flags a (near) deficiency does the solver fall back to the
//!    symmetric eigen-decomposition `H = V Λ Vᵀ`, which splits the tangent into an observable
//!    part (eigenvalues `λ_i > rank_threshold·λ_max`) and an unobservable one.
//! 2. **Step-size test at x** with the undamped Gauss-Newton step `δ_GN = −H⁺g`:
//!    `‖δ_GN‖₂ ≤ step_tolerance`. It uses the *undamped* step, so a tiny step caused by a huge
//!    Levenberg-Marquardt damping is never mistaken for convergence.
//! 3. **Step.** Well conditioned: `(H + μD) δ = −g` by Cholesky (for `μ = 0` the factor of step
//!    1 is reused). Deficient: the damped normal equations restricted to the observable basis
//!    `V_o`, `V_oᵀ(H + μD)V_o y = −V_oᵀ g`, `δ = V_o y` (Cholesky again); with `μ = 0` this is the
//!    minimum-norm step `δ = −H⁺g`, so unobservable directions are left untouched instead of
//!    being driven by round-off. `D = diag(H)` clamped to `[1e-6, 1e32]` (Marquardt scaling,
//!    Ceres' `min_lm_diagonal` / `max_lm_diagonal`). Then `x ← x ⊕ δ`.
//!
//! Levenberg-Marquardt (Nielsen's update, Madsen, Nielsen, Tingleff, *Methods for Non-Linear
//! Least Squares Problems*, 2004, §3.2): gain ratio
//! `ρ = (F(x) − F(x⊕δ)) / (−gᵀδ − ½δᵀHδ)`; if `ρ > 0` the step is accepted and
//! `μ ← μ·max(⅓, 1 − (2ρ − 1)³)`, `ν ← 2`; otherwise `μ ← μν`, `ν ← 2ν` and `x` is kept.
//! Plain Gauss-Newton (`μ = 0`) accepts every step.
//!
//! # Termination (Ceres-like)
//! - `|F_old − F_new| ≤ function_tolerance·F_old` after an accepted step, or, after a rejected
//!   LM step, the undamped model decrease `½gᵀH⁺g ≤ function_tolerance·F` (round-off at the
//!   optimum makes ρ ≤ 0; [`StopReason::CostChange`]);
//! - `‖δ_GN‖₂ ≤ step_tolerance` for the undamped step at the current point (absolute, tangent
//!   units; [`StopReason::StepNorm`]);
//! - `‖g‖_∞ ≤ gradient_tolerance` (also checked at the start);
//! - argmin's `max_iters`, `target_cost`, timeout and Ctrl-C;
//! - LM only: `μ > 1e32` (no decreasing step can be found; [`StopReason::DampingExhausted`],
//!   which is **not** convergence).
//!
//! # What argmin does and what this module does
//! argmin provides the [`Executor`](argmin::core::Executor) loop, [`IterState`] bookkeeping
//! (current/previous/best parameter and cost, iteration counter, function counts, timing),
//! max-iteration / target-cost / timeout termination, observers (e.g. logging each iteration
//! with the key/values `mu`, `rho`, `step_norm`, `rank`, `accepted`, `cholesky` emitted here)
//! and checkpointing. Everything numerical (the manifold retraction, normal equations, rank
//! analysis, damping, convergence tests, covariance) is written here, on nalgebra: argmin's own
//! Gauss-Newton works on vector spaces (`x ← x − (JᵀJ)⁻¹Jᵀr` through argmin-math traits) and has
//! no retraction or rank handling.
//!
//! # Submodules
//! [`normal_equations`]: factorisation, rank test and steps; [`iteration`]: one iteration
//! (argmin's [`Solver`](argmin::core::Solver)), damping update and convergence tests;
//! [`solution`]: covariance, unobservable directions and the [`solve`] / [`finish`] entry points.

pub mod iteration;
pub mod normal_equations;
pub mod solution;

pub use solution::{Solution, finish, solve};

use crate::numdiff::{Method, NumDiffError, NumDiffOptions, jacobian};
use argmin::core::IterState;
use nalgebra::{DMatrix, DVector};
use preint_lie::Manifold;

/// A whitened nonlinear least-squares problem on a manifold (see the module docs).
pub trait LeastSquares {
    /// The estimated state.
    type State: Manifold;
    /// Residual `r(x)` (length m) and Jacobian `∂r(x ⊕ δ)/∂δ` (m × dim x) at `x`.
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>);
    /// Residual only (used for trial points of Levenberg-Marquardt); override when it is
    /// much cheaper than the Jacobian.
    fn residual(&self, x: &Self::State) -> DVector<f64> {
        self.residual_jacobian(x).0
    }
}

/// A [`LeastSquares`] problem from a residual function, its Jacobian by numeric
/// differentiation ([`crate::numdiff`], central differences by default). Handy for prototyping
/// and for checking an analytic problem.
pub struct NumericLeastSquares<X, F> {
    f: F,
    method: Method,
    options: NumDiffOptions,
    _x: std::marker::PhantomData<fn(&X)>,
}

impl<X: Manifold, F: Fn(&X) -> DVector<f64>> NumericLeastSquares<X, F> {
    /// Wraps the residual function `f` (central differences, default options).
    pub fn new(f: F) -> Self {
        Self {
            f,
            method: Method::Central,
            options: NumDiffOptions::default(),
            _x: std::marker::PhantomData,
        }
    }
    /// Chooses the differentiation method and options.
    pub fn with_method(mut self, method: Method, options: NumDiffOptions) -> Self {
        self.method = method;
        self.options = options;
        self
    }
}

impl<X: Manifold, F: Fn(&X) -> DVector<f64>> LeastSquares for NumericLeastSquares<X, F> {
    type State = X;
    fn residual_jacobian(&self, x: &X) -> (DVector<f64>, DMatrix<f64>) {
        let r = (self.f)(x);
        let j = match jacobian(&self.f, x, self.method, &self.options) {
            Ok(j) => j,
            // Non-finite or inconsistent residuals: a NaN Jacobian, which the solver reports
            // as a typed error.
            Err(_) => DMatrix::from_element(r.len(), x.dim(), f64::NAN),
        };
        (r, j)
    }
    fn residual(&self, x: &X) -> DVector<f64> {
        (self.f)(x)
    }
}

/// Errors of the solver.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GnError {
    /// No initial state was given to the executor.
    #[error("no initial state: call `configure(|s| s.param(x0))`")]
    NoInitialState,
    /// Residual or Jacobian has the wrong shape.
    #[error(
        "residual has {residuals} rows and the Jacobian is {rows}×{cols}; the state has dimension {dim}"
    )]
    Shape {
        /// Residual length.
        residuals: usize,
        /// Jacobian rows.
        rows: usize,
        /// Jacobian columns.
        cols: usize,
        /// State tangent dimension.
        dim: usize,
    },
    /// NaN or infinity in the residual or Jacobian at the current state.
    #[error("non-finite {0} at the current state")]
    NonFinite(&'static str),
    /// The reduced normal equations were not positive definite (should not happen).
    #[error("Cholesky factorisation of the reduced normal equations failed")]
    Cholesky,
    /// An option is out of its domain.
    #[error("invalid option: {0}")]
    InvalidOption(&'static str),
    /// Numeric differentiation failed.
    #[error(transparent)]
    NumDiff(#[from] NumDiffError),
    /// Any other error raised inside argmin (e.g. by an observer).
    #[error("argmin: {0}")]
    Argmin(String),
}

/// Why the solver stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// Relative cost decrease below `function_tolerance`.
    CostChange,
    /// Step norm below `step_tolerance`.
    StepNorm,
    /// Gradient max-norm below `gradient_tolerance`.
    Gradient,
    /// argmin's `max_iters` reached.
    MaxIters,
    /// LM damping exceeded 1e32 without finding a decreasing step.
    DampingExhausted,
    /// argmin's target cost reached.
    TargetCost,
    /// Timeout, interrupt or another argmin reason (its text).
    Other(String),
}

impl StopReason {
    /// `true` for the three convergence criteria.
    pub fn converged(&self) -> bool {
        matches!(
            self,
            StopReason::CostChange | StopReason::StepNorm | StopReason::Gradient
        )
    }
}

/// Damping mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Damping {
    /// Plain Gauss-Newton: every step accepted.
    None,
    /// Levenberg-Marquardt with initial `μ` (Ceres: 1/initial_trust_region_radius = 1e-4).
    LevenbergMarquardt {
        /// Initial damping μ₀ (dimensionless, multiplies `diag(JᵀJ)`).
        initial_mu: f64,
    },
}

/// The solver; implements argmin's [`Solver`](argmin::core::Solver). Fields are the options
/// (defaults in [`GaussNewton::default`]); internal damping state is private.
#[derive(Clone, Debug)]
pub struct GaussNewton {
    /// Damping mode (default: Levenberg-Marquardt with μ₀ = 1e-4).
    pub damping: Damping,
    /// Relative cost-change tolerance (default 1e-10; Ceres 1e-6).
    pub function_tolerance: f64,
    /// Absolute step-norm tolerance in tangent units (default 1e-12).
    pub step_tolerance: f64,
    /// Gradient max-norm tolerance (default 1e-12; Ceres 1e-10).
    pub gradient_tolerance: f64,
    /// Eigenvalues of `JᵀJ` below `rank_threshold·λ_max` are unobservable (default 1e-10, i.e.
    /// singular values of J below 1e-5 of the largest).
    pub rank_threshold: f64,
    mu: f64,
    nu: f64,
    reason: Option<StopReason>,
}

impl Default for GaussNewton {
    fn default() -> Self {
        Self {
            damping: Damping::LevenbergMarquardt { initial_mu: 1e-4 },
            function_tolerance: 1e-10,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-12,
            rank_threshold: 1e-10,
            mu: 0.0,
            nu: 2.0,
            reason: None,
        }
    }
}

impl GaussNewton {
    /// Levenberg-Marquardt with the defaults.
    pub fn levenberg_marquardt() -> Self {
        Self::default()
    }
    /// Plain (undamped) Gauss-Newton with the default tolerances.
    pub fn undamped() -> Self {
        Self {
            damping: Damping::None,
            ..Self::default()
        }
    }
    /// The reason recorded by the last run, if the solver itself stopped it.
    pub fn stop_reason(&self) -> Option<&StopReason> {
        self.reason.as_ref()
    }
}

/// argmin state used by [`GaussNewton`]: parameter `X`, gradient `Jᵀr`, Jacobian `J`,
/// Hessian approximation `JᵀJ`, residuals `r`, cost `½‖r‖²`.
pub type GnState<X> = IterState<X, DVector<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>, f64>;
