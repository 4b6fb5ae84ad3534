//! Each scheme: covariance (9 and 15) against a seeded Monte Carlo, exactness on the inputs
//! its rule integrates exactly. (Its order and bias Jacobians: the generic scheme contract,
//! `scheme_contract.rs`.)

mod common;

use common::*;
use nalgebra::{Cholesky, DMatrix, DVector, Matrix3};
use preint::{ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Preintegrator, Scheme};
use preint_lie::SO3;

const SCHEMES: &[Scheme] = Scheme::ALL;

fn run(params: &PreintParams, bias: &ImuBias, s: &[ImuSample]) -> PreintegratedImu {
    let mut pi = Preintegrator::new(params.clone(), *bias).unwrap();
    pi.integrate_slice(s).unwrap();
    pi.finish().unwrap()
}

fn params(scheme: Scheme, level: Level) -> PreintParams {
    PreintParams::default()
        .with_scheme(scheme)
        .with_level(level)
        .with_gravity(gravity())
}

/// Noisy samples: white noise of covariance Σ/Δt per sample and, if `walk`, a bias random walk
/// (steps of covariance Σ_rw·Δt). Returns the samples and the final bias deviation b_N − b_0.
fn noisy(
    clean: &[ImuSample],
    prm: &PreintParams,
    walk: bool,
    rng: &mut Gauss,
) -> (Vec<ImuSample>, V3, V3) {
    let h = (clean[1].t_ns - clean[0].t_ns) as f64 * 1e-9;
    let lg = Cholesky::new(prm.gyro_cov / h).unwrap().l();
    let la = Cholesky::new(prm.acc_cov / h).unwrap().l();
    let lbg = Cholesky::new(prm.gyro_bias_rw_cov * h).unwrap().l();
    let lba = Cholesky::new(prm.acc_bias_rw_cov * h).unwrap().l();
    let (mut bg, mut ba) = (V3::zeros(), V3::zeros());
    let mut out = Vec::with_capacity(clean.len());
    for (k, s) in clean.iter().enumerate() {
        out.push(ImuSample::new(
            s.t_ns,
            s.gyro + bg + rng.correlated(&lg),
            s.acc + ba + rng.correlated(&la),
        ));
        if walk && k + 1 < clean.len() {
            bg += rng.correlated(&lbg);
            ba += rng.correlated(&lba);
        }
    }
    // The last sample's bias is b_N (Euler never uses it; midpoint/hermite4 use it in the last
    // interval, a one-step difference the model neglects).
    (out, bg, ba)
}

/// Mean NEES of `errs` (rows) under `cov`, and the largest entry of |S − I| where S is the
/// sample covariance of the whitened errors.
fn consistency(errs: &[DVector<f64>], cov: &DMatrix<f64>) -> (f64, f64) {
    let n = cov.nrows();
    let l = Cholesky::new(cov.clone())
        .expect("covariance not positive definite")
        .l();
    let mut s = DMatrix::<f64>::zeros(n, n);
    let mut nees = 0.0;
    for e in errs {
        let z = l.solve_lower_triangular(e).unwrap();
        nees += z.norm_squared();
        s += &z * z.transpose();
    }
    let m = errs.len() as f64;
    s /= m;
    (nees / m, (s - DMatrix::<f64>::identity(n, n)).amax())
}

/// Mean NEES over N runs of a correct d-dim covariance: χ²_{dN}/N; band at ±3.29σ
/// (two-sided 0.1 %), σ = √(2d/N). Whitened sample covariance entries have σ ≤ √(2/N); 5σ.
fn assert_consistent(what: &str, errs: &[DVector<f64>], cov: &DMatrix<f64>) {
    let d = cov.nrows() as f64;
    let n = errs.len() as f64;
    let (nees, dev) = consistency(errs, cov);
    let half = 3.29 * (2.0 * d / n).sqrt();
    eprintln!(
        "{what}: mean NEES {nees:.3} (band {:.2}–{:.2}), max |S − I| {dev:.3}",
        d - half,
        d + half
    );
    assert!(
        (nees - d).abs() <= half,
        "{what}: mean NEES {nees} outside {d} ± {half}"
    );
    assert!(
        dev <= 5.0 * (2.0 / n).sqrt(),
        "{what}: whitened covariance off by {dev}"
    );
}

fn err9(m: &PreintegratedImu, m0: &PreintegratedImu) -> DVector<f64> {
    DVector::from_column_slice(m.delta_error(m0).as_slice())
}

#[test]
fn covariance_matches_monte_carlo() {
    let scene = Scene::smooth();
    let clean = scene.samples(5_000_000, 1_000_000_000);
    let bias = ImuBias::zero();
    // EuRoC densities ×10 (still linear regime), anisotropic accelerometer to exercise the
    // general path as well.
    for (scheme, aniso) in [
        (Scheme::Euler, false),
        (Scheme::Midpoint, false),
        (Scheme::Midpoint, true),
        (Scheme::Hermite4, false),
        (Scheme::Galilean, false),
        (Scheme::Galilean, true),
    ] {
        let mut prm = params(scheme, Level::Covariance);
        prm.gyro_cov *= 100.0;
        prm.acc_cov *= 100.0;
        if aniso {
            prm.acc_cov = Matrix3::new(4.0, 1.0, 0.5, 1.0, 2.0, -0.3, 0.5, -0.3, 1.0) * 1e-4;
        }
        let m0 = run(&prm, &bias, &clean);
        let fast = prm.clone().with_level(Level::Deltas);
        let mut rng = Gauss::new(42 + scheme as u64);
        let errs: Vec<_> = (0..300)
            .map(|_| {
                err9(
                    &run(&fast, &bias, &noisy(&clean, &prm, false, &mut rng).0),
                    &m0,
                )
            })
            .collect();
        let cov = DMatrix::from_fn(9, 9, |i, j| m0.cov[(i, j)]);
        assert_consistent(&format!("{scheme:?} aniso={aniso} cov9"), &errs, &cov);
    }
}

#[test]
fn combined_covariance_matches_monte_carlo_with_bias_walk() {
    let scene = Scene::smooth();
    let clean = scene.samples(5_000_000, 1_000_000_000);
    let bias = ImuBias::zero();
    for &scheme in SCHEMES {
        let mut prm = params(scheme, Level::Combined);
        prm.gyro_cov *= 100.0;
        prm.acc_cov *= 100.0;
        // Random walk large enough to dominate the white noise over 1 s, so the cross terms
        // matter.
        prm.gyro_bias_rw_cov *= 1e4;
        prm.acc_bias_rw_cov *= 1e3;
        let m0 = run(&prm, &bias, &clean);
        let fast = prm.clone().with_level(Level::Deltas);
        let mut rng = Gauss::new(7 + scheme as u64);
        let errs: Vec<_> = (0..300)
            .map(|_| {
                let (s, bg, ba) = noisy(&clean, &prm, true, &mut rng);
                let e = err9(&run(&fast, &bias, &s), &m0);
                DVector::from_iterator(15, e.iter().chain(bg.iter()).chain(ba.iter()).copied())
            })
            .collect();
        let cov = DMatrix::from_fn(15, 15, |i, j| m0.cov15[(i, j)]);
        assert_consistent(&format!("{scheme:?} cov15"), &errs, &cov);
        // Without the cross terms the same errors are inconsistent (the test has power).
        let mut no_cross = cov.clone();
        no_cross.view_mut((0, 9), (9, 6)).fill(0.0);
        no_cross.view_mut((9, 0), (6, 9)).fill(0.0);
        let (_, dev) = consistency(&errs, &no_cross);
        assert!(
            dev > 5.0 * (2.0f64 / 300.0).sqrt(),
            "cross terms undetectable: {dev}"
        );
    }
}

#[test]
fn rk4_and_midpoint_agree_with_exact_rotation_for_constant_rate() {
    // Constant body rate: every scheme's ΔR is exact (Exp(ωT)), independent of the step.
    let w = V3::new(0.4, -1.1, 2.0);
    let s: Vec<_> = (0..=100)
        .map(|k| ImuSample::new(k * 10_000_000, w, V3::new(0.0, 0.0, 9.81)))
        .collect();
    for &scheme in SCHEMES {
        let m = run(&params(scheme, Level::Deltas), &ImuBias::zero(), &s);
        let e = m.delta_r.minus(&SO3::exp(&w));
        assert!(e.norm() < 1e-13, "{scheme:?}: {e}");
    }
}

/// Windows cut between samples by `preintegrate` (interpolated boundary samples whose noise
/// is that of the stream samples) and their merge, against a seeded Monte Carlo of the stream
/// noise: the window's and the merged 9×9 covariances are consistent with the spread of the
/// merged deltas.
#[test]
fn window_and_merged_covariances_match_monte_carlo() {
    let scene = Scene::smooth();
    let clean = scene.samples(5_000_000, 1_200_000_000);
    let bias = ImuBias::zero();
    let (a, b, c) = (102_500_000, 601_234_567, 1_100_000_001);
    for &scheme in SCHEMES {
        let mut prm = params(scheme, Level::Covariance);
        prm.gyro_cov *= 100.0;
        prm.acc_cov *= 100.0;
        let win = |p: &PreintParams, s: &[ImuSample], t0, t1| {
            preint::preintegrate(p, &bias, s, t0, t1).unwrap()
        };
        let m0 = preint::merge(&win(&prm, &clean, a, b), &win(&prm, &clean, b, c)).unwrap();
        let w0 = win(&prm, &clean, a, b);
        let fast = prm.clone().with_level(Level::Deltas);
        let mut rng = Gauss::new(99 + scheme as u64);
        let (mut em, mut ew) = (vec![], vec![]);
        for _ in 0..300 {
            let s = noisy(&clean, &prm, false, &mut rng).0;
            let (x, y) = (win(&fast, &s, a, b), win(&fast, &s, b, c));
            ew.push(err9(&x, &w0));
            em.push(err9(&preint::merge(&x, &y).unwrap(), &m0));
        }
        let cov = |m: &PreintegratedImu| DMatrix::from_fn(9, 9, |i, j| m.cov[(i, j)]);
        assert_consistent(
            &format!("{scheme:?} window between samples"),
            &ew,
            &cov(&w0),
        );
        assert_consistent(&format!("{scheme:?} merged windows"), &em, &cov(&m0));
    }
}

/// `delta_error` is the right-perturbation chart of the covariance: perturbing a measurement by
/// ΔR·Exp(δφ), Δv + δv, Δp + δp gives back [δφ, δv, δp], in that order.
#[test]
fn delta_error_reads_back_a_known_perturbation() {
    let scene = Scene::smooth();
    let m0 = run(
        &params(Scheme::Midpoint, Level::Deltas),
        &ImuBias::zero(),
        &scene.samples(5_000_000, 1_000_000_000),
    );
    let (dphi, dv, dp) = (
        nalgebra::Vector3::new(2e-3, -1e-3, 3e-3),
        nalgebra::Vector3::new(0.1, 0.2, -0.3),
        nalgebra::Vector3::new(-0.05, 0.04, 0.01),
    );
    let mut m = m0.clone();
    m.delta_r = m0.delta_r.compose(&SO3::exp(&dphi));
    m.delta_v += dv;
    m.delta_p += dp;
    let e = m.delta_error(&m0);
    for (k, want) in dphi.iter().chain(dv.iter()).chain(dp.iter()).enumerate() {
        assert!((e[k] - want).abs() < 1e-14, "entry {k}: {} vs {want}", e[k]);
    }
    assert_eq!(m0.delta_error(&m0), nalgebra::SVector::<f64, 9>::zeros());
}

/// hermite4's rules are exact for cubics (module doc of `preint::hermite4`), which two
/// polynomial motions check against closed forms written out here, on a uniform 100 Hz grid
/// through `preint::preintegrate` (window [0.1 s, 0.9 s] inside [0, 1 s], so every node has
/// a centred stencil):
/// - rotation about a fixed axis n at the rate `ω(t) = n·(c₀ + c₁t + c₂t² + c₃t³)`: no coning,
///   and `Ω` is the exact integral of the cubic, so `ΔR = Exp(n ∫ω)` to round-off;
/// - no rotation and a cubic specific force `a(t)`: the derivative of the quadratic through
///   three samples is off by `h² a'''/6`, the same at every node, so it cancels in the end
///   corrections and `Δv = ∫a` to round-off. (Δp, the corrected trapezoid on the quartic v, is
///   off by `h⁴ T v⁗/720` = 1.4e-10 m here, as measured; bounded at 1e-9.)
///
/// Euler and midpoint are off by ≥ 1e-8 rad and 1e-7 m/s (measured 6.7e-7, 2.9e-5 midpoint).
#[test]
fn rk4_is_exact_for_cubic_rates_and_forces() {
    let (t0, t1) = (100_000_000i64, 900_000_000i64);
    let grid: Vec<f64> = (0..=100).map(|k| k as f64 * 0.01).collect();
    let n = nalgebra::Vector3::new(0.3, -0.4, 0.866).normalize();
    let c = [0.4, -1.2, 2.5, -1.7];
    let w = |t: f64| c[0] + c[1] * t + c[2] * t * t + c[3] * t * t * t;
    let w_int =
        |t: f64| c[0] * t + c[1] * t * t / 2.0 + c[2] * t.powi(3) / 3.0 + c[3] * t.powi(4) / 4.0;
    let ac = [
        nalgebra::Vector3::new(0.5, -0.3, 9.81),
        nalgebra::Vector3::new(1.1, 0.4, -0.2),
        nalgebra::Vector3::new(-2.0, 0.7, 0.9),
        nalgebra::Vector3::new(1.5, -1.3, 0.6),
    ];
    let a = |t: f64| ac[0] + ac[1] * t + ac[2] * (t * t) + ac[3] * (t * t * t);
    // ∫ a over [t0, t] and ∫∫.
    let a_int = |t: f64| {
        ac[0] * t + ac[1] * (t * t / 2.0) + ac[2] * (t.powi(3) / 3.0) + ac[3] * (t.powi(4) / 4.0)
    };
    let a_int2 = |t: f64| {
        ac[0] * (t * t / 2.0)
            + ac[1] * (t.powi(3) / 6.0)
            + ac[2] * (t.powi(4) / 12.0)
            + ac[3] * (t.powi(5) / 20.0)
    };
    let ns = |t: f64| (t * 1e9).round() as i64;
    let rot: Vec<ImuSample> = grid
        .iter()
        .map(|&t| ImuSample::new(ns(t), n * w(t), nalgebra::Vector3::zeros()))
        .collect();
    let acc: Vec<ImuSample> = grid
        .iter()
        .map(|&t| ImuSample::new(ns(t), nalgebra::Vector3::zeros(), a(t)))
        .collect();
    let (ta, tb) = (0.1, 0.9);
    let r_exact = SO3::exp(&(n * (w_int(tb) - w_int(ta))));
    let v_exact = a_int(tb) - a_int(ta);
    let p_exact = a_int2(tb) - a_int2(ta) - a_int(ta) * (tb - ta);
    for &scheme in SCHEMES {
        let prm = params(scheme, Level::Deltas);
        let mr = preint::preintegrate(&prm, &ImuBias::zero(), &rot, t0, t1).unwrap();
        let ma = preint::preintegrate(&prm, &ImuBias::zero(), &acc, t0, t1).unwrap();
        let er = (r_exact.inverse().compose(&mr.delta_r)).log().norm();
        let ev = (ma.delta_v - v_exact).norm();
        let ep = (ma.delta_p - p_exact).norm();
        eprintln!("{scheme:?}: rotation {er:.2e} rad, velocity {ev:.2e} m/s, position {ep:.2e} m");
        if scheme == Scheme::Hermite4 {
            assert!(er < 1e-14, "hermite4 rotation error {er}");
            assert!(ev < 1e-13, "hermite4 velocity error {ev}");
            assert!(ep < 1e-9, "hermite4 position error {ep}");
        } else {
            assert!(
                er > 1e-8 && ev > 1e-7,
                "{scheme:?} unexpectedly exact: {er} {ev}"
            );
        }
    }
}
