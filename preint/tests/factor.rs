//! ImuFactor / CombinedImuFactor / NavState / predict: hand-computed values, every Jacobian block
//! against central differences on the manifold, whitening, typed errors.

use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};
use preint::ResidualMode;
use preint::edges::EdgeNoise;
use preint::sqrt_information;
use preint::{
    BiasJacobians, CombinedImuFactor, Cov9, Cov15, FactorError, ImuBias, ImuFactor, Level,
    NavState, PreintegratedImu, predict,
};
use preint_lie::{Manifold, SO3};

mod common;
use common::factor_vars::{NAMES, Rng, Vars, analytic, numeric};

fn random_pim(rng: &mut Rng, delta_r: SO3) -> PreintegratedImu {
    common::factor_vars::random_pim(rng, 1_000_000_000, Some(delta_r), None)
}

fn random_state(rng: &mut Rng) -> NavState {
    NavState::new(rng.rot(), rng.v3(5.0), rng.v3(2.0))
}

/// A state_j near the prediction (small residual) with a given offset in the NavState chart.
fn state_j_near(
    pim: &PreintegratedImu,
    xi: &NavState,
    b: &ImuBias,
    off: &SVector<f64, 9>,
) -> NavState {
    predict(pim, xi, b).retract(off)
}

fn assert_jac_close(ana: &DMatrix<f64>, num: &DMatrix<f64>, tol: f64, what: &str) {
    for c in 0..ana.ncols() {
        for r in 0..ana.nrows() {
            let (a, n) = (ana[(r, c)], num[(r, c)]);
            assert!(
                (a - n).abs() <= tol * (1.0 + a.abs()),
                "{what}: block {} row {r} col {}: analytic {a:e} numeric {n:e}",
                NAMES[c / 3],
                c % 3
            );
        }
    }
}

fn check_all_jacobians(pim: &PreintegratedImu, vars: &Vars, what: &str) {
    let f9 = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let (_, j9) = f9.evaluate(&vars.0, &vars.1, &vars.2);
    let num9 = numeric(vars, |v| f9.residual(&v.0, &v.1, &v.2), 1e-5);
    assert_jac_close(&analytic(&j9), &num9, 2e-7, what);

    let f15 = CombinedImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let (_, j15) = f15.evaluate(&vars.0, &vars.1, &vars.2, &vars.3);
    let num15 = numeric(vars, |v| f15.residual(&v.0, &v.1, &v.2, &v.3), 1e-5);
    assert_jac_close(&analytic(&j15), &num15, 2e-7, what);
}

#[test]
fn jacobians_match_central_differences_random_states() {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    for case in 0..25 {
        let pim = {
            let r = rng.rot();
            random_pim(&mut rng, r)
        };
        let xi = random_state(&mut rng);
        // Non-zero bias change: J δb_g up to ~0.07 rad.
        let bi = ImuBias::new(
            pim.bias_hat.gyro + rng.v3(0.1),
            pim.bias_hat.acc + rng.v3(0.5),
        );
        let bj = ImuBias::new(bi.gyro + rng.v3(0.01), bi.acc + rng.v3(0.05));
        // Residuals far from zero too: random offsets up to 0.8 rad / 1 m.
        let off = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 0.5);
        let xj = state_j_near(&pim, &xi, &bi, &off);
        check_all_jacobians(&pim, &(xi, xj, bi, bj), &format!("random case {case}"));
    }
}

#[test]
fn jacobians_with_relative_rotation_near_pi() {
    let mut rng = Rng(42);
    for (k, angle) in [std::f64::consts::PI - 1e-3, std::f64::consts::PI - 1e-7]
        .into_iter()
        .enumerate()
    {
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        let pim = random_pim(&mut rng, SO3::exp(&(axis * angle)));
        let xi = random_state(&mut rng);
        let bi = ImuBias::new(pim.bias_hat.gyro + rng.v3(0.02), pim.bias_hat.acc);
        let off = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 0.01);
        let xj = state_j_near(&pim, &xi, &bi, &off);
        // R_iᵀ R_j really is ~π away.
        let rel = xi.r.inverse().compose(&xj.r).log().norm();
        assert!(rel > 3.0, "relative rotation {rel}");
        check_all_jacobians(&pim, &(xi, xj, bi, bi), &format!("near-pi case {k}"));
    }
}

#[test]
fn jacobians_with_rotation_residual_of_large_angle() {
    // r_φ itself of 2.8 rad (inside the chart, away from the Log cut at π).
    let mut rng = Rng(7);
    let pim = {
        let r = rng.rot();
        random_pim(&mut rng, r)
    };
    let xi = random_state(&mut rng);
    let bi = ImuBias::new(pim.bias_hat.gyro + rng.v3(0.05), pim.bias_hat.acc);
    let mut off = SVector::<f64, 9>::zeros();
    off.fixed_rows_mut::<3>(0)
        .copy_from(&(Vector3::new(1.0, 2.0, -0.5).normalize() * 2.8));
    let xj = state_j_near(&pim, &xi, &bi, &off);
    let r = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise)
        .unwrap()
        .residual(&xi, &xj, &bi);
    assert!((r.fixed_rows::<3>(0).norm() - 2.8).abs() < 1e-9);
    check_all_jacobians(&pim, &(xi, xj, bi, bi), "large r_phi");
}

#[test]
fn jacobians_near_identity() {
    // ΔR = I, R_j = R_i, bias = bias_hat, state_j = prediction + 1e-9: every Log at θ → 0.
    let mut rng = Rng(3);
    let pim = random_pim(&mut rng, SO3::identity());
    let xi = NavState::new(SO3::identity(), rng.v3(1.0), rng.v3(1.0));
    let bi = pim.bias_hat;
    let off = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 1e-9);
    let xj = state_j_near(&pim, &xi, &bi, &off);
    check_all_jacobians(&pim, &(xi, xj, bi, bi), "near identity");
}

#[test]
fn residual_is_zero_at_the_prediction_and_equals_the_chart_offset_to_first_order() {
    let mut rng = Rng(11);
    let pim = {
        let r = rng.rot();
        random_pim(&mut rng, r)
    };
    let xi = random_state(&mut rng);
    let b = ImuBias::new(
        pim.bias_hat.gyro + rng.v3(0.05),
        pim.bias_hat.acc + rng.v3(0.2),
    );
    let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let xj = predict(&pim, &xi, &b);
    assert!(f.residual(&xi, &xj, &b).amax() < 1e-12);
    // Rotation residual offset: R_j ← R̂_j Exp(δ) gives r_φ = δ exactly.
    let d = Vector3::new(0.01, -0.02, 0.03);
    let xj2 = NavState::new(xj.r.plus(&d), xj.p, xj.v);
    let r = f.residual(&xi, &xj2, &b);
    assert!((r.fixed_rows::<3>(0) - d).amax() < 1e-14);
    assert!(r.fixed_rows::<6>(3).amax() < 1e-12);
}

#[test]
fn predict_free_fall_and_rest_by_hand() {
    // Free fall: the IMU measures zero specific force → ΔR = I, Δv = Δp = 0.
    let pim = PreintegratedImu {
        t_i_ns: 0,
        t_j_ns: 2_000_000_000,
        delta_t: 2.0,
        delta_r: SO3::identity(),
        delta_v: Vector3::zeros(),
        delta_p: Vector3::zeros(),
        cov: Cov9::identity(),
        cov15: Cov15::identity(),
        jac: BiasJacobians::default(),
        jac_td: Default::default(),
        bias_hat: ImuBias::zero(),
        gravity: Vector3::new(0.0, 0.0, -9.81),
        omega_coriolis: None,
        coriolis: preint::CoriolisMode::Exact,
        level: Level::Combined,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    };
    let xi = NavState::new(
        SO3::identity(),
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(1.0, 0.0, 0.0),
    );
    let xj = predict(&pim, &xi, &ImuBias::zero());
    assert!((xj.v - Vector3::new(1.0, 0.0, -19.62)).amax() < 1e-12);
    // p_j = p_i + v_i Δt + ½ g Δt² = (1 + 2, 2, 3 − 19.62)
    assert!((xj.p - Vector3::new(3.0, 2.0, 3.0 - 19.62)).amax() < 1e-12);

    // At rest, body rotated 90° about world x: body y = world z, so the accelerometer reads
    // +9.81 on body y; Δv = (0, 9.81, 0)·Δt, Δp = ½(0, 9.81, 0)·Δt².
    let rx = SO3::exp(&Vector3::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0));
    let rest = PreintegratedImu {
        delta_v: Vector3::new(0.0, 9.81 * 2.0, 0.0),
        delta_p: Vector3::new(0.0, 0.5 * 9.81 * 4.0, 0.0),
        ..pim.clone()
    };
    let xi = NavState::new(rx, Vector3::new(1.0, 2.0, 3.0), Vector3::zeros());
    let xj = predict(&rest, &xi, &ImuBias::zero());
    assert!(xj.v.amax() < 1e-12, "{:?}", xj.v);
    assert!((xj.p - xi.p).amax() < 1e-12, "{:?}", xj.p);
    assert!(xj.r.minus(&rx).norm() < 1e-15);

    // Bias correction by hand: Δv(b) = Δv + ∂Δv/∂b_a δb_a with ∂Δv/∂b_a = −Δt I.
    let biased = PreintegratedImu {
        jac: BiasJacobians {
            d_v_d_ba: -Matrix3::identity() * 2.0,
            ..BiasJacobians::default()
        },
        ..rest
    };
    let b = ImuBias::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 0.1));
    let xj = predict(&biased, &xi, &b);
    // v_j = R_i (0, 0, −0.2): R_x(90°) maps body z to world −y, so v_j = (0, 0.2, 0).
    assert!(
        (xj.v - Vector3::new(0.0, 0.2, 0.0)).amax() < 1e-12,
        "{:?}",
        xj.v
    );
}

#[test]
fn navstate_retract_local_roundtrip_and_perturbation_frames() {
    let mut rng = Rng(5);
    let x = random_state(&mut rng);
    let d = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 0.3);
    let y = x.retract(&d);
    assert!((x.local(&y) - d).amax() < 1e-14);
    // Position perturbation is in the body frame, velocity in the world frame.
    let mut dp = SVector::<f64, 9>::zeros();
    dp[3] = 1.0;
    let y = x.retract(&dp);
    assert!((y.p - x.p - x.r.matrix().column(0)).amax() < 1e-15);
    let mut dv = SVector::<f64, 9>::zeros();
    dv[6] = 1.0;
    assert!((x.retract(&dv).v - x.v - Vector3::x()).amax() < 1e-15);
    // Manifold impl agrees.
    let yy = Manifold::retract(&x, d.as_slice());
    let mut out = [0.0; 9];
    Manifold::local(&x, &yy, &mut out);
    assert!(
        (DVector::from_column_slice(&out) - DVector::from_column_slice(d.as_slice())).amax()
            < 1e-14
    );
    assert_eq!(Manifold::dim(&x), 9);
}

#[test]
fn whitening_is_upper_cholesky_of_information() {
    let mut rng = Rng(13);
    let pim = {
        let r = rng.rot();
        random_pim(&mut rng, r)
    };
    let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let u = *f.sqrt_information();
    for r in 0..9 {
        assert!(u[(r, r)] > 0.0);
        for c in 0..r {
            assert_eq!(u[(r, c)], 0.0, "U must be upper triangular");
        }
    }
    // UᵀU Σ = I.
    let prod = u.transpose() * u * pim.cov;
    assert!((prod - Cov9::identity()).amax() < 1e-9, "{prod}");
    // Unique: equals the transposed lower Cholesky factor of Σ⁻¹ (computed by nalgebra).
    let info = pim.cov.try_inverse().unwrap();
    let l = nalgebra::Cholesky::new(info).unwrap().l();
    assert!((u - l.transpose()).amax() < 1e-8 * u.amax());

    let xi = random_state(&mut rng);
    let b = pim.bias_hat;
    let xj = state_j_near(&pim, &xi, &b, &SVector::from_fn(|_, _| rng.s() * 0.01));
    let (r, j) = f.evaluate(&xi, &xj, &b);
    let (rw, jw) = f.evaluate_whitened(&xi, &xj, &b);
    assert!((rw - u * r).amax() < 1e-12 * rw.amax());
    assert!((jw.state_i() - u * j.state_i()).amax() < 1e-12 * jw.state_i().amax());
    assert!((jw.bias_i() - u * j.bias_i()).amax() < 1e-12 * jw.bias_i().amax());
    let chi2_ref = r.dot(&pim.cov.lu().solve(&r).unwrap());
    assert!((f.chi2(&xi, &xj, &b) - chi2_ref).abs() < 1e-9 * chi2_ref);
    assert!((f.cost(&xi, &xj, &b) - 0.5 * chi2_ref).abs() < 1e-9 * chi2_ref);
}

#[test]
fn chi2_by_hand_with_diagonal_covariance() {
    let mut rng = Rng(17);
    let mut pim = random_pim(&mut rng, SO3::identity());
    let sig = [0.01, 0.02, 0.03, 0.1, 0.2, 0.3, 1.0, 2.0, 3.0];
    pim.cov = Cov9::from_diagonal(&SVector::<f64, 9>::from_fn(|i, _| sig[i] * sig[i]));
    let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let u = f.sqrt_information();
    for i in 0..9 {
        assert!((u[(i, i)] - 1.0 / sig[i]).abs() < 1e-12 / sig[i]);
    }
    // r = (0.01, 0, 0, 0, 0.2, 0, 0, 0, 3): chi2 = 1 + 1 + 1 = 3.
    let xi = NavState::identity();
    let xj0 = predict(&pim, &xi, &pim.bias_hat);
    let xj = NavState::new(
        xj0.r.plus(&Vector3::new(0.01, 0.0, 0.0)),
        xj0.p + Vector3::new(0.0, 0.0, 3.0),
        xj0.v + Vector3::new(0.0, 0.2, 0.0),
    );
    assert!((f.chi2(&xi, &xj, &pim.bias_hat) - 3.0).abs() < 1e-9);
}

#[test]
fn typed_errors_instead_of_panics() {
    let mut rng = Rng(19);
    let pim = {
        let r = rng.rot();
        random_pim(&mut rng, r)
    };
    // Singular (noise-free) covariance.
    let z = PreintegratedImu {
        cov: Cov9::zeros(),
        ..pim.clone()
    };
    assert!(matches!(
        ImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::CovarianceNotPositiveDefinite { dim: 9, .. })
    ));
    // Rank-deficient but non-zero.
    let mut c = pim.cov;
    c.row_mut(4).fill(0.0);
    c.column_mut(4).fill(0.0);
    let z = PreintegratedImu {
        cov: c,
        ..pim.clone()
    };
    assert!(matches!(
        ImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::CovarianceNotPositiveDefinite { dim: 9, .. })
    ));
    // Indefinite.
    assert!(matches!(
        sqrt_information(&(-Cov9::identity())),
        Err(FactorError::CovarianceNotPositiveDefinite { .. })
    ));
    let mut c = pim.cov;
    c[(2, 3)] = f64::NAN;
    let z = PreintegratedImu {
        cov: c,
        ..pim.clone()
    };
    assert_eq!(
        ImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::NonFinite { field: "cov" })
    );
    let z = PreintegratedImu {
        delta_v: Vector3::new(f64::INFINITY, 0.0, 0.0),
        ..pim.clone()
    };
    assert_eq!(
        ImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::NonFinite { field: "delta_v" })
    );
    let z = PreintegratedImu {
        delta_t: 0.0,
        ..pim.clone()
    };
    assert!(matches!(
        ImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::NonPositiveDeltaT { .. })
    ));
    // Combined factor: zero bias random walk → singular cov15.
    let mut c15 = pim.cov15;
    c15.view_mut((9, 0), (6, 15)).fill(0.0);
    c15.view_mut((0, 9), (15, 6)).fill(0.0);
    let z = PreintegratedImu {
        cov15: c15,
        ..pim.clone()
    };
    assert!(matches!(
        CombinedImuFactor::with_mode(z, ResidualMode::ComponentWise),
        Err(FactorError::CovarianceNotPositiveDefinite { dim: 15, .. })
    ));
    // Non-finite state: non-finite residual, no panic.
    let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let bad = NavState::new(
        SO3::identity(),
        Vector3::new(f64::NAN, 0.0, 0.0),
        Vector3::zeros(),
    );
    assert!(
        !f.residual(&bad, &bad, &pim.bias_hat)
            .iter()
            .all(|x| x.is_finite())
    );
}

#[test]
fn combined_factor_bias_rows_and_whitening() {
    let mut rng = Rng(23);
    let pim = {
        let r = rng.rot();
        random_pim(&mut rng, r)
    };
    let f = CombinedImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let f9 = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let xi = random_state(&mut rng);
    let bi = ImuBias::new(rng.v3(0.01), rng.v3(0.1));
    let bj = ImuBias::new(
        bi.gyro + Vector3::new(1e-3, 2e-3, 3e-3),
        bi.acc + Vector3::new(-0.1, 0.0, 0.2),
    );
    let xj = state_j_near(&pim, &xi, &bi, &SVector::from_fn(|_, _| rng.s() * 0.01));
    let r = f.residual(&xi, &xj, &bi, &bj);
    assert_eq!(
        r.fixed_rows::<9>(0).into_owned(),
        f9.residual(&xi, &xj, &bi)
    );
    assert!(
        (r.fixed_rows::<6>(9)
            - SVector::<f64, 6>::from_column_slice(&[1e-3, 2e-3, 3e-3, -0.1, 0.0, 0.2]))
        .amax()
            < 1e-15
    );
    // The factor weights its residual [−δ, b_j − b_i] with D cov15 D, D = diag(−I₉, I₆)
    // (`PreintegratedImu::residual_cov15`), not with the error state's cov15.
    let d = Cov15::from_diagonal(&SVector::<f64, 15>::from_fn(
        |i, _| {
            if i < 9 { -1.0 } else { 1.0 }
        },
    ));
    let sigma_r = d * pim.cov15 * d;
    assert_eq!(pim.residual_cov15(), sigma_r);
    let u = f.sqrt_information();
    assert!((u.transpose() * u * sigma_r - Cov15::identity()).amax() < 1e-9);
    let chi2_ref = r.dot(&sigma_r.lu().solve(&r).unwrap());
    assert!((f.chi2(&xi, &xj, &bi, &bj) - chi2_ref).abs() < 1e-9 * chi2_ref);
    let (rw, jw) = f.evaluate_whitened(&xi, &xj, &bi, &bj);
    let (_, j) = f.evaluate(&xi, &xj, &bi, &bj);
    assert!((rw - u * r).amax() < 1e-12 * rw.amax());
    assert!((jw.bias_j() - u * j.bias_j()).amax() < 1e-12 * jw.bias_j().amax());
}

/// A factor needs the covariance it weights with: `CombinedImuFactor` rejects a
/// `Level::Covariance` measurement (its `cov15` lacks the random walk's effect on the deltas
/// and the cross blocks, yet is positive definite, so a Cholesky check alone would accept it),
/// `ImuFactor` rejects `Level::Deltas`.
#[test]
fn factors_check_the_level() {
    use preint::{ImuSample, PreintParams, Scheme, preintegrate};
    let s: Vec<_> = (0..101i64)
        .map(|k| {
            let t = k as f64 * 0.01;
            ImuSample::new(
                k * 10_000_000,
                Vector3::new(0.3 * t.sin(), 0.1, -0.2),
                Vector3::new(0.2, t.cos(), 9.81),
            )
        })
        .collect();
    let run = |level: Level| {
        let p = PreintParams::default()
            .with_scheme(Scheme::Midpoint)
            .with_level(level);
        preintegrate(&p, &ImuBias::zero(), &s, 0, 1_000_000_000).unwrap()
    };
    let cov = run(Level::Covariance);
    assert!(
        sqrt_information(&cov.cov15).is_ok(),
        "cov15 is positive definite"
    );
    assert_eq!(
        CombinedImuFactor::with_mode(cov.clone(), ResidualMode::ComponentWise),
        Err(FactorError::LevelTooLow {
            needed: Level::Combined,
            got: Level::Covariance
        })
    );
    assert!(ImuFactor::with_mode(cov, ResidualMode::ComponentWise).is_ok());
    assert!(
        CombinedImuFactor::with_mode(run(Level::Combined), ResidualMode::ComponentWise).is_ok()
    );
    let e = ImuFactor::with_mode(run(Level::Deltas), ResidualMode::ComponentWise).unwrap_err();
    assert_eq!(
        e,
        FactorError::LevelTooLow {
            needed: Level::Covariance,
            got: Level::Deltas
        }
    );
    assert!(e.to_string().contains("Deltas"), "{e}");
}

/// With the bias correction on the group ([`preint::BiasCorrection::Group`]), every block of
/// both factors (component-wise residual) against central differences at `δb ≠ 0`: the bias
/// blocks follow the group form's derivative (`preint::bias_correction`).
#[test]
fn jacobians_match_central_differences_with_group_bias_correction() {
    let mut rng = Rng(0x06A0_B1A5);
    for case in 0..20 {
        let mut pim = {
            let r = rng.rot();
            random_pim(&mut rng, r)
        };
        pim.bias_correction = preint::BiasCorrection::Group;
        let xi = random_state(&mut rng);
        // J_R δb_g up to ~0.15 rad, so the group and additive forms differ well above the
        // tolerance.
        let bi = ImuBias::new(
            pim.bias_hat.gyro + rng.v3(0.2),
            pim.bias_hat.acc + rng.v3(0.5),
        );
        let bj = ImuBias::new(bi.gyro + rng.v3(0.01), bi.acc + rng.v3(0.05));
        let off = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 0.5);
        let xj = state_j_near(&pim, &xi, &bi, &off);
        check_all_jacobians(&pim, &(xi, xj, bi, bj), &format!("group case {case}"));
        // The additive Jacobian is not the group one (the test can fail).
        let mut add = pim.clone();
        add.bias_correction = preint::BiasCorrection::Additive;
        let f_g = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
        let f_a = ImuFactor::with_mode(add, ResidualMode::ComponentWise).unwrap();
        let d = (f_g.evaluate(&xi, &xj, &bi).1.bg_i - f_a.evaluate(&xi, &xj, &bi).1.bg_i).amax();
        assert!(
            d > 1e-3,
            "group case {case}: bias blocks differ by only {d:e}"
        );
    }
}
