//! The SE₂(3) Logmap residual of both factors ([`ResidualMode::Logmap`]): every Jacobian block
//! against central differences on the manifold (with and without an Earth rate, residuals far
//! from zero, a bias change), the residual against an independent SE(3) logarithm, its
//! weighting, and the component-wise path left as it is.

use nalgebra::{DMatrix, SMatrix, SVector, Vector3};
use preint::{
    CombinedImuFactor, CoriolisMode, ImuBias, ImuFactor, NavState, PreintegratedImu, ResidualMode,
    predict,
};
use preint_lie::{SE3, SO3};

mod common;
use common::factor_vars::{NAMES, Rng, Vars, analytic, numeric};

fn random_pim(rng: &mut Rng, omega: Option<(Vector3<f64>, CoriolisMode)>) -> PreintegratedImu {
    common::factor_vars::random_pim(rng, 0, None, omega)
}

fn assert_jac_close(ana: &DMatrix<f64>, num: &DMatrix<f64>, what: &str) {
    for c in 0..ana.ncols() {
        for r in 0..ana.nrows() {
            let (a, n) = (ana[(r, c)], num[(r, c)]);
            assert!(
                (a - n).abs() <= 2e-7 * (1.0 + a.abs()),
                "{what}: block {} row {r} col {}: analytic {a:e} numeric {n:e}",
                NAMES[c / 3],
                c % 3
            );
        }
    }
}

fn check(pim: &PreintegratedImu, v: &Vars, what: &str) {
    let f9 = ImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
    let (_, j9) = f9.evaluate(&v.0, &v.1, &v.2);
    let num9 = numeric(v, |x| f9.residual(&x.0, &x.1, &x.2), 1e-5);
    assert_jac_close(&analytic(&j9), &num9, &format!("{what} (9)"));
    let f15 = CombinedImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
    let (_, j15) = f15.evaluate(&v.0, &v.1, &v.2, &v.3);
    let num15 = numeric(v, |x| f15.residual(&x.0, &x.1, &x.2, &x.3), 1e-5);
    assert_jac_close(&analytic(&j15), &num15, &format!("{what} (15)"));
}

fn random_vars(rng: &mut Rng, pim: &PreintegratedImu, off: f64) -> Vars {
    let xi = NavState::new(SO3::exp(&rng.v3(1.4)), rng.v3(5.0), rng.v3(2.0));
    let bi = ImuBias::new(
        pim.bias_hat.gyro + rng.v3(0.1),
        pim.bias_hat.acc + rng.v3(0.5),
    );
    let bj = ImuBias::new(bi.gyro + rng.v3(0.01), bi.acc + rng.v3(0.05));
    let d = SVector::<f64, 9>::from_fn(|_, _| rng.s() * off);
    let xj = predict(pim, &xi, &bi).retract(&d);
    (xi, xj, bi, bj)
}

#[test]
fn logmap_jacobians_match_central_differences() {
    let mut rng = Rng(0x5EED_1066);
    for case in 0..20 {
        let pim = random_pim(&mut rng, None);
        // Residuals far from zero: offsets up to 0.8 rad / 0.8 m / 0.8 m/s.
        let v = random_vars(&mut rng, &pim, 0.8);
        check(&pim, &v, &format!("case {case}"));
    }
}

#[test]
fn logmap_jacobians_near_identity() {
    let mut rng = Rng(3);
    let mut pim = random_pim(&mut rng, None);
    pim.delta_r = SO3::identity();
    let xi = NavState::new(SO3::identity(), rng.v3(1.0), rng.v3(1.0));
    let b = pim.bias_hat;
    let d = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 1e-9);
    let xj = predict(&pim, &xi, &b).retract(&d);
    check(&pim, &(xi, xj, b, b), "near identity");
}

#[test]
fn logmap_jacobians_with_earth_rate_in_every_coriolis_mode() {
    let mut rng = Rng(77);
    for mode in [
        CoriolisMode::FirstOrder,
        CoriolisMode::SecondOrder,
        CoriolisMode::Exact,
    ] {
        // A fast rate (0.3 rad/s) so that every rotating-frame term matters.
        let w = rng.v3(0.3);
        let pim = random_pim(&mut rng, Some((w, mode)));
        let v = random_vars(&mut rng, &pim, 0.5);
        check(&pim, &v, &format!("{mode:?}"));
    }
}

/// `Log` of the SE₂(3) element `(R, v, p)` from two independent SE(3) logarithms of `(R, v)` and
/// `(R, p)` (translation first), in the order [φ, v, p].
fn log_se23(r: &SO3, v: &Vector3<f64>, p: &Vector3<f64>) -> SVector<f64, 9> {
    let lv = SE3::new(*r, *v).log();
    let lp = SE3::new(*r, *p).log();
    let mut o = SVector::<f64, 9>::zeros();
    o.fixed_rows_mut::<3>(0).copy_from(&lv.fixed_rows::<3>(3));
    o.fixed_rows_mut::<3>(3).copy_from(&lv.fixed_rows::<3>(0));
    o.fixed_rows_mut::<3>(6).copy_from(&lp.fixed_rows::<3>(0));
    o
}

#[test]
fn logmap_residual_is_the_se23_log_of_the_predicted_to_actual_state() {
    let mut rng = Rng(12);
    for _ in 0..10 {
        let pim = random_pim(&mut rng, None);
        let (xi, xj, bi, _) = random_vars(&mut rng, &pim, 0.6);
        let f = ImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
        let xh = predict(&pim, &xi, &bi);
        let rt = xh.r.inverse();
        let want = log_se23(
            &rt.compose(&xj.r),
            &rt.act(&(xj.v - xh.v)),
            &rt.act(&(xj.p - xh.p)),
        );
        let got = f.residual(&xi, &xj, &bi);
        assert!((got - want).amax() < 1e-12, "{got} vs {want}");
        assert!(
            want.fixed_rows::<6>(3).amax() > 0.1,
            "a non-trivial residual"
        );
    }
}

#[test]
fn logmap_weighting_is_the_mapped_covariance_and_chi2_agrees_to_first_order() {
    let mut rng = Rng(99);
    let pim = random_pim(&mut rng, None);
    let (xi, _, _, _) = random_vars(&mut rng, &pim, 0.0);
    // At the integration bias, so that ΔR(b) = ΔR.
    let bi = pim.bias_hat;
    let cw = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let lm = ImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
    assert_eq!(lm.residual_mode(), ResidualMode::Logmap);
    // Σ_L = T cov Tᵀ, T = diag(I, ΔRᵀ, ΔRᵀ): check Σ_L⁻¹ = UᵀU against the explicit product.
    let rt = pim.delta_r.matrix().transpose();
    let mut t = SMatrix::<f64, 9, 9>::identity();
    t.fixed_view_mut::<3, 3>(3, 3).copy_from(&rt);
    t.fixed_view_mut::<3, 3>(6, 6).copy_from(&rt);
    let u = lm.sqrt_information();
    let prod = (u.transpose() * u) * (t * pim.cov * t.transpose());
    assert!((prod - SMatrix::<f64, 9, 9>::identity()).amax() < 1e-8);
    // A small offset: the two χ² agree to first order (relative difference ~ the offset).
    for scale in [1e-3, 1e-5] {
        let d = SVector::<f64, 9>::from_fn(|_, _| rng.s() * scale);
        let xj = predict(&pim, &xi, &bi).retract(&d);
        let (a, b) = (cw.chi2(&xi, &xj, &bi), lm.chi2(&xi, &xj, &bi));
        assert!((a - b).abs() < 20.0 * scale * a, "{scale}: {a} vs {b}");
    }
}

/// The default residual is Logmap (`docs/EVIDENCE.md`: closer to its χ² away from low noise),
/// `new()` uses it, and the two modes share the rotation and bias rows.
#[test]
fn the_default_is_logmap_and_the_modes_share_rotation_and_bias_rows() {
    let mut rng = Rng(5);
    let pim = random_pim(&mut rng, None);
    let (xi, xj, bi, bj) = random_vars(&mut rng, &pim, 0.3);
    assert_eq!(ResidualMode::default(), ResidualMode::Logmap);
    let d9 = ImuFactor::new(pim.clone()).unwrap();
    let l9 = ImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
    let c9 = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    assert_eq!(d9.residual_mode(), ResidualMode::Logmap);
    assert_eq!(d9.residual(&xi, &xj, &bi), l9.residual(&xi, &xj, &bi));
    assert!((d9.residual(&xi, &xj, &bi) - c9.residual(&xi, &xj, &bi)).amax() > 1e-3);
    let c15 = CombinedImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let l15 = CombinedImuFactor::with_mode(pim.clone(), ResidualMode::Logmap).unwrap();
    let (rc, rl) = (
        c15.residual(&xi, &xj, &bi, &bj),
        l15.residual(&xi, &xj, &bi, &bj),
    );
    // Same rotation and bias rows, different velocity and position rows.
    assert_eq!(rc.fixed_rows::<3>(0), rl.fixed_rows::<3>(0));
    assert_eq!(rc.fixed_rows::<6>(9), rl.fixed_rows::<6>(9));
    assert!((rc.fixed_rows::<6>(3) - rl.fixed_rows::<6>(3)).amax() > 1e-3);
    assert_eq!(ResidualMode::parse("logmap"), Some(ResidualMode::Logmap));
    assert_eq!(
        ResidualMode::parse("Component"),
        Some(ResidualMode::ComponentWise)
    );
    assert_eq!(ResidualMode::parse("tangent"), None);
}

/// The Logmap residual with the bias correction on the group ([`preint::BiasCorrection::Group`]):
/// every block of both factors against central differences at `δb ≠ 0`, without and with an
/// Earth rate.
#[test]
fn logmap_jacobians_with_group_bias_correction() {
    let mut rng = Rng(0x06B0_B1A5);
    let omegas = [
        None,
        None,
        None,
        Some((Vector3::new(0.1, -0.2, 0.25), CoriolisMode::Exact)),
        Some((Vector3::new(-0.2, 0.1, 0.3), CoriolisMode::SecondOrder)),
    ];
    for (case, omega) in omegas.into_iter().enumerate() {
        let mut pim = random_pim(&mut rng, omega);
        pim.bias_correction = preint::BiasCorrection::Group;
        let v = random_vars(&mut rng, &pim, 0.5);
        check(&pim, &v, &format!("group case {case}"));
    }
}
