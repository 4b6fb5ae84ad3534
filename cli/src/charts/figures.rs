//! The charts the commands and the report draw: accuracy against cost, convergence, Allan
//! deviation, attitude error against time.

use super::{Chart, Series, draw, pareto_front};
use crate::analysis::accuracy::{Row, order};
use crate::format::IMU_AXES;
use crate::{CliError, scheme};
use preint_calib::allan::ImuAllan;
use std::path::{Path, PathBuf};

/// Writes the accuracy-vs-cost chart (position error against µs per second of IMU data, one
/// line per scheme, the Pareto front dashed) as `accuracy_vs_cost_{scene}.svg` in `dir`.
pub fn accuracy_vs_cost(rows: &[Row], scene: &str, dir: &Path) -> Result<PathBuf, CliError> {
    let mut series: Vec<Series> = scheme::ALL
        .iter()
        .map(|&s| {
            Series::line(
                scheme::label(s),
                rows.iter()
                    .filter(|r| r.scheme == s)
                    .map(|r| (r.cost_per_s() * 1e-3, r.err[2]))
                    .collect(),
            )
        })
        .collect();
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.cost_per_s() * 1e-3, r.err[2]))
        .collect();
    let front: Vec<(f64, f64)> = pareto_front(&pts).into_iter().map(|i| pts[i]).collect();
    series.push(Series::reference("Pareto front", front));
    let path = dir.join(format!("accuracy_vs_cost_{scene}.svg"));
    let title = format!("{scene}: position error after 1 s vs cost");
    let chart = Chart {
        title: &title,
        x_label: "cost [µs per second of IMU data]",
        y_label: "position error [m]",
        log_x: true,
        log_y: true,
    };
    draw(&path, &chart, &series).map_err(CliError::Failed)?;
    Ok(path)
}

/// Writes the error-vs-rate chart (rotation and position error of each scheme, the fitted
/// log-log slope in the legend) as `convergence_{scene}.svg` in `dir`.
pub fn convergence(rows: &[Row], scene: &str, dir: &Path) -> Result<PathBuf, CliError> {
    let mut series = Vec::new();
    for &s in &scheme::ALL {
        for c in [0, 2] {
            let ord = order(rows, s, c).map_or(String::new(), |o| format!(", slope {o:.2}"));
            series.push(Series::line(
                format!(
                    "{} {}{ord}",
                    scheme::label(s),
                    if c == 0 { "rot" } else { "pos" }
                ),
                rows.iter()
                    .filter(|r| r.scheme == s)
                    .map(|r| (r.rate, r.err[c]))
                    .collect(),
            ));
        }
    }
    let path = dir.join(format!("convergence_{scene}.svg"));
    let title = format!("{scene}: error vs rate (noise-free, 1 s window)");
    let chart = Chart {
        title: &title,
        x_label: "rate [Hz]",
        y_label: "error [rad or m]",
        log_x: true,
        log_y: true,
    };
    draw(&path, &chart, &series).map_err(CliError::Failed)?;
    Ok(path)
}

/// Writes the Allan chart of the three axes of one sensor (`sensor` 0: gyro, channels 0..3;
/// 1: accelerometer, 3..6), with the fitted white-noise (slope −½) and random-walk (slope +½)
/// lines.
pub fn allan(a: &ImuAllan, sensor: usize, path: &Path) -> Result<(), CliError> {
    let mut series = Vec::new();
    for ch in sensor * 3..sensor * 3 + 3 {
        let pts = a.curves[ch].iter().map(|p| (p.tau, p.adev)).collect();
        series.push(Series::line(IMU_AXES[ch], pts));
    }
    let taus: Vec<f64> = a.curves[sensor * 3].iter().map(|p| p.tau).collect();
    for ch in sensor * 3..sensor * 3 + 3 {
        let f = &a.fits[ch];
        series.push(Series::reference(
            format!("{} N/√τ", IMU_AXES[ch]),
            taus.iter()
                .map(|&t| (t, f.white_density / t.sqrt()))
                .collect(),
        ));
        if !f.random_walk_is_bound {
            series.push(Series::reference(
                format!("{} K√(τ/3)", IMU_AXES[ch]),
                taus.iter()
                    .map(|&t| (t, f.random_walk * (t / 3.0).sqrt()))
                    .collect(),
            ));
        }
    }
    let (title, y_label) = if sensor == 0 {
        ("Allan deviation: gyroscope", "σ(τ) [rad/s]")
    } else {
        ("Allan deviation: accelerometer", "σ(τ) [m/s²]")
    };
    let chart = Chart {
        title,
        x_label: "τ [s]",
        y_label,
        log_x: true,
        log_y: true,
    };
    draw(path, &chart, &series).map_err(CliError::Failed)
}

/// Writes an attitude-error-against-time chart (log error axis) of named `(t [s], error
/// [rad])` curves.
pub fn attitude_error(
    curves: &[(&str, Vec<(f64, f64)>)],
    title: &str,
    path: &Path,
) -> Result<(), CliError> {
    let series: Vec<Series> = curves
        .iter()
        .map(|(name, pts)| Series::line(*name, pts.clone()))
        .collect();
    let chart = Chart {
        title,
        x_label: "time [s]",
        y_label: "attitude error [rad]",
        log_x: false,
        log_y: true,
    };
    draw(path, &chart, &series).map_err(CliError::Failed)
}
