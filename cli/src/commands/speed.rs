//! `preint speed`: throughput of each scheme on this machine, with and without covariance.
//!
//! Method: a synthetic smooth stream of N samples at 200 Hz (sinusoidal rates and specific
//! force), integrated once per scheme and level with `Preintegrator::integrate_slice`
//! (`keep_samples` off, so nothing is stored); the median of 11 runs is reported as ns/sample
//! (criterion reports a mean over its samples; the README compares the two).
//! The criterion benchmark `cargo bench -p preint` measures the same loop.

use super::{CliError, Output};
use crate::Command;
use crate::commands::integrate::scheme_name;
pub use preint::sample::synthetic_stream;
use preint::{ImuBias, ImuNoise, ImuSample, Level, PreintParams, Preintegrator, Scheme};
use serde_json::json;
use std::fmt::Write as _;
use std::time::Instant;

/// One run: the ns/sample of `scheme` at `level` over `samples`.
fn one_run(scheme: Scheme, level: Level, samples: &[ImuSample]) -> Result<f64, CliError> {
    let mut params = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level);
    params.keep_samples = false;
    let mut p =
        Preintegrator::new(params, ImuBias::zero()).map_err(|e| CliError::Failed(e.to_string()))?;
    let t0 = Instant::now();
    p.integrate_slice(samples)
        .map_err(|e| CliError::Failed(e.to_string()))?;
    let m = p.finish().map_err(|e| CliError::Failed(e.to_string()))?;
    let dt = t0.elapsed().as_secs_f64();
    std::hint::black_box(&m);
    Ok(dt * 1e9 / samples.len() as f64)
}

/// Best-of-`runs` ns/sample of each scheme at `level` over `samples`, for the cost
/// comparisons of `bench-steps` and `advise`. The schemes take turns within each round, so a
/// burst of load on the machine slows all of them alike instead of deciding which one looks
/// cheaper; the best run is the least disturbed.
pub fn best_ns_per_sample(
    schemes: &[Scheme],
    level: Level,
    samples: &[ImuSample],
    runs: usize,
) -> Result<Vec<f64>, CliError> {
    let mut best = vec![f64::INFINITY; schemes.len()];
    for _ in 0..runs.max(1) {
        for (b, &scheme) in best.iter_mut().zip(schemes) {
            *b = b.min(one_run(scheme, level, samples)?);
        }
    }
    Ok(best)
}

/// Median over `runs` of the ns/sample, as `preint speed` reports it (comparable with
/// criterion's estimate over its samples).
fn median_ns_per_sample(
    scheme: Scheme,
    level: Level,
    samples: &[ImuSample],
    runs: usize,
) -> Result<f64, CliError> {
    let mut t = (0..runs.max(1))
        .map(|_| one_run(scheme, level, samples))
        .collect::<Result<Vec<_>, _>>()?;
    t.sort_by(f64::total_cmp);
    Ok(t[t.len() / 2])
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Speed { samples } = cmd else {
        unreachable!()
    };
    if *samples < 10 {
        return Err(CliError::Usage("--samples must be at least 10".into()));
    }
    let stream = synthetic_stream(*samples);
    let mut rows = Vec::new();
    let mut h = format!(
        "{} samples, median of 11 runs, ns per sample (this machine):\n",
        samples
    );
    let _ = writeln!(
        h,
        "{:<10} {:>12} {:>16} {:>14}",
        "scheme", "deltas only", "+cov+bias jac", "+15x15 cov"
    );
    for scheme in [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4] {
        let d = median_ns_per_sample(scheme, Level::Deltas, &stream, 11)?;
        let c = median_ns_per_sample(scheme, Level::Covariance, &stream, 11)?;
        let c15 = median_ns_per_sample(scheme, Level::Combined, &stream, 11)?;
        let _ = writeln!(
            h,
            "{:<10} {:>12.1} {:>16.1} {:>14.1}",
            scheme_name(scheme),
            d,
            c,
            c15
        );
        rows.push(json!({"scheme": scheme_name(scheme), "ns_per_sample": {"deltas": d, "covariance": c, "combined": c15}}));
    }
    let json = json!({"samples": samples, "rate_hz": 200.0, "schemes": rows,
        "method": "median of 11 runs of Preintegrator::integrate_slice over a synthetic 200 Hz stream"});
    Ok(Output { human: h, json })
}
