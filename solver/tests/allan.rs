//! Allan deviation: hand-computed values, recovery of known white-noise density and random
//! walk from synthetic series, slope −½ for pure white noise, input validation.

use nalgebra::Vector3;
use preint::ImuSample;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use solver::allan::{AllanError, ImuAllan, allan_deviation, fit_noise, log_spaced_cluster_sizes};

/// White noise of density `n` [u/√Hz] plus a random walk of density `k` [u/s/√Hz], sampled every
/// `dt`: per-sample std n/√dt, bias step std k√dt (ARCHITECTURE.md conventions).
fn synth(rng: &mut StdRng, len: usize, dt: f64, n: f64, k: f64, offset: f64) -> Vec<f64> {
    let mut b = offset;
    (0..len)
        .map(|_| {
            let w: f64 = rng.sample(StandardNormal);
            let z: f64 = rng.sample(StandardNormal);
            let y = b + w * n / dt.sqrt();
            b += z * k * dt.sqrt();
            y
        })
        .collect()
}

#[test]
fn hand_computed_alternating_series() {
    // ±1 alternating: m = 1 → σ² = ½⟨(y_{k+1} − y_k)²⟩ = 2; m = 2 → every cluster mean is 0.
    let y: Vec<f64> = (0..1000)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let pts = allan_deviation(&y, 0.01, &[1, 2, 4]).unwrap();
    assert!((pts[0].adev - 2f64.sqrt()).abs() < 1e-12, "{}", pts[0].adev);
    assert!(pts[1].adev < 1e-12 && pts[2].adev < 1e-12);
    assert!((pts[0].tau - 0.01).abs() < 1e-15 && (pts[2].tau - 0.04).abs() < 1e-15);
    // Confidence: σ/√(2(N/m − 1)) with N/m = 1000.
    assert!((pts[0].adev_err - 2f64.sqrt() / (2.0 * 999.0f64).sqrt()).abs() < 1e-12);
}

#[test]
fn cluster_sizes_are_log_spaced() {
    let ms = log_spaced_cluster_sizes(1000, 10);
    assert_eq!(&ms[..10], &[1, 2, 3, 4, 5, 6, 8, 10, 13, 16]);
    assert_eq!(*ms.last().unwrap(), 1000);
    assert!(ms.windows(2).all(|w| w[1] > w[0]));
    // About 10 per decade over 3 decades once m is large enough to be distinct.
    assert!((25..=31).contains(&ms.len()), "{}", ms.len());
}

/// Pure white noise: every reliable point sits on a slope −½ line, the fitted density is the
/// simulated one, and the random walk is only a bound (no +½ region).
#[test]
fn pure_white_noise_gives_slope_minus_half() {
    let mut rng = StdRng::seed_from_u64(11);
    let dt = 0.01;
    let n = 2e-3;
    let y = synth(&mut rng, 200_000, dt, n, 0.0, 9.81);
    let ms = log_spaced_cluster_sizes(y.len() / 2, 10);
    let pts = allan_deviation(&y, dt, &ms).unwrap();
    let rel: Vec<_> = pts.iter().filter(|p| p.clusters >= 8.0).collect();
    // Least-squares log-log slope over all reliable points.
    let k = rel.len() as f64;
    let (mx, my) = (
        rel.iter().map(|p| p.tau.ln()).sum::<f64>() / k,
        rel.iter().map(|p| p.adev.ln()).sum::<f64>() / k,
    );
    let sxy: f64 = rel
        .iter()
        .map(|p| (p.tau.ln() - mx) * (p.adev.ln() - my))
        .sum();
    let sxx: f64 = rel.iter().map(|p| (p.tau.ln() - mx).powi(2)).sum();
    let slope = sxy / sxx;
    assert!((slope + 0.5).abs() < 0.03, "slope {slope}");
    let fit = fit_noise(&pts, 0).unwrap();
    assert!((fit.white_density / n - 1.0).abs() < 0.05, "{fit:?}");
    assert!(fit.random_walk_is_bound, "{fit:?}");
    // Every point agrees with N/√τ within 4 of its own σ-error bands.
    for p in &rel {
        let model = n / p.tau.sqrt();
        assert!((p.adev - model).abs() < 4.0 * p.adev_err, "{p:?}");
    }
}

/// White noise + random walk, 10 h at 20 Hz (720 000 samples): both densities within 10 %, for
/// each of 4 seeds. (Crossover at τ = √3 N/K ≈ 17 s; the +½ region spans ~100 s … 4500 s.)
#[test]
fn white_noise_and_random_walk_recovered_within_10_percent() {
    let dt = 0.05;
    let (n, k) = (1e-3, 1e-4);
    for seed in 0..4 {
        let mut rng = StdRng::seed_from_u64(100 + seed);
        let y = synth(&mut rng, 720_000, dt, n, k, 0.0);
        let ms = log_spaced_cluster_sizes(y.len() / 2, 10);
        let fit = fit_noise(&allan_deviation(&y, dt, &ms).unwrap(), 0).unwrap();
        eprintln!(
            "seed {seed}: N {:.4e} ({:+.1} %), K {:.4e} ({:+.1} %), K range {:?}",
            fit.white_density,
            100.0 * (fit.white_density / n - 1.0),
            fit.random_walk,
            100.0 * (fit.random_walk / k - 1.0),
            fit.random_walk_tau_range
        );
        assert!(!fit.random_walk_is_bound);
        assert!(
            (fit.white_density / n - 1.0).abs() < 0.10,
            "seed {seed}: {fit:?}"
        );
        assert!(
            (fit.random_walk / k - 1.0).abs() < 0.10,
            "seed {seed}: {fit:?}"
        );
    }
}

#[test]
fn imu_samples_to_kalibr_noise_uses_max_over_axes() {
    let mut rng = StdRng::seed_from_u64(7);
    let dt = 0.005;
    let len = 60_000;
    let dens = [1e-4, 2e-4, 1.5e-4, 1e-3, 3e-3, 2e-3];
    let ch: Vec<Vec<f64>> = dens
        .iter()
        .enumerate()
        .map(|(i, d)| synth(&mut rng, len, dt, *d, 0.0, if i == 5 { 9.81 } else { 0.0 }))
        .collect();
    let samples: Vec<ImuSample> = (0..len)
        .map(|i| {
            ImuSample::new(
                1_400_000_000_000_000_000 + i as i64 * 5_000_000,
                Vector3::new(ch[0][i], ch[1][i], ch[2][i]),
                Vector3::new(ch[3][i], ch[4][i], ch[5][i]),
            )
        })
        .collect();
    let a = ImuAllan::from_samples(&samples, 10).unwrap();
    assert!((a.dt - dt).abs() < 1e-12);
    let noise = a.to_imu_noise();
    assert!(
        (noise.gyro_noise_density / 2e-4 - 1.0).abs() < 0.05,
        "{noise:?}"
    );
    assert!(
        (noise.acc_noise_density / 3e-3 - 1.0).abs() < 0.05,
        "{noise:?}"
    );
    assert!((noise.update_rate_hz - 200.0).abs() < 1e-6);
    let yaml = a.kalibr_yaml();
    assert!(yaml.contains("gyroscope_noise_density"), "{yaml}");

    // A gap in the timestamps is an error, not a silently wrong τ.
    let mut gappy = samples.clone();
    gappy.remove(100);
    assert!(matches!(
        ImuAllan::from_samples(&gappy, 10),
        Err(AllanError::Timestamps(_))
    ));
}

#[test]
fn bad_inputs_give_typed_errors() {
    assert_eq!(
        allan_deviation(&[1.0; 4], 0.01, &[1]),
        Err(AllanError::TooFewSamples(4))
    );
    assert_eq!(
        allan_deviation(&[1.0; 10], 0.0, &[1]),
        Err(AllanError::BadPeriod(0.0))
    );
    let mut y = vec![0.0; 10];
    y[3] = f64::NAN;
    assert!(matches!(
        allan_deviation(&y, 0.01, &[1]),
        Err(AllanError::NonFinite { index: 3, .. })
    ));
    let a = vec![0.0; 100];
    let b = vec![0.0; 99];
    assert_eq!(
        ImuAllan::from_channels([&a, &a, &a, &a, &a, &b], 0.01, 10),
        Err(AllanError::LengthMismatch(100, 99))
    );
}
