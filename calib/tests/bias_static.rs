//! Static one-attitude calibration: Monte Carlo consistency (200 seeded trials), the
//! unobservable accelerometer bias, the prior, and typed errors.
//!
//! Data: `sim`'s `static` scene model ([`StaticScene`] at attitude R_wb = Ry(pitch)·Rx(roll),
//! [`preint_sim::simulate`]): ω_m = b_g + n_g, a_m = R_wbᵀ(0, 0, 9.81) + b_a + n_a, white noise of
//! Kalibr density σ (per-sample std σ/√Δt) and, where stated, a bias random walk. The truth
//! (attitude, biases, and with a random walk the bias at the middle sample) is the
//! simulation's, never computed by the code under test.

use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, ImuSample};
use preint_calib::bias::{AccBiasPrior, BiasError, StaticOptions, calibrate_static};
use preint_lie::SO3;
use preint_sim::{SimConfig, StaticScene, rng_from_seed, simulate};
use rand::RngExt;
use rand_distr::StandardNormal;

fn attitude(roll: f64, pitch: f64) -> SO3 {
    SO3::exp(&Vector3::new(0.0, pitch, 0.0)).compose(&SO3::exp(&Vector3::new(roll, 0.0, 0.0)))
}

/// `duration` seconds at `rate` of the static scene at `r_wb`, initial biases (bg, ba), noise
/// `noise` (its random walks on). Returns the samples and the true bias at the middle sample
/// (the value the estimator refers to).
#[allow(clippy::too_many_arguments)]
fn static_data(
    seed: u64,
    rate: f64,
    duration: f64,
    r_wb: &SO3,
    bg: Vector3<f64>,
    ba: Vector3<f64>,
    noise: &ImuNoise,
) -> (Vec<ImuSample>, ImuBias) {
    let cfg = SimConfig {
        noise: *noise,
        initial_bias: ImuBias::new(bg, ba),
        bias_random_walk: true,
        ..SimConfig::default()
    };
    // `duration` s of samples: the last one at duration − Δt.
    let out = simulate(
        &StaticScene::new(*r_wb, Vector3::new(1.0, 2.0, 3.0)),
        rate,
        duration - 1.0 / rate,
        &cfg,
        seed,
    )
    .unwrap();
    let mid = out.truth[out.samples.len() / 2].bias;
    (out.samples, mid)
}

/// EuRoC white-noise densities without bias random walk.
fn white_only() -> ImuNoise {
    ImuNoise {
        gyro_random_walk: 0.0,
        acc_random_walk: 0.0,
        ..ImuNoise::euroc()
    }
}

fn std_dev(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt()
}

/// 200 seeded trials, 10 s at 100 Hz, EuRoC white-noise densities, b_a = 0 (so the specific-force
/// direction is the attitude's). Checks (a) each estimate within 3σ of the truth in ≥ 95 % of
/// the trials and (b) the mean reported σ within 20 % of the empirical RMS error (about the
/// truth). With 200 trials the empirical σ itself has ≈ 5 % relative error.
#[test]
fn monte_carlo_200_trials_coverage_and_predicted_sigma() {
    let noise = white_only();
    let bg = Vector3::new(0.004, -0.012, 0.0025);
    let (roll, pitch) = (0.3, -0.2);
    let r = attitude(roll, pitch);
    let trials = 200;
    let mut err: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut sig: Vec<Vec<f64>> = vec![Vec::new(); 5];
    for seed in 0..trials {
        let (s, _) = static_data(seed, 100.0, 10.0, &r, bg, Vector3::zeros(), &noise);
        let c = calibrate_static(&s, &noise, &StaticOptions::default()).unwrap();
        for i in 0..3 {
            err[i].push(c.gyro_bias[i] - bg[i]);
            sig[i].push(c.gyro_bias_std[i]);
        }
        err[3].push(c.roll - roll);
        sig[3].push(c.roll_std);
        err[4].push(c.pitch - pitch);
        sig[4].push(c.pitch_std);
    }
    let names = ["b_gx", "b_gy", "b_gz", "roll", "pitch"];
    for q in 0..5 {
        let inside = err[q]
            .iter()
            .zip(&sig[q])
            .filter(|(e, s)| e.abs() <= 3.0 * **s)
            .count();
        let emp = std_dev(&err[q]);
        let rep = sig[q].iter().sum::<f64>() / sig[q].len() as f64;
        println!(
            "{}: within 3σ {inside}/{trials}, empirical σ {emp:.3e}, reported σ {rep:.3e}, ratio {:.3}",
            names[q],
            rep / emp
        );
        assert!(
            inside as f64 >= 0.95 * trials as f64,
            "{}: {inside}",
            names[q]
        );
        assert!(
            (rep / emp - 1.0).abs() <= 0.2,
            "{}: {rep} vs {emp}",
            names[q]
        );
    }
    // Independent check of the predicted gyro σ: σ_g/√T with T = 1000 × 0.01 s.
    let expected = noise.gyro_noise_density / 10f64.sqrt();
    let rep = sig[0].iter().sum::<f64>() / sig[0].len() as f64;
    assert!((rep / expected - 1.0).abs() < 0.01, "{rep} vs {expected}");
}

/// With a gyro bias random walk (EuRoC σ_bg, exaggerated ×20 so that it matters over 20 s)
/// the reported σ includes `σ_bg²·T/12` and still predicts the spread of the estimate about the
/// mid-recording bias (100 trials, σ within 20 %, 3σ coverage ≥ 95 %).
#[test]
fn random_walk_term_predicts_the_spread() {
    let noise = ImuNoise {
        gyro_random_walk: 20.0 * 1.9393e-5,
        acc_random_walk: 0.0,
        ..ImuNoise::euroc()
    };
    let bg = Vector3::new(0.01, 0.0, -0.01);
    let trials = 100;
    let mut err = Vec::new();
    let mut sig = Vec::new();
    for seed in 0..trials {
        let (s, mid) = static_data(
            5000 + seed,
            50.0,
            20.0,
            &SO3::identity(),
            bg,
            Vector3::zeros(),
            &noise,
        );
        let c = calibrate_static(&s, &noise, &StaticOptions::default()).unwrap();
        err.push(c.gyro_bias.x - mid.gyro.x);
        sig.push(c.gyro_bias_std.x);
    }
    let emp = std_dev(&err);
    let rep = sig.iter().sum::<f64>() / trials as f64;
    let white = noise.gyro_noise_density / 20f64.sqrt();
    println!("random walk: empirical {emp:.3e}, reported {rep:.3e}, white only {white:.3e}");
    assert!(rep > 1.5 * white, "the random-walk term matters here");
    assert!((rep / emp - 1.0).abs() <= 0.2, "{rep} vs {emp}");
    let inside = err
        .iter()
        .zip(&sig)
        .filter(|(e, s)| e.abs() <= 3.0 * **s)
        .count();
    assert!(inside as f64 >= 0.95 * trials as f64);
}

#[test]
fn acc_bias_is_reported_unobservable_without_prior() {
    let noise = ImuNoise::euroc();
    let r = attitude(0.1, 0.05);
    let (s, _) = static_data(
        7,
        200.0,
        5.0,
        &r,
        Vector3::zeros(),
        Vector3::new(0.1, -0.05, 0.2),
        &noise,
    );
    let c = calibrate_static(&s, &noise, &StaticOptions::default()).unwrap();
    assert!(c.acc_bias.is_none() && c.acc_bias_std.is_none());
    assert!(c.unobservable.contains(&"acc_bias") && c.unobservable.contains(&"yaw"));
    assert!(c.acc_bias_note.contains("unobservable"));
    // 6 residuals, rank 5 (yaw): one degree of freedom, |f̄| vs |g|.
    assert_eq!(c.dof, 1);
    // The reported direction is that of the specific force: tilted by the horizontal bias.
    let f = r.inverse().act(&Vector3::new(0.0, 0.0, 9.81)) + Vector3::new(0.1, -0.05, 0.2);
    assert!((c.up_body - f.normalize()).norm() < 1e-3);
}

/// With a prior N(μ_p, σ_p²) on b_a whose mean is drawn around the truth with σ_p, roll/pitch
/// are within 3σ in ≥ 95 % of 100 trials, b_a,z (along gravity, observed by the data) too, and
/// the horizontal b_a σ stays ≈ the prior's (the data cannot tell it from tilt).
#[test]
fn acc_bias_prior_is_used_and_consistent() {
    let noise = white_only();
    let ba = Vector3::new(0.08, -0.05, 0.12);
    let (roll, pitch) = (0.0, 0.0);
    let r = attitude(roll, pitch);
    let sp = 0.02;
    let mut rng = rng_from_seed(99);
    let trials = 100;
    let mut inside = [0usize; 3];
    for seed in 0..trials {
        let (s, _) = static_data(1000 + seed, 100.0, 5.0, &r, Vector3::zeros(), ba, &noise);
        let jitter: Vector3<f64> = Vector3::new(
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
        );
        let opts = StaticOptions {
            acc_bias_prior: Some(AccBiasPrior {
                mean: ba + jitter * sp,
                std: Vector3::repeat(sp),
            }),
            ..Default::default()
        };
        let c = calibrate_static(&s, &noise, &opts).unwrap();
        let est = c.acc_bias.unwrap();
        let sd = c.acc_bias_std.unwrap();
        assert!((sd.x / sp - 1.0).abs() < 0.01 && (sd.y / sp - 1.0).abs() < 0.01);
        assert!(sd.z < 0.1 * sp, "b_a,z observed by the data: {}", sd.z);
        inside[0] += ((c.roll - roll).abs() <= 3.0 * c.roll_std) as usize;
        inside[1] += ((c.pitch - pitch).abs() <= 3.0 * c.pitch_std) as usize;
        inside[2] += ((est.z - ba.z).abs() <= 3.0 * sd.z) as usize;
        assert_eq!(c.unobservable, vec!["yaw"]);
    }
    for k in inside {
        assert!(k as f64 >= 0.95 * trials as f64, "{inside:?}");
    }
}

/// The measured per-axis densities `std(samples)·√Δt` equal the simulated white-noise
/// densities within 5 % (4000 samples: sampling error of a std ≈ 1.1 %). White noise only: a
/// bias random walk would add its own spread to the samples.
#[test]
fn measured_density_matches_the_simulated_one() {
    let noise = white_only();
    let (s, _) = static_data(
        3,
        200.0,
        20.0,
        &SO3::identity(),
        Vector3::zeros(),
        Vector3::zeros(),
        &noise,
    );
    let c = calibrate_static(&s, &noise, &StaticOptions::default()).unwrap();
    for i in 0..3 {
        let (g, a) = (
            c.measured_gyro_density[i] / noise.gyro_noise_density,
            c.measured_acc_density[i] / noise.acc_noise_density,
        );
        assert!(
            (g - 1.0).abs() < 0.05 && (a - 1.0).abs() < 0.05,
            "axis {i}: {g} {a}"
        );
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let noise = ImuNoise::euroc();
    let opts = StaticOptions::default();
    let (good, _) = static_data(
        1,
        100.0,
        1.0,
        &SO3::identity(),
        Vector3::zeros(),
        Vector3::zeros(),
        &noise,
    );
    assert!(matches!(
        calibrate_static(&good[..3], &noise, &opts),
        Err(BiasError::TooFew { .. })
    ));
    let mut nan = good.clone();
    nan[5].gyro.x = f64::NAN;
    assert!(matches!(
        calibrate_static(&nan, &noise, &opts),
        Err(BiasError::NonFinite { index: 5, .. })
    ));
    let mut back = good.clone();
    back[7].t_ns = back[6].t_ns;
    assert!(matches!(
        calibrate_static(&back, &noise, &opts),
        Err(BiasError::NotIncreasing { index: 7, .. })
    ));
    let bad_noise = ImuNoise {
        gyro_noise_density: 0.0,
        ..noise
    };
    assert!(matches!(
        calibrate_static(&good, &bad_noise, &opts),
        Err(BiasError::InvalidParameter { .. })
    ));
    let bad_prior = StaticOptions {
        acc_bias_prior: Some(AccBiasPrior {
            mean: Vector3::zeros(),
            std: Vector3::new(0.1, -1.0, 0.1),
        }),
        ..Default::default()
    };
    assert!(matches!(
        calibrate_static(&good, &noise, &bad_prior),
        Err(BiasError::InvalidParameter { .. })
    ));
    // Zero specific force (free fall): no gravity direction.
    let zero: Vec<ImuSample> = good
        .iter()
        .map(|s| ImuSample::new(s.t_ns, s.gyro, Vector3::zeros()))
        .collect();
    assert!(matches!(
        calibrate_static(&zero, &noise, &opts),
        Err(BiasError::InvalidParameter { .. })
    ));
}
