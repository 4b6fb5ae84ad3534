//! Small dense Gauss-Newton / Levenberg-Marquardt on manifolds, run by argmin's [`Executor`].
//!
//! # Problem
//! Minimise `F(x) = ½‖r(x)‖²` over `x ∈ X`, `X: Manifold` (products of `SO3`, vectors, …).
//! A [`LeastSquares`] problem returns the residual `r(x)` (m) and its Jacobian
//! `J = ∂r(x ⊕ δ)/∂δ |_{δ=0}` (m × n) w.r.t. the **right-perturbation tangent** of the `lie`
//! conventions. Residuals are expected to be **whitened** (divided by their standard deviation,
//! or multiplied by a square-root information), so that `JᵀJ` is the Fisher information and its
//! inverse the covariance of the estimate's tangent error.
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
//! Levenberg-Marquardt (Nielsen's update, Madsen–Nielsen–Tingleff 2004 §3.2): gain ratio
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
//! argmin provides the [`Executor`] loop, [`IterState`] bookkeeping (current/previous/best
//! parameter and cost, iteration counter, function counts, timing), max-iteration / target-cost
//! / timeout termination, observers (e.g. logging each iteration with the key/values `mu`,
//! `rho`, `step_norm`, `rank`, `accepted`, `cholesky` emitted here) and checkpointing. Everything numerical (the
//! manifold retraction, normal equations, rank analysis, damping, convergence tests,
//! covariance) is written here, on nalgebra: argmin's own Gauss-Newton works on vector spaces
//! (`x ← x − (JᵀJ)⁻¹Jᵀr` through argmin-math traits) and has no retraction or rank handling.

use crate::numdiff::{Method, NumDiffError, NumDiffOptions, jacobian};
use argmin::core::{
    Executor, IterState, KV, OptimizationResult, Problem, Solver, State, TerminationReason,
    TerminationStatus,
};
use nalgebra::{Cholesky, DMatrix, DVector, Dyn, SymmetricEigen};
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

/// The solver; implements argmin's [`Solver`]. Fields are the options (defaults in
/// [`GaussNewton::default`]); internal damping state is private.
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

/// Observability analysis of `H = JᵀJ`.
#[derive(Clone, Debug)]
struct Spectrum {
    obs: DMatrix<f64>,
    obs_eig: DVector<f64>,
    unobs: DMatrix<f64>,
}

fn spectrum(h: &DMatrix<f64>, rel: f64) -> Spectrum {
    let n = h.nrows();
    let eig = SymmetricEigen::new(h.clone());
    let lmax = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let thr = rel * lmax;
    let mut obs = Vec::new();
    let mut unobs = Vec::new();
    for i in 0..n {
        if lmax > 0.0 && eig.eigenvalues[i] > thr {
            obs.push(i);
        } else {
            unobs.push(i);
        }
    }
    let cols = |idx: &[usize]| DMatrix::from_fn(n, idx.len(), |r, c| eig.eigenvectors[(r, idx[c])]);
    Spectrum {
        obs: cols(&obs),
        obs_eig: DVector::from_iterator(obs.len(), obs.iter().map(|&i| eig.eigenvalues[i])),
        unobs: canonical_basis(cols(&unobs)),
    }
}

/// Makes the sign of each basis vector deterministic (largest-magnitude entry positive).
fn canonical_basis(mut b: DMatrix<f64>) -> DMatrix<f64> {
    for mut c in b.column_iter_mut() {
        let k = c.iamax();
        if c[k] < 0.0 {
            c.neg_mut();
        }
    }
    b
}

/// Safety factor of the Cholesky rank test (module docs): the system is treated as well
/// conditioned when the estimated `λ_min > RANK_TEST_SAFETY·rank_threshold·λ_max`.
const RANK_TEST_SAFETY: f64 = 100.0;
/// Power / inverse iterations of the rank test.
const RANK_TEST_ITERS: usize = 30;

/// A fixed pseudo-random unit vector (splitmix64 hash of the index): a start vector with no
/// structure, so that it is not orthogonal to the eigenvectors the test looks for.
fn start_vector(n: usize) -> DVector<f64> {
    let v = DVector::from_fn(n, |i, _| {
        let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let nrm = v.norm();
    v / nrm
}

/// Estimates `(λ_min, λ_max)` of the SPD matrix `h` with Cholesky factor `ch`: inverse
/// iteration (`λ_min` estimate ≥ the true value) and power iteration (≤ the true value, at
/// least `max diag`).
fn extreme_eigenvalues(h: &DMatrix<f64>, ch: &Cholesky<f64, Dyn>) -> (f64, f64) {
    let n = h.nrows();
    let mut v = start_vector(n);
    let mut lmax = h.diagonal().max();
    for _ in 0..RANK_TEST_ITERS {
        let w = h * &v;
        let nw = w.norm();
        if !(nw.is_finite() && nw > 0.0) {
            break;
        }
        lmax = lmax.max(nw);
        v = w / nw;
    }
    let mut v = start_vector(n);
    let mut lmin = f64::INFINITY;
    for _ in 0..RANK_TEST_ITERS {
        let w = ch.solve(&v);
        let nw = w.norm();
        if !(nw.is_finite() && nw > 0.0) {
            return (0.0, lmax);
        }
        lmin = 1.0 / nw;
        v = w / nw;
    }
    (lmin, lmax)
}

/// Factorisation of the normal equations `H = JᵀJ` (module docs, step 1).
enum Normal {
    /// Well conditioned: `H = LLᵀ`.
    Full(Cholesky<f64, Dyn>),
    /// Cholesky failed or the rank test flagged a deficiency: eigen-decomposition.
    Deficient(Spectrum),
}

impl Normal {
    fn of(h: &DMatrix<f64>, rel: f64) -> Self {
        let n = h.nrows();
        if n > 0
            && let Some(ch) = h.clone().cholesky()
        {
            let (lmin, lmax) = extreme_eigenvalues(h, &ch);
            if lmax.is_finite() && lmin > RANK_TEST_SAFETY * rel * lmax {
                return Normal::Full(ch);
            }
        }
        Normal::Deficient(spectrum(h, rel))
    }

    fn rank(&self, n: usize) -> usize {
        match self {
            Normal::Full(_) => n,
            Normal::Deficient(sp) => sp.obs.ncols(),
        }
    }

    /// The undamped Gauss-Newton step `−H⁺g`.
    fn gn_step(&self, g: &DVector<f64>) -> DVector<f64> {
        match self {
            Normal::Full(ch) => -ch.solve(g),
            Normal::Deficient(sp) => {
                let y = sp.obs.tr_mul(g).component_div(&sp.obs_eig);
                -(&sp.obs * y)
            }
        }
    }

    /// The damped step `−(H + μD)⁻¹g` (restricted to the observable subspace when deficient).
    fn damped_step(
        &self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        mu: f64,
        gn: &DVector<f64>,
    ) -> Result<DVector<f64>, GnError> {
        if mu == 0.0 {
            return Ok(gn.clone());
        }
        let n = h.nrows();
        let mut a = h.clone();
        for i in 0..n {
            a[(i, i)] += mu * h[(i, i)].clamp(1e-6, 1e32);
        }
        match self {
            Normal::Full(_) => match a.cholesky() {
                Some(ch) => Ok(-ch.solve(g)),
                None => Normal::Deficient(spectrum(h, 0.0)).damped_step(h, g, mu, gn),
            },
            Normal::Deficient(sp) => {
                if sp.obs.ncols() == 0 {
                    return Ok(DVector::zeros(n));
                }
                let ar = sp.obs.tr_mul(&(&a * &sp.obs));
                let ch = ar.cholesky().ok_or(GnError::Cholesky)?;
                Ok(-(&sp.obs * ch.solve(&sp.obs.tr_mul(g))))
            }
        }
    }
}

/// `JᵀJ` through a transposed copy, so that nalgebra uses its blocked matrix product
/// (`tr_mul` evaluates one dot product per entry, ≈ 20× slower for the 1000×400 Jacobians of
/// the known-pose problem); symmetrised exactly.
fn gram(j: &DMatrix<f64>) -> DMatrix<f64> {
    let h = j.transpose() * j;
    (&h + h.transpose()) * 0.5
}

fn evaluate<P: LeastSquares>(
    problem: &mut Problem<P>,
    x: &P::State,
) -> Result<(DVector<f64>, DMatrix<f64>), GnError> {
    let (r, j) = problem
        .problem("residual_jacobian", |p| Ok(p.residual_jacobian(x)))
        .map_err(|e| GnError::Argmin(e.to_string()))?;
    let n = x.dim();
    if j.nrows() != r.len() || j.ncols() != n {
        return Err(GnError::Shape {
            residuals: r.len(),
            rows: j.nrows(),
            cols: j.ncols(),
            dim: n,
        });
    }
    if r.iter().any(|v| !v.is_finite()) {
        return Err(GnError::NonFinite("residual"));
    }
    if j.iter().any(|v| !v.is_finite()) {
        return Err(GnError::NonFinite("Jacobian"));
    }
    Ok((r, j))
}

fn converged<X: Clone>(state: GnState<X>, s: &mut GaussNewton, why: StopReason) -> GnState<X> {
    s.reason = Some(why);
    state.terminate_with(TerminationReason::SolverConverged)
}

impl<P: LeastSquares> Solver<P, GnState<P::State>> for GaussNewton {
    fn name(&self) -> &str {
        match self.damping {
            Damping::None => "Gauss-Newton (manifold)",
            Damping::LevenbergMarquardt { .. } => "Levenberg-Marquardt (manifold)",
        }
    }

    fn init(
        &mut self,
        problem: &mut Problem<P>,
        mut state: GnState<P::State>,
    ) -> Result<(GnState<P::State>, Option<KV>), argmin::core::Error> {
        let opts_ok = [
            self.function_tolerance,
            self.step_tolerance,
            self.gradient_tolerance,
            self.rank_threshold,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0);
        if !opts_ok {
            return Err(GnError::InvalidOption("tolerances must be finite and ≥ 0").into());
        }
        self.mu = match self.damping {
            Damping::None => 0.0,
            Damping::LevenbergMarquardt { initial_mu } => {
                if !(initial_mu.is_finite() && initial_mu > 0.0) {
                    return Err(GnError::InvalidOption("initial_mu must be > 0").into());
                }
                initial_mu
            }
        };
        self.nu = 2.0;
        self.reason = None;
        let x = state.take_param().ok_or(GnError::NoInitialState)?;
        let (r, j) = evaluate(problem, &x)?;
        let g = j.tr_mul(&r);
        let h = gram(&j);
        let cost = 0.5 * r.norm_squared();
        let gnorm = g.amax();
        state = state
            .param(x)
            .cost(cost)
            .gradient(g)
            .hessian(h)
            .jacobian(j)
            .residuals(r);
        if gnorm <= self.gradient_tolerance {
            state = converged(state, self, StopReason::Gradient);
        }
        Ok((state, None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<P>,
        mut state: GnState<P::State>,
    ) -> Result<(GnState<P::State>, Option<KV>), argmin::core::Error> {
        let x = state.take_param().ok_or(GnError::NoInitialState)?;
        let g = state.take_gradient().ok_or(GnError::NoInitialState)?;
        let h = state.take_hessian().ok_or(GnError::NoInitialState)?;
        let cost = state.get_cost();
        let n = h.nrows();
        let normal = Normal::of(&h, self.rank_threshold);
        let k = normal.rank(n);
        let cholesky = matches!(normal, Normal::Full(_));

        // Convergence at x, judged with the undamped Gauss-Newton step (module docs, step 2).
        let gn = normal.gn_step(&g);
        let gn_decrease = -(g.dot(&gn) + 0.5 * gn.dot(&(&h * &gn)));
        if gn.norm() <= self.step_tolerance {
            let kv = argmin::kv!(
                "mu" => self.mu;
                "rho" => f64::NAN;
                "step_norm" => 0.0;
                "rank" => k as u64;
                "accepted" => false;
                "cholesky" => cholesky;
            );
            let st = state.param(x).cost(cost).gradient(g).hessian(h);
            return Ok((converged(st, self, StopReason::StepNorm), Some(kv)));
        }

        let delta = normal.damped_step(&h, &g, self.mu, &gn)?;
        let step_norm = delta.norm();
        let predicted = -(g.dot(&delta) + 0.5 * delta.dot(&(&h * &delta)));

        let x_new = x.retract(delta.as_slice());
        let lm = !matches!(self.damping, Damping::None);
        let mut rho = f64::NAN;
        let mut accepted = false;
        let mut new_eval = None;
        if lm {
            let r_new = problem
                .problem("residual", |p| Ok(p.residual(&x_new)))
                .map_err(|e| GnError::Argmin(e.to_string()))?;
            let cost_new = 0.5 * r_new.norm_squared();
            let m = state.get_residuals().map_or(r_new.len(), |r| r.len());
            if r_new.len() != m {
                return Err(GnError::Shape {
                    residuals: r_new.len(),
                    rows: m,
                    cols: n,
                    dim: n,
                }
                .into());
            }
            if cost_new.is_finite() {
                rho = (cost - cost_new) / predicted;
            }
            if rho > 0.0 {
                accepted = true;
                self.mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                self.nu = 2.0;
            } else {
                self.mu *= self.nu;
                self.nu *= 2.0;
            }
        } else {
            accepted = true;
        }
        if accepted {
            let (r, j) = evaluate(problem, &x_new)?;
            let cost_new = 0.5 * r.norm_squared();
            if !lm {
                rho = (cost - cost_new) / predicted;
            }
            new_eval = Some((r, j, cost_new));
        }
        let kv = argmin::kv!(
            "mu" => self.mu;
            "rho" => rho;
            "step_norm" => step_norm;
            "rank" => k as u64;
            "accepted" => accepted;
            "cholesky" => cholesky;
        );

        let mut state = match new_eval {
            Some((r, j, cost_new)) => {
                let g_new = j.tr_mul(&r);
                let h_new = gram(&j);
                let gnorm = g_new.amax();
                let st = state
                    .param(x_new)
                    .cost(cost_new)
                    .gradient(g_new)
                    .hessian(h_new)
                    .jacobian(j)
                    .residuals(r);
                if (cost - cost_new).abs() <= self.function_tolerance * cost {
                    converged(st, self, StopReason::CostChange)
                } else if gnorm <= self.gradient_tolerance {
                    converged(st, self, StopReason::Gradient)
                } else {
                    st
                }
            }
            None => {
                let st = state.param(x).cost(cost).gradient(g).hessian(h);
                // Rejected step: converged only if even the undamped Gauss-Newton step could
                // not lower the cost by more than the function tolerance (at the optimum,
                // round-off makes ρ ≤ 0); a tiny step caused by a large μ is not convergence.
                if gn_decrease <= self.function_tolerance * cost {
                    converged(st, self, StopReason::CostChange)
                } else {
                    st
                }
            }
        };
        if !state.terminated() && self.mu > 1e32 {
            self.reason = Some(StopReason::DampingExhausted);
            state = state.terminate_with(TerminationReason::SolverExit(
                "Levenberg-Marquardt damping exceeded 1e32".into(),
            ));
        }
        Ok((state, Some(kv)))
    }
}

/// Result of a solve.
#[derive(Clone, Debug)]
pub struct Solution<X> {
    /// Estimate (argmin's best parameter: lowest cost seen).
    pub estimate: X,
    /// Covariance of the tangent error at the estimate: `(JᵀJ)⁻¹`, or its pseudo-inverse
    /// `Σ_observable v vᵀ/λ` when some directions are unobservable (then it carries no
    /// information along [`Solution::unobservable`]).
    pub covariance: DMatrix<f64>,
    /// Orthonormal basis (columns, tangent coordinates) of the unobservable directions at the
    /// estimate: eigenvectors of `JᵀJ` with `λ ≤ rank_threshold·λ_max`. Empty (n×0) when all are
    /// observable.
    pub unobservable: DMatrix<f64>,
    /// Number of observable directions (rank of `JᵀJ` at the threshold).
    pub rank: usize,
    /// Iterations performed (argmin's counter).
    pub iterations: u64,
    /// Final cost `½‖r‖²` at the estimate.
    pub cost: f64,
    /// Number of residuals m.
    pub residual_count: usize,
    /// Why it stopped.
    pub stop: StopReason,
}

impl<X> Solution<X> {
    /// Standard deviations `√diag(covariance)` of the tangent coordinates; `+∞` for coordinates
    /// that have a component larger than 1e-6 along an unobservable direction.
    pub fn std_devs(&self) -> DVector<f64> {
        let n = self.covariance.nrows();
        DVector::from_fn(n, |i, _| {
            let leak = self.unobservable.row(i).amax();
            if self.unobservable.ncols() > 0 && leak > 1e-6 {
                f64::INFINITY
            } else {
                self.covariance[(i, i)].max(0.0).sqrt()
            }
        })
    }

    /// `2F/(m − rank)`: the residual variance factor (≈ 1 when the whitening is right); multiply
    /// the covariance by it when the residuals' scale was unknown.
    pub fn variance_factor(&self) -> f64 {
        let dof = self.residual_count as f64 - self.rank as f64;
        if dof > 0.0 {
            2.0 * self.cost / dof
        } else {
            f64::NAN
        }
    }
}

/// Turns an argmin result into a [`Solution`]: re-evaluates `J` at the best parameter,
/// computes the covariance and the unobservable basis. Use this after running the
/// [`Executor`] yourself (e.g. with observers).
pub fn finish<P: LeastSquares>(
    result: OptimizationResult<P, GaussNewton, GnState<P::State>>,
) -> Result<Solution<P::State>, GnError> {
    let OptimizationResult {
        mut problem,
        solver,
        mut state,
    } = result;
    let iterations = state.get_iter();
    let stop = match &state.termination_status {
        TerminationStatus::Terminated(TerminationReason::MaxItersReached) => StopReason::MaxIters,
        TerminationStatus::Terminated(TerminationReason::TargetCostReached) => {
            StopReason::TargetCost
        }
        TerminationStatus::Terminated(r) => solver
            .reason
            .clone()
            .unwrap_or_else(|| StopReason::Other(r.text().to_string())),
        TerminationStatus::NotTerminated => StopReason::Other("not terminated".into()),
    };
    let x = state
        .take_best_param()
        .or_else(|| state.take_param())
        .ok_or(GnError::NoInitialState)?;
    let (r, j) = evaluate(&mut problem, &x)?;
    let h = gram(&j);
    let n = h.nrows();
    let (covariance, unobservable, rank) = match Normal::of(&h, solver.rank_threshold) {
        Normal::Full(ch) => (ch.inverse(), DMatrix::zeros(n, 0), n),
        Normal::Deficient(sp) => {
            let inv = DVector::from_iterator(sp.obs_eig.len(), sp.obs_eig.iter().map(|l| 1.0 / l));
            let cov = &sp.obs * DMatrix::from_diagonal(&inv) * sp.obs.transpose();
            let rank = sp.obs.ncols();
            (cov, sp.unobs, rank)
        }
    };
    Ok(Solution {
        estimate: x,
        covariance,
        rank,
        unobservable,
        iterations,
        cost: 0.5 * r.norm_squared(),
        residual_count: r.len(),
        stop,
    })
}

/// Solves `problem` from `x0` with at most `max_iters` iterations:
/// `Executor::new(problem, solver).configure(|s| s.param(x0).max_iters(max_iters)).run()`,
/// then [`finish`].
pub fn solve<P: LeastSquares>(
    problem: P,
    x0: P::State,
    solver: GaussNewton,
    max_iters: u64,
) -> Result<Solution<P::State>, GnError> {
    let res = Executor::new(problem, solver)
        .configure(|s| s.param(x0).max_iters(max_iters))
        .run()
        .map_err(|e| match e.downcast::<GnError>() {
            Ok(g) => g,
            Err(e) => GnError::Argmin(e.to_string()),
        })?;
    finish(res)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(eigs: &[f64], seed: f64) -> DMatrix<f64> {
        let n = eigs.len();
        let a = DMatrix::from_fn(n, n, |i, j| ((i * n + j) as f64 * seed).sin());
        let q = a.qr().q();
        &q * DMatrix::from_diagonal(&DVector::from_column_slice(eigs)) * q.transpose()
    }

    /// The rank test's eigenvalue estimates against nalgebra's symmetric eigen-decomposition.
    #[test]
    fn extreme_eigenvalue_estimates_match_eigen_decomposition() {
        for eigs in [
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            vec![1e-6, 1e-3, 1.0, 10.0, 100.0, 1e4, 1e5, 1e6],
            vec![3.0, 3.0, 3.0, 3.0],
        ] {
            let h = spd(&eigs, 0.7);
            let ch = h.clone().cholesky().unwrap();
            let (lmin, lmax) = extreme_eigenvalues(&h, &ch);
            let e = SymmetricEigen::new(h.clone()).eigenvalues;
            let (tmin, tmax) = (e.min(), e.max());
            // Both sides carry round-off ≈ ε·λ_max in λ_min (1e-4 relative at cond 1e12).
            let tol = 1e-6 + 1e3 * f64::EPSILON * tmax / tmin;
            assert!(((lmin - tmin) / tmin).abs() < tol, "{lmin} vs {tmin}");
            assert!(((lmax - tmax) / tmax).abs() < 1e-6, "{lmax} vs {tmax}");
        }
    }

    /// Cholesky path for a well-conditioned matrix; eigen path when λ_min/λ_max is below
    /// 100·rank_threshold, or exactly singular; in both cases the covariance is right.
    #[test]
    fn rank_test_chooses_the_path() {
        let rel = 1e-10;
        let good = spd(&[1e-4, 1.0, 2.0, 50.0], 0.3);
        assert!(matches!(Normal::of(&good, rel), Normal::Full(_)));
        let near = spd(&[5e-9, 1.0, 2.0, 10.0], 0.3); // ratio 5e-10 < 100·1e-10 = 1e-8
        let Normal::Deficient(sp) = Normal::of(&near, rel) else {
            panic!("near-deficient matrix taken as well conditioned")
        };
        assert_eq!(sp.obs.ncols(), 4, "still above the rank threshold itself");
        let singular = spd(&[0.0, 1.0, 2.0, 10.0], 0.3);
        let Normal::Deficient(sp) = Normal::of(&singular, rel) else {
            panic!("singular matrix taken as well conditioned")
        };
        assert_eq!(sp.obs.ncols(), 3);
        // The undamped step agrees between the two paths on a full-rank system.
        let g = DVector::from_column_slice(&[1.0, -2.0, 0.5, 3.0]);
        let a = Normal::of(&good, rel).gn_step(&g);
        let b = Normal::Deficient(spectrum(&good, rel)).gn_step(&g);
        assert!((&a - &b).amax() < 1e-9 * a.amax(), "{a} vs {b}");
        let exact = -good.clone().try_inverse().unwrap() * &g;
        assert!((&a - &exact).amax() < 1e-9 * a.amax());
    }
}
