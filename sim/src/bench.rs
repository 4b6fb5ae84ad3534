//! The benchmark stream: the samples on which `preint speed`, `tools/instructions.sh` and the
//! criterion benches of the `preint` crate measure the cost per sample, so that their figures
//! are comparable (`docs/PERFORMANCE.md`).

use nalgebra::Vector3;
use preint::ImuSample;

/// A smooth synthetic stream of `n` samples at 200 Hz (t = 0, 5 ms, …), with sinusoidal body
/// rates [rad/s] and specific force [m/s²] around +9.81 on z.
pub fn synthetic_stream(n: usize) -> Vec<ImuSample> {
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.005;
            ImuSample::new(
                k as i64 * 5_000_000,
                Vector3::new(
                    0.3 * (1.1 * t).sin(),
                    0.2 * (0.7 * t).cos(),
                    0.5 * (0.3 * t).sin() + 0.1,
                ),
                Vector3::new(
                    0.5 * (0.9 * t).sin(),
                    0.3 * (1.3 * t).cos(),
                    9.81 + 0.2 * (0.5 * t).sin(),
                ),
            )
        })
        .collect()
}
