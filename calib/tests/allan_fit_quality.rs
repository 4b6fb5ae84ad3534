//! The Allan fit's goodness of fit (`ImuAllan::fit`): the model curve against the measured
//! one in units of its statistical error, credible on simulated white noise plus random walk
//! and on the real ADIS16405 hour, not credible when a disturbance the model lacks shapes the
//! curve.

use preint_calib::allan::{ImuAllan, MAX_MODEL_Z, model_deviation};
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

/// Six channels of `n` samples at 100 Hz: white noise N = 1e-3 u/√Hz, random walk `k` u/s/√Hz
/// and a sinusoid of amplitude `a` at 1 Hz.
fn channels(n: usize, k: f64, a: f64, seed: u64) -> Vec<Vec<f64>> {
    let dt: f64 = 0.01;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..6)
        .map(|_| {
            let mut w = 0.0;
            (0..n)
                .map(|i| {
                    w += k * dt.sqrt() * rng.sample::<f64, _>(StandardNormal);
                    let s = a * (std::f64::consts::TAU * i as f64 * dt).sin();
                    1e-3 / dt.sqrt() * rng.sample::<f64, _>(StandardNormal) + w + s
                })
                .collect()
        })
        .collect()
}

fn allan(ch: &[Vec<f64>], dt: f64) -> ImuAllan {
    ImuAllan::from_channels([&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]], dt, 10).unwrap()
}

#[test]
fn white_noise_and_random_walk_fit_credibly() {
    for seed in 0..3 {
        let a = allan(&channels(360_000, 1e-4, 0.0, seed), 0.01);
        let f = a.fit();
        assert!(f.credible, "seed {seed}: {}", f.why);
        assert!(f.dof > 60 && f.p_value.is_nan(), "{f:?}");
        // Σz²/points near 1 or below: the errors ε are those of the points (correlated).
        assert!(f.chi2_dof < 2.0, "{f:?}");
        for c in 0..6 {
            assert!(model_deviation(&a.curves[c], &a.fits[c]).max_abs_z <= MAX_MODEL_Z);
        }
    }
}

/// A 1 Hz disturbance of amplitude 1e-2 u on the white noise (whose σ at 1 s is 1e-3 u): the curve has a
/// bump no line of the model follows.
#[test]
fn a_disturbance_makes_the_fit_not_credible() {
    let f = allan(&channels(60_000, 0.0, 1e-2, 1), 0.01).fit();
    assert!(!f.credible, "{}", f.why);
    assert!(
        f.why.contains("misses the measured Allan deviation"),
        "{}",
        f.why
    );
    assert!(f.why.contains("likely cause"), "{}", f.why);
}

/// The real static ADIS16405 hour (tests/data/adis16405, 10 Hz block means): credible.
#[test]
fn adis16405_fit_is_credible() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let mut cols = vec![Vec::new(); 6];
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|x| x.trim().parse().unwrap()).collect();
        for c in 0..6 {
            cols[c].push(f[1 + c]);
        }
    }
    let f = allan(&cols, 0.1).fit();
    assert!(f.credible, "{}", f.why);
}
