//! Accuracy against cost per scheme and rate on a built-in scene.
//!
//! For each rate, noise-free samples of the scene on the grid `t_k = k·round(1e9/rate)` ns
//! ([`preint_sim::SceneState::ideal_sample`]) are preintegrated over `[1 s, 1 s + window]` and
//! compared with the scene's exact deltas ([`preint_sim::exact_deltas`]): rotation error = angle
//! of `ΔR*ᵀΔR` \[rad\], velocity and position errors = norms [m/s, m]. Cost = measured ns/sample
//! of the scheme (with covariance and bias Jacobians, [`preint_analysis::speed::best_ns_per_sample`]) ×
//! rate = ns per second of IMU data.

use crate::{CliError, input, scheme};
use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, Level, PreintParams, Scheme, preintegrate};
use preint_analysis::checks;
use preint_analysis::speed::{best_ns_per_sample, synthetic_stream};

/// One scheme at one rate.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scheme.
    pub scheme: Scheme,
    /// Sample rate \[Hz\].
    pub rate: f64,
    /// Measured cost [ns/sample].
    pub ns_per_sample: f64,
    /// Errors against the exact deltas: [rad, m/s, m].
    pub err: [f64; 3],
}

impl Row {
    /// Cost per second of IMU data \[ns\].
    pub fn cost_per_s(&self) -> f64 {
        self.ns_per_sample * self.rate
    }
}

/// Longest window \[s\] of [`measure`].
pub const MAX_WINDOW_S: f64 = 1000.0;

/// Most samples of one rate's grid in [`measure`] (560 MB).
pub const MAX_SAMPLES: usize = 10_000_000;

/// Errors of every scheme at every rate on `scene_name` (noise-free, window
/// `[1 s, 1 s + window_s]`, gravity (0, 0, −9.81) m/s²), plus measured costs. Windows longer
/// than [`MAX_WINDOW_S`] and grids of more than [`MAX_SAMPLES`] are refused before allocating.
pub fn measure(scene_name: &str, rates: &[f64], window_s: f64) -> Result<Vec<Row>, CliError> {
    let scene = input::scene(scene_name)?;
    checks::positive("--window", window_s)?;
    if window_s > MAX_WINDOW_S {
        return Err(CliError::Usage(format!(
            "--window must be at most {MAX_WINDOW_S} s (the exact deltas are integrated over it), got {window_s}"
        )));
    }
    let g = Vector3::new(0.0, 0.0, -9.81);
    let t_i: i64 = 1_000_000_000;
    let t_j = t_i + (window_s * 1e9).round() as i64;
    let (r_true, v_true, p_true) = preint_sim::exact_deltas(scene.as_ref(), t_i, t_j, g);
    let ns = best_ns_per_sample(
        &scheme::ALL,
        Level::Covariance,
        &synthetic_stream(50_000),
        3,
    )?;
    let mut rows = Vec::new();
    let pb = preint_analysis::progress::bar(rates.len() as u64, "bench-steps");
    for &rate in rates {
        if let Some(pb) = &pb {
            pb.set_message(format!("{rate} Hz"));
            pb.inc(1);
        }
        let step = (1e9 / rate).round() as i64;
        if step <= 0 {
            return Err(CliError::Usage(format!(
                "--rates {rate:e}: above 1e9 Hz, the sample period would be below the 1 ns \
                 resolution of the timestamps"
            )));
        }
        // Grid covering the window plus four samples each side (hermite4 needs neighbours).
        let (k0, k1) = (t_i / step - 4, t_j / step + 5);
        if k1 - k0 + 1 > MAX_SAMPLES as i64 {
            return Err(CliError::Usage(format!(
                "--rates {rate:e}: {rate} Hz over a {window_s} s window is {} samples, more than \
                 {MAX_SAMPLES} (56 bytes each in memory); lower the rate or the window",
                k1 - k0 + 1
            )));
        }
        let samples: Vec<_> = (k0..=k1)
            .map(|k| {
                let t = k * step;
                scene.state(preint_sim::t_s(t)).ideal_sample(t, &g)
            })
            .collect();
        for (&scheme, &ns_per_sample) in scheme::ALL.iter().zip(&ns) {
            // The grid is uniform: its interval is the rate asked about, not a gap of a
            // recording (below 4 Hz it exceeds the default gap limit).
            let params = PreintParams {
                max_gap_ns: step.max(preint::DEFAULT_MAX_GAP_NS),
                ..PreintParams::from_noise(&ImuNoise::euroc())
                    .with_scheme(scheme)
                    .with_level(Level::Deltas)
                    .with_gravity(g)
            };
            let m = preintegrate(&params, &ImuBias::zero(), &samples, t_i, t_j).map_err(|e| {
                CliError::Failed(format!("{} at {rate} Hz: {e}", scheme::label(scheme)))
            })?;
            let err = [
                m.delta_r.minus(&r_true).norm(),
                (m.delta_v - v_true).norm(),
                (m.delta_p - p_true).norm(),
            ];
            rows.push(Row {
                scheme,
                rate,
                ns_per_sample,
                err,
            });
        }
    }
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(rows)
}

/// Least-squares slope of log(err) against log(rate) of component `comp` (0 rotation,
/// 1 velocity, 2 position), over points above the round-off floor (err > 1e-13); `None` with
/// fewer than two such points.
pub fn order(rows: &[Row], scheme: Scheme, comp: usize) -> Option<f64> {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.scheme == scheme && r.err[comp] > 1e-13)
        .map(|r| (r.rate.ln(), r.err[comp].ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    Some(-sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_of_a_power_law() {
        let rows: Vec<Row> = [10.0, 20.0, 40.0]
            .iter()
            .map(|&rate: &f64| Row {
                scheme: Scheme::Midpoint,
                rate,
                ns_per_sample: 1.0,
                err: [rate.powi(-2), 1e-14, 3.0 * rate.powi(-4)],
            })
            .collect();
        assert!((order(&rows, Scheme::Midpoint, 0).unwrap() - 2.0).abs() < 1e-12);
        assert!(order(&rows, Scheme::Midpoint, 1).is_none());
        assert!((order(&rows, Scheme::Midpoint, 2).unwrap() - 4.0).abs() < 1e-12);
        assert!(order(&rows, Scheme::Euler, 0).is_none());
    }
}
