//! `preint bench-steps`: accuracy against cost per scheme and rate on a built-in scene.
//!
//! For each rate, noise-free samples of the scene on the grid `t_k = k·round(1e9/rate)` ns are
//! preintegrated over `[1 s, 1 s + window]` and compared with the scene's exact deltas
//! (`preint_sim::exact_deltas`): rotation error = angle of `ΔR*ᵀΔR` \[rad\], velocity and position errors
//! = norms [m/s, m]. Cost = measured ns/sample of the scheme (with covariance and bias Jacobians)
//! × rate = ns per second of IMU data.

use super::integrate::scheme_name;
use super::speed::{best_ns_per_sample, synthetic_stream};
use super::{CliError, Output};
use crate::Command;
use crate::charts::{Chart, Series, draw, pareto_front};
use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, Level, PreintParams, Scheme, preintegrate};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// Noise-free, bias-free reading of `scene` at `t_ns`: `ω_b` and `R_wbᵀ(a − g)`.
pub fn ideal_sample(
    scene: &dyn preint_sim::Scene,
    t_ns: i64,
    g: &Vector3<f64>,
) -> preint::ImuSample {
    let s = scene.state(preint_sim::t_s(t_ns));
    preint::ImuSample::new(t_ns, s.omega_b, s.r_wb.inverse().act(&(s.a - g)))
}

/// One row of the table.
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

/// Errors of every scheme at every rate on `scene_name` (noise-free), plus measured costs.
pub fn measure(scene_name: &str, rates: &[f64], window_s: f64) -> Result<Vec<Row>, CliError> {
    let scene = preint_sim::scene_by_name(scene_name).ok_or_else(|| {
        CliError::Usage(format!(
            "unknown scene `{scene_name}`; expected one of {}",
            preint_sim::SCENE_NAMES.join(", ")
        ))
    })?;
    if !(window_s.is_finite() && window_s > 0.0) {
        return Err(CliError::Usage(format!(
            "--window must be positive, got {window_s}"
        )));
    }
    let g = Vector3::new(0.0, 0.0, -9.81);
    let t_i: i64 = 1_000_000_000;
    let t_j = t_i + (window_s * 1e9).round() as i64;
    let (r_true, v_true, p_true) = preint_sim::exact_deltas(scene.as_ref(), t_i, t_j, g);
    let schemes = [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4];
    let ns = best_ns_per_sample(&schemes, Level::Covariance, &synthetic_stream(50_000), 3)?;
    let cost: std::collections::HashMap<_, _> =
        schemes.iter().map(|&s| scheme_name(s)).zip(ns).collect();
    let mut rows = Vec::new();
    for &rate in rates {
        let step = (1e9 / rate).round() as i64;
        if step <= 0 {
            return Err(CliError::Usage(format!("rate {rate} Hz is too high")));
        }
        // Grid covering the window plus four samples each side (rk4 needs neighbours).
        let k0 = t_i / step - 4;
        let k1 = t_j / step + 5;
        let samples: Vec<_> = (k0..=k1)
            .map(|k| ideal_sample(scene.as_ref(), k * step, &g))
            .collect();
        for scheme in [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4] {
            let params = PreintParams::from_noise(&ImuNoise::euroc())
                .with_scheme(scheme)
                .with_level(Level::Deltas)
                .with_gravity(g);
            let m = preintegrate(&params, &ImuBias::zero(), &samples, t_i, t_j)
                .map_err(|e| CliError::Failed(format!("{scheme:?} at {rate} Hz: {e}")))?;
            let err = [
                m.delta_r.minus(&r_true).norm(),
                (m.delta_v - v_true).norm(),
                (m.delta_p - p_true).norm(),
            ];
            rows.push(Row {
                scheme,
                rate,
                ns_per_sample: cost[scheme_name(scheme)],
                err,
            });
        }
    }
    Ok(rows)
}

/// Least-squares slope of log(err) against log(rate), over points above the round-off floor.
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

/// Writes the accuracy-vs-cost chart (position error; Pareto front marked) and the
/// error-vs-rate chart (all three components for each scheme). Returns the paths.
pub fn charts(rows: &[Row], scene: &str, dir: &Path) -> Result<Vec<String>, CliError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::Failed(format!("{}: {e}", dir.display())))?;
    let schemes = [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4];
    let mut series: Vec<Series> = schemes
        .iter()
        .map(|&s| {
            Series::line(
                scheme_name(s),
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
    let p1 = dir.join(format!("accuracy_vs_cost_{scene}.svg"));
    let title = format!("{scene}: position error after 1 s vs cost");
    draw(
        &p1,
        &Chart {
            title: &title,
            x_label: "cost [µs per second of IMU data]",
            y_label: "position error [m]",
            log_x: true,
            log_y: true,
        },
        &series,
    )
    .map_err(CliError::Failed)?;
    let mut series = Vec::new();
    for &s in &schemes {
        for c in [0, 2] {
            let ord = order(rows, s, c).map_or(String::new(), |o| format!(", slope {o:.2}"));
            series.push(Series::line(
                format!(
                    "{} {}{ord}",
                    scheme_name(s),
                    if c == 0 { "rot" } else { "pos" }
                ),
                rows.iter()
                    .filter(|r| r.scheme == s)
                    .map(|r| (r.rate, r.err[c]))
                    .collect(),
            ));
        }
    }
    let p2 = dir.join(format!("convergence_{scene}.svg"));
    let title = format!("{scene}: error vs rate (noise-free, 1 s window)");
    draw(
        &p2,
        &Chart {
            title: &title,
            x_label: "rate [Hz]",
            y_label: "error [rad or m]",
            log_x: true,
            log_y: true,
        },
        &series,
    )
    .map_err(CliError::Failed)?;
    Ok(vec![p1.display().to_string(), p2.display().to_string()])
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::BenchSteps {
        scene,
        rates,
        window,
        out,
    } = cmd
    else {
        unreachable!()
    };
    let rows = measure(scene, rates, *window)?;
    let files = match out {
        Some(dir) => charts(&rows, scene, dir)?,
        None => Vec::new(),
    };
    let json_rows: Vec<_> = rows
        .iter()
        .map(|r| json!({"scheme": scheme_name(r.scheme), "rate": r.rate, "ns_per_sample": r.ns_per_sample,
                        "cost_ns_per_s": r.cost_per_s(), "rot_err": r.err[0], "vel_err": r.err[1], "pos_err": r.err[2]}))
        .collect();
    let orders: serde_json::Map<String, serde_json::Value> = [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4]
        .iter()
        .map(|&s| (scheme_name(s).to_string(), json!({"rot": order(&rows, s, 0), "vel": order(&rows, s, 1), "pos": order(&rows, s, 2)})))
        .collect();
    let json = json!({"scene": scene, "window_s": window, "rows": json_rows, "fitted_order": orders,
        "units": {"rot_err": "rad", "vel_err": "m/s", "pos_err": "m", "ns_per_sample": "ns (with covariance and bias Jacobians)"},
        "files": files});
    let mut h = format!(
        "{scene}: noise-free, window [1 s, {} s], errors against the exact deltas\n",
        1.0 + window
    );
    let _ = writeln!(
        h,
        "{:<9} {:>8} {:>11} {:>12} {:>11} {:>11} {:>11}",
        "scheme", "rate Hz", "ns/sample", "µs/s data", "rot [rad]", "vel [m/s]", "pos [m]"
    );
    for r in &rows {
        let _ = writeln!(
            h,
            "{:<9} {:>8.1} {:>11.1} {:>12.1} {:>11.2e} {:>11.2e} {:>11.2e}",
            scheme_name(r.scheme),
            r.rate,
            r.ns_per_sample,
            r.cost_per_s() * 1e-3,
            r.err[0],
            r.err[1],
            r.err[2]
        );
    }
    for s in [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4] {
        let f = |c| order(&rows, s, c).map_or("-".into(), |o: f64| format!("{o:.2}"));
        let _ = writeln!(
            h,
            "fitted order {:<9} rot {} vel {} pos {}",
            scheme_name(s),
            f(0),
            f(1),
            f(2)
        );
    }
    if !files.is_empty() {
        let _ = writeln!(h, "wrote {}", files.join(", "));
    }
    Ok(Output { human: h, json })
}
