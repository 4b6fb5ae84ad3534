//! Earth rotation (`omega_coriolis`, [`CoriolisMode`]): every factor Jacobian of every mode
//! against central differences on the manifold, zero residual at the prediction, a body at
//! rest in the rotating frame stays at rest (deltas by quadrature), merge and validation
//! errors, the kernels against quadrature.

use nalgebra::{DMatrix, Matrix3, SVector, Vector3};
use preint::ResidualMode;
use preint::earth::{EARTH_RATE_RAD_S, earth_rate_enu, gamma_p, gamma_v};
use preint::{
    CombinedImuFactor, CoriolisMode, Cov15, FactorError, ImuBias, ImuFactor, MergeError, NavState,
    PreintParams, PreintegratedImu, merge, predict,
};
use preint_lie::{SO3, hat};

mod common;
use common::factor_vars::{Rng, analytic, numeric};

fn random_pim(rng: &mut Rng, omega: Vector3<f64>, mode: CoriolisMode) -> PreintegratedImu {
    common::factor_vars::random_pim(rng, 1_000_000_000, None, Some((omega, mode)))
}

const MODES: [CoriolisMode; 3] = [
    CoriolisMode::FirstOrder,
    CoriolisMode::SecondOrder,
    CoriolisMode::Exact,
];

fn assert_jac_close(ana: &DMatrix<f64>, num: &DMatrix<f64>, tol: f64, what: &str) {
    for c in 0..ana.ncols() {
        for r in 0..ana.nrows() {
            let (a, n) = (ana[(r, c)], num[(r, c)]);
            assert!(
                (a - n).abs() <= tol * (1.0 + a.abs()),
                "{what}: column {c} row {r}: analytic {a:e} numeric {n:e}"
            );
        }
    }
}

#[test]
fn jacobians_of_every_mode_match_central_differences() {
    let mut rng = Rng(0xD1B54A32D192ED03);
    for case in 0..12 {
        for mode in MODES {
            // A fast-rotating frame (|ω| up to 0.35 rad/s) so that every term is visible.
            let omega = rng.v3(0.2);
            let pim = random_pim(&mut rng, omega, mode);
            let xi = NavState::new(SO3::exp(&rng.v3(1.4)), rng.v3(5.0), rng.v3(2.0));
            let bi = ImuBias::new(
                pim.bias_hat.gyro + rng.v3(0.1),
                pim.bias_hat.acc + rng.v3(0.5),
            );
            let bj = ImuBias::new(bi.gyro + rng.v3(0.01), bi.acc + rng.v3(0.05));
            let off = SVector::<f64, 9>::from_fn(|_, _| rng.s() * 0.5);
            let xj = predict(&pim, &xi, &bi).retract(&off);
            let vars = (xi, xj, bi, bj);
            let what = format!("case {case} {mode:?}");
            let f9 = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
            let (_, j9) = f9.evaluate(&xi, &xj, &bi);
            let num9 = numeric(&vars, |v| f9.residual(&v.0, &v.1, &v.2), 1e-5);
            assert_jac_close(&analytic(&j9), &num9, 2e-7, &what);
            let f15 = CombinedImuFactor::with_mode(pim, ResidualMode::ComponentWise).unwrap();
            let (_, j15) = f15.evaluate(&xi, &xj, &bi, &bj);
            let num15 = numeric(&vars, |v| f15.residual(&v.0, &v.1, &v.2, &v.3), 1e-5);
            assert_jac_close(&analytic(&j15), &num15, 2e-7, &what);
        }
    }
}

#[test]
fn residual_is_zero_at_the_prediction_and_minus_the_delta_error_to_first_order() {
    let mut rng = Rng(99);
    for mode in MODES {
        let omega = rng.v3(0.2);
        let pim = random_pim(&mut rng, omega, mode);
        let xi = NavState::new(SO3::exp(&rng.v3(1.0)), rng.v3(50.0), rng.v3(10.0));
        let b = ImuBias::new(
            pim.bias_hat.gyro + rng.v3(0.02),
            pim.bias_hat.acc + rng.v3(0.2),
        );
        let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
        let xj = predict(&pim, &xi, &b);
        let r0 = f.residual(&xi, &xj, &b);
        assert!(r0.amax() < 1e-11, "{mode:?}: {r0:?}");
        // A measurement whose Δv is larger by d predicts nothing else: r_v = −d exactly.
        let d = Vector3::new(1e-3, -2e-3, 3e-3);
        let mut moved = pim.clone();
        moved.delta_v += d;
        let r = ImuFactor::with_mode(moved, ResidualMode::ComponentWise)
            .unwrap()
            .residual(&xi, &xj, &b);
        assert!((r.fixed_rows::<3>(3) + d).amax() < 1e-11, "{mode:?}: {r:?}");
    }
}

/// Simpson's rule on [0, 1] for a 3-vector integrand, n (even) intervals.
fn simpson(f: impl Fn(f64) -> Vector3<f64>, n: usize) -> Vector3<f64> {
    let h = 1.0 / n as f64;
    let mut s = f(0.0) + f(1.0);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * (h / 3.0)
}

/// A body at rest at `p` in a frame rotating at ω (R = I): the gyro reads ω, the accelerometer
/// the constant `f = ω×(ω×p) − g`; the body turns as `Exp(ω t)` inertially, so
/// `ΔR = Exp(ωT)`, `Δv = ∫₀ᵀ Exp(ωs) f ds`, `Δp = ∫₀ᵀ (T − s) Exp(ωs) f ds` (quadrature here).
fn at_rest(p: Vector3<f64>, omega: Vector3<f64>, t: f64, mode: CoriolisMode) -> PreintegratedImu {
    let g = Vector3::new(0.0, 0.0, -9.81);
    let f = omega.cross(&omega.cross(&p)) - g;
    let e = |s: f64| SO3::exp(&(omega * (s * t))).act(&f);
    let mut rng = Rng(1);
    let mut pim = random_pim(&mut rng, omega, mode);
    pim.delta_t = t;
    pim.delta_r = SO3::exp(&(omega * t));
    pim.delta_v = simpson(e, 4000) * t;
    pim.delta_p = simpson(|s| e(s) * (1.0 - s), 4000) * (t * t);
    pim.bias_hat = ImuBias::zero();
    pim
}

#[test]
fn a_body_at_rest_in_the_rotating_frame_stays_at_rest_in_the_exact_mode() {
    let omega = Vector3::new(0.1, -0.2, 0.4);
    let p = Vector3::new(30.0, -20.0, 10.0);
    let xi = NavState::new(SO3::identity(), p, Vector3::zeros());
    let mut errs = Vec::new();
    for mode in MODES {
        let pim = at_rest(p, omega, 2.0, mode);
        let xj = predict(&pim, &xi, &ImuBias::zero());
        let err = (xj.p - p).norm().max((xj.v).norm()).max(xj.r.log().norm());
        errs.push(err);
    }
    // Exact to the quadrature's accuracy; the additive modes are off by O(|ω|T) terms.
    assert!(errs[2] < 1e-10, "{errs:?}");
    assert!(errs[0] > 1e-2 && errs[1] > 1e-3, "{errs:?}");
}

#[test]
fn exact_prediction_composes_over_merged_windows() {
    let omega = earth_rate_enu(45.0) * 1000.0;
    let mut rng = Rng(5);
    let mut a = random_pim(&mut rng, omega, CoriolisMode::Exact);
    a.cov15 = Cov15::identity() * 1e-4;
    let mut b = random_pim(&mut rng, omega, CoriolisMode::Exact);
    (b.t_i_ns, b.t_j_ns, b.delta_t) = (a.t_j_ns, a.t_j_ns + 1_300_000_000, 1.3);
    b.bias_hat = a.bias_hat;
    b.cov15 = a.cov15;
    let m = merge(&a, &b).unwrap();
    let xi = NavState::new(SO3::exp(&rng.v3(1.0)), rng.v3(100.0), rng.v3(30.0));
    let two = predict(&b, &predict(&a, &xi, &a.bias_hat), &a.bias_hat);
    let one = predict(&m, &xi, &a.bias_hat);
    assert!(one.local(&two).amax() < 1e-11, "{:?}", one.local(&two));
}

#[test]
fn merge_refuses_different_earth_rates_or_modes() {
    let mut rng = Rng(8);
    let w = Vector3::new(0.0, 5e-5, 5e-5);
    let a = random_pim(&mut rng, w, CoriolisMode::Exact);
    let mut b = a.clone();
    (b.t_i_ns, b.t_j_ns) = (a.t_j_ns, a.t_j_ns + 700_000_000);
    let other_rate = PreintegratedImu {
        omega_coriolis: Some(w * 2.0),
        ..b.clone()
    };
    assert_eq!(merge(&a, &other_rate), Err(MergeError::EarthRateMismatch));
    let no_rate = PreintegratedImu {
        omega_coriolis: None,
        ..b.clone()
    };
    assert_eq!(merge(&a, &no_rate), Err(MergeError::EarthRateMismatch));
    let other_mode = PreintegratedImu {
        coriolis: CoriolisMode::FirstOrder,
        ..b.clone()
    };
    assert_eq!(merge(&a, &other_mode), Err(MergeError::EarthRateMismatch));
    assert!(merge(&a, &b).is_ok());
}

#[test]
fn non_finite_rates_are_refused() {
    let bad = PreintParams::default().with_omega_coriolis(Vector3::new(f64::NAN, 0.0, 0.0));
    assert!(bad.validate().is_err());
    let mut rng = Rng(3);
    let pim = random_pim(
        &mut rng,
        Vector3::new(0.0, f64::INFINITY, 0.0),
        CoriolisMode::Exact,
    );
    assert_eq!(
        ImuFactor::with_mode(pim, ResidualMode::ComponentWise).unwrap_err(),
        FactorError::NonFinite {
            field: "omega_coriolis"
        }
    );
}

#[test]
fn kernels_match_quadrature_on_both_sides_of_the_series_switch() {
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    for theta in [0.0, 1e-6, 0.0999, 0.1001, 0.7, 3.0] {
        let w = axis * theta;
        let x = Vector3::new(1.0, 2.0, -3.0);
        let qv = simpson(|s| SO3::exp(&(w * s)).act(&x), 2000);
        let qp = simpson(|s| SO3::exp(&(w * s)).act(&x) * s, 2000);
        assert!((gamma_v(&w) * x - qv).amax() < 1e-13, "J_l at {theta}");
        assert!((gamma_p(&w) * x - qp).amax() < 1e-13, "Γ_P at {theta}");
    }
    // Series coefficients ½, ⅓, ⅛ (the PR #2688 check): Γ_P(w) ≈ ½I + ⅓[w]× + ⅛[w]×².
    let w = axis * 1e-3;
    let k = hat(&w);
    let series = Matrix3::identity() * 0.5 + k / 3.0 + k * k / 8.0;
    // The next term, [w]×³/30, is ~3e-11.
    assert!((gamma_p(&w) - series).amax() < 1e-10);
}

#[test]
fn earth_rate_from_latitude_is_enu() {
    let w = earth_rate_enu(30.0);
    assert_eq!(w.x, 0.0);
    assert!((w.y - EARTH_RATE_RAD_S * 3f64.sqrt() / 2.0).abs() < 1e-19);
    assert!((w.z - EARTH_RATE_RAD_S * 0.5).abs() < 1e-19);
    assert!((w.norm() - 7.292115e-5).abs() < 1e-18);
}

#[test]
fn without_a_rate_the_mode_is_ignored() {
    let mut rng = Rng(12);
    let mut pim = random_pim(&mut rng, Vector3::zeros(), CoriolisMode::Exact);
    pim.omega_coriolis = None;
    let xi = NavState::new(SO3::exp(&rng.v3(1.0)), rng.v3(5.0), rng.v3(2.0));
    let reference = predict(&pim, &xi, &pim.bias_hat);
    for mode in MODES {
        pim.coriolis = mode;
        assert_eq!(predict(&pim, &xi, &pim.bias_hat), reference);
    }
}
