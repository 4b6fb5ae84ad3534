//! Streams and preintegrators for the slice-versus-one-by-one checks: a smooth stream with
//! uneven stamps, a deltas-only preintegrator with a fixed bias, and pushing samples one at a
//! time.

use super::V3;
use preint::{ImuBias, ImuSample, Level, PreintError, PreintParams, Preintegrator, Scheme};

/// A smooth stream with slightly uneven stamps (every interval its own h).
pub fn jittered(n: usize) -> Vec<ImuSample> {
    (0..n as i64)
        .map(|k| {
            let t = k as f64 * 5e-3;
            let jitter = (k * 7919 % 13) * 10_000;
            ImuSample::new(
                k * 5_000_000 + jitter,
                V3::new(
                    0.4 * (1.3 * t).sin(),
                    0.3 * (0.7 * t).cos(),
                    0.2 + 0.5 * t.sin(),
                ),
                V3::new(
                    0.6 * (0.9 * t).sin(),
                    0.2 * t.cos(),
                    9.81 + 0.3 * (2.1 * t).sin(),
                ),
            )
        })
        .collect()
}

/// A `Level::Deltas` preintegrator of `scheme` (keeping its samples when `keep`) at a fixed
/// non-zero bias.
pub fn deltas_only(scheme: Scheme, keep: bool) -> Preintegrator {
    let mut prm = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Deltas);
    prm.keep_samples = keep;
    let bias = ImuBias::new(V3::new(0.01, -0.02, 0.005), V3::new(0.1, 0.05, -0.2));
    Preintegrator::new(prm, bias).unwrap()
}

/// One by one, stopping at the first error like `integrate_slice` does.
pub fn one_by_one(pi: &mut Preintegrator, s: &[ImuSample]) -> Result<(), PreintError> {
    for x in s {
        pi.integrate(x)?;
    }
    Ok(())
}
