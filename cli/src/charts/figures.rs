//! The charts the commands and the report draw: accuracy against cost with the Pareto front,
//! error against rate, the advice's error-to-noise ratio against rate, Allan deviation,
//! attitude error against time.

use super::{
    Axis, Color, Figure, Marker, NEUTRAL, OTHER_COLORS, Panel, Series, Stroke, draw, scheme_color,
};
use crate::analysis::accuracy::{Row, order};
use crate::analysis::report::{hz, pareto_front};
use crate::{CliError, scheme};
use preint_analysis::advise::Candidate;
use preint_analysis::format::IMU_AXES;
use preint_calib::allan::ImuAllan;
use std::path::{Path, PathBuf};

fn write(path: &Path, fig: &Figure) -> Result<(), CliError> {
    draw(path, fig).map_err(CliError::Failed)
}

/// Writes the accuracy-vs-cost chart as `accuracy_vs_cost_{scene}.svg` in `dir`: position
/// error against µs per second of IMU data, one line per scheme (a point per rate), and the
/// Pareto front as a thin grey dashed line under them with grey rings on its points.
pub fn accuracy_vs_cost(rows: &[Row], scene: &str, dir: &Path) -> Result<PathBuf, CliError> {
    let pt = |r: &Row| (r.cost_per_s() * 1e-3, r.err[2]);
    let pts: Vec<(f64, f64)> = rows.iter().map(pt).collect();
    let front: Vec<usize> = pareto_front(&pts);
    let mut series = vec![
        Series::reference(
            "Pareto front",
            front.iter().map(|&i| pts[i]).collect(),
            NEUTRAL,
        )
        .with_marker(Marker::Ring)
        .with_tips(
            front
                .iter()
                .map(|&i| {
                    let r = &rows[i];
                    format!(
                        "Pareto front: {} at {} Hz, {:.3} µs/s, {:.2e} m",
                        scheme::label(r.scheme),
                        r.rate,
                        pts[i].0,
                        pts[i].1
                    )
                })
                .collect(),
        )
        .drawn_behind(),
    ];
    for s in scheme::ALL {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.scheme == s).collect();
        let tips = mine
            .iter()
            .map(|r| {
                let (c, e) = pt(r);
                format!(
                    "{} at {} Hz: {c:.3} µs/s, {e:.2e} m",
                    scheme::label(s),
                    r.rate
                )
            })
            .collect();
        series.push(
            Series::line(
                scheme::label(s),
                mine.iter().map(|r| pt(r)).collect(),
                scheme_color(s),
            )
            .with_tips(tips),
        );
    }
    // The front first in the drawing, last in the legend.
    series.rotate_left(1);
    let path = dir.join(format!("accuracy_vs_cost_{scene}.svg"));
    let fig = Figure {
        title: format!("{scene}: position error of a 1 s window against cost"),
        panels: vec![Panel {
            title: String::new(),
            x: Axis::log("cost [µs per second of IMU data]"),
            y: Axis::log("position error [m]"),
            series,
        }],
    };
    write(&path, &fig)?;
    Ok(path)
}

/// Writes the error-vs-rate chart as `convergence_{scene}.svg` in `dir`: rotation error and
/// position error of each scheme in two panels, the fitted log-log slopes (convergence orders)
/// in the legend.
pub fn convergence(rows: &[Row], scene: &str, dir: &Path) -> Result<PathBuf, CliError> {
    let name = |s| {
        let o = |c| order(rows, s, c).map_or("–".to_string(), |o| format!("{o:.2}"));
        format!(
            "{}: order {} (rotation), {} (position)",
            scheme::label(s),
            o(0),
            o(2)
        )
    };
    let panel = |c: usize, title: &str, y: &str| Panel {
        title: title.into(),
        x: Axis::log("rate [Hz]"),
        y: Axis::log(y),
        series: scheme::ALL
            .iter()
            .map(|&s| {
                Series::line(
                    name(s),
                    rows.iter()
                        .filter(|r| r.scheme == s)
                        .map(|r| (r.rate, r.err[c]))
                        .collect(),
                    scheme_color(s),
                )
            })
            .collect(),
    };
    let path = dir.join(format!("convergence_{scene}.svg"));
    let fig = Figure {
        title: format!("{scene}: error against rate (noise-free, 1 s window)"),
        panels: vec![
            panel(0, "rotation", "rotation error [rad]"),
            panel(2, "position", "position error [m]"),
        ],
    };
    write(&path, &fig)?;
    Ok(path)
}

/// Writes the advice chart to `path`: per scene (one panel each), the worst ratio of
/// discretisation error to noise σ (over rotation, velocity and position) of each scheme
/// against rate, the acceptance threshold `fraction` as a grey dashed line and the recommended
/// (scheme, rate) ringed.
pub fn advice(
    scenes: &[(&str, &[Candidate], Option<usize>)],
    fraction: f64,
    path: &Path,
) -> Result<(), CliError> {
    let ratio = |c: &Candidate| {
        (0..3)
            .map(|k| c.disc_err[k] / c.noise_sigma[k])
            .fold(0.0, f64::max)
    };
    let panels = scenes
        .iter()
        .map(|&(scene, cands, rec)| {
            let mut series: Vec<Series> = scheme::ALL
                .iter()
                .map(|&s| {
                    let mine: Vec<&Candidate> = cands.iter().filter(|c| c.scheme == s).collect();
                    let tips = mine
                        .iter()
                        .map(|c| {
                            format!(
                                "{} at {} Hz: error/σ {:.2e}, {:.1} µs/s",
                                scheme::label(s),
                                hz(c.rate_hz),
                                ratio(c),
                                c.cost_ns_per_s * 1e-3
                            )
                        })
                        .collect();
                    let pts = mine.iter().map(|c| (c.rate_hz, ratio(c))).collect();
                    Series::line(scheme::label(s), pts, scheme_color(s)).with_tips(tips)
                })
                .collect();
            let rates: Vec<f64> = cands.iter().map(|c| c.rate_hz).collect();
            let (lo, hi) = rates
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
            series.push(
                Series::reference(
                    format!("threshold {fraction}·σ"),
                    vec![(lo, fraction), (hi, fraction)],
                    NEUTRAL,
                )
                .drawn_behind(),
            );
            if let Some(c) = rec.map(|i| &cands[i]) {
                let tip = format!(
                    "recommended: {} at {} Hz",
                    scheme::label(c.scheme),
                    hz(c.rate_hz)
                );
                series.push(
                    Series::markers(
                        "recommended",
                        vec![(c.rate_hz, ratio(c))],
                        Color(0, 0, 0),
                        Marker::Ring,
                    )
                    .with_tips(vec![tip]),
                );
            }
            Panel {
                title: scene.to_string(),
                x: Axis::log("rate [Hz]"),
                y: Axis::log("worst discretisation error / σ"),
                series,
            }
        })
        .collect();
    let fig = Figure {
        title: "Discretisation error relative to the noise, per scheme and rate".into(),
        panels,
    };
    write(path, &fig)
}

/// Writes the Allan chart of the three axes of one sensor (`sensor` 0: gyro, channels 0..3;
/// 1: accelerometer, 3..6) to `path`: the measured curves, the fitted white-noise (slope −½,
/// dashed) and random-walk (slope +½, dotted) lines, and the readings marked: the noise density
/// N at τ = 1 s (diamond) and the random walk K at τ = 3 s (square).
pub fn allan(a: &ImuAllan, sensor: usize, path: &Path) -> Result<(), CliError> {
    let chans = sensor * 3..sensor * 3 + 3;
    let floor = chans
        .clone()
        .flat_map(|c| a.curves[c].iter().map(|p| p.adev))
        .fold(f64::INFINITY, f64::min)
        / 2.0;
    let mut taus: Vec<f64> = a.curves[sensor * 3].iter().map(|p| p.tau).collect();
    taus.extend([1.0, 3.0]);
    taus.sort_by(f64::total_cmp);
    // A fitted line over the τ where it is within reach of the data (above `floor`), and always
    // from its reading at `tau_r` towards the side where it was fitted (`below`: smaller τ).
    let line = |f: &dyn Fn(f64) -> f64, tau_r: f64, below: bool| -> Vec<(f64, f64)> {
        taus.iter()
            .map(|&t| (t, f(t)))
            .filter(|&(t, y)| y >= floor || (if below { t <= tau_r } else { t >= tau_r }))
            .collect()
    };
    let mut series = Vec::new();
    for (k, ch) in chans.clone().enumerate() {
        let (f, color) = (&a.fits[ch], OTHER_COLORS[k]);
        series.push(Series::curve(
            IMU_AXES[ch],
            a.curves[ch].iter().map(|p| (p.tau, p.adev)).collect(),
            color,
        ));
        series.push(Series::reference(
            "",
            line(&|t| f.white_density / t.sqrt(), 1.0, true),
            color,
        ));
        let n_tip = format!(
            "{}: N = {:.3e}{} (σ at τ = 1 s)",
            IMU_AXES[ch],
            f.white_density,
            if f.white_density_is_bound {
                ", upper bound"
            } else {
                ""
            }
        );
        series.push(
            Series::markers("", vec![(1.0, f.white_density)], color, Marker::Diamond)
                .with_tips(vec![n_tip]),
        );
        if !f.random_walk_is_bound {
            series.push(
                Series::reference(
                    "",
                    line(&|t| f.random_walk * (t / 3.0).sqrt(), 3.0, false),
                    color,
                )
                .with_stroke(Stroke::Dotted)
                .with_width(1.8),
            );
            let k_tip = format!("{}: K = {:.3e} (σ at τ = 3 s)", IMU_AXES[ch], f.random_walk);
            series.push(
                Series::markers("", vec![(3.0, f.random_walk)], color, Marker::Square)
                    .with_tips(vec![k_tip]),
            );
        }
    }
    write(path, &allan_figure(sensor, series))
}

/// The Allan figure of one sensor (`0` gyroscope, `1` accelerometer): its channels' `series`
/// and the legend keys of the fitted lines and read-off points.
fn allan_figure(sensor: usize, mut series: Vec<Series>) -> Figure {
    series.extend([
        Series::key("white noise N/√τ", NEUTRAL, Stroke::Dashed, Marker::None),
        Series::key("random walk K√(τ/3)", NEUTRAL, Stroke::Dotted, Marker::None),
        Series::key("N read at τ = 1 s", NEUTRAL, Stroke::None, Marker::Diamond),
        Series::key("K read at τ = 3 s", NEUTRAL, Stroke::None, Marker::Square),
    ]);
    let (title, y_label) = if sensor == 0 {
        ("Allan deviation: gyroscope", "σ(τ) [rad/s]")
    } else {
        ("Allan deviation: accelerometer", "σ(τ) [m/s²]")
    };
    Figure {
        title: title.into(),
        panels: vec![Panel {
            title: String::new(),
            x: Axis::log("τ [s]"),
            y: Axis::log(y_label),
            series,
        }],
    }
}

/// Writes an attitude-error-against-time chart (log error axis) of named `(t [s], error
/// [rad])` curves to `path`; the second curve is dashed, so that it stays visible where it
/// lies on the first.
pub fn attitude_error(
    curves: &[(&str, Vec<(f64, f64)>)],
    title: &str,
    path: &Path,
) -> Result<(), CliError> {
    let series: Vec<Series> = curves
        .iter()
        .enumerate()
        .map(|(i, (name, pts))| {
            let s = Series::curve(*name, pts.clone(), OTHER_COLORS[i % OTHER_COLORS.len()]);
            match i {
                0 => s.with_width(3.5),
                1 => s.with_stroke(Stroke::Dashed).with_width(2.0),
                _ => s.with_width(2.2),
            }
        })
        .collect();
    let fig = Figure {
        title: title.into(),
        panels: vec![Panel {
            title: String::new(),
            x: Axis::linear("time [s]"),
            y: Axis::log("attitude error [rad]"),
            series,
        }],
    };
    write(path, &fig)
}
