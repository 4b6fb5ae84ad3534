//! The result of a solve: estimate, covariance of its tangent error, unobservable directions;
//! and the entry points [`solve`] and [`finish`].

use super::iteration::evaluate;
use super::normal_equations::{Normal, gram};
use super::{GaussNewton, GnError, GnState, LeastSquares, StopReason};
use argmin::core::{Executor, OptimizationResult, State, TerminationReason, TerminationStatus};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

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

    /// The N×N block of [`Solution::covariance`] for the tangent coordinates
    /// `offset..offset + N` (e.g. one 3-vector or one attitude of the state). With unobservable
    /// directions it is the block of the pseudo-inverse: the marginal covariance of quantities
    /// that do not depend on them (see [`Solution::std_devs`] for a test).
    ///
    /// # Panics
    /// If `offset + N` exceeds the tangent dimension.
    pub fn marginal_covariance<const N: usize>(&self, offset: usize) -> SMatrix<f64, N, N> {
        self.covariance
            .fixed_view::<N, N>(offset, offset)
            .into_owned()
    }

    /// `√diag` of [`Solution::marginal_covariance`] (negative round-off clamped to 0).
    ///
    /// # Panics
    /// If `offset + N` exceeds the tangent dimension.
    pub fn marginal_std<const N: usize>(&self, offset: usize) -> SVector<f64, N> {
        SVector::from_fn(|i, _| self.covariance[(offset + i, offset + i)].max(0.0).sqrt())
    }

    /// `2F/(m − rank)`: the residual variance factor (≈ 1 when the whitening is right); multiply
    /// the covariance by it when the residuals' scale is unknown.
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
    let (covariance, unobservable, rank) = Normal::of(&h, solver.rank_threshold).covariance(n);
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
///
/// ```
/// use nalgebra::{DMatrix, DVector, Vector3};
/// use preint_calib::{GaussNewton, LeastSquares, solve};
/// use preint_lie::SO3;
///
/// // The rotation that maps three body vectors onto their world images, each observed with
/// // σ = 0.01 (whitened residuals r_k = (R b_k − w_k)/σ, Jacobian −R [b_k]× / σ).
/// struct Align {
///     body: Vec<Vector3<f64>>,
///     world: Vec<Vector3<f64>>,
/// }
/// impl LeastSquares for Align {
///     type State = SO3;
///     fn residual_jacobian(&self, r: &SO3) -> (DVector<f64>, DMatrix<f64>) {
///         let n = self.body.len();
///         let (mut res, mut jac) = (DVector::zeros(3 * n), DMatrix::zeros(3 * n, 3));
///         for (k, (b, w)) in self.body.iter().zip(&self.world).enumerate() {
///             res.fixed_rows_mut::<3>(3 * k).copy_from(&((r.act(b) - w) / 0.01));
///             let d = -r.matrix() * preint_lie::hat(b) / 0.01;
///             jac.fixed_view_mut::<3, 3>(3 * k, 0).copy_from(&d);
///         }
///         (res, jac)
///     }
/// }
///
/// let truth = SO3::exp(&Vector3::new(0.3, -0.2, 0.9));
/// let body = vec![Vector3::x(), Vector3::y(), Vector3::new(1.0, 1.0, 1.0)];
/// let world = body.iter().map(|b| truth.act(b)).collect();
/// let sol = solve(Align { body, world }, SO3::identity(), GaussNewton::default(), 50).unwrap();
/// assert!(sol.stop.converged());
/// assert!((sol.estimate.inverse().compose(&truth)).log().norm() < 1e-10);
/// assert_eq!(sol.rank, 3);
/// // Covariance of the rotation error, (JᵀJ)⁻¹ [rad²]: of order σ² = 1e-4.
/// assert!(sol.covariance.diagonal().max() < 1e-4);
/// ```
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
