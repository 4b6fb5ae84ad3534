//! The bias random walk, marginalised: its covariance `Σ_w` over the stacked raw residual.
//!
//! The biases follow random walks of densities `σ_bg` \[rad/s²/√Hz\], `σ_ba` \[m/s³/√Hz\]
//! ([`ImuNoise`], Kalibr units). Write `b(t) = b̄ + w(t)` with `b̄ = b(t_ref)` and `w` a
//! two-sided Wiener process from `t_ref` (for every component, independent):
//!
//! ```text
//! Cov(w(s), w(t)) = σ_b² κ(s, t) I,   κ(s, t) = min(|s − t_ref|, |t − t_ref|)  if s, t on the same side of t_ref
//!                                                0                             otherwise
//! ```
//!
//! With a flat prior on `b̄` this is the same law of `b(·)` for every `t_ref` (increments are
//! independent with variance `σ_b²|t − s|`), so χ² does not depend on `t_ref`; `t_ref` only says
//! which bias `b̄` is. No parameter is added (the walk is integrated out), so the BIC's `k` stays
//! the number of calibration parameters.
//!
//! # Drift coefficients
//! Every raw residual block β (3 rows) gets, to first order, a drift term linear in the walk at
//! the sample times it uses, `d_β = Σ_i C_β,i w(t_i)`:
//!
//! - still interval k (N_k samples, both sensors): `e_ω,k`, `e_f,k` contain the interval means
//!   of the walk, `C_i = I/N_k` for every sample of the interval (the averaging over the
//!   interval's duration; centred on `t_ref`, the variance is `σ_b²T/12`, the static problem's
//!   term).
//! - link k (gyro): the link window is integrated with `b̄_g`, the truth with `b̄_g + w(t)`, so
//!   the midpoint increments differ by `δφ_j = −½Δt_j (w(t_j) + w(t_j+1))`, and
//!   `ΔR_true = Π Exp(φ_j + δφ_j) ≈ ΔR·Exp(Σ_j B_j δφ_j)` with `B_j = ΔR_j+1,nᵀ Jr(φ_j)`
//!   (the rotation from the end of step j to the end of the window). Hence
//!   `C_i = −½ (B_i−1 Δt_i−1 + B_i Δt_i)` (missing terms at the two ends are 0) and
//!   `Σ_i C_i = J_b` (a constant offset of the bias moves `e_R` by `J_b w`). Without rotation
//!   (`B_j = I`) `d = −∫ (b_g(t) − b̄_g) dt`, the bias drift integrated over the motion; with it
//!   the drift is carried to the end frame of the window ([`rotation_drift_coefficients`]).
//!
//! # Cross-covariance
//! `Cov(d_β, d_γ) = σ_b² Σ_i Σ_j C_β,i C_γ,jᵀ κ(t_i, t_j)`, and with
//! `min(a, b) = ∫₀^∞ 1[s ≤ a]·1[s ≤ b] ds` on each side of `t_ref` (`s = |t − t_ref|`):
//!
//! ```text
//! Cov(d_β, d_γ) = σ_b² Σ_sides ∫₀^∞ T_β(s) T_γ(s)ᵀ ds,     T_β(s) = Σ_{i on the side, s_i ≥ s} C_β,i
//! ```
//!
//! (step functions; O(n_β + n_γ) per pair after sorting, [`wiener_cross_covariance`]). For
//! blocks on the same side with all of β's samples nearer `t_ref` than all of γ's this is
//! `σ_b² (Σ_i C_β,i s_i)(Σ_j C_γ,j)ᵀ`: e.g. two interval means after `t_ref` covary by
//! `σ_b²·(mean time of the earlier one − t_ref)`. Blocks of different sensors are independent.
//! The coefficients are evaluated once, at the initial gyro bias and `S_g = I` (as `Σ_φ`; the
//! error is second order: products of the drift with the bias error or with `s_g`). `Σ_w` is
//! added to the white-noise part `D`, `Σ = L Lᵀ` by Cholesky (m ≈ 100), and the stacked
//! residual is whitened with `L⁻¹`.

use super::super::BiasError;
use super::super::still::StillInterval;
use super::data::Observations;
use nalgebra::{DMatrix, Matrix3, Vector3};
use preint::{ImuNoise, ImuSample, dt_seconds};
use preint_lie::SO3;

/// Per-sample drift coefficients `C_i` of a link rotation residual (module docs): to first
/// order, if the true gyro bias at sample i is `b_g + w_i` while the window is integrated
/// (midpoint rule, `S_g = I`) with the constant `b_g`,
/// `Log(ΔR(b_g)ᵀ ΔR_true) ≈ Σ_i C_i w_i`, with `C_i = −½(B_i−1 Δt_i−1 + B_i Δt_i)`,
/// `B_j = ΔR_j+1,nᵀ Jr(φ_j)`. Units: \[s\]. `Σ_i C_i = ∂ΔR/∂b_g` of
/// [`rotation_preintegration`](super::rotation_preintegration). One entry per sample; `samples`
/// must have increasing timestamps (not checked here).
pub fn rotation_drift_coefficients(samples: &[ImuSample], b_g: &Vector3<f64>) -> Vec<Matrix3<f64>> {
    let n = samples.len();
    let mut prefix = SO3::identity();
    // (ΔR_0,j+1 Jr(φ_j), Δt_j) per step j.
    let mut steps = Vec::with_capacity(n.saturating_sub(1));
    for w in samples.windows(2) {
        let dt = dt_seconds(w[0].t_ns, w[1].t_ns);
        let phi = (w[0].gyro + w[1].gyro - 2.0 * b_g) * (0.5 * dt);
        let (e, jr) = SO3::exp_jr(&phi);
        prefix = prefix.compose(&e);
        steps.push((prefix.matrix() * jr, dt));
    }
    // ΔR_j+1,nᵀ = ΔR_0,nᵀ ΔR_0,j+1.
    let total_t = prefix.matrix().transpose();
    let mut c = vec![Matrix3::zeros(); n];
    for (j, (pj, dt)) in steps.iter().enumerate() {
        let half = total_t * pj * (-0.5 * dt);
        c[j] += half;
        c[j + 1] += half;
    }
    c
}

/// `Σ_i Σ_j A_i B_jᵀ κ(t_i, t_j)` \[s × units of A·B\] for two linear functionals
/// `Σ_i A_i w(t_i)`, `Σ_j B_j w(t_j)` of a two-sided unit Wiener process from `t_ref_ns`
/// (module docs: `κ(s, t) = min(|s − t_ref|, |t − t_ref|)` on the same side, else 0): their
/// cross-covariance per unit random-walk density² (multiply by `σ_b²`). Terms are
/// `(t_ns, coefficient)` in any order; computed as `Σ_sides ∫₀^∞ T_A(s) T_B(s)ᵀ ds` over the
/// step functions `T(s) = Σ_{s_i ≥ s} C_i`, in O((n_A + n_B) log(n_A + n_B)).
///
/// ```
/// use nalgebra::Matrix3;
/// use preint_calib::bias::multipose::wiener_cross_covariance;
///
/// // w(2 s) and w(3 s) from t_ref = 0 covary by min(2, 3) = 2 s; w(−1 s) is independent.
/// let a = [(2_000_000_000, Matrix3::identity())];
/// let b = [(3_000_000_000, Matrix3::identity())];
/// let c = [(-1_000_000_000, Matrix3::identity())];
/// assert!((wiener_cross_covariance(&a, &b, 0) - Matrix3::identity() * 2.0).amax() < 1e-12);
/// assert_eq!(wiener_cross_covariance(&a, &c, 0), Matrix3::zeros());
/// ```
pub fn wiener_cross_covariance(
    a: &[(i64, Matrix3<f64>)],
    b: &[(i64, Matrix3<f64>)],
    t_ref_ns: i64,
) -> Matrix3<f64> {
    let mut out = Matrix3::zeros();
    for after in [true, false] {
        // (s [s], which functional, coefficient) of the terms strictly on this side.
        let mut ev: Vec<(f64, bool, &Matrix3<f64>)> = Vec::new();
        for (is_a, list) in [(true, a), (false, b)] {
            for (t, c) in list {
                let d = if after { t - t_ref_ns } else { t_ref_ns - t };
                if d > 0 {
                    ev.push((d as f64 * 1e-9, is_a, c));
                }
            }
        }
        ev.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut ta: Matrix3<f64> = ev.iter().filter(|e| e.1).map(|e| e.2).sum();
        let mut tb: Matrix3<f64> = ev.iter().filter(|e| !e.1).map(|e| e.2).sum();
        let mut s_prev = 0.0;
        for (s, is_a, c) in ev {
            if s > s_prev {
                out += ta * tb.transpose() * (s - s_prev);
                s_prev = s;
            }
            // T(s') for s' > s no longer holds this term.
            if is_a {
                ta -= c;
            } else {
                tb -= c;
            }
        }
    }
    out
}

/// Terms `(t_ns, C_i)` of a linear functional `Σ_i C_i w(t_i)` of a bias random walk.
type WalkTerms = Vec<(i64, Matrix3<f64>)>;

/// A drift functional of one residual block: its first row in the stacked residual and its
/// terms.
type Functional = (usize, WalkTerms);

/// The covariance `Σ = D + Σ_w` of the stacked raw residual at the truth: the block-diagonal
/// white-noise part `D` plus the random walk's (module docs).
pub(super) fn residual_covariance(
    samples: &[ImuSample],
    noise: &ImuNoise,
    obs: &Observations,
) -> DMatrix<f64> {
    let mut cov = white_noise_covariance(obs);
    let (gyro, acc) = drift_functionals(samples, obs);
    for (sigma, fs) in [
        (noise.gyro_random_walk, &gyro),
        (noise.acc_random_walk, &acc),
    ] {
        if sigma != 0.0 {
            add_walk_covariance(&mut cov, sigma, fs, obs.t_ref_ns);
        }
    }
    cov
}

/// `D`: per interval `s_ω² I`, `s_f² I`, per link `Σ_φ`.
fn white_noise_covariance(obs: &Observations) -> DMatrix<f64> {
    let k = obs.intervals.len();
    let m = 6 * k + 3 * obs.links.len();
    let mut cov = DMatrix::zeros(m, m);
    for (i, iv) in obs.intervals.iter().enumerate() {
        for c in 0..3 {
            cov[(6 * i + c, 6 * i + c)] = iv.s_w * iv.s_w;
            cov[(6 * i + 3 + c, 6 * i + 3 + c)] = iv.s_f * iv.s_f;
        }
    }
    for (l, link) in obs.links.iter().enumerate() {
        let row = 6 * k + 3 * l;
        cov.view_mut((row, row), (3, 3)).copy_from(&link.cov);
    }
    cov
}

/// The drift functionals of the gyro blocks (interval means, then links) and of the
/// accelerometer blocks (interval means).
fn drift_functionals(
    samples: &[ImuSample],
    obs: &Observations,
) -> (Vec<Functional>, Vec<Functional>) {
    let k = obs.intervals.len();
    let mean_terms = |iv: &StillInterval| {
        let c = Matrix3::identity() / iv.len() as f64;
        samples[iv.start..iv.end]
            .iter()
            .map(|s| (s.t_ns, c))
            .collect::<Vec<_>>()
    };
    let mut gyro = Vec::new();
    let mut acc = Vec::new();
    for (i, iv) in obs.ivs.iter().enumerate() {
        let terms = mean_terms(iv);
        gyro.push((6 * i, terms.clone()));
        acc.push((6 * i + 3, terms));
    }
    for (l, link) in obs.links.iter().enumerate() {
        let c = rotation_drift_coefficients(&link.samples, &obs.bg0);
        let terms = link.samples.iter().map(|s| s.t_ns).zip(c).collect();
        gyro.push((6 * k + 3 * l, terms));
    }
    (gyro, acc)
}

/// Adds `σ_b² Cov(d_β, d_γ)` for every pair of the functionals `fs` of one sensor.
fn add_walk_covariance(cov: &mut DMatrix<f64>, sigma: f64, fs: &[Functional], t_ref_ns: i64) {
    let s2 = sigma * sigma;
    for (a, (ra, ta)) in fs.iter().enumerate() {
        for (rb, tb) in &fs[a..] {
            let c = wiener_cross_covariance(ta, tb, t_ref_ns) * s2;
            let mut blk = cov.view_mut((*ra, *rb), (3, 3));
            blk += c;
            if ra != rb {
                let mut blk = cov.view_mut((*rb, *ra), (3, 3));
                blk += c.transpose();
            }
        }
    }
}

/// `W = L⁻¹` of the Cholesky factor `L Lᵀ = Σ` of [`residual_covariance`].
pub(super) fn whitening_matrix(
    samples: &[ImuSample],
    noise: &ImuNoise,
    obs: &Observations,
) -> Result<DMatrix<f64>, BiasError> {
    let cov = residual_covariance(samples, noise, obs);
    let m = cov.nrows();
    let chol = cov.cholesky().ok_or_else(|| BiasError::InvalidParameter {
        name: "noise",
        reason: "residual covariance with the bias random walk is not positive definite".into(),
    })?;
    chol.l()
        .solve_lower_triangular(&DMatrix::identity(m, m))
        .ok_or_else(|| BiasError::InvalidParameter {
            name: "noise",
            reason: "singular Cholesky factor of the residual covariance".into(),
        })
}

#[cfg(test)]
mod tests {
    use super::super::super::still::StillOptions;
    use super::super::data::prepare;
    use super::super::residuals::Problem;
    use super::super::test_data::{data, five_poses};
    use super::super::{MultiPoseModel, MultiPoseOptions, rotation_preintegration};
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use nalgebra::{DVector, SVector};
    use preint_sim::{MultiPoseStaticScene, SimConfig, simulate};

    /// [`wiener_cross_covariance`] against the definition `Σ_i Σ_j A_i B_jᵀ κ(t_i, t_j)`
    /// summed directly (O(n²)), for terms on both sides of `t_ref`, at `t_ref` and at equal
    /// times, in random order.
    #[test]
    fn wiener_cross_covariance_matches_the_double_sum() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let t_ref = 5_000_000_000i64;
        let mut terms = |n: usize| -> Vec<(i64, Matrix3<f64>)> {
            (0..n)
                .map(|i| {
                    let t = if i == 0 {
                        t_ref
                    } else if i == 1 {
                        t_ref + 1_000_000_000
                    } else {
                        rng.random_range(0..10_000_000_000i64)
                    };
                    (t, Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)))
                })
                .collect()
        };
        let (a, b) = (terms(40), terms(25));
        let kappa = |s: i64, t: i64| {
            let (ds, dt) = (s - t_ref, t - t_ref);
            if (ds > 0 && dt > 0) || (ds < 0 && dt < 0) {
                ds.abs().min(dt.abs()) as f64 * 1e-9
            } else {
                0.0
            }
        };
        for (x, y) in [(&a, &b), (&a, &a), (&b, &a)] {
            let mut direct = Matrix3::zeros();
            for (ti, ci) in x.iter() {
                for (tj, cj) in y.iter() {
                    direct += ci * cj.transpose() * kappa(*ti, *tj);
                }
            }
            let fast = wiener_cross_covariance(x, y, t_ref);
            assert!(
                (fast - direct).amax() < 1e-12 * direct.amax(),
                "{fast} vs {direct}"
            );
        }
    }

    /// The mean of a walk over an interval centred on `t_ref` has variance `σ_b²·T/12`
    /// (the static problem's term, `static_bias` module docs); two interval means after
    /// `t_ref` covary by `σ_b²·(mid-time of the earlier − t_ref)`; opposite sides: 0.
    #[test]
    fn interval_mean_variances_are_the_closed_forms() {
        let dt = 5_000_000i64; // 200 Hz
        let mean = |from: i64, n: usize| -> Vec<(i64, Matrix3<f64>)> {
            (0..n)
                .map(|i| (from + i as i64 * dt, Matrix3::identity() / n as f64))
                .collect()
        };
        let t_ref = 50 * dt * 1000;
        // 2001 samples centred on t_ref: T = 2001·Δt.
        let c = mean(t_ref - 1000 * dt, 2001);
        let t = 2001.0 * dt as f64 * 1e-9;
        let v = wiener_cross_covariance(&c, &c, t_ref)[(0, 0)];
        assert!((v / (t / 12.0) - 1.0).abs() < 1e-5, "{v} vs {}", t / 12.0);
        let a = mean(t_ref + 400 * dt, 600);
        let b = mean(t_ref + 1500 * dt, 300);
        let ab = wiener_cross_covariance(&a, &b, t_ref);
        let mid_a = (400.0 + 299.5) * dt as f64 * 1e-9;
        assert!((ab - Matrix3::identity() * mid_a).amax() < 1e-12, "{ab}");
        let earlier = mean(t_ref - 900 * dt, 300);
        assert_eq!(
            wiener_cross_covariance(&a, &earlier, t_ref),
            Matrix3::zeros()
        );
    }

    /// The link drift coefficients are the derivative of the rotation preintegration with
    /// respect to a per-sample bias perturbation: checked with Ridders ([`check_jacobian`]) on
    /// `θ ↦ ΔR(b_g + w(θ))`, `w_i(θ) = θ₀ + θ₁τ_i + θ₂ sin(2πτ_i)` (τ ∈ [0, 1] along a
    /// rotating window), and `Σ_i C_i = ∂ΔR/∂b_g`.
    #[test]
    fn rotation_drift_coefficients_are_the_per_sample_bias_derivative() {
        let (samples, _) = data();
        let seg = &samples[350..800];
        let bg = Vector3::new(0.002, -0.001, 0.003);
        let (t0, t1) = (seg[0].t_ns, seg[seg.len() - 1].t_ns);
        let tau = |t: i64| (t - t0) as f64 / (t1 - t0) as f64;
        let basis = |t: i64| [1.0, tau(t), (2.0 * std::f64::consts::PI * tau(t)).sin()];
        let f = |th: &SVector<f64, 9>| {
            let shifted: Vec<ImuSample> = seg
                .iter()
                .map(|s| {
                    let b = basis(s.t_ns);
                    let w = (0..3).fold(Vector3::zeros(), |acc, k| {
                        acc + th.fixed_rows::<3>(3 * k).into_owned() * b[k]
                    });
                    ImuSample::new(s.t_ns, s.gyro - w, s.acc)
                })
                .collect();
            rotation_preintegration(&shifted, &bg, &Vector3::zeros()).0
        };
        let c = rotation_drift_coefficients(seg, &bg);
        let mut jac = DMatrix::zeros(3, 9);
        for (s, ci) in seg.iter().zip(&c) {
            for (k, bk) in basis(s.t_ns).iter().enumerate() {
                let mut blk = jac.view_mut((0, 3 * k), (3, 3));
                blk += ci * *bk;
            }
        }
        let rep = check_jacobian(f, &SVector::zeros(), &[jac], &CheckOptions::default()).unwrap();
        println!("drift coefficients: {:.2e}", rep.worst_rel_error);
        let (_, jb, _) = rotation_preintegration(seg, &bg, &Vector3::zeros());
        let sum: Matrix3<f64> = c.iter().sum();
        assert!((sum - jb).amax() < 1e-12 * jb.amax(), "{sum} vs {jb}");
    }

    /// The random-walk covariance `Σ_w` against Monte Carlo: noise-free `sim` data of a
    /// 5-pose protocol (S = I), plus bias random walks drawn here, one-sided from the first
    /// sample (`b_k = b_k−1 + σ_b√Δt z_k`, the discrete random walk; not the model's two-sided
    /// construction), 1500 draws; the raw residuals at the truth (true attitudes,
    /// `b̄` = the drawn walk at `t_ref`) through the nonlinear residual function. Every entry of
    /// the empirical covariance is within 5 of its sampling standard deviations
    /// `√((Σ_ij² + Σ_ii Σ_jj)/n)` of `Σ_w`, and every variance within 5·√(2/n) relative.
    #[test]
    fn random_walk_covariance_matches_monte_carlo() {
        use rand::{RngExt, SeedableRng};
        use rand_distr::StandardNormal;
        let poses = five_poses();
        let scene = MultiPoseStaticScene::new(poses.clone(), 3.0, 2.0, Vector3::zeros()).unwrap();
        let clean = simulate(&scene, 200.0, scene.duration_s(), &SimConfig::default(), 1)
            .unwrap()
            .samples;
        let noise = ImuNoise::euroc();
        let base = MultiPoseOptions {
            still: Some(StillOptions::from_noise(&noise, 200.0)),
            include_random_walk: false,
            ..MultiPoseOptions::default()
        };
        let pr0 = prepare(&clean, &noise, &base, 9.81).unwrap();
        let white = ImuNoise {
            gyro_random_walk: 0.0,
            acc_random_walk: 0.0,
            ..noise
        };
        let sigma_w = residual_covariance(&clean, &noise, &pr0.obs)
            - residual_covariance(&clean, &white, &pr0.obs);
        let m = sigma_w.nrows();
        let k_ref = clean
            .iter()
            .position(|s| s.t_ns == pr0.obs.t_ref_ns)
            .unwrap();
        let dt = 0.005f64;
        let mut rng = rand::rngs::StdRng::seed_from_u64(99);
        let draws = 1500;
        let mut emp = DMatrix::<f64>::zeros(m, m);
        for _ in 0..draws {
            let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
            let mut walk = Vec::with_capacity(clean.len());
            for k in 0..clean.len() {
                if k > 0 {
                    let z = |rng: &mut rand::rngs::StdRng| {
                        Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal))
                    };
                    bg += z(&mut rng) * (noise.gyro_random_walk * dt.sqrt());
                    ba += z(&mut rng) * (noise.acc_random_walk * dt.sqrt());
                }
                walk.push((bg, ba));
            }
            let data: Vec<ImuSample> = clean
                .iter()
                .zip(&walk)
                .map(|(s, (g, a))| ImuSample::new(s.t_ns, s.gyro + g, s.acc + a))
                .collect();
            let pr = prepare(&data, &noise, &base, 9.81).unwrap();
            assert_eq!(pr.obs.ivs, pr0.obs.ivs);
            assert_eq!(pr.obs.t_ref_ns, pr0.obs.t_ref_ns);
            let problem = Problem {
                obs: &pr.obs,
                g: base.gravity,
                model: MultiPoseModel::BiasOnly,
                whitening: &pr.whitening,
            };
            let mut p = DVector::zeros(6);
            p.fixed_rows_mut::<3>(0).copy_from(&walk[k_ref].0);
            p.fixed_rows_mut::<3>(3).copy_from(&walk[k_ref].1);
            let (e, _) = problem.eval_raw(&(p, poses.clone()), false);
            emp += &e * e.transpose();
        }
        emp /= draws as f64;
        let n = draws as f64;
        let (mut worst, mut worst_var) = (0.0f64, 0.0f64);
        for i in 0..m {
            for j in 0..m {
                let (sij, sii, sjj) = (sigma_w[(i, j)], sigma_w[(i, i)], sigma_w[(j, j)]);
                let sd = ((sij * sij + sii * sjj) / n).sqrt();
                worst = worst.max((emp[(i, j)] - sij).abs() / sd);
            }
            worst_var = worst_var.max((emp[(i, i)] / sigma_w[(i, i)] - 1.0).abs());
        }
        println!(
            "Σ_w vs Monte Carlo ({draws} draws, {m} residuals): worst entry {worst:.2} sd, worst \
             variance ratio error {:.1} %",
            100.0 * worst_var
        );
        assert!(worst <= 5.0, "{worst}");
        assert!(worst_var <= 5.0 * (2.0 / n).sqrt(), "{worst_var}");
    }
}
