//! The Allan fits are right within their stated errors on correct data: white noise of density
//! N = 1e-3 u/√Hz plus a random walk K, 100 Hz, six channels, in three cases,
//!
//! - (a) ten minutes of white noise only (K = 0),
//! - (b) an hour with K = 1e-4 u/s/√Hz (crossover τ* = √3·N/K = 17 s),
//! - (c) an hour with K = 3e-3 u/s/√Hz (strong random walk, τ* = 0.6 s),
//!
//! each over seeds (3 here, 40 with `PREINT_FULL=1`; `--nocapture` prints the table). Asserted
//! per case:
//! - N fitted on every channel, within 3 of its stated σ in ≥ 97 % of channel-runs; K within 3
//!   of its stated σ where fitted and, where it is a bound, the truth at or below the bound, in
//!   ≥ 97 % of channel-runs;
//! - no bias: the mean of the pulls `(estimate − truth)/σ` within 3 standard errors of 0
//!   (`3/√fits`), and their RMS in [0.7, 1.4] (stated errors neither optimistic nor
//!   pessimistic by more than 40 %);
//! - the fit credible (`ImuAllan::fit`, max |z| ≤ 5) in ≥ 99 % of runs.
//!
//! Measured with 40 seeds: the table in docs/EVIDENCE.md ("Calibration and noise
//! identification").

use preint_calib::allan::{ImuAllan, model_deviation};
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

const DT: f64 = 0.01;
const N: f64 = 1e-3;

/// Six channels of `n` samples: white noise N plus a random walk of density `k` (per-sample
/// std N/√Δt, walk step std k√Δt).
fn channels(n: usize, k: f64, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..6)
        .map(|_| {
            let mut walk = 0.0;
            (0..n)
                .map(|_| {
                    let y = N / DT.sqrt() * rng.sample::<f64, _>(StandardNormal) + walk;
                    walk += k * DT.sqrt() * rng.sample::<f64, _>(StandardNormal);
                    y
                })
                .collect()
        })
        .collect()
}

/// What one case's runs gave.
#[derive(Default)]
struct Tally {
    runs: usize,
    credible: usize,
    max_z: f64,
    n_pulls: Vec<f64>,
    n_rel: Vec<f64>,
    n_stated: Vec<f64>,
    k_pulls: Vec<f64>,
    k_rel: Vec<f64>,
    k_stated: Vec<f64>,
    /// Channel-runs whose K is a bound, and those of them with the truth above the bound.
    k_bounds: usize,
    k_bounds_below_truth: usize,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

fn within3(v: &[f64]) -> usize {
    v.iter().filter(|p| p.abs() <= 3.0).count()
}

fn run_case(n: usize, k: f64, seeds: std::ops::Range<u64>) -> Tally {
    let mut t = Tally::default();
    for seed in seeds {
        let ch = channels(n, k, seed);
        let a = ImuAllan::from_channels([&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]], DT, 10)
            .unwrap();
        let f = a.fit();
        t.runs += 1;
        t.credible += f.credible as usize;
        if !f.credible {
            println!("  seed {seed}: {}", f.why);
        }
        for (c, fit) in a.fits.iter().enumerate() {
            t.max_z = t.max_z.max(model_deviation(&a.curves[c], fit).max_abs_z);
            assert!(!fit.white_density_is_bound, "seed {seed} ch {c}: {fit:?}");
            t.n_pulls
                .push((fit.white_density - N) / fit.white_density_err);
            t.n_rel.push(fit.white_density / N - 1.0);
            t.n_stated.push(fit.white_density_err / N);
            if fit.random_walk_is_bound {
                t.k_bounds += 1;
                t.k_bounds_below_truth += (fit.random_walk < k) as usize;
            } else {
                t.k_pulls.push((fit.random_walk - k) / fit.random_walk_err);
                if k > 0.0 {
                    t.k_rel.push(fit.random_walk / k - 1.0);
                    t.k_stated.push(fit.random_walk_err / k);
                }
            }
        }
    }
    t
}

/// The table row of a case (relative figures in %).
fn row(name: &str, t: &Tally) -> String {
    let n_fits = t.n_pulls.len();
    let k_ok = within3(&t.k_pulls) + t.k_bounds - t.k_bounds_below_truth;
    let pair = |v: &[f64], scale: f64| {
        if v.is_empty() {
            "—".to_string()
        } else {
            format!("{:+.2} / {:.2}", scale * mean(v), scale * rms(v))
        }
    };
    format!(
        "| {name} | {}/{} | {:.2} | {}/{n_fits} | {} | {} (stated {:.2}) | {k_ok}/{n_fits} ({} bounds, {} below the truth) | {} | {} (stated {}) |",
        t.credible,
        t.runs,
        t.max_z,
        within3(&t.n_pulls),
        pair(&t.n_pulls, 1.0),
        pair(&t.n_rel, 100.0),
        100.0 * mean(&t.n_stated),
        t.k_bounds,
        t.k_bounds_below_truth,
        pair(&t.k_pulls, 1.0),
        pair(&t.k_rel, 100.0),
        if t.k_stated.is_empty() {
            "—".to_string()
        } else {
            format!("{:.2}", 100.0 * mean(&t.k_stated))
        },
    )
}

fn check(name: &str, t: &Tally) {
    let fits = t.n_pulls.len() as f64;
    assert!(
        within3(&t.n_pulls) as f64 >= 0.97 * fits,
        "{name}: N within 3σ"
    );
    let k_ok = within3(&t.k_pulls) + t.k_bounds - t.k_bounds_below_truth;
    assert!(k_ok as f64 >= 0.97 * fits, "{name}: K within 3σ or bounded");
    for (what, pulls) in [("N", &t.n_pulls), ("K", &t.k_pulls)] {
        if pulls.len() < 6 {
            continue;
        }
        let m = mean(pulls);
        assert!(
            m.abs() <= 3.0 / (pulls.len() as f64).sqrt(),
            "{name}: {what} biased, mean pull {m}"
        );
        let r = rms(pulls);
        assert!((0.7..=1.4).contains(&r), "{name}: {what} pull RMS {r}");
    }
    assert!(
        t.credible as f64 >= 0.99 * t.runs as f64,
        "{name}: credible in {} of {} runs",
        t.credible,
        t.runs
    );
}

#[test]
fn estimates_are_right_within_their_stated_errors() {
    let full = std::env::var("PREINT_FULL").is_ok_and(|v| v == "1");
    let seeds = if full { 40 } else { 3 };
    println!(
        "| case | credible | max \\|z\\| | N within 3σ | N pull mean / RMS | N error mean / RMS [%] | K within 3σ or ≤ bound | K pull mean / RMS | K error mean / RMS [%] |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, n, k, first) in [
        ("(a) 10 min, white only", 60_000, 0.0, 0),
        ("(b) 1 h, K = 1e-4", 360_000, 1e-4, 1000),
        ("(c) 1 h, K = 3e-3", 360_000, 3e-3, 2000),
    ] {
        let t = run_case(n, k, first..first + seeds);
        println!("{}", row(name, &t));
        check(name, &t);
    }
}
