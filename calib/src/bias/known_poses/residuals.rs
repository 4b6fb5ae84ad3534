//! The preintegration-factor residuals of consecutive known poses and their analytic Jacobian.
//!
//! For the pair (i, j = i+1), Forster et al. (T-RO 2017) eq. 45 with the first-order bias
//! correction of eq. 44 (see [`preint::ImuFactor`]), `Δt = t_j − t_i`, order **[r_φ, r_v, r_p]**:
//!
//! ```text
//! r_φ = Log(ΔR(b_g)ᵀ R̃_iᵀ R̃_j)
//! r_v = R̃_iᵀ(v_j − v_i − g Δt) − Δv(b)
//! r_p = R̃_iᵀ(p̃_j − p̃_i − v_i Δt − ½ g Δt²) − Δp(b)
//! ```
//!
//! With calibration parameters ([`super::extras`]) the correction is `J_b δb + J_e e`, `e` the
//! state's correction of the time offset and intrinsics, added to the `J_R δb_g` inside `ΔR`
//! and to `Δv`, `Δp`.
//!
//! Jacobians: `∂r_φ/∂b_g = −Jr⁻¹(r_φ) Eᵀ Jr(φ_c) J_R` (`E = Exp(r_φ)`, `φ_c` the rotation
//! correction), `∂r_φ/∂e = −Jr⁻¹(r_φ) Eᵀ Jr(φ_c) J_e,φ`, `∂r_v/∂e = −J_e,v`, `∂r_p/∂e = −J_e,p`,
//! `∂r_v/∂b = −J_v`, `∂r_p/∂b = −J_p`, `∂r_v/∂v_i = −R̃_iᵀ`, `∂r_v/∂v_j = R̃_iᵀ`,
//! `∂r_p/∂v_i = −R̃_iᵀΔt`, `∂r_v/∂δ = −R̃_iᵀ G Δt`, `∂r_p/∂δ = −½Δt² R̃_iᵀ G` with
//! `G = ∂g/∂δ` ([`super::gravity`]); checked against Ridders' numeric Jacobian in this module's
//! tests. The solver sees them whitened by the pose-noise covariance
//! ([`super::pose_noise`]).

use super::extras::Param;
use super::extrinsic::{self, WindowTerms};
use super::gravity::GravityDir;
use super::pose_noise::Whitening;
use super::{BiasPrior, KnownPose};
use crate::gauss_newton::LeastSquares;
use nalgebra::{DMatrix, DVector, Vector3};
use preint::{PreintegratedImu, SensorPose};
use preint_lie::{jr, jr_inv};

/// The problem at one linearisation point (the windows preintegrated at `b̂` and the
/// calibration's estimate); state `([b_g, b_a, v_0, …, v_P−1, e_0, …, e_m−1], R_wg)`.
pub(super) struct Problem<'a> {
    /// The given poses (of the frame b; [`super::extrinsic`]).
    pub(super) poses: &'a [KnownPose],
    /// The scalars of `e`.
    pub(super) active: &'a [Param],
    /// The extrinsic transform at the linearisation point, moved by `e`'s correction.
    pub(super) extrinsic: SensorPose,
    pub(super) pims: &'a [PreintegratedImu],
    /// Per window, the 9 × m Jacobian of its deltas with respect to `e` ([`super::extras`]).
    pub(super) extras: &'a [DMatrix<f64>],
    /// `g₀ = (0, 0, −|g|)`.
    pub(super) g0: Vector3<f64>,
    pub(super) white: &'a Whitening,
    /// The scale of the given positions at the linearisation point, moved by `e`'s
    /// [`Param::Scale`] entry (1 for metric poses).
    pub(super) scale: f64,
    /// The prior on the biases, when given: 6 rows `(b − μ)/σ` after the windows'.
    pub(super) prior: Option<BiasPrior>,
}

impl Problem<'_> {
    /// Unwhitened residual (9 per pair) and, if `want_j`, Jacobian (else 0×0).
    pub(super) fn raw(
        &self,
        x: &(DVector<f64>, GravityDir),
        want_j: bool,
    ) -> (DVector<f64>, DMatrix<f64>) {
        let (p, rwg) = x;
        let np = p.len();
        let m = 9 * self.pims.len();
        let mut r = DVector::zeros(m);
        let mut j = if want_j {
            DMatrix::zeros(m, np + 2)
        } else {
            DMatrix::zeros(0, 0)
        };
        let v3 = |o: usize| Vector3::new(p[o], p[o + 1], p[o + 2]);
        let bg = v3(0);
        let ba = v3(3);
        let eo = 6 + 3 * self.poses.len();
        let e = p.rows(eo, np - eo);
        let (g, gd) = rwg.gravity(&self.g0);
        let dx = extrinsic::state_correction(p, eo, self.active);
        let x = extrinsic::moved(&self.extrinsic, &dx);
        let scale_col = self.active.iter().position(|q| *q == Param::Scale);
        let s = self.scale + scale_col.map_or(0.0, |k| e[k]);
        for (k, pim) in self.pims.iter().enumerate() {
            let je = &self.extras[k];
            let c = je * e;
            let given = &(
                extrinsic::scaled(&self.poses[k], s),
                extrinsic::scaled(&self.poses[k + 1], s),
            );
            let given = (&given.0, &given.1);
            let (pi, pj) = (
                &extrinsic::imu_pose(given.0, &x),
                &extrinsic::imu_pose(given.1, &x),
            );
            let (vi, vj) = (v3(6 + 3 * k), v3(6 + 3 * k + 3));
            let jb = &pim.jac;
            let dbg = bg - pim.bias_hat.gyro;
            let dba = ba - pim.bias_hat.acc;
            let phi_b = jb.d_r_d_bg * dbg + c.fixed_rows::<3>(0);
            let dr = pim.delta_r.plus(&phi_b);
            let dv = pim.delta_v + jb.d_v_d_bg * dbg + jb.d_v_d_ba * dba + c.fixed_rows::<3>(3);
            let dp = pim.delta_p + jb.d_p_d_bg * dbg + jb.d_p_d_ba * dba + c.fixed_rows::<3>(6);
            let dt = pim.delta_t;
            let rit = pi.r.inverse();
            let err = dr.inverse().compose(&rit.compose(&pj.r));
            let rphi = err.log();
            let yv = rit.act(&(vj - vi - g * dt));
            let yp = rit.act(&(pj.p - pi.p - vi * dt - g * (0.5 * dt * dt)));
            let (rv, rp) = (yv - dv, yp - dp);
            let row = 9 * k;
            r.fixed_rows_mut::<3>(row).copy_from(&rphi);
            r.fixed_rows_mut::<3>(row + 3).copy_from(&rv);
            r.fixed_rows_mut::<3>(row + 6).copy_from(&rp);
            if !want_j {
                continue;
            }
            let ritm = *rit.matrix();
            let d_rphi = -jr_inv(&rphi) * err.matrix().transpose() * jr(&phi_b);
            j.view_mut((row, 0), (3, 3))
                .copy_from(&(d_rphi * jb.d_r_d_bg));
            let m = np - eo;
            if m > 0 {
                j.view_mut((row, eo), (3, m))
                    .copy_from(&(d_rphi * je.rows(0, 3)));
                j.view_mut((row + 3, eo), (6, m))
                    .copy_from(&(-je.rows(3, 6)));
            }
            j.view_mut((row + 3, 0), (3, 3)).copy_from(&(-jb.d_v_d_bg));
            j.view_mut((row + 3, 3), (3, 3)).copy_from(&(-jb.d_v_d_ba));
            j.view_mut((row + 6, 0), (3, 3)).copy_from(&(-jb.d_p_d_bg));
            j.view_mut((row + 6, 3), (3, 3)).copy_from(&(-jb.d_p_d_ba));
            let ci = 6 + 3 * k;
            j.view_mut((row + 3, ci), (3, 3)).copy_from(&(-ritm));
            j.view_mut((row + 3, ci + 3), (3, 3)).copy_from(&ritm);
            j.view_mut((row + 6, ci), (3, 3)).copy_from(&(-ritm * dt));
            j.view_mut((row + 3, np), (3, 2))
                .copy_from(&(-ritm * gd * dt));
            j.view_mut((row + 6, np), (3, 2))
                .copy_from(&(-ritm * gd * (0.5 * dt * dt)));
            let terms = WindowTerms {
                given,
                rit: ritm,
                m: *rit.compose(&pj.r).matrix(),
                rphi,
                y: (yv, yp),
            };
            self.extrinsic_columns(&mut j, row, eo, &terms, &dx.0);
            if let Some(c) = scale_col {
                // ∂r_p/∂s = R_s,iᵀ(p̃_j − p̃_i).
                let d = ritm * (self.poses[k + 1].p - self.poses[k].p);
                j.view_mut((row + 6, eo + c), (3, 1)).copy_from(&d);
            }
        }
        (r, j)
    }

    /// The whitened residual and Jacobian with the prior's rows below them.
    fn with_prior(
        &self,
        p: &DVector<f64>,
        (r, j): (DVector<f64>, DMatrix<f64>),
    ) -> (DVector<f64>, DMatrix<f64>) {
        let Some(prior) = &self.prior else {
            return (r, j);
        };
        let m = r.len();
        let mut r = r.resize_vertically(m + 6, 0.0);
        let want_j = j.nrows() > 0;
        let mut j = if want_j {
            j.resize_vertically(m + 6, 0.0)
        } else {
            j
        };
        let mean = [prior.mean.gyro, prior.mean.acc];
        for k in 0..6 {
            let std = if k < 3 { prior.gyro_std } else { prior.acc_std };
            r[m + k] = (p[k] - mean[k / 3][k % 3]) / std;
            if want_j {
                j[(m + k, k)] = 1.0 / std;
            }
        }
        (r, j)
    }
}

impl Problem<'_> {
    /// Writes the columns of the extrinsic parameters of `e` for the window at `row`.
    fn extrinsic_columns(
        &self,
        j: &mut DMatrix<f64>,
        row: usize,
        eo: usize,
        w: &WindowTerms,
        dth: &Vector3<f64>,
    ) {
        if !self
            .active
            .iter()
            .any(|p| matches!(p, Param::ExtrinsicRotation(_) | Param::LeverArm(_)))
        {
            return;
        }
        let (d_rot, d_p) = extrinsic::jacobians(w, dth);
        for (k, p) in self.active.iter().enumerate() {
            let col = match p {
                Param::ExtrinsicRotation(a) => d_rot.column(*a),
                Param::LeverArm(a) => d_p.column(*a),
                Param::TimeOffset | Param::Intrinsic(_) | Param::Scale => continue,
            };
            j.view_mut((row, eo + k), (9, 1)).copy_from(&col);
        }
    }
}

impl LeastSquares for Problem<'_> {
    /// ([b_g, b_a, v_0, …, v_P−1, e], R_wg with its 2-DoF tangent).
    type State = (DVector<f64>, GravityDir);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        let (r, j) = self.raw(x, true);
        self.with_prior(&x.0, (self.white.apply(r), self.white.apply(j)))
    }
    fn residual(&self, x: &Self::State) -> DVector<f64> {
        let r = self.white.apply(self.raw(x, false).0);
        self.with_prior(&x.0, (r, DMatrix::zeros(0, 0))).0
    }
}

#[cfg(test)]
mod tests {
    use super::super::extras::{Calibration, Estimate, identity_pose, parameters, window};
    use super::super::pose_noise::residual_covariance;
    use super::super::test_data::{pims, setup};
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
    use preint::{ImuBias, ImuNoise};
    use preint_lie::SO3;

    #[test]
    fn analytic_jacobian_matches_ridders_with_pose_noise_whitening() {
        let s = setup(ImuNoise::euroc());
        let bias_hat = ImuBias::new(Vector3::new(0.003, -0.002, 0.005), Vector3::zeros());
        let pims = pims(&s, &bias_hat);
        // Without calibration parameters, and with all 25 (time offset, gyro, g-sensitivity,
        // accelerometer) at non-identity intrinsics.
        let none = vec![DMatrix::zeros(9, 0); pims.len()];
        check_problem(&s, &pims, &none, (&[], identity_pose()), (1.0, None));
        let all = Estimate {
            time_offset: true,
            gyro_intrinsics: true,
            g_sensitivity: true,
            accel_intrinsics: true,
            extrinsic_rotation: true,
            lever_arm: true,
        };
        let mut active = parameters(&all, IntrinsicsModel::Kalibr);
        assert_eq!(active.len(), 31);
        // And the scale of up-to-scale positions, with a prior on the biases.
        active.push(Param::Scale);
        // Poses of a frame turned by ≈ 70° from the IMU, 0.3 m away.
        let x_bs = SensorPose::new(
            SO3::exp(&Vector3::new(0.9, -0.6, 0.5)),
            Vector3::new(0.3, -0.1, 0.2),
        );
        let mut x0 = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
        x0.t_w[(1, 0)] = 2e-3;
        x0.t_w[(2, 2)] = 1.01;
        x0.t_a[(0, 0)] = 0.99;
        x0.t_g[(0, 2)] = 3e-4;
        let calib = Calibration {
            intrinsics: x0,
            td_s: 0.0,
            extrinsic: x_bs,
            scale: 0.7,
        };
        let (pims, extras): (Vec<_>, Vec<_>) = s
            .poses
            .windows(2)
            .map(|w| {
                window(
                    &s.params,
                    &calib,
                    &active,
                    &bias_hat,
                    &s.samples,
                    (w[0].t_ns, w[1].t_ns),
                )
                .unwrap()
            })
            .unzip();
        let prior = BiasPrior {
            mean: ImuBias::new(Vector3::new(1e-3, 0.0, -2e-3), Vector3::new(0.05, 0.0, 0.1)),
            gyro_std: 0.01,
            acc_std: 0.2,
        };
        check_problem(&s, &pims, &extras, (&active, x_bs), (0.7, Some(prior)));
    }

    /// The analytic Jacobian of the whitened problem against Ridders' away from the optimum.
    fn check_problem(
        s: &super::super::test_data::Setup,
        pims: &[PreintegratedImu],
        extras: &[DMatrix<f64>],
        (active, x_bs): (&[Param], SensorPose),
        (scale, prior): (f64, Option<BiasPrior>),
    ) {
        let imu = extrinsic::imu_poses(&s.poses, &x_bs, scale);
        let q = extrinsic::lever_in_imu(&x_bs);
        let (diag, sub) = residual_covariance(pims, &imu, (2e-3, 4e-3), &q);
        let white = Whitening::new(&diag, &sub).unwrap();
        let g0 = Vector3::new(0.0, 0.0, -9.81);
        let problem = Problem {
            poses: &s.poses,
            active,
            extrinsic: x_bs,
            pims,
            extras,
            g0,
            white: &white,
            scale,
            prior,
        };
        let n = s.poses.len();
        // Away from the optimum: biases off by 1e-3 rad/s and 0.05 m/s², velocities off,
        // gravity tilted by ≈ 3°.
        let m = extras[0].ncols();
        let mut p = DVector::zeros(6 + 3 * n + m);
        p.fixed_rows_mut::<3>(0)
            .copy_from(&Vector3::new(0.005, -0.004, 0.007));
        p.fixed_rows_mut::<3>(3)
            .copy_from(&Vector3::new(0.1, -0.02, 0.15));
        for k in 0..n {
            let v = s.truth[50 * k].v + Vector3::new(0.01, -0.02, 0.005) * k as f64;
            p.fixed_rows_mut::<3>(6 + 3 * k).copy_from(&v);
        }
        // Calibration corrections of a few milliseconds / per mille.
        for k in 0..m {
            p[6 + 3 * n + k] = 1e-3 * ((k as f64) * 0.7).sin();
        }
        let x = (p, GravityDir(SO3::exp(&Vector3::new(0.04, -0.03, 0.2))));
        let (_, j) = problem.residual_jacobian(&x);
        let rows = 9 * pims.len() + if prior.is_some() { 6 } else { 0 };
        assert_eq!(j.nrows(), rows);
        let np = 6 + 3 * n + m;
        let blocks = [j.columns(0, np).into_owned(), j.columns(np, 2).into_owned()];
        let rep = check_jacobian(
            |x: &(DVector<f64>, GravityDir)| problem.residual(x),
            &x,
            &blocks,
            &CheckOptions::default(),
        )
        .unwrap();
        println!(
            "known-pose problem, {m} calibration parameters: worst relative error {:.2e}",
            rep.worst_rel_error
        );
    }
}
