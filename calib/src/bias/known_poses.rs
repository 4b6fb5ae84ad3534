//! Biases, velocities and the gravity direction from segments with known poses (motion
//! capture or a VIO front end): the inertial-only initialisation of ORB-SLAM3 (Campos et al.
//! 2020, 2021) and VINS-Mono's gyro-bias estimation, with preintegration factors.
//!
//! # Model
//! Poses `(R̃_k, p̃_k)` (R_wb body → world, p \[m\] in the world) are measured at times
//! `t_0 < … < t_P−1`; for each consecutive pair the samples are preintegrated
//! ([`preint::preintegrate`]) at the current bias estimate `b̂`. Unknowns: `b = [b_g, b_a]`
//! (constant over the segment), the velocities `v_k` [m/s, world] at the pose times, and the
//! gravity direction `g = R_wg·g₀`, `g₀ = (0, 0, −|g|)`. `R_wg ∈ SO3` is perturbed on the right
//! by `(δ₀, δ₁, 0)` only: a rotation about `g₀` changes nothing, so the tangent has 2 DoF (as
//! ORB-SLAM3 zeroes that update component) and the problem has no gauge freedom.
//! Residual of the pair (i, j = i+1), Forster eq. 45 with the first-order bias correction
//! eq. 44 (see [`preint::factor`]), `Δt = t_j − t_i`, order **[r_φ, r_v, r_p]**:
//!
//! ```text
//! r_φ = Log(ΔR(b_g)ᵀ R̃_iᵀ R̃_j)
//! r_v = R̃_iᵀ(v_j − v_i − g Δt) − Δv(b)
//! r_p = R̃_iᵀ(p̃_j − p̃_i − v_i Δt − ½ g Δt²) − Δp(b)
//! ```
//!
//! Analytic Jacobians: `∂r_φ/∂b_g = −Jr⁻¹(r_φ) Eᵀ Jr(J_R δb_g) J_R` (`E = Exp(r_φ)`),
//! `∂r_v/∂b = −J_v`, `∂r_p/∂b = −J_p`, `∂r_v/∂v_i = −R̃_iᵀ`, `∂r_v/∂v_j = R̃_iᵀ`,
//! `∂r_p/∂v_i = −R̃_iᵀΔt`, `∂r_v/∂δ = −R̃_iᵀ G Δt`, `∂r_p/∂δ = −½Δt² R̃_iᵀ G` with
//! `G = ∂g/∂δ = −R_wg [g₀]×` restricted to its first two columns (checked against Ridders'
//! numeric Jacobian in this module's tests).
//!
//! # Pose noise (exact to first order, correlations included)
//! The known poses are noisy: `R̃ = R·Exp(n_R)`, `n_R ~ N(0, σ_R² I)` (body-frame attitude
//! error) and `p̃ = p + n_p`, `n_p ~ N(0, σ_p² I)` (world frame). An attitude error of pose i
//! enters all three residual blocks — `r_φ` through `−Jr⁻¹(r_φ) R̃_jᵀR̃_i`, `r_v` through
//! `[R̃_iᵀ(v_j − v_i − gΔt)]× ≈ [Δv]×` and `r_p` through `[R̃_iᵀ(p̃_j − …)]× ≈ [Δp]×` — and the
//! attitude error of pose j enters `r_φ` through `Jr⁻¹(r_φ)`; a position error enters `r_p`
//! through `∓R̃_iᵀ`. (With σ_R = 0.1° and |Δv| ≈ |g|·0.5 s the `r_v` term is ≈ 0.012 m/s, ten
//! times the IMU's own velocity noise over 0.5 s: leaving it out makes the velocities wrong by
//! decimetres per second on EuRoC.) With `A_k` the 9×12 Jacobian of residual k w.r.t. the noise
//! of its two poses, the residuals' covariance is
//!
//! ```text
//! Σ = blockdiag(Σ_imu,k) + A S Aᵀ      (S = diag(σ_R² I, σ_p² I) per pose)
//! ```
//!
//! which is **block tridiagonal**: consecutive factors share a pose, and that correlation is
//! kept (`Σ_k,k−1 = A_k^(i) S A_k−1^(j)ᵀ`). Whitening uses its block Cholesky factor `Σ = LLᵀ`
//! (L block lower bidiagonal, O(P) 9×9 blocks): `r_w = L⁻¹r`, `J_w = L⁻¹J`. This is the same
//! estimator, to first order in the pose noise, as making every pose a state with a prior of
//! that noise (the poses marginalised out analytically), at the cost of the small problem
//! (`6 + 3P + 2` unknowns instead of `9P + 8`). `A` is evaluated at the preintegrated deltas of
//! the current linearisation (`[Δv]×`, `[Δp]×` in place of the state-dependent terms, equal at
//! the solution up to the residual; `r_φ` at `b̂`) and refreshed at every re-linearisation, so
//! the weights are constant within one Gauss-Newton solve. Neglected: the second-order effect
//! of the pose noise (≈ σ_R²), and the correlation of the IMU noise between windows that share
//! a boundary sample (standard in preintegration).
//!
//! Because the bias correction is first order, the problem is re-linearised: after a solve
//! the windows are re-integrated at the new bias and the problem solved again, until the bias
//! moves by less than 1e-6 (or `max_relinearizations`).
//!
//! Limits: the biases are constant over the segment (over T seconds a random walk of density
//! σ_b moves them by ≈ σ_b√T, e.g. 0.013 m/s² in 20 s for EuRoC's σ_ba: keep segments short or
//! expect that much model error); dense linear algebra, O(P³) per iteration.

use super::{BiasError, check_samples};
use crate::gauss_newton::{GaussNewton, LeastSquares, StopReason, solve};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x2, SMatrix, Vector3};
use preint::{ImuBias, ImuSample, PreintParams, PreintegratedImu, preintegrate};
use preint_lie::{Manifold, SO3, hat, jr, jr_inv};

type M9 = SMatrix<f64, 9, 9>;
type M9x3 = SMatrix<f64, 9, 3>;

/// A known pose: time \[ns\], attitude R_wb (body → world) and position p [m, world].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownPose {
    /// Time \[ns\].
    pub t_ns: i64,
    /// Attitude R_wb.
    pub r: SO3,
    /// Position \[m\].
    pub p: Vector3<f64>,
}

/// Options of [`calibrate_known_poses`].
#[derive(Clone, Debug, PartialEq)]
pub struct KnownPoseOptions {
    /// Preintegration parameters (noise densities, scheme; its `gravity` gives the initial
    /// gravity vector and its magnitude |g|).
    pub params: PreintParams,
    /// Standard deviation σ_R \[rad\] of each known attitude, `R̃ = R·Exp(n_R)`,
    /// `n_R ~ N(0, σ_R² I)` (default 0: exact attitudes).
    pub pose_rot_std: f64,
    /// Standard deviation σ_p \[m\] of each known position per world axis (default 0).
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

/// Result of [`calibrate_known_poses`]. Standard deviations come from the solver covariance
/// of the whitened problem (predicted from the noise densities and the pose noise, not
/// rescaled by the residuals); compare [`KnownPoseCalibration::chi2_per_dof`] with 1.
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
    /// Standard deviation of each component of `gravity` [m/s²] (the component along gravity
    /// has ≈ 0: only the direction is estimated).
    pub gravity_std: Vector3<f64>,
    /// Angle between the estimated gravity and the initial one \[rad\].
    pub gravity_tilt: f64,
    /// Velocities at the pose times [m/s, world].
    pub velocities: Vec<Vector3<f64>>,
    /// Their standard deviations [m/s].
    pub velocity_std: Vec<Vector3<f64>>,
    /// χ² of the whitened residuals.
    pub chi2: f64,
    /// Degrees of freedom: residuals − unknowns = `9(P − 1) − (3P + 8)`.
    pub dof: usize,
    /// Total Gauss-Newton iterations.
    pub iterations: u64,
    /// Number of solves (re-linearisations + 1).
    pub solves: usize,
    /// Why the last solve stopped.
    pub stop: StopReason,
}

impl KnownPoseCalibration {
    /// `χ²/dof` (≈ 1 when the noise densities and pose noise are right; NaN for dof = 0).
    pub fn chi2_per_dof(&self) -> f64 {
        if self.dof == 0 {
            f64::NAN
        } else {
            self.chi2 / self.dof as f64
        }
    }
}

/// Gravity direction `R_wg` with the 2-DoF right perturbation `R_wg·Exp((δ₀, δ₁, 0))` (module
/// docs). `local` returns the first two components of `Log(R_aᵀR_b)`, the inverse of
/// `retract` for perturbations of that form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GravityDir(pub(crate) SO3);

impl Manifold for GravityDir {
    fn dim(&self) -> usize {
        2
    }
    fn retract(&self, d: &[f64]) -> Self {
        GravityDir(self.0.plus(&Vector3::new(d[0], d[1], 0.0)))
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        let v = o.0.minus(&self.0);
        out[0] = v.x;
        out[1] = v.y;
    }
}

impl GravityDir {
    /// `g = R_wg·g₀` and `G = ∂g/∂δ = −R_wg [g₀]×` (first two columns).
    fn gravity(&self, g0: &Vector3<f64>) -> (Vector3<f64>, Matrix3x2<f64>) {
        let full: Matrix3<f64> = -self.0.matrix() * hat(g0);
        (self.0.act(g0), full.fixed_columns::<2>(0).into_owned())
    }
}

/// Lower-triangular inverse of the Cholesky factor of a 9×9 SPD matrix, `None` if not SPD.
fn chol_lower_inv(m: &M9) -> Option<M9> {
    let sym = (m + m.transpose()) * 0.5;
    let l = sym.cholesky()?.l();
    let inv = l.try_inverse()?;
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

/// Whitening by the block Cholesky factor of a block-tridiagonal covariance (module docs):
/// `w_0 = L₀₀⁻¹ r_0`, `w_k = L_kk⁻¹ (r_k − M_k w_k−1)` with `M_k = Σ_k,k−1 L_k−1,k−1⁻ᵀ`,
/// `L_kk L_kkᵀ = Σ_kk − M_k M_kᵀ`.
struct Whitening {
    /// `L_kk⁻¹` per block.
    lkk_inv: Vec<M9>,
    /// `M_k` (zero for k = 0, and for all k without pose noise).
    m: Vec<M9>,
}

impl Whitening {
    /// `diag` = Σ_kk, `sub[k]` = Σ_k,k−1 (`sub[0]` unused).
    fn new(diag: &[M9], sub: &[M9]) -> Option<Self> {
        let n = diag.len();
        let mut lkk_inv: Vec<M9> = Vec::with_capacity(n);
        let mut m = Vec::with_capacity(n);
        for k in 0..n {
            let mk = if k == 0 {
                M9::zeros()
            } else {
                sub[k] * lkk_inv[k - 1].transpose()
            };
            let schur = diag[k] - mk * mk.transpose();
            lkk_inv.push(chol_lower_inv(&schur)?);
            m.push(mk);
        }
        Some(Self { lkk_inv, m })
    }

    /// Whitens `r` (9 rows per block) and, if given, `j` in place.
    fn apply(&self, r: &mut DVector<f64>, j: Option<&mut DMatrix<f64>>) {
        let mut prev = SMatrix::<f64, 9, 1>::zeros();
        for k in 0..self.lkk_inv.len() {
            let rk: SMatrix<f64, 9, 1> = r.fixed_rows::<9>(9 * k).into_owned();
            let w = self.lkk_inv[k] * (rk - self.m[k] * prev);
            r.fixed_rows_mut::<9>(9 * k).copy_from(&w);
            prev = w;
        }
        if let Some(j) = j {
            let n = j.ncols();
            let mut prev = DMatrix::<f64>::zeros(9, n);
            let li = |m: &M9| DMatrix::from_column_slice(9, 9, m.as_slice());
            for k in 0..self.lkk_inv.len() {
                let mut jk = j.rows(9 * k, 9).into_owned();
                if k > 0 && self.m[k].amax() > 0.0 {
                    jk -= li(&self.m[k]) * &prev;
                }
                let w = li(&self.lkk_inv[k]) * jk;
                j.rows_mut(9 * k, 9).copy_from(&w);
                prev = w;
            }
        }
    }
}

struct Problem<'a> {
    poses: &'a [KnownPose],
    pims: &'a [PreintegratedImu],
    g0: Vector3<f64>,
    white: &'a Whitening,
}

impl Problem<'_> {
    /// Unwhitened residual (9 per pair) and Jacobian.
    fn raw(&self, x: &(DVector<f64>, GravityDir), want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
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
        let (g, gd) = rwg.gravity(&self.g0);
        for (k, pim) in self.pims.iter().enumerate() {
            let (pi, pj) = (&self.poses[k], &self.poses[k + 1]);
            let (vi, vj) = (v3(6 + 3 * k), v3(6 + 3 * k + 3));
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
            let row = 9 * k;
            r.fixed_rows_mut::<3>(row).copy_from(&rphi);
            r.fixed_rows_mut::<3>(row + 3).copy_from(&rv);
            r.fixed_rows_mut::<3>(row + 6).copy_from(&rp);
            if !want_j {
                continue;
            }
            let ritm = *rit.matrix();
            j.view_mut((row, 0), (3, 3))
                .copy_from(&(-jr_inv(&rphi) * e.matrix().transpose() * jr(&phi_b) * jb.d_r_d_bg));
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
        }
        (r, j)
    }
}

impl LeastSquares for Problem<'_> {
    /// ([b_g, b_a, v_0, …, v_P−1], R_wg with its 2-DoF tangent).
    type State = (DVector<f64>, GravityDir);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        let (mut r, mut j) = self.raw(x, true);
        self.white.apply(&mut r, Some(&mut j));
        (r, j)
    }
    fn residual(&self, x: &Self::State) -> DVector<f64> {
        let (mut r, _) = self.raw(x, false);
        self.white.apply(&mut r, None);
        r
    }
}

/// Jacobians of residual k w.r.t. the attitude noise of its poses i and j (9×3 each), at the
/// preintegrated deltas (module docs).
fn pose_noise_jacobians(pim: &PreintegratedImu, pi: &KnownPose, pj: &KnownPose) -> (M9x3, M9x3) {
    let rjt_ri = pj.r.inverse().compose(&pi.r);
    let rphi = pim
        .delta_r
        .inverse()
        .compose(&pi.r.inverse().compose(&pj.r))
        .log();
    let jri = jr_inv(&rphi);
    let mut ai = M9x3::zeros();
    ai.fixed_rows_mut::<3>(0)
        .copy_from(&(-jri * rjt_ri.matrix()));
    ai.fixed_rows_mut::<3>(3).copy_from(&hat(&pim.delta_v));
    ai.fixed_rows_mut::<3>(6).copy_from(&hat(&pim.delta_p));
    let mut aj = M9x3::zeros();
    aj.fixed_rows_mut::<3>(0).copy_from(&jri);
    (ai, aj)
}

/// Block-tridiagonal residual covariance `blockdiag(Σ_imu) + A S Aᵀ` (module docs): diagonal
/// blocks and sub-diagonal blocks `Σ_k,k−1`.
fn residual_covariance(
    pims: &[PreintegratedImu],
    poses: &[KnownPose],
    s_r: f64,
    s_p: f64,
) -> (Vec<M9>, Vec<M9>) {
    let (vr, vp) = (s_r * s_r, s_p * s_p);
    let pos_rows = |rit: &Matrix3<f64>| {
        let mut a = M9x3::zeros();
        a.fixed_rows_mut::<3>(6).copy_from(rit);
        a
    };
    let mut diag = Vec::with_capacity(pims.len());
    let mut sub = Vec::with_capacity(pims.len());
    let mut prev_j: Option<(M9x3, M9x3)> = None;
    for (k, pim) in pims.iter().enumerate() {
        let (pi, pj) = (&poses[k], &poses[k + 1]);
        let (ai, aj) = pose_noise_jacobians(pim, pi, pj);
        let rit = *pi.r.inverse().matrix();
        let (bi, bj) = (pos_rows(&(-rit)), pos_rows(&rit));
        diag.push(
            pim.cov
                + (ai * ai.transpose() + aj * aj.transpose()) * vr
                + (bi * bi.transpose() + bj * bj.transpose()) * vp,
        );
        sub.push(match prev_j {
            Some((aj_prev, bj_prev)) => {
                ai * aj_prev.transpose() * vr + bi * bj_prev.transpose() * vp
            }
            None => M9::zeros(),
        });
        prev_j = Some((aj, bj));
    }
    (diag, sub)
}

/// Estimates `b_g`, `b_a`, the velocities at the pose times and the gravity direction from
/// IMU samples and known (optionally noisy) poses (module docs).
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
    if poses
        .iter()
        .any(|p| !(p.p.iter().all(|v| v.is_finite()) && p.r.matrix().iter().all(|v| v.is_finite())))
    {
        return Err(BiasError::InvalidParameter {
            name: "poses",
            reason: "non-finite position or attitude".into(),
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
    let gnorm = opts.params.gravity.norm();
    if !(gnorm.is_finite() && gnorm > 0.0) {
        return Err(BiasError::InvalidParameter {
            name: "params.gravity",
            reason: "must be finite and non-zero".into(),
        });
    }
    let g0 = Vector3::new(0.0, 0.0, -gnorm);
    let g_init = opts.params.gravity;
    // R_wg with R_wg·g0 = g_init (minimal rotation).
    let rwg0 = {
        let a = g0.normalize();
        let b = g_init.normalize();
        let ax = a.cross(&b);
        let s = ax.norm();
        if s < 1e-12 {
            if a.dot(&b) > 0.0 {
                SO3::identity()
            } else {
                SO3::exp(&Vector3::new(std::f64::consts::PI, 0.0, 0.0))
            }
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
    let mut x = (p0, GravityDir(rwg0));
    let mut bias_hat = opts.initial_bias;
    let mut iterations = 0;
    let mut solves = 0;
    loop {
        let mut pims = Vec::with_capacity(n - 1);
        for w in poses.windows(2) {
            pims.push(preintegrate(
                &opts.params,
                &bias_hat,
                samples,
                w[0].t_ns,
                w[1].t_ns,
            )?);
        }
        let (diag, sub) = residual_covariance(&pims, poses, opts.pose_rot_std, opts.pose_pos_std);
        let white = Whitening::new(&diag, &sub).ok_or_else(|| BiasError::InvalidParameter {
            name: "params",
            reason: "the residual covariance (preintegration + pose noise) is not positive \
                     definite: give non-zero noise densities"
                .into(),
        })?;
        let problem = Problem {
            poses,
            pims: &pims,
            g0,
            white: &white,
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
            let (gravity, gd) = x.1.gravity(&g0);
            let cg = cov.fixed_view::<2, 2>(np, np).into_owned();
            let gcov = gd * cg * gd.transpose();
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

#[cfg(test)]
mod tests {
    //! The problem's analytic Jacobian and the pose-noise model against Ridders' numeric
    //! derivatives ([`crate::check_jacobian`]), and the block-tridiagonal whitening against a
    //! dense inverse.
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint::{ImuNoise, Scheme};
    use preint_sim::{EulerScene, SimConfig, simulate};

    struct Setup {
        samples: Vec<ImuSample>,
        truth: Vec<preint_sim::GroundTruthState>,
        poses: Vec<KnownPose>,
        params: PreintParams,
    }

    /// 3 s of the `aggressive` scene at 200 Hz, poses every 0.25 s from the ground truth.
    fn setup(noise: ImuNoise) -> Setup {
        let cfg = SimConfig {
            noise,
            initial_bias: ImuBias::new(
                Vector3::new(0.004, -0.003, 0.006),
                Vector3::new(0.08, -0.05, 0.12),
            ),
            bias_random_walk: false,
            ..SimConfig::default()
        };
        let out = simulate(&EulerScene::aggressive(), 200.0, 3.0, &cfg, 3).unwrap();
        let poses = (0..=12)
            .map(|k| {
                let st = &out.truth[50 * k];
                KnownPose {
                    t_ns: st.t_ns,
                    r: st.rotation(),
                    p: st.p,
                }
            })
            .collect();
        let params = PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(Scheme::Hermite4);
        Setup {
            samples: out.samples,
            truth: out.truth,
            poses,
            params,
        }
    }

    fn pims(s: &Setup, b: &ImuBias) -> Vec<PreintegratedImu> {
        s.poses
            .windows(2)
            .map(|w| preintegrate(&s.params, b, &s.samples, w[0].t_ns, w[1].t_ns).unwrap())
            .collect()
    }

    #[test]
    fn analytic_jacobian_matches_ridders_with_pose_noise_whitening() {
        let s = setup(ImuNoise::euroc());
        let bias_hat = ImuBias::new(Vector3::new(0.003, -0.002, 0.005), Vector3::zeros());
        let pims = pims(&s, &bias_hat);
        let (diag, sub) = residual_covariance(&pims, &s.poses, 2e-3, 4e-3);
        let white = Whitening::new(&diag, &sub).unwrap();
        let g0 = Vector3::new(0.0, 0.0, -9.81);
        let problem = Problem {
            poses: &s.poses,
            pims: &pims,
            g0,
            white: &white,
        };
        let n = s.poses.len();
        // Away from the optimum: biases off by 1e-3 rad/s and 0.05 m/s², velocities off,
        // gravity tilted by ≈ 3°.
        let mut p = DVector::zeros(6 + 3 * n);
        p.fixed_rows_mut::<3>(0)
            .copy_from(&Vector3::new(0.005, -0.004, 0.007));
        p.fixed_rows_mut::<3>(3)
            .copy_from(&Vector3::new(0.1, -0.02, 0.15));
        for k in 0..n {
            let v = s.truth[50 * k].v + Vector3::new(0.01, -0.02, 0.005) * k as f64;
            p.fixed_rows_mut::<3>(6 + 3 * k).copy_from(&v);
        }
        let x = (p, GravityDir(SO3::exp(&Vector3::new(0.04, -0.03, 0.2))));
        let (_, j) = problem.residual_jacobian(&x);
        let np = 6 + 3 * n;
        let blocks = [j.columns(0, np).into_owned(), j.columns(np, 2).into_owned()];
        let rep = check_jacobian(
            |x: &(DVector<f64>, GravityDir)| problem.residual(x),
            &x,
            &blocks,
            &CheckOptions::default(),
        )
        .unwrap();
        println!(
            "known-pose problem: worst relative error {:.2e}",
            rep.worst_rel_error
        );
    }

    /// The pose-noise Jacobians `A` (module docs) against Ridders' derivative of the raw
    /// residual w.r.t. perturbations of the two poses (`R ← R·Exp(δφ)`, `p ← p + δp`), at the
    /// true state of noise-free data, where `[Δv]×`, `[Δp]×` equal the state-dependent terms
    /// `[R_iᵀ(v_j − v_i − gΔt)]×`, `[R_iᵀ(p_j − …)]×` up to rk4's discretisation error of Δv, Δp
    /// on this scene (≈ 3e-7 m/s, 1.5e-7 m: relative errors up to ≈ 8e-6 on entries ≈ 0.02,
    /// hence the tolerance 3e-5; a wrong sign or block would give O(1)).
    #[test]
    fn pose_noise_jacobians_match_ridders_at_the_truth() {
        let s = setup(ImuNoise::zero(200.0));
        let truth_bias = ImuBias::new(
            Vector3::new(0.004, -0.003, 0.006),
            Vector3::new(0.08, -0.05, 0.12),
        );
        let pims = pims(&s, &truth_bias);
        let g0 = Vector3::new(0.0, 0.0, -9.81);
        for k in [0usize, 5, 11] {
            let pim = &pims[k];
            let (pi, pj) = (s.poses[k], s.poses[k + 1]);
            let (vi, vj) = (s.truth[50 * k].v, s.truth[50 * (k + 1)].v);
            let raw = |x: &(SO3, Vector3<f64>, SO3, Vector3<f64>)| {
                let rit = x.0.inverse();
                let dt = pim.delta_t;
                let rphi = pim.delta_r.inverse().compose(&rit.compose(&x.2)).log();
                let rv = rit.act(&(vj - vi - g0 * dt)) - pim.delta_v;
                let rp = rit.act(&(x.3 - x.1 - vi * dt - g0 * (0.5 * dt * dt))) - pim.delta_p;
                DVector::from_iterator(9, rphi.iter().chain(rv.iter()).chain(rp.iter()).copied())
            };
            let (ai, aj) = pose_noise_jacobians(pim, &pi, &pj);
            let rit = *pi.r.inverse().matrix();
            let mut bi = DMatrix::zeros(9, 3);
            bi.view_mut((6, 0), (3, 3)).copy_from(&(-rit));
            let mut bj = DMatrix::zeros(9, 3);
            bj.view_mut((6, 0), (3, 3)).copy_from(&rit);
            let opts = CheckOptions {
                tolerance: 3e-5,
                ..CheckOptions::default()
            };
            let rep = check_jacobian(
                raw,
                &(pi.r, pi.p, pj.r, pj.p),
                &[crate::to_dmatrix(&ai), bi, crate::to_dmatrix(&aj), bj],
                &opts,
            )
            .unwrap();
            println!("pose-noise Jacobian, pair {k}: {:.2e}", rep.worst_rel_error);
        }
    }

    /// `‖L⁻¹r‖² = rᵀΣ⁻¹r` with Σ assembled densely from its blocks and inverted by nalgebra.
    #[test]
    fn block_tridiagonal_whitening_equals_dense_inverse() {
        let s = setup(ImuNoise::euroc());
        let pims = pims(&s, &ImuBias::zero());
        let (diag, sub) = residual_covariance(&pims, &s.poses, 3e-3, 5e-3);
        let white = Whitening::new(&diag, &sub).unwrap();
        let m = 9 * diag.len();
        let mut dense = DMatrix::zeros(m, m);
        for k in 0..diag.len() {
            dense.view_mut((9 * k, 9 * k), (9, 9)).copy_from(&diag[k]);
            if k > 0 {
                dense
                    .view_mut((9 * k, 9 * (k - 1)), (9, 9))
                    .copy_from(&sub[k]);
                dense
                    .view_mut((9 * (k - 1), 9 * k), (9, 9))
                    .copy_from(&sub[k].transpose());
            }
        }
        let inv = dense.clone().try_inverse().unwrap();
        for t in 0..3 {
            let r = DVector::from_fn(m, |i, _| ((i * 7 + t * 13) as f64 * 0.37).sin() * 1e-3);
            let mut w = r.clone();
            let mut jm = DMatrix::from_fn(m, 2, |i, c| ((i + c) as f64).cos());
            let j0 = jm.clone();
            white.apply(&mut w, Some(&mut jm));
            let q = (r.transpose() * &inv * &r)[(0, 0)];
            assert!(
                (w.norm_squared() / q - 1.0).abs() < 1e-9,
                "{} vs {q}",
                w.norm_squared()
            );
            let jj = j0.transpose() * &inv * &j0;
            assert!((jm.transpose() * &jm - &jj).amax() < 1e-9 * jj.amax());
        }
        // Consecutive residuals share a pose: the correlation is really there.
        assert!(sub[1].amax() > 0.1 * diag[1].amax().sqrt() * diag[0].amax().sqrt() * 1e-3);
    }
}
