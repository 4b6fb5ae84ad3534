//! The stacked residual of a candidate model, its analytic Jacobian and its whitening.
//!
//! # Raw residuals
//! Stacked as `[e_ω,0, e_f,0, …, e_ω,K−1, e_f,K−1, e_R,0, …, e_R,K−2]` (m = 6K + 3(K − 1)
//! scalars):
//!
//! ```text
//! e_ω,k = ω̄_k − b_g                            white-noise covariance s_ω,k² I,  s_ω,k = σ_g/√T_k
//! e_f,k = f̄_k − S_a R_kᵀ(−g) − b_a             white-noise covariance s_f,k² I,  s_f,k = σ_a/√T_k
//! e_R,k = Log(ΔR_k(b_g, S_g)ᵀ R_kᵀ R_k+1)      white-noise covariance Σ_φ,k
//! ```
//!
//! (The still residual `e_ω` uses `ω_b = 0`, so `S_g` does not enter it.) `ΔR_k` and its
//! Jacobians `J_b`, `J_θ` come from [`rotation_preintegration_general`].
//!
//! # Jacobians
//! Right perturbations of the attitudes, `R_k ← R_k·Exp(δφ_k)`. With `u_k = R_kᵀ(−g)`:
//! `∂e_f/∂δφ_k = −S_a [u_k]×`, `∂e_f/∂s_a,c = −((I + N_a) u_k)_c e_c`,
//! `∂e_f/∂N₁₀ = −(1 + s_a,1) u_k,0 e₁`, `∂e_f/∂N₂₀ = −(1 + s_a,2) u_k,0 e₂`,
//! `∂e_f/∂N₂₁ = −(1 + s_a,2) u_k,1 e₂`. With `E = Exp(e_R)`: `∂e_R/∂δφ_k+1 = Jr⁻¹(e_R)`,
//! `∂e_R/∂δφ_k = −Jr⁻¹(e_R) R_k+1ᵀ R_k`, `∂e_R/∂b_g = −Jr⁻¹(e_R) Eᵀ J_b`,
//! `∂e_R/∂θ = −Jr⁻¹(e_R) Eᵀ J_θ`. All are checked against Ridders' numeric Jacobian in this
//! module's tests, with both whitenings.
//!
//! # Whitening
//! The solver sees `r = L⁻¹e` with `L Lᵀ = Σ`, the covariance of `e` at the truth:
//! `Σ = D + Σ_w`, `D` the block-diagonal white-noise part above, `Σ_w` the bias random walk's
//! part ([`random_walk`](super::random_walk); dense, it correlates different intervals and
//! links). Without a random walk `Σ = D` and the whitening is block by block:
//! `r_ω,k = e_ω,k/s_ω,k`, `r_f,k = e_f,k/s_f,k`, `r_R,k = U_k e_R,k` with `U_kᵀU_k = Σ_φ,k⁻¹`.
//! χ² = ‖r‖² = eᵀΣ⁻¹e either way; the whitened Jacobian is `L⁻¹ ∂e/∂x` (Σ does not depend on
//! the state).

use super::data::Observations;
use super::link_rotation::rotation_preintegration_general;
use super::model::{GyroModel, MultiPoseModel, Params, acc_misalignment_matrix, acc_scale_matrix};
use crate::gauss_newton::LeastSquares;
use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DVector, DefaultAllocator, Dim, Dyn, OMatrix, U3, Vector3};
use preint_lie::{SO3, hat, jr_inv};

/// How the raw residual vector `e` is whitened (module docs).
pub(super) enum Whitening {
    /// `Σ = D`: per interval `1/s_ω`, `1/s_f`, per link `U_k`.
    Block,
    /// `Σ = D + Σ_w`: `r = W e` with `W = L⁻¹`, `L Lᵀ = Σ` (lower triangular, m×m).
    Full(DMatrix<f64>),
}

/// The least-squares problem of one candidate model; state `(p, [R_0, …, R_K−1])` with `p` the
/// model's parameter vector ([`super::model`]).
pub(super) struct Problem<'a> {
    pub(super) obs: &'a Observations,
    /// World gravity \[m/s²\].
    pub(super) g: Vector3<f64>,
    pub(super) model: MultiPoseModel,
    pub(super) whitening: &'a Whitening,
}

/// `(p, [R_0, …, R_K−1])`.
pub(super) type State = (DVector<f64>, Vec<SO3>);

impl Problem<'_> {
    /// Raw (unwhitened) residuals `e` and, if `want_j`, `∂e/∂x` (module docs; else a 0×0
    /// matrix).
    pub(super) fn eval_raw(&self, x: &State, want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
        let (p, rs) = x;
        let k = self.obs.intervals.len();
        let n = self.model.param_count() + 3 * k;
        let m = 6 * k + 3 * self.obs.links.len();
        let mut r = DVector::zeros(m);
        let mut j = if want_j {
            DMatrix::zeros(m, n)
        } else {
            DMatrix::zeros(0, 0)
        };
        let params = self.model.unpack(p);
        self.still_residuals(&params, rs, &mut r, want_j.then_some(&mut j));
        self.link_residuals(&params, rs, &mut r, want_j.then_some(&mut j));
        (r, j)
    }

    /// `e_ω,k`, `e_f,k` of every still interval and their Jacobian rows.
    fn still_residuals(
        &self,
        params: &Params,
        rs: &[SO3],
        r: &mut DVector<f64>,
        mut j: Option<&mut DMatrix<f64>>,
    ) {
        let np = self.model.param_count();
        let layout = self.model.layout();
        let Params {
            b_g: bg,
            b_a: ba,
            s_a: sa,
            m_a: ma,
            ..
        } = *params;
        let s_a = acc_scale_matrix(&sa, &ma);
        let lower = acc_misalignment_matrix(&ma);
        for (i, iv) in self.obs.intervals.iter().enumerate() {
            let u = rs[i].inverse().act(&(-self.g));
            let pred = s_a * u + ba;
            let row = 6 * i;
            for c in 0..3 {
                r[row + c] = iv.w_mean[c] - bg[c];
                r[row + 3 + c] = iv.f_mean[c] - pred[c];
            }
            let Some(j) = j.as_deref_mut() else {
                continue;
            };
            let nu = lower * u;
            for c in 0..3 {
                j[(row + c, c)] = -1.0;
                j[(row + 3 + c, 3 + c)] = -1.0;
                if let Some(o) = layout.acc_scale {
                    j[(row + 3 + c, o + c)] = -nu[c];
                }
            }
            if let Some(o) = layout.acc_mis {
                // ∂(S_a u)/∂N₁₀ = (1+s₁) u₀ e₁, ∂/∂N₂₀ = (1+s₂) u₀ e₂, ∂/∂N₂₁ = (1+s₂) u₁ e₂.
                j[(row + 4, o)] = -(1.0 + sa[1]) * u[0];
                j[(row + 5, o + 1)] = -(1.0 + sa[2]) * u[0];
                j[(row + 5, o + 2)] = -(1.0 + sa[2]) * u[1];
            }
            let d_phi = -(s_a * hat(&u));
            j.view_mut((row + 3, np + 3 * i), (3, 3)).copy_from(&d_phi);
        }
    }

    /// `e_R,k` of every link and their Jacobian rows.
    fn link_residuals(
        &self,
        params: &Params,
        rs: &[SO3],
        r: &mut DVector<f64>,
        mut j: Option<&mut DMatrix<f64>>,
    ) {
        let np = self.model.param_count();
        let k = self.obs.intervals.len();
        let gm = GyroModel::of(self.model, params);
        let o_gyro = self.model.layout().gyro();
        for (l, link) in self.obs.links.iter().enumerate() {
            let (dr, jb, jt) =
                rotation_preintegration_general(&link.samples, &params.b_g, &gm.s, &gm.dirs);
            let e = dr.inverse().compose(&rs[l].inverse().compose(&rs[l + 1]));
            let res = e.log();
            let row = 6 * k + 3 * l;
            r.fixed_rows_mut::<3>(row).copy_from(&res);
            let Some(j) = j.as_deref_mut() else {
                continue;
            };
            let jri = jr_inv(&res);
            let d_prev = -jri * (rs[l + 1].inverse().compose(&rs[l])).matrix();
            let jet = -jri * e.matrix().transpose();
            j.view_mut((row, np + 3 * (l + 1)), (3, 3)).copy_from(&jri);
            j.view_mut((row, np + 3 * l), (3, 3)).copy_from(&d_prev);
            j.view_mut((row, 0), (3, 3)).copy_from(&(jet * jb));
            if let Some(o) = o_gyro {
                let d = DMatrix::from_column_slice(3, 3, jet.as_slice()) * &jt;
                j.view_mut((row, o), (3, self.model.gyro_params()))
                    .copy_from(&d);
            }
        }
    }

    /// Whitened residuals `r` and Jacobian `∂r/∂x` (module docs).
    fn eval(&self, x: &State, want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
        let (e, j) = self.eval_raw(x, want_j);
        let r = self.whiten(e);
        let j = if want_j { self.whiten(j) } else { j };
        (r, j)
    }

    /// `L⁻¹x` for the stacked rows of `x` (a residual vector or a Jacobian).
    fn whiten<C: Dim>(&self, mut x: OMatrix<f64, Dyn, C>) -> OMatrix<f64, Dyn, C>
    where
        DefaultAllocator: Allocator<Dyn, C> + Allocator<U3, C>,
    {
        match self.whitening {
            Whitening::Full(w) => w * &x,
            Whitening::Block => {
                let k = self.obs.intervals.len();
                for (i, iv) in self.obs.intervals.iter().enumerate() {
                    let row = 6 * i;
                    x.rows_mut(row, 3).unscale_mut(iv.s_w);
                    x.rows_mut(row + 3, 3).unscale_mut(iv.s_f);
                }
                for (l, link) in self.obs.links.iter().enumerate() {
                    let row = 6 * k + 3 * l;
                    let ux = link.sqrt_info * x.fixed_rows::<3>(row);
                    x.fixed_rows_mut::<3>(row).copy_from(&ux);
                }
                x
            }
        }
    }
}

impl LeastSquares for Problem<'_> {
    type State = State;
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        self.eval(x, true)
    }
    fn residual(&self, x: &Self::State) -> DVector<f64> {
        self.eval(x, false).0
    }
}

#[cfg(test)]
mod tests {
    //! The problem's analytic Jacobian against Ridders' numeric one ([`crate::check_jacobian`],
    //! relative error ≤ 1e-8), for every candidate model, at a state away from the optimum (so
    //! that residuals, scales and misalignments are all non-zero).
    use super::super::MultiPoseOptions;
    use super::super::data::{Prepared, prepare};
    use super::super::test_data::data;
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint_lie::Manifold;

    /// Both whitenings: block-diagonal (random walk off) and full (`L⁻¹`, EuRoC random walk).
    #[test]
    fn analytic_jacobians_match_ridders_for_every_model() {
        let (samples, noise) = data();
        for include_random_walk in [false, true] {
            let opts = MultiPoseOptions {
                include_random_walk,
                ..MultiPoseOptions::default()
            };
            let pr = prepare(&samples, &noise, &opts, 9.81).unwrap();
            assert_eq!(pr.marginalised, include_random_walk);
            check_problem_jacobians(&pr, &opts);
        }
    }

    fn check_problem_jacobians(pr: &Prepared, opts: &MultiPoseOptions) {
        assert_eq!(pr.obs.intervals.len(), 5);
        for model in MultiPoseModel::ALL {
            let np = model.param_count();
            let problem = Problem {
                obs: &pr.obs,
                g: opts.gravity,
                model,
                whitening: &pr.whitening,
            };
            // Parameters: biases near the truth, every model term non-zero.
            let p = DVector::from_fn(np, |i, _| match i {
                0..=2 => 0.003 - 0.001 * i as f64,
                3..=5 => 0.05 * (i as f64 - 4.0),
                _ => 0.004 * ((i as f64) * 1.3).sin(),
            });
            let rs: Vec<SO3> = pr
                .r0
                .iter()
                .enumerate()
                .map(|(k, r)| r.plus(&Vector3::new(0.01 * k as f64, -0.02, 0.015)))
                .collect();
            let x = (p, rs);
            let (_, j) = problem.residual_jacobian(&x);
            let blocks = [
                j.columns(0, np).into_owned(),
                j.columns(np, j.ncols() - np).into_owned(),
            ];
            let f = |x: &(DVector<f64>, Vec<SO3>)| problem.residual(x);
            let rep = check_jacobian(f, &x, &blocks, &CheckOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", model.name()));
            println!(
                "{}: worst relative error {:.2e}",
                model.name(),
                rep.worst_rel_error
            );
            assert_eq!(x.dim(), np + 15);
        }
    }
}
