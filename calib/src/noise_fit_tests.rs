use super::*;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

/// How each basis grows with the window length `T` (white noise ∝ T, random walk ∝ T³, the
/// ground truth's error independent of T, its bias error ∝ T²).
const POWER: [i32; PARAMS] = [1, 1, 3, 3, 0, 0, 0, 2, 2];

/// True `√θ`, of order 1 so that every basis matters.
const TRUTH: [f64; PARAMS] = [1.0, 0.8, 0.6, 0.5, 1.2, 0.9, 0.7, 0.4, 0.3];

fn normal(rng: &mut StdRng) -> f64 {
    rng.sample(StandardNormal)
}

/// `windows` windows of lengths 0.5, 1, 2, 4 s in turn; each basis `T^p M Mᵀ` with `M` a
/// random 9×3 matrix (rank 3, as the real ones), `r ~ N(0, Σ(θ))`.
fn synthetic(rng: &mut StdRng, truth: &[f64; PARAMS], windows: usize) -> Vec<NoiseWindow> {
    (0..windows)
        .map(|i| {
            let t: f64 = [0.5, 1.0, 2.0, 4.0][i % 4];
            let basis: [SMatrix<f64, 9, 9>; PARAMS] = std::array::from_fn(|k| {
                let m = SMatrix::<f64, 9, 3>::from_fn(|_, _| normal(rng));
                m * m.transpose() * t.powi(POWER[k]) / 3.0
            });
            let theta = SVector::<f64, PARAMS>::from_fn(|k, _| truth[k] * truth[k]);
            let s = sigma(
                &NoiseWindow {
                    length_s: t,
                    r: SVector::zeros(),
                    basis,
                    gravity_jacobian: SMatrix::zeros(),
                    block: i,
                },
                &theta,
            );
            let l = s.cholesky().expect("positive definite").l();
            let z = SVector::<f64, 9>::from_fn(|_, _| normal(rng));
            NoiseWindow {
                length_s: t,
                r: l * z,
                basis,
                gravity_jacobian: SMatrix::zeros(),
                block: i,
            }
        })
        .collect()
}

/// One draw: every parameter recovered within 3σ, the χ²/dof after near 1, ℓ no lower than at
/// the truth.
#[test]
fn recovers_the_parameters_of_synthetic_windows() {
    let mut rng = StdRng::seed_from_u64(7);
    let w = synthetic(&mut rng, &TRUTH, 200);
    let f = fit(&w, &NoiseFitOptions::default()).unwrap();
    for (p, truth) in f.params.iter().zip(TRUTH) {
        assert!(p.withheld.is_none(), "{p:?}");
        assert!((p.value - truth).abs() < 3.0 * p.std, "{p:?} vs {truth}");
        assert!(p.std < 0.25 * truth, "{p:?}");
    }
    for l in &f.per_length {
        assert_eq!(l.count, 50);
        assert!((l.after - 1.0).abs() < 0.2, "{l:?}");
        assert!(l.before.is_nan(), "no start values: Σ singular at 0");
    }
    let theta = SVector::<f64, PARAMS>::from_fn(|k, _| TRUTH[k] * TRUTH[k]);
    let r: Vec<_> = w.iter().map(|w| w.r).collect();
    let at_truth = evaluate(&w, &r, &theta).ok().unwrap().ll;
    assert!(
        f.log_likelihood >= at_truth - 1e-9,
        "{} < {at_truth}",
        f.log_likelihood
    );
}

/// Over 200 seeded trials, the 3σ interval of each parameter covers its true value in at
/// least 95 % of them.
#[test]
fn three_sigma_coverage_over_seeded_trials() {
    let trials = 200;
    let mut covered = [0usize; PARAMS];
    for seed in 0..trials {
        let mut rng = StdRng::seed_from_u64(1000 + seed);
        let w = synthetic(&mut rng, &TRUTH, 96);
        let f = fit(&w, &NoiseFitOptions::default()).unwrap();
        for (k, p) in f.params.iter().enumerate() {
            let (t, s) = p.theta;
            if (t - TRUTH[k] * TRUTH[k]).abs() <= 3.0 * s {
                covered[k] += 1;
            }
        }
    }
    for (k, c) in covered.iter().enumerate() {
        let rate = *c as f64 / trials as f64;
        eprintln!("{:?}: 3σ coverage {rate}", Param::ALL[k]);
        assert!(rate >= 0.95, "{:?}: coverage {rate}", Param::ALL[k]);
    }
}

/// A parameter whose true value is 0 ends on the bound, withheld with a small 2σ upper bound,
/// and the others are still recovered.
#[test]
fn a_zero_parameter_is_a_bound_not_a_value() {
    let mut truth = TRUTH;
    truth[5] = 0.0;
    let mut rng = StdRng::seed_from_u64(3);
    let w = synthetic(&mut rng, &truth, 200);
    let f = fit(&w, &NoiseFitOptions::default()).unwrap();
    let p = &f.params[5];
    match p.withheld {
        Some(Withheld::AtBound { upper }) => assert!(upper < 0.5, "{upper}"),
        Some(Withheld::NotSeparable) => assert!(p.value < 0.5, "{p:?}"),
        other => panic!("σ_p reported as {other:?} {p:?}"),
    }
    for k in [0, 1, 4, 6] {
        let q = &f.params[k];
        assert!((q.value - truth[k]).abs() < 3.0 * q.std, "{q:?}");
    }
}

/// A held parameter keeps its value and σ 0; the χ² before uses the start and held values.
#[test]
fn held_parameters_and_the_chi2_before() {
    let mut rng = StdRng::seed_from_u64(11);
    let w = synthetic(&mut rng, &TRUTH, 120);
    let mut opts = NoiseFitOptions {
        start: TRUTH.map(|x| 2.0 * x),
        ..NoiseFitOptions::default()
    };
    opts.held[4] = Some(TRUTH[4]);
    let f = fit(&w, &opts).unwrap();
    assert_eq!(f.params[4].withheld, Some(Withheld::Held));
    assert_eq!(f.params[4].value, TRUTH[4]);
    for l in &f.per_length {
        // Most σ doubled: χ²/dof near 1/4 before, near 1 after.
        assert!(l.before < 0.45, "{l:?}");
        assert!((l.after - 1.0).abs() < 0.25, "{l:?}");
    }
    assert!(matches!(
        fit(&w[..1], &opts),
        Err(NoiseFitError::TooFewWindows { .. })
    ));
    opts.start[0] = f64::NAN;
    assert_eq!(
        fit(&w, &opts).unwrap_err(),
        NoiseFitError::BadValue(Param::GyroNoiseDensity)
    );
}

/// `windows` synthetic windows whose residuals carry the mean `G_w δg` of a world gravity
/// error `dg`: `G_w` zero in rotation and `∝ T`, `T²` in velocity and position, as the real
/// residuals' derivatives are.
fn with_gravity_error(rng: &mut StdRng, windows: usize, dg: &SVector<f64, 3>) -> Vec<NoiseWindow> {
    let mut w = synthetic(rng, &TRUTH, windows);
    for w in &mut w {
        let t = w.length_s;
        let m = SMatrix::<f64, 3, 3>::from_fn(|_, _| normal(rng));
        let mut g = SMatrix::<f64, 9, 3>::zeros();
        g.fixed_view_mut::<3, 3>(3, 0).copy_from(&(m * -t));
        g.fixed_view_mut::<3, 3>(6, 0)
            .copy_from(&(m * (-0.5 * t * t)));
        w.gravity_jacobian = g;
        w.r += g * dg;
    }
    w
}

/// A world gravity error is recovered within 3σ per axis and supported by the information
/// criterion, the parameters still within 3σ; without one, over 40 seeded trials the
/// correction is supported at most twice (the criterion's false-alarm rate is well below 5 %)
/// and an unsupported correction leaves the fit without it.
#[test]
fn the_gravity_correction_is_found_when_present_and_withheld_when_not() {
    let opts = NoiseFitOptions {
        fit_gravity: true,
        ..NoiseFitOptions::default()
    };
    let dg = SVector::<f64, 3>::new(0.3, -0.2, 0.1);
    let mut rng = StdRng::seed_from_u64(42);
    let w = with_gravity_error(&mut rng, 200, &dg);
    let f = fit(&w, &opts).unwrap();
    let g = f.gravity.expect("asked for");
    assert!(g.supported, "{g:?}");
    for k in 0..3 {
        let s = g.cov[(k, k)].sqrt();
        assert!((g.correction[k] + dg[k]).abs() < 3.0 * s, "{g:?}");
        assert!(s < 0.1, "{g:?}");
    }
    for (p, truth) in f.params.iter().zip(TRUTH) {
        assert!((p.value - truth).abs() < 3.0 * p.std, "{p:?} vs {truth}");
    }
    let mut supported = 0;
    for seed in 0..40 {
        let mut rng = StdRng::seed_from_u64(500 + seed);
        let w = with_gravity_error(&mut rng, 96, &SVector::zeros());
        let f = fit(&w, &opts).unwrap();
        let g = f.gravity.unwrap();
        if g.supported {
            supported += 1;
        } else {
            let plain = fit(&w, &NoiseFitOptions::default()).unwrap();
            assert_eq!(f.log_likelihood, plain.log_likelihood);
        }
    }
    assert!(supported <= 2, "supported in {supported} of 40 trials");
}

/// Windows that share data: each of 200 independent windows given twice in one block. The
/// estimate is the same; the inverse Fisher information would shrink every σ by √2 (ratio
/// 0.71), the sandwich keeps each within 40 % of the independent windows' σ and their mean
/// ratio within 15 % of 1 (the sandwich is itself an estimate from 200 blocks).
#[test]
fn shared_windows_keep_the_sigma_of_the_data() {
    let mut rng = StdRng::seed_from_u64(11);
    let w = synthetic(&mut rng, &TRUTH, 200);
    let once = fit(&w, &NoiseFitOptions::default()).unwrap();
    let twice: Vec<NoiseWindow> = w.iter().flat_map(|x| [x.clone(), x.clone()]).collect();
    assert!(sandwich::shared(&twice) && !sandwich::shared(&w));
    let f = fit(&twice, &NoiseFitOptions::default()).unwrap();
    let mut mean = 0.0;
    for (a, b) in once.params.iter().zip(&f.params) {
        assert!(
            (a.theta.0 - b.theta.0).abs() < 1e-6 * a.theta.0,
            "{a:?} {b:?}"
        );
        let ratio = b.theta.1 / a.theta.1;
        assert!(
            (0.8..1.4).contains(&ratio),
            "{:?}: σ ratio {ratio}",
            a.param
        );
        mean += ratio / PARAMS as f64;
    }
    assert!((0.85..1.15).contains(&mean), "mean σ ratio {mean}");
}
