//! Gyroscope calibration from known attitudes only (motion capture of orientation, or any
//! source without positions): the gyro bias and, on request, the time offset, the gyroscope
//! intrinsics and its g-sensitivity ([`super::extras`]).
//!
//! # Model
//! The rotation rows of the known-pose problem ([`super::residuals`]) alone: for consecutive
//! attitudes `R̃_i`, `R̃_j`, `r_φ = Log((ΔR Exp(φ_c))ᵀ R̃_iᵀ R̃_j)` with `φ_c = J_R δb_g + J_e,φ e`,
//! whitened by the window's rotation covariance plus the attitude noise (σ_R), whose
//! correlation between windows that share an attitude is kept ([`super::pose_noise`], 3-row
//! blocks). Unknowns `[b_g, e]`: no velocity, gravity or accelerometer term, so the
//! accelerometer bias and intrinsics are neither estimated nor needed beyond their initial
//! values (the g-sensitivity reads the accelerometer's corrected samples, as in
//! [`preint::intrinsics`]).

use super::KnownPose;
use super::extras::{
    self, Calibration, Layout, Param, ParameterEstimate, Relinearised, fit_excited, parameters,
    relinearise,
};
use super::pose_noise::{Whitening, pose_noise_jacobians};
use super::{KnownPoseOptions, check_calibration_options};
use crate::bias::BiasError;
use crate::bias::validate::{check_non_negative, check_samples};
use crate::gauss_newton::{GaussNewton, LeastSquares, Solution, StopReason, solve};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use preint::intrinsics::ImuIntrinsics;
use preint::{ImuBias, ImuSample, PreintegratedImu};
use preint_lie::{SO3, jr, jr_inv};

/// A known attitude: time \[ns\] and R_wb (body → world).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownAttitude {
    /// Time \[ns\].
    pub t_ns: i64,
    /// Attitude R_wb.
    pub r: SO3,
}

/// Result of [`calibrate_known_attitudes`]; standard deviations as in
/// [`super::KnownPoseCalibration`].
#[derive(Clone, Debug)]
pub struct KnownAttitudeCalibration {
    /// Gyro bias \[rad/s\], in the IMU frame of the intrinsics.
    pub gyro_bias: Vector3<f64>,
    /// Its standard deviation \[rad/s\].
    pub gyro_bias_std: Vector3<f64>,
    /// The intrinsics: estimated where [`KnownAttitudeCalibration::parameters`] says excited.
    pub intrinsics: ImuIntrinsics,
    /// The time offset \[s\].
    pub time_offset_s: f64,
    /// Every parameter asked for ([`super::extras::parameters`] order).
    pub parameters: Vec<ParameterEstimate>,
    /// Joint covariance of `[b_g, e]` (`e` the excited parameters in order).
    pub covariance: DMatrix<f64>,
    /// χ² of the whitened residuals.
    pub chi2: f64,
    /// Degrees of freedom: `3(P − 1)` residuals minus the unknowns' rank.
    pub dof: usize,
    /// Total Gauss-Newton iterations.
    pub iterations: u64,
    /// Number of solves.
    pub solves: usize,
    /// Why the last solve stopped.
    pub stop: StopReason,
}

impl KnownAttitudeCalibration {
    /// `χ²/dof` (NaN for dof = 0).
    pub fn chi2_per_dof(&self) -> f64 {
        super::per_dof(self.chi2, self.dof)
    }

    /// The goodness of fit: `chi2` against `χ²_dof` ([`crate::fit`]).
    pub fn fit(&self) -> crate::Fit {
        crate::Fit::new(self.chi2, self.dof)
    }
}

/// Estimates the gyro bias and the requested gyroscope parameters from known attitudes (module
/// docs). `opts` as for [`super::calibrate_known_poses`]; `pose_pos_std` is unused and
/// `estimate.accel_intrinsics` is refused (it needs positions).
pub fn calibrate_known_attitudes(
    samples: &[ImuSample],
    attitudes: &[KnownAttitude],
    opts: &KnownPoseOptions,
) -> Result<KnownAttitudeCalibration, BiasError> {
    check_samples(samples, 2)?;
    opts.params.validate()?;
    let as_poses: Vec<super::KnownPose> = attitudes
        .iter()
        .map(|a| super::KnownPose {
            t_ns: a.t_ns,
            r: a.r,
            p: Vector3::zeros(),
        })
        .collect();
    super::check_poses(samples, &as_poses)?;
    check_non_negative("pose_rot_std", opts.pose_rot_std)?;
    check_calibration_options(opts)?;
    if opts.estimate.extrinsic() || opts.initial_extrinsic.is_some() {
        return Err(BiasError::InvalidParameter {
            name: "estimate",
            reason: "the extrinsic transform (extrinsic-rotation, lever-arm) is estimated and \
                     applied by the known-pose problem: give positions with the attitudes"
                .into(),
        });
    }
    if opts.estimate_scale || opts.bias_prior.is_some() {
        return Err(BiasError::InvalidParameter {
            name: "estimate_scale",
            reason: "the scale and the bias prior belong to the known-pose problem (positions \
                     and attitudes); attitudes alone have no positions to scale"
                .into(),
        });
    }
    if opts.estimate.accel_intrinsics {
        return Err(BiasError::InvalidParameter {
            name: "estimate",
            reason: "accel-intrinsics need known positions; attitudes alone calibrate the \
                     gyroscope"
                .into(),
        });
    }
    let asked = parameters(&opts.estimate, opts.initial_intrinsics.model);
    let out = fit_excited(
        &asked,
        &Calibration::initial(opts),
        &opts.excitation,
        |active| {
            let f = fit(samples, attitudes, opts, active)?;
            let stds = f.sol.std_devs();
            let calib = f.calib;
            Ok((f, calib, (0..active.len()).map(|k| stds[3 + k]).collect()))
        },
    )?;
    let Relinearised {
        sol,
        calib,
        iterations,
        solves,
        ..
    } = out.fit;
    Ok(KnownAttitudeCalibration {
        gyro_bias: extras_v3(&sol.estimate),
        gyro_bias_std: sol.marginal_std::<3>(0),
        intrinsics: calib.intrinsics,
        time_offset_s: calib.td_s,
        parameters: out.parameters,
        covariance: sol.covariance.clone(),
        chi2: 2.0 * sol.cost,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations,
        solves,
        stop: sol.stop,
    })
}

fn extras_v3(p: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

type Fit = Relinearised<DVector<f64>>;

/// The re-linearised fit (as [`super::calibrate_known_poses`]'s).
fn fit(
    samples: &[ImuSample],
    attitudes: &[KnownAttitude],
    opts: &KnownPoseOptions,
    active: &[Param],
) -> Result<Fit, BiasError> {
    let layout = Layout {
        vec: |x: &DVector<f64>| x,
        vec_mut: |x: &mut DVector<f64>| x,
        eo: 3,
        bias: |p, lin| ImuBias::new(extras_v3(p), lin.acc),
    };
    let mut x = DVector::zeros(3 + active.len());
    x.fixed_rows_mut::<3>(0).copy_from(&opts.initial_bias.gyro);
    relinearise(opts, active, x, &layout, |lin, x| {
        solve_linearised(samples, attitudes, opts, lin, active, x)
    })
}

/// One solve at the linearisation point.
fn solve_linearised(
    samples: &[ImuSample],
    attitudes: &[KnownAttitude],
    opts: &KnownPoseOptions,
    lin: &(ImuBias, Calibration),
    active: &[Param],
    x: DVector<f64>,
) -> Result<Solution<DVector<f64>>, BiasError> {
    let times = attitudes.windows(2).map(|w| (w[0].t_ns, w[1].t_ns));
    let (pims, jacs) = extras::windows(&opts.params, lin, active, samples, times)?;
    let je: Vec<DMatrix<f64>> = jacs.iter().map(|j| j.rows(0, 3).into_owned()).collect();
    let (diag, sub) = rotation_covariance(&pims, attitudes, opts.pose_rot_std);
    let white = Whitening::<3>::new(&diag, &sub).ok_or_else(|| BiasError::InvalidParameter {
        name: "params",
        reason: "the rotation covariance (preintegration + attitude noise) is not positive \
                 definite: give a non-zero gyro noise density"
            .into(),
    })?;
    let problem = AttitudeProblem {
        attitudes,
        pims: &pims,
        extras: &je,
        white: &white,
    };
    Ok(solve(problem, x, GaussNewton::default(), opts.max_iters)?)
}

/// `r_φ` of window `k` with its `−Jr⁻¹(r_φ)` and the attitude noise's Jacobians.
fn rotation_residual(
    pim: &PreintegratedImu,
    ri: &SO3,
    rj: &SO3,
    phi_c: &Vector3<f64>,
) -> (Vector3<f64>, Matrix3<f64>) {
    let err = pim
        .delta_r
        .plus(phi_c)
        .inverse()
        .compose(&ri.inverse().compose(rj));
    let r = err.log();
    (r, -jr_inv(&r) * err.matrix().transpose() * jr(phi_c))
}

/// Block-tridiagonal covariance of the `r_φ` rows: the windows' rotation covariance plus the
/// attitude noise `σ_R` through `A_i = −Jr⁻¹(r_φ) R̃_jᵀR̃_i`, `A_j = Jr⁻¹(r_φ)`.
fn rotation_covariance(
    pims: &[PreintegratedImu],
    attitudes: &[KnownAttitude],
    s_r: f64,
) -> (Vec<Matrix3<f64>>, Vec<Matrix3<f64>>) {
    let vr = s_r * s_r;
    let mut diag = Vec::with_capacity(pims.len());
    let mut sub = Vec::with_capacity(pims.len());
    let mut prev_aj: Option<Matrix3<f64>> = None;
    let pose = |a: &KnownAttitude| KnownPose {
        t_ns: a.t_ns,
        r: a.r,
        p: Vector3::zeros(),
    };
    for (k, pim) in pims.iter().enumerate() {
        // The rotation rows of the full problem's attitude-noise Jacobians.
        let (ai9, aj9) = pose_noise_jacobians(
            pim,
            &pose(&attitudes[k]),
            &pose(&attitudes[k + 1]),
            &Vector3::zeros(),
        );
        let ai: Matrix3<f64> = ai9.fixed_rows::<3>(0).into_owned();
        let aj: Matrix3<f64> = aj9.fixed_rows::<3>(0).into_owned();
        diag.push(
            pim.cov.fixed_view::<3, 3>(0, 0) + (ai * ai.transpose() + aj * aj.transpose()) * vr,
        );
        sub.push(prev_aj.map_or_else(Matrix3::zeros, |p| ai * p.transpose() * vr));
        prev_aj = Some(aj);
    }
    (diag, sub)
}

/// The attitude-only problem at one linearisation point; state `[b_g, e]`.
struct AttitudeProblem<'a> {
    attitudes: &'a [KnownAttitude],
    pims: &'a [PreintegratedImu],
    /// Per window, the 3 × m rotation rows of the calibration Jacobian.
    extras: &'a [DMatrix<f64>],
    white: &'a Whitening<3>,
}

impl AttitudeProblem<'_> {
    fn raw(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let m = x.len() - 3;
        let bg = extras_v3(x);
        let e = x.rows(3, m);
        let mut r = DVector::zeros(3 * self.pims.len());
        let mut j = DMatrix::zeros(3 * self.pims.len(), x.len());
        for (k, pim) in self.pims.iter().enumerate() {
            let jr_b = pim.jac.d_r_d_bg;
            let phi_c = jr_b * (bg - pim.bias_hat.gyro) + &self.extras[k] * e;
            let (a, b) = (&self.attitudes[k], &self.attitudes[k + 1]);
            let (rk, d) = rotation_residual(pim, &a.r, &b.r, &phi_c);
            r.fixed_rows_mut::<3>(3 * k).copy_from(&rk);
            j.view_mut((3 * k, 0), (3, 3)).copy_from(&(d * jr_b));
            if m > 0 {
                j.view_mut((3 * k, 3), (3, m))
                    .copy_from(&(d * &self.extras[k]));
            }
        }
        (r, j)
    }
}

impl LeastSquares for AttitudeProblem<'_> {
    type State = DVector<f64>;
    fn residual_jacobian(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let (r, j) = self.raw(x);
        (self.white.apply(r), self.white.apply(j))
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_data::setup;
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint::ImuNoise;
    use preint::intrinsics::IntrinsicsModel;

    /// The analytic Jacobian of the whitened attitude problem (bias, time offset, gyro
    /// intrinsics and g-sensitivity, attitude noise) against Ridders' away from the optimum.
    #[test]
    fn analytic_jacobian_matches_ridders() {
        let s = setup(ImuNoise::euroc());
        let atts: Vec<KnownAttitude> = s
            .poses
            .iter()
            .map(|p| KnownAttitude {
                t_ns: p.t_ns,
                r: p.r,
            })
            .collect();
        let est = extras::Estimate {
            time_offset: true,
            gyro_intrinsics: true,
            g_sensitivity: true,
            ..extras::Estimate::default()
        };
        let active = parameters(&est, IntrinsicsModel::Kalibr);
        let mut x0 = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
        x0.t_w[(1, 0)] = 2e-3;
        x0.t_g[(2, 2)] = 2e-4;
        let calib = Calibration {
            intrinsics: x0,
            td_s: 0.0,
            extrinsic: extras::identity_pose(),
            scale: 1.0,
        };
        let bias_hat = ImuBias::new(Vector3::new(0.003, -0.002, 0.005), Vector3::zeros());
        let (pims, je): (Vec<_>, Vec<DMatrix<f64>>) = atts
            .windows(2)
            .map(|w| {
                let (p, j) = extras::window(
                    &s.params,
                    &calib,
                    &active,
                    &bias_hat,
                    &s.samples,
                    (w[0].t_ns, w[1].t_ns),
                )
                .unwrap();
                (p, j.rows(0, 3).into_owned())
            })
            .unzip();
        let (diag, sub) = rotation_covariance(&pims, &atts, 2e-3);
        let white = Whitening::<3>::new(&diag, &sub).unwrap();
        let problem = AttitudeProblem {
            attitudes: &atts,
            pims: &pims,
            extras: &je,
            white: &white,
        };
        let x = DVector::from_fn(3 + active.len(), |i, _| 1e-3 * ((i as f64) * 0.9).cos());
        let (_, j) = problem.residual_jacobian(&x);
        let rep = check_jacobian(
            |x: &DVector<f64>| problem.residual_jacobian(x).0,
            &x,
            &[j],
            &CheckOptions::default(),
        )
        .unwrap();
        println!(
            "attitude problem: worst relative error {:.2e}",
            rep.worst_rel_error
        );
    }
}
