//! One Gauss-Newton / Levenberg-Marquardt iteration: argmin's [`Solver`] for [`GaussNewton`]
//! (module docs of [`super`], "Iteration" and "Termination").
//!
//! Each iteration factors the normal equations ([`super::normal_equations`]), tests the
//! undamped step for convergence, takes the damped step, and for Levenberg-Marquardt judges it
//! by the gain ratio `ρ = (F(x) − F(x⊕δ)) / (−gᵀδ − ½δᵀHδ)` with Nielsen's damping update
//! (Madsen, Nielsen, Tingleff 2004, §3.2): accepted (`ρ > 0`):
//! `μ ← μ·max(⅓, 1 − (2ρ − 1)³)`, `ν ← 2`; rejected: `μ ← μν`, `ν ← 2ν`.

use super::normal_equations::{Normal, gram};
use super::{Damping, GaussNewton, GnError, GnState, LeastSquares, StopReason};
use argmin::core::{KV, Problem, Solver, State, TerminationReason};
use nalgebra::{DMatrix, DVector};
use preint_lie::Manifold;

/// Residual, Jacobian and cost `½‖r‖²` at a point.
type Evaluation = (DVector<f64>, DMatrix<f64>, f64);

/// Evaluates `r` and `J` at `x` through argmin's [`Problem`] (which counts the evaluations) and
/// checks their shapes and finiteness.
pub(crate) fn evaluate<P: LeastSquares>(
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

/// Terminates `state` as converged for the reason `why`, recorded in the solver.
fn converged<X: Clone>(state: GnState<X>, s: &mut GaussNewton, why: StopReason) -> GnState<X> {
    s.reason = Some(why);
    state.terminate_with(TerminationReason::SolverConverged)
}

/// The key/values logged per iteration.
fn iteration_kv(
    mu: f64,
    rho: f64,
    step_norm: f64,
    rank: usize,
    accepted: bool,
    cholesky: bool,
) -> KV {
    argmin::kv!(
        "mu" => mu;
        "rho" => rho;
        "step_norm" => step_norm;
        "rank" => rank as u64;
        "accepted" => accepted;
        "cholesky" => cholesky;
    )
}

impl GaussNewton {
    /// Checks the options and resets the damping state for a new run.
    fn reset(&mut self) -> Result<(), GnError> {
        let opts_ok = [
            self.function_tolerance,
            self.step_tolerance,
            self.gradient_tolerance,
            self.rank_threshold,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0);
        if !opts_ok {
            return Err(GnError::InvalidOption("tolerances must be finite and ≥ 0"));
        }
        self.mu = match self.damping {
            Damping::None => 0.0,
            Damping::LevenbergMarquardt { initial_mu } => {
                if !(initial_mu.is_finite() && initial_mu > 0.0) {
                    return Err(GnError::InvalidOption("initial_mu must be > 0"));
                }
                initial_mu
            }
        };
        self.nu = 2.0;
        self.reason = None;
        Ok(())
    }

    /// Nielsen's damping update after a step with gain ratio `rho` (module docs).
    fn update_damping(&mut self, rho: f64) {
        if rho > 0.0 {
            self.mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            self.nu = 2.0;
        } else {
            self.mu *= self.nu;
            self.nu *= 2.0;
        }
    }

    /// Tries the step to `x_new` from a point of cost `cost` whose quadratic model predicts the
    /// decrease `predicted`: returns the gain ratio ρ and, if the step is accepted, the
    /// evaluation at `x_new`. Plain Gauss-Newton accepts every step; Levenberg-Marquardt first
    /// evaluates the residual alone and accepts when `ρ > 0`, updating the damping.
    fn trial<P: LeastSquares>(
        &mut self,
        problem: &mut Problem<P>,
        state: &GnState<P::State>,
        x_new: &P::State,
        cost: f64,
        predicted: f64,
    ) -> Result<(f64, Option<Evaluation>), GnError> {
        let eval_at = |problem: &mut Problem<P>| -> Result<Evaluation, GnError> {
            let (r, j) = evaluate(problem, x_new)?;
            let cost_new = 0.5 * r.norm_squared();
            Ok((r, j, cost_new))
        };
        if matches!(self.damping, Damping::None) {
            let eval = eval_at(problem)?;
            return Ok(((cost - eval.2) / predicted, Some(eval)));
        }
        let r_new = problem
            .problem("residual", |p| Ok(p.residual(x_new)))
            .map_err(|e| GnError::Argmin(e.to_string()))?;
        let m = state.get_residuals().map_or(r_new.len(), |r| r.len());
        if r_new.len() != m {
            let n = x_new.dim();
            return Err(GnError::Shape {
                residuals: r_new.len(),
                rows: m,
                cols: n,
                dim: n,
            });
        }
        let cost_new = 0.5 * r_new.norm_squared();
        let rho = if cost_new.is_finite() {
            (cost - cost_new) / predicted
        } else {
            f64::NAN
        };
        self.update_damping(rho);
        let eval = if rho > 0.0 {
            Some(eval_at(problem)?)
        } else {
            None
        };
        Ok((rho, eval))
    }

    /// The state after an accepted step to `x_new`, terminated when the relative cost change
    /// or the gradient is below its tolerance.
    fn accepted<X: Clone>(
        &mut self,
        state: GnState<X>,
        x_new: X,
        (r, j, cost_new): Evaluation,
        cost: f64,
    ) -> GnState<X> {
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
        self.reset()?;
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
        let normal = Normal::of(&h, self.rank_threshold);
        let rank = normal.rank(h.nrows());
        let cholesky = matches!(normal, Normal::Full(_));

        // Convergence at x, judged with the undamped Gauss-Newton step (module docs, step 2).
        let gn = normal.gn_step(&g);
        let gn_decrease = -(g.dot(&gn) + 0.5 * gn.dot(&(&h * &gn)));
        if gn.norm() <= self.step_tolerance {
            let kv = iteration_kv(self.mu, f64::NAN, 0.0, rank, false, cholesky);
            let st = state.param(x).cost(cost).gradient(g).hessian(h);
            return Ok((converged(st, self, StopReason::StepNorm), Some(kv)));
        }

        let delta = normal.damped_step(&h, &g, self.mu, &gn)?;
        let predicted = -(g.dot(&delta) + 0.5 * delta.dot(&(&h * &delta)));
        let x_new = x.retract(delta.as_slice());
        let (rho, eval) = self.trial(problem, &state, &x_new, cost, predicted)?;
        let kv = iteration_kv(self.mu, rho, delta.norm(), rank, eval.is_some(), cholesky);

        let mut state = match eval {
            Some(eval) => self.accepted(state, x_new, eval, cost),
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
