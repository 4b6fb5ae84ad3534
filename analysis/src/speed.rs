//! Throughput of the schemes on this machine.
//!
//! Method: a synthetic smooth stream of N samples at 200 Hz (sinusoidal rates and specific
//! force, [`synthetic_stream`]), integrated once per scheme and level with
//! `Preintegrator::integrate_slice` (`keep_samples` off, so nothing is stored); the time per
//! sample is the wall-clock time of the whole run over N. The criterion benchmark
//! `cargo bench -p preint` measures the same loop.

use crate::Error;
use preint::{ImuBias, ImuNoise, ImuSample, Level, PreintParams, Preintegrator, Scheme};
pub use preint_sim::synthetic_stream;
use std::time::Instant;

/// One run: the ns/sample of `scheme` at `level` over `samples`.
pub fn one_run(scheme: Scheme, level: Level, samples: &[ImuSample]) -> Result<f64, Error> {
    let mut params = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level);
    params.keep_samples = false;
    let mut p = Preintegrator::new(params, ImuBias::zero()).map_err(Error::failed)?;
    let t0 = Instant::now();
    p.integrate_slice(samples).map_err(Error::failed)?;
    let m = p.finish().map_err(Error::failed)?;
    let dt = t0.elapsed().as_secs_f64();
    std::hint::black_box(&m);
    Ok(dt * 1e9 / samples.len() as f64)
}

/// Best-of-`runs` ns/sample of each scheme at `level` over `samples`, for cost comparisons.
/// The schemes take turns within each round, so a burst of load on the machine slows all of
/// them alike instead of deciding which one looks cheaper; the best run is the least disturbed.
pub fn best_ns_per_sample(
    schemes: &[Scheme],
    level: Level,
    samples: &[ImuSample],
    runs: usize,
) -> Result<Vec<f64>, Error> {
    let mut best = vec![f64::INFINITY; schemes.len()];
    for _ in 0..runs.max(1) {
        for (b, &scheme) in best.iter_mut().zip(schemes) {
            *b = b.min(one_run(scheme, level, samples)?);
        }
    }
    Ok(best)
}

/// Median over `runs` of the ns/sample (comparable with criterion's estimate over its samples).
pub fn median_ns_per_sample(
    scheme: Scheme,
    level: Level,
    samples: &[ImuSample],
    runs: usize,
) -> Result<f64, Error> {
    let mut t = (0..runs.max(1))
        .map(|_| one_run(scheme, level, samples))
        .collect::<Result<Vec<_>, _>>()?;
    t.sort_by(f64::total_cmp);
    Ok(t[t.len() / 2])
}

/// The median ns/sample of one scheme at the three levels.
#[derive(Clone, Copy, Debug)]
pub struct Throughput {
    /// The scheme.
    pub scheme: Scheme,
    /// Deltas only ([`Level::Deltas`]) [ns/sample].
    pub deltas: f64,
    /// With the 9×9 covariance and bias Jacobians ([`Level::Covariance`]) [ns/sample].
    pub covariance: f64,
    /// With the 15×15 covariance ([`Level::Combined`]) [ns/sample].
    pub combined: f64,
}

/// [`Throughput`] of every scheme over a synthetic stream of `samples` samples, the median of
/// `runs` runs each.
pub fn throughput(samples: usize, runs: usize) -> Result<Vec<Throughput>, Error> {
    let stream = synthetic_stream(samples);
    let pb = crate::progress::bar(Scheme::ALL.len() as u64, "speed");
    let rows = Scheme::ALL
        .iter()
        .copied()
        .map(|scheme| {
            if let Some(pb) = &pb {
                pb.set_message(scheme.name());
            }
            let row = Throughput {
                scheme,
                deltas: median_ns_per_sample(scheme, Level::Deltas, &stream, runs)?,
                covariance: median_ns_per_sample(scheme, Level::Covariance, &stream, runs)?,
                combined: median_ns_per_sample(scheme, Level::Combined, &stream, runs)?,
            };
            if let Some(pb) = &pb {
                pb.inc(1);
            }
            Ok(row)
        })
        .collect();
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    rows
}
