//! Biases, velocities and the gravity direction from segments with known poses (motion
//! capture or a VIO front end): the inertial-only initialisation of ORB-SLAM3 (Campos et al.
//! 2020, 2021) and VINS-Mono's gyro-bias estimation, with preintegration factors.
//!
//! # Model
//! Poses `(R_k, p_k)` (R_wb, p in the world, m) are known at times `t_0 < … < t_P−1`; for each
//! consecutive pair the samples are preintegrated ([`preint::preintegrate`]) at the current bias
//! estimate `b̂`. Unknowns: `b = [b_g, b_a]` (constant over the segment), the velocities `v_k`
//! [m/s, world] at the pose times, and the gravity direction `g = R_wg·(0, 0, −|g|)`
//! (`R_wg ∈ SO3`, right perturbation; its rotation about z changes nothing, so 2 DoF — the
//! solver's rank analysis reports that gauge, as ORB-SLAM3 zeroes that update component).
//! Residual of the pair (i, j = i+1), Forster eq. 45 with the first-order bias correction
//! eq. 44 (see [`preint::factor`]), `Δt = t_j − t_i`:
//!
//! ```text
//! r_φ = Log(ΔR(b_g)ᵀ R_iᵀ R_j)
//! r_v = R_iᵀ(v_j − v_i − g Δt) − Δv(b)
//! r_p = R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp(b)
//! ```
//!
//! whitened by the upper Cholesky factor of `Σ⁻¹`, `Σ = cov_preint + diag(2σ_R² I, 0, 2σ_p² I)`
//! where `σ_R` [rad], `σ_p` [m] are the (optional) pose noise of the known poses (each residual
//! sees two poses; the correlation between consecutive factors through a shared pose is
//! neglected). Analytic Jacobians: `∂r_φ/∂b_g = −Jr⁻¹(r_φ) Eᵀ Jr(J_R δb_g) J_R`,
//! `∂r_v/∂b = −J_v`, `∂r_p/∂b = −J_p`, `∂r_v/∂v_i = −R_iᵀ`, `∂r_v/∂v_j = R_iᵀ`,
//! `∂r_p/∂v_i = −R_iᵀΔt`, `∂r_v/∂δg = −R_iᵀΔt·G`, `∂r_p/∂δg = −½Δt² R_iᵀ G` with
//! `G = ∂g/∂δ = −R_wg [(0, 0, −|g|)]×`.
//!
//! Because the bias correction is first order, the problem is re-linearised: after a solve
//! the windows are re-integrated at the new bias and the problem solved again, until the bias
//! moves by less than 1e-6 (or `max_relinearizations`).

use super::{BiasError, check_samples};
use crate::gauss_newton::{GaussNewton, LeastSquares, StopReason, solve};
use lie::{SO3, hat, jr, jr_inv};
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, Vector3};
use preint::factor::sqrt_information;
use preint::{ImuBias, ImuSample, PreintParams, PreintegratedImu, preintegrate};

/// A known pose: time [ns], attitude R_wb (body → world) and position p [m, world].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownPose {
    /// Time [ns].
    pub t_ns: i64,
    /// Attitude R_wb.
    pub r: SO3,
    /// Position [m].
    pub p: Vector3<f64>,
}

/// Options of [`calibrate_known_poses`].
#[derive(Clone, Debug, PartialEq)]
pub struct KnownPoseOptions {
    /// Preintegration parameters (noise densities, scheme; its `gravity` gives the initial
    /// gravity vector and its magnitude |g|).
    pub params: PreintParams,
    /// Standard deviation of the known attitudes σ_R [rad] (default 0).
    pub pose_rot_std: f64,
    /// Standard deviation of the known positions σ_p [m] (default 0).
    pub pose_pos_std: f64,
    /// Initial bias (default zero).
    pub initial_bias: ImuBias,
    /// Maximum number of re-linearisations (default 4).
    pub max_relinearizations: usize,
    /// Gauss-Newton iterations per solve (default 50).
    pub max_iters: u64,
}

impl KnownPoseOptions {
    /// Defaults around the given preintegration parameters.
    pub fn new(params: PreintParams) -> Self {
        Self {
            params,
            pose_rot_std: 0.0,
            pose_pos_std: 0.0,
            initial_bias: ImuBias::zero(),
            max_relinearizations: 4,
            max_iters: 50,
        }
    }
}

/// Result of [`calibrate_known_poses`].
#[derive(Clone, Debug)]
pub struct KnownPoseCalibration {
    /// Bias estimate [b_g rad/s, b_a m/s²].
    pub bias: ImuBias,
    /// Standard deviation of b_g [rad/s].
    pub gyro_bias_std: Vector3<f64>,
    /// Standard deviation of b_a [m/s²].
    pub acc_bias_std: Vector3<f64>,
    /// Gravity vector in the world frame [m/s²] (magnitude fixed to |params.gravity|).
    pub gravity: Vector3<f64>,
    /// Standard deviation of each component of `gravity` [m/s²].
    pub gravity_std: Vector3<f64>,
    /// Angle between the estimated gravity and the initial one [rad].
    pub gravity_tilt: f64,
    /// Velocities at the pose times [m/s, world].
    pub velocities: Vec<Vector3<f64>>,
    /// Their standard deviations [m/s].
    pub velocity_std: Vec<Vector3<f64>>,
    /// χ² of the whitened residuals.
    pub chi2: f64,
    /// Degrees of freedom (residuals − rank).
    pub dof: usize,
    /// Total Gauss-Newton iterations.
    pub iterations: u64,
    /// Number of solves (re-linearisations + 1).
    pub solves: usize,
    /// Why the last solve stopped.
    pub stop: StopReason,
}

struct Pair {
    pim: PreintegratedImu,
    u: SMatrix<f64, 9, 9>,
}

struct Problem<'a> {
    poses: &'a [KnownPose],
    pairs: &'a [Pair],
    g0: Vector3<f64>,
}

impl LeastSquares for Problem<'_> {
    /// ([b_g, b_a, v_0, …, v_P−1], R_wg).
    type State = (DVector<f64>, SO3);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        let (p, rwg) = x;
        let np = p.len();
        let m = 9 * self.pairs.len();
        let mut r = DVector::zeros(m);
        let mut j = DMatrix::zeros(m, np + 3);
        let v3 = |o: usize| Vector3::new(p[o], p[o + 1], p[o + 2]);
        let bg = v3(0);
        let ba = v3(3);
        let g = rwg.act(&self.g0);
        let gd: Matrix3<f64> = -rwg.matrix() * hat(&self.g0);
        for (k, pair) in self.pairs.iter().enumerate() {
            let (pi, pj) = (&self.poses[k], &self.poses[k + 1]);
            let (vi, vj) = (v3(6 + 3 * k), v3(6 + 3 * k + 3));
            let pim = &pair.pim;
            let jb = &pim.jac;
            let dbg = bg - pim.bias_hat.gyro;
            let dba = ba - pim.bias_hat.acc;
            let phi_b = jb.d_r_d_bg * dbg;
            let dr = pim.delta_r.plus(&phi_b);
            let dv = pim.delta_v + jb.d_v_d_bg * dbg + jb.d_v_d_ba * dba;
            let dp = pim.delta_p + jb.d_p_d_bg * dbg + jb.d_p_d_ba * dba;
            let dt = pim.delta_t;
            let rit = pi.r.inverse();
            let e = dr.inverse().compose(&rit.compose(&pj.r));
            let rphi = e.log();
            let rv = rit.act(&(vj - vi - g * dt)) - dv;
            let rp = rit.act(&(pj.p - pi.p - vi * dt - g * (0.5 * dt * dt))) - dp;
            let mut raw = SMatrix::<f64, 9, 1>::zeros();
            raw.fixed_rows_mut::<3>(0).copy_from(&rphi);
            raw.fixed_rows_mut::<3>(3).copy_from(&rv);
            raw.fixed_rows_mut::<3>(6).copy_from(&rp);
            r.fixed_rows_mut::<9>(9 * k).copy_from(&(pair.u * raw));
            let ritm = *rit.matrix();
            let mut jl = DMatrix::<f64>::zeros(9, np + 3);
            jl.view_mut((0, 0), (3, 3))
                .copy_from(&(-jr_inv(&rphi) * e.matrix().transpose() * jr(&phi_b) * jb.d_r_d_bg));
            jl.view_mut((3, 0), (3, 3)).copy_from(&(-jb.d_v_d_bg));
            jl.view_mut((3, 3), (3, 3)).copy_from(&(-jb.d_v_d_ba));
            jl.view_mut((6, 0), (3, 3)).copy_from(&(-jb.d_p_d_bg));
            jl.view_mut((6, 3), (3, 3)).copy_from(&(-jb.d_p_d_ba));
            let ci = 6 + 3 * k;
            jl.view_mut((3, ci), (3, 3)).copy_from(&(-ritm));
            jl.view_mut((3, ci + 3), (3, 3)).copy_from(&ritm);
            jl.view_mut((6, ci), (3, 3)).copy_from(&(-ritm * dt));
            jl.view_mut((3, np), (3, 3)).copy_from(&(-ritm * gd * dt));
            jl.view_mut((6, np), (3, 3))
                .copy_from(&(-ritm * gd * (0.5 * dt * dt)));
            let u = DMatrix::from_column_slice(9, 9, pair.u.as_slice());
            j.view_mut((9 * k, 0), (9, np + 3)).copy_from(&(u * jl));
        }
        (r, j)
    }
}

/// Estimates `b_g`, `b_a`, the velocities at the pose times and the gravity direction from
/// IMU samples and known poses (module docs).
///
/// `poses`: at least 3, strictly increasing times inside the sample span. Errors are typed
/// ([`BiasError`]); no panics on bad input.
pub fn calibrate_known_poses(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
) -> Result<KnownPoseCalibration, BiasError> {
    check_samples(samples, 2)?;
    opts.params.validate()?;
    if poses.len() < 3 {
        return Err(BiasError::TooFew {
            what: "poses",
            found: poses.len(),
            needed: 3,
        });
    }
    for (i, w) in poses.windows(2).enumerate() {
        if w[1].t_ns <= w[0].t_ns {
            return Err(BiasError::InvalidParameter {
                name: "poses",
                reason: format!(
                    "pose {} time {} ns is not after the previous",
                    i + 1,
                    w[1].t_ns
                ),
            });
        }
    }
    let (t0, t1) = (samples[0].t_ns, samples[samples.len() - 1].t_ns);
    if poses[0].t_ns < t0 || poses[poses.len() - 1].t_ns > t1 {
        return Err(BiasError::InvalidParameter {
            name: "poses",
            reason: format!("pose times must lie within the samples' span [{t0}, {t1}] ns"),
        });
    }
    if poses.iter().any(|p| !p.p.iter().all(|v| v.is_finite())) {
        return Err(BiasError::InvalidParameter {
            name: "poses",
            reason: "non-finite position".into(),
        });
    }
    for (name, v) in [
        ("pose_rot_std", opts.pose_rot_std),
        ("pose_pos_std", opts.pose_pos_std),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(BiasError::InvalidParameter {
                name,
                reason: format!("must be finite and ≥ 0, got {v}"),
            });
        }
    }
    let g0 = Vector3::new(0.0, 0.0, -opts.params.gravity.norm());
    let g_init = opts.params.gravity;
    // R_wg with R_wg·g0 = g_init (minimal rotation).
    let rwg0 = {
        let a = g0.normalize();
        let b = g_init.normalize();
        let ax = a.cross(&b);
        let s = ax.norm();
        if s < 1e-12 {
            SO3::identity()
        } else {
            SO3::exp(&(ax / s * s.atan2(a.dot(&b))))
        }
    };
    // Initial velocities by central differences of the positions.
    let n = poses.len();
    let mut p0 = DVector::zeros(6 + 3 * n);
    p0.fixed_rows_mut::<3>(0).copy_from(&opts.initial_bias.gyro);
    p0.fixed_rows_mut::<3>(3).copy_from(&opts.initial_bias.acc);
    for k in 0..n {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let dt = (poses[b].t_ns - poses[a].t_ns) as f64 * 1e-9;
        p0.fixed_rows_mut::<3>(6 + 3 * k)
            .copy_from(&((poses[b].p - poses[a].p) / dt));
    }
    let mut x = (p0, rwg0);
    let mut bias_hat = opts.initial_bias;
    let mut iterations = 0;
    let mut solves = 0;
    let extra_r = 2.0 * opts.pose_rot_std.powi(2);
    let extra_p = 2.0 * opts.pose_pos_std.powi(2);
    loop {
        let mut pairs = Vec::with_capacity(n - 1);
        for w in poses.windows(2) {
            let pim = preintegrate(&opts.params, &bias_hat, samples, w[0].t_ns, w[1].t_ns)?;
            let mut cov = pim.cov;
            for i in 0..3 {
                cov[(i, i)] += extra_r;
                cov[(6 + i, 6 + i)] += extra_p;
            }
            let u = sqrt_information(&cov).map_err(|e| BiasError::InvalidParameter {
                name: "params",
                reason: format!("preintegration covariance: {e}"),
            })?;
            pairs.push(Pair { pim, u });
        }
        let problem = Problem {
            poses,
            pairs: &pairs,
            g0,
        };
        let sol = solve(problem, x.clone(), GaussNewton::default(), opts.max_iters)?;
        solves += 1;
        iterations += sol.iterations;
        let p = &sol.estimate.0;
        let b = ImuBias::new(
            Vector3::new(p[0], p[1], p[2]),
            Vector3::new(p[3], p[4], p[5]),
        );
        let moved = (b.gyro - bias_hat.gyro).norm() + (b.acc - bias_hat.acc).norm();
        x = sol.estimate.clone();
        bias_hat = b;
        if moved < 1e-6 || solves > opts.max_relinearizations {
            let cov = &sol.covariance;
            let s3 = |o: usize| Vector3::from_fn(|i, _| cov[(o + i, o + i)].max(0.0).sqrt());
            let np = p.len();
            let rwg = &x.1;
            let gd: Matrix3<f64> = -rwg.matrix() * hat(&g0);
            let cg: Matrix3<f64> = cov.fixed_view::<3, 3>(np, np).into_owned();
            let gcov = gd * cg * gd.transpose();
            let gravity = rwg.act(&g0);
            let cosang = (gravity.dot(&g_init) / (gravity.norm() * g_init.norm())).clamp(-1.0, 1.0);
            return Ok(KnownPoseCalibration {
                bias: b,
                gyro_bias_std: s3(0),
                acc_bias_std: s3(3),
                gravity,
                gravity_std: gcov.diagonal().map(|v| v.max(0.0).sqrt()),
                gravity_tilt: cosang.acos(),
                velocities: (0..n)
                    .map(|k| Vector3::new(p[6 + 3 * k], p[7 + 3 * k], p[8 + 3 * k]))
                    .collect(),
                velocity_std: (0..n).map(|k| s3(6 + 3 * k)).collect(),
                chi2: 2.0 * sol.cost,
                dof: sol.residual_count.saturating_sub(sol.rank),
                iterations,
                solves,
                stop: sol.stop,
            });
        }
    }
}
