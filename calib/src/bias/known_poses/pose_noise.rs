//! The noise of the known poses, propagated into the residuals (exact to first order,
//! correlations included), and the whitening by the resulting block-tridiagonal covariance.
//!
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

use super::KnownPose;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, Dyn, Matrix3, OMatrix, SMatrix, Vector3};
use preint::PreintegratedImu;
use preint_lie::{hat, jr_inv};

type M9 = SMatrix<f64, 9, 9>;
type M9x3 = SMatrix<f64, 9, 3>;

/// Jacobians of residual k w.r.t. the attitude noise of its IMU poses i and j (9×3 each), at
/// the preintegrated deltas (module docs); `q` is the lever arm in the IMU frame, through which
/// the attitude noise of the given poses also moves the IMU positions
/// ([`super::extrinsic`], "Pose noise"; zero for poses of the IMU).
pub(super) fn pose_noise_jacobians(
    pim: &PreintegratedImu,
    pi: &KnownPose,
    pj: &KnownPose,
    q: &Vector3<f64>,
) -> (M9x3, M9x3) {
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
    ai.fixed_rows_mut::<3>(6)
        .copy_from(&(hat(&pim.delta_p) + hat(q)));
    let mut aj = M9x3::zeros();
    aj.fixed_rows_mut::<3>(0).copy_from(&jri);
    aj.fixed_rows_mut::<3>(6)
        .copy_from(&(-(rjt_ri.matrix().transpose() * hat(q))));
    (ai, aj)
}

/// Block-tridiagonal residual covariance `blockdiag(Σ_imu) + A S Aᵀ` (module docs) for pose
/// standard deviations `s_r` \[rad\], `s_p` \[m\] of the IMU poses `poses` (lever arm `q` in
/// the IMU frame, [`pose_noise_jacobians`]): diagonal blocks and sub-diagonal blocks
/// `Σ_k,k−1` (`sub[0]` is zero).
pub(super) fn residual_covariance(
    pims: &[PreintegratedImu],
    poses: &[KnownPose],
    (s_r, s_p): (f64, f64),
    q: &Vector3<f64>,
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
        let (ai, aj) = pose_noise_jacobians(pim, pi, pj, q);
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

/// Lower-triangular inverse of the Cholesky factor of an N×N SPD matrix, `None` if not SPD.
fn chol_lower_inv<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    let sym = (m + m.transpose()) * 0.5;
    let l = sym.cholesky()?.l();
    let inv = l.try_inverse()?;
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

/// Whitening by the block Cholesky factor of a block-tridiagonal covariance (module docs):
/// `w_0 = L₀₀⁻¹ r_0`, `w_k = L_kk⁻¹ (r_k − M_k w_k−1)` with `M_k = Σ_k,k−1 L_k−1,k−1⁻ᵀ`,
/// `L_kk L_kkᵀ = Σ_kk − M_k M_kᵀ`.
/// Blocks of `N` rows: 9 for `[r_φ, r_v, r_p]`, 3 for attitudes only.
pub(super) struct Whitening<const N: usize = 9> {
    /// `L_kk⁻¹` per block.
    lkk_inv: Vec<SMatrix<f64, N, N>>,
    /// `M_k` (zero for k = 0, and for all k without pose noise).
    m: Vec<SMatrix<f64, N, N>>,
}

impl<const N: usize> Whitening<N> {
    /// `diag` = Σ_kk, `sub[k]` = Σ_k,k−1 (`sub[0]` unused); `None` if Σ is not positive
    /// definite.
    pub(super) fn new(diag: &[SMatrix<f64, N, N>], sub: &[SMatrix<f64, N, N>]) -> Option<Self> {
        let n = diag.len();
        let mut lkk_inv: Vec<SMatrix<f64, N, N>> = Vec::with_capacity(n);
        let mut m = Vec::with_capacity(n);
        for k in 0..n {
            let mk = if k == 0 {
                SMatrix::zeros()
            } else {
                sub[k] * lkk_inv[k - 1].transpose()
            };
            let schur = diag[k] - mk * mk.transpose();
            lkk_inv.push(chol_lower_inv(&schur)?);
            m.push(mk);
        }
        Some(Self { lkk_inv, m })
    }

    /// `L⁻¹x` for `x` with N rows per block: a residual vector or a Jacobian.
    pub(super) fn apply<C: Dim>(&self, mut x: OMatrix<f64, Dyn, C>) -> OMatrix<f64, Dyn, C>
    where
        DefaultAllocator: Allocator<Dyn, C> + Allocator<Const<N>, C>,
    {
        let mut prev: Option<OMatrix<f64, Const<N>, C>> = None;
        for k in 0..self.lkk_inv.len() {
            let mut xk: OMatrix<f64, Const<N>, C> = x.fixed_rows::<N>(N * k).into_owned();
            if let Some(p) = &prev
                && self.m[k].amax() > 0.0
            {
                xk -= self.m[k] * p;
            }
            let w = self.lkk_inv[k] * xk;
            x.fixed_rows_mut::<N>(N * k).copy_from(&w);
            prev = Some(w);
        }
        x
    }
}

#[cfg(test)]
mod tests {
    //! The pose-noise model against Ridders' numeric derivatives ([`crate::check_jacobian`]),
    //! and the block-tridiagonal whitening against a dense inverse.
    use super::super::test_data::{pims, setup};
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use nalgebra::{DMatrix, DVector, Vector3};
    use preint::{ImuBias, ImuNoise};
    use preint_lie::SO3;

    /// Noise-free data, its windows preintegrated at the true bias, and gravity.
    fn noise_free_at_the_truth() -> (
        super::super::test_data::Setup,
        Vec<PreintegratedImu>,
        Vector3<f64>,
    ) {
        let s = setup(ImuNoise::zero(200.0));
        let truth_bias = ImuBias::new(
            Vector3::new(0.004, -0.003, 0.006),
            Vector3::new(0.08, -0.05, 0.12),
        );
        let pims = pims(&s, &truth_bias);
        (s, pims, Vector3::new(0.0, 0.0, -9.81))
    }

    /// The pose-noise Jacobians `A` (module docs) against Ridders' derivative of the raw
    /// residual w.r.t. perturbations of the two poses (`R ← R·Exp(δφ)`, `p ← p + δp`), at the
    /// true state of noise-free data, where `[Δv]×`, `[Δp]×` equal the state-dependent terms
    /// `[R_iᵀ(v_j − v_i − gΔt)]×`, `[R_iᵀ(p_j − …)]×` up to the Hermite scheme's discretisation
    /// error of Δv, Δp on this scene (≈ 3e-7 m/s, 1.5e-7 m: relative errors up to ≈ 8e-6 on
    /// entries ≈ 0.02, hence the tolerance 3e-5; a wrong sign or block would give O(1)).
    #[test]
    fn pose_noise_jacobians_match_ridders_at_the_truth() {
        let (s, pims, g0) = noise_free_at_the_truth();
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
            let (ai, aj) = pose_noise_jacobians(pim, &pi, &pj, &Vector3::zeros());
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

    /// With poses of another frame b (the IMU 0.4 m away and turned by ≈ 60°), the Jacobians
    /// `A` (lever-arm terms included) times `R_bsᵀ` against Ridders' derivative of the raw
    /// residual w.r.t. attitude perturbations of the *given* poses, mapped to the IMU poses
    /// through the transform ([`super::super::extrinsic`]); same point and tolerance as above.
    /// Without the lever-arm terms the position rows are off by `|[q]×| ≈ 0.4`.
    #[test]
    fn pose_noise_jacobians_with_a_lever_arm_match_ridders() {
        use super::super::extrinsic::{imu_pose, lever_in_imu};
        let (s, pims, g0) = noise_free_at_the_truth();
        let x = preint::SensorPose::new(
            SO3::exp(&Vector3::new(0.7, 0.4, -0.6)),
            Vector3::new(0.2, -0.3, 0.15),
        );
        // The given poses: R_b = R_s R_bsᵀ, p_b = p_s − R_b p_bs.
        let given = |p: &KnownPose| {
            let r = p.r.compose(&x.rotation.inverse());
            KnownPose {
                t_ns: p.t_ns,
                r,
                p: p.p - r.act(&x.translation),
            }
        };
        let q = lever_in_imu(&x);
        for k in [0usize, 5, 11] {
            let pim = &pims[k];
            let (bi, bj) = (given(&s.poses[k]), given(&s.poses[k + 1]));
            let (vi, vj) = (s.truth[50 * k].v, s.truth[50 * (k + 1)].v);
            let raw = |n: &(SO3, SO3)| {
                let si = imu_pose(&KnownPose { r: n.0, ..bi }, &x);
                let sj = imu_pose(&KnownPose { r: n.1, ..bj }, &x);
                let rit = si.r.inverse();
                let dt = pim.delta_t;
                let rphi = pim.delta_r.inverse().compose(&rit.compose(&sj.r)).log();
                let rv = rit.act(&(vj - vi - g0 * dt)) - pim.delta_v;
                let rp = rit.act(&(sj.p - si.p - vi * dt - g0 * (0.5 * dt * dt))) - pim.delta_p;
                DVector::from_iterator(9, rphi.iter().chain(rv.iter()).chain(rp.iter()).copied())
            };
            let (ai, aj) = pose_noise_jacobians(pim, &s.poses[k], &s.poses[k + 1], &q);
            let rbs_t = x.rotation.inverse().matrix().into_owned();
            let opts = CheckOptions {
                tolerance: 3e-5,
                ..CheckOptions::default()
            };
            let rep = check_jacobian(
                raw,
                &(bi.r, bj.r),
                &[
                    crate::to_dmatrix(&(ai * rbs_t)),
                    crate::to_dmatrix(&(aj * rbs_t)),
                ],
                &opts,
            )
            .unwrap();
            println!(
                "pose-noise Jacobian with a lever arm, pair {k}: {:.2e}",
                rep.worst_rel_error
            );
        }
    }

    /// `‖L⁻¹r‖² = rᵀΣ⁻¹r` with Σ assembled densely from its blocks and inverted by nalgebra.
    #[test]
    fn block_tridiagonal_whitening_equals_dense_inverse() {
        let s = setup(ImuNoise::euroc());
        let pims = pims(&s, &ImuBias::zero());
        let (diag, sub) = residual_covariance(&pims, &s.poses, (3e-3, 5e-3), &Vector3::zeros());
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
            let j0 = DMatrix::from_fn(m, 2, |i, c| ((i + c) as f64).cos());
            let w = white.apply(r.clone());
            let jm = white.apply(j0.clone());
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
