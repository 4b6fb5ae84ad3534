//! The statistics of the overlapping Allan variance (`preint_calib::allan::edf`): its
//! equivalent degrees of freedom against the published formulas (NIST SP 1065 Table 5,
//! Greenhall and Riley 2003 Table 2) and against Monte Carlo, the covariance of two τ
//! against Monte Carlo, and the normal deviate and quantile of `χ²_ν/ν` against closed forms.

use preint_calib::allan::allan_deviation;
use preint_calib::allan::edf::{
    NoiseLevels, avar_covariance, chi2_quantile_ratio, edf, normal_deviate,
};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

const WALK: NoiseLevels = NoiseLevels {
    white: 0.0,
    random_walk: 1.0,
};

/// White noise: NIST SP 1065 (2008) Table 5, `ν = [3(N−1)/(2m) − 2(N−2)/N]·4m²/(4m² + 5)`
/// with N = n + 1 phase points, for short clusters (the formula is an approximation; it is
/// within 0.03 % of the exact sum up to m = 100); for long clusters, Greenhall and Riley's
/// Table 2, `1/ν = (a₀ − a₁/r)/r`, `r = (N − 2m)/m`, (a₀, a₁) = (2/3, 1/3), and for a random
/// walk (1.079, 0.368), within 0.1 %.
#[test]
fn edf_meets_the_published_formulas() {
    let n = 80_000;
    let white = NoiseLevels::white(1.0);
    let nx = (n + 1) as f64;
    for m in [1usize, 2, 5, 10, 33, 100] {
        let mm = m as f64;
        let sp1065 = (3.0 * (nx - 1.0) / (2.0 * mm) - 2.0 * (nx - 2.0) / nx) * 4.0 * mm * mm
            / (4.0 * mm * mm + 5.0);
        let nu = edf(&white, 0.01, n, m);
        assert!((nu / sp1065 - 1.0).abs() < 3e-4, "m {m}: {nu} vs {sp1065}");
    }
    let table = |r: f64, a0: f64, a1: f64| r / (a0 - a1 / r);
    for (n, m) in [
        (80_000usize, 1000usize),
        (80_000, 10_000),
        (200_000, 10_000),
    ] {
        let r = (n + 1 - 2 * m) as f64 / m as f64;
        let (w, k) = (edf(&white, 0.01, n, m), edf(&WALK, 0.01, n, m));
        let (tw, tk) = (table(r, 2.0 / 3.0, 1.0 / 3.0), table(r, 1.079, 0.368));
        println!(
            "n {n}, m {m} (r = {r:.1}): white {w:.3} (table {tw:.3}), walk {k:.3} (table {tk:.3})"
        );
        assert!((w / tw - 1.0).abs() < 1e-3, "white n {n} m {m}");
        assert!((k / tk - 1.0).abs() < 1e-3, "walk n {n} m {m}");
    }
    // At 8 clusters a random walk has 5.9 EDF, fewer than the 7 of independent clusters.
    assert!(edf(&WALK, 0.01, 80_000, 10_000) < 0.85 * 7.0);
}

/// `R` replicas of `n` samples of white noise (unit density at Δt = 1) or a random walk (unit
/// density), with their Allan variances at the cluster sizes `ms`.
fn replicas(walk: bool, n: usize, ms: &[usize], r: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..r)
        .map(|_| {
            let mut b = 0.0;
            let y: Vec<f64> = (0..n)
                .map(|_| {
                    let z: f64 = rng.sample(StandardNormal);
                    if walk {
                        b += z;
                        b
                    } else {
                        z
                    }
                })
                .collect();
            allan_deviation(&y, 1.0, ms)
                .unwrap()
                .iter()
                .map(|p| p.adev * p.adev)
                .collect()
        })
        .collect()
}

fn mean_var(v: &[f64]) -> (f64, f64) {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (
        m,
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64,
    )
}

/// Monte Carlo, 4000 replicas of 4000 samples at m = 500 (8 clusters): the EDF `2E²/Var` of
/// the estimates is the computed one within 10 % (the sampling error of a variance from 4000
/// draws of a χ² with 6–10 EDF is ≈ 4 %), for white noise (ν = 10.2) and for a random walk
/// (ν = 5.9, which rules out the 7 of independent clusters); and the correlation of the
/// estimates at m = 50 and 63 of white noise (0.89) within 0.02 of `avar_covariance`'s.
#[test]
fn edf_and_covariance_match_monte_carlo() {
    let (n, r) = (4000, 4000);
    for (walk, seed) in [(false, 1), (true, 2)] {
        let ms = [50, 63, 500];
        let runs = replicas(walk, n, &ms, r, seed);
        let levels = if walk { WALK } else { NoiseLevels::white(1.0) };
        let (m, v) = mean_var(&runs.iter().map(|x| x[2]).collect::<Vec<_>>());
        let (empirical, computed) = (2.0 * m * m / v, edf(&levels, 1.0, n, 500));
        println!(
            "walk {walk}: EDF at 8 clusters: Monte Carlo {empirical:.2}, computed {computed:.2}"
        );
        assert!((empirical / computed - 1.0).abs() < 0.10, "walk {walk}");
        if walk {
            assert!(empirical < 0.9 * 7.0, "{empirical}");
            continue;
        }
        let (a, b): (Vec<f64>, Vec<f64>) = runs.iter().map(|x| (x[0], x[1])).unzip();
        let ((ma, va), (mb, vb)) = (mean_var(&a), mean_var(&b));
        let cov = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - ma) * (y - mb))
            .sum::<f64>()
            / (r - 1) as f64;
        let rho = cov / (va * vb).sqrt();
        let predicted = avar_covariance(&levels, 1.0, n, 50, 63)
            / (avar_covariance(&levels, 1.0, n, 50, 50) * avar_covariance(&levels, 1.0, n, 63, 63))
                .sqrt();
        println!("correlation at m = 50, 63: Monte Carlo {rho:.3}, computed {predicted:.3}");
        assert!((rho - predicted).abs() < 0.02);
    }
}

/// With ν = 2, `χ²₂/2` is exponential: `P(χ²₂/2 ≤ r) = 1 − e^{−r}`, so the ratios whose
/// deviates are ∓3 are `−ln(1 − Φ(−3))` and `−ln Φ(−3)`, `Φ(−3) = 0.0013498980316301`. For
/// large ν the deviate of `1 + 3√(2/ν)` is 3 (the normal limit).
#[test]
fn normal_deviate_and_quantile_meet_closed_forms() {
    let phi3: f64 = 0.001_349_898_031_630_094_6;
    let (low, high) = (-(1.0 - phi3).ln(), -phi3.ln());
    assert!((chi2_quantile_ratio(-3.0, 2.0) / low - 1.0).abs() < 1e-9);
    assert!((chi2_quantile_ratio(3.0, 2.0) / high - 1.0).abs() < 1e-9);
    assert!((normal_deviate(low, 2.0) + 3.0).abs() < 1e-6);
    assert!((normal_deviate(high, 2.0) - 3.0).abs() < 1e-6);
    let nu = 1e6;
    assert!((normal_deviate(1.0 + 3.0 * (2.0f64 / nu).sqrt(), nu) - 3.0).abs() < 0.01);
    // Beyond the f64 range of the tail probabilities, the leading terms: with ν = 2,
    // ln P = ln r and ln Q = −r, and ln Φ(−t) ≈ −t²/2 − ln t − ln √(2π).
    let ln_phi = |t: f64| -0.5 * t * t - t.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln();
    let z = normal_deviate(1e-320, 2.0);
    assert!(
        z < -37.0 && (ln_phi(-z) / (1e-320f64).ln() - 1.0).abs() < 1e-6,
        "{z}"
    );
    let z = normal_deviate(800.0, 2.0);
    assert!(z > 37.0 && (ln_phi(z) / -800.0 - 1.0).abs() < 1e-6, "{z}");
    assert_eq!(normal_deviate(0.0, 6.0), f64::NEG_INFINITY);
}
