//! `preint calibrate --estimate noise`: the maximum-likelihood noise densities, bias random
//! walks and ground-truth errors from the `ImuFactor`s of back-to-back windows of several
//! lengths between the ground-truth states ([`preint_calib::noise_fit`], the windows of
//! [`preint_analysis::noise_windows`], cut as `factor --window` cuts them).
//!
//! The densities start from `--noise` (else a moment estimate); a ground-truth error given by
//! its flag (`--pose-rot-std`, `--pose-pos-std`, `--vel-std`, `--bias-gyro-std`,
//! `--bias-acc-std`) is held at that value, the others are fitted. The χ² per length "before" is
//! at the densities of `--noise` (EuRoC's without it) and the given ground-truth errors (0 when
//! not given). `--out` writes a Kalibr `imu.yaml` (a withheld density keeps its start value).

use super::Args;
use crate::commands::factor::evaluate::window;
use crate::commands::factor::windows::{check_lengths, for_each_window, length_ns, overlap};
use crate::fit::{fit_text, strict};
use crate::{CliError, Output};
use nalgebra::Vector3;
use preint::{ImuNoise, Level, PreintParams};
use preint_analysis::checks;
use preint_analysis::consistency::fit_json;
use preint_analysis::noise_windows::noise_window;
use preint_calib::Fit;
use preint_calib::noise_fit::{self, NoiseFit, NoiseFitOptions, PARAMS, Withheld};
use preint_io::read_euroc_groundtruth;
use serde_json::{Map, Value, json};
use std::fmt::Write as _;

/// The window lengths \[s\] when `--window` is not given.
const DEFAULT_WINDOWS_S: [f64; 4] = [0.5, 1.0, 2.0, 4.0];

/// The JSON key of each parameter, in the order of [`Param::ALL`].
const KEYS: [&str; PARAMS] = [
    "gyroscope_noise_density",
    "accelerometer_noise_density",
    "gyroscope_random_walk",
    "accelerometer_random_walk",
    "rot_std",
    "pos_std",
    "vel_std",
    "bias_gyro_std",
    "bias_acc_std",
];

/// Everything `calibrate --estimate noise` computes.
struct NoiseRun {
    imu: String,
    fit: NoiseFit,
    /// Windows skipped per length, in increasing length.
    skipped: Vec<(f64, usize)>,
    rate_hz: f64,
    start: ImuNoise,
}

fn held(args: &Args) -> Result<[Option<f64>; PARAMS], CliError> {
    let given = [
        ("--pose-rot-std", args.pose_rot_std),
        ("--pose-pos-std", args.pose_pos_std),
        ("--vel-std", args.vel_std),
        ("--bias-gyro-std", args.bias_gyro_std),
        ("--bias-acc-std", args.bias_acc_std),
    ];
    let mut h = [None; PARAMS];
    for (k, (flag, v)) in given.into_iter().enumerate() {
        if let Some(v) = v {
            checks::non_negative(flag, v)?;
        }
        h[4 + k] = v;
    }
    Ok(h)
}

fn compute(args: &Args) -> Result<NoiseRun, CliError> {
    let poses = args.poses.as_ref().ok_or_else(|| {
        CliError::Usage(
            "--estimate noise needs --poses GT (EuRoC ground truth with velocities and biases)"
                .into(),
        )
    })?;
    let lengths: &[f64] = args.window.as_deref().unwrap_or(&DEFAULT_WINDOWS_S);
    check_lengths(lengths)?;
    checks::gravity("--gravity", args.gravity)?;
    let held = held(args)?;
    let start = preint_analysis::noise::or_default(args.noise.as_deref())?;
    let mut params = PreintParams {
        body_p_sensor: args.body_p_sensor,
        ..PreintParams::from_noise(&start)
            .with_scheme(args.scheme)
            .with_level(Level::Covariance)
            .with_gravity(Vector3::new(0.0, 0.0, -args.gravity))
    };
    let gt = read_euroc_groundtruth(poses)?;
    let input = args.input.to_input();
    let (w, _, _) = window(&input, &start, &mut params, (args.from, args.to))?;
    let samples = w.samples.as_slice();
    let (span, dt) = overlap(samples, &gt, (&input.label(), poses), "--estimate noise")?;
    let mut sorted = lengths.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let (mut windows, mut skipped) = (Vec::new(), Vec::new());
    for &l in &sorted {
        let (mut ws, s) =
            for_each_window((samples, &gt), (span, dt), length_ns(l, span)?, |w, g| {
                noise_window(&params, w, g, l).ok()
            });
        windows.append(&mut ws);
        skipped.push((l, s));
    }
    let mut st = [0.0; PARAMS];
    if args.noise.is_some() {
        st[..4].copy_from_slice(&[
            start.gyro_noise_density,
            start.acc_noise_density,
            start.gyro_random_walk,
            start.acc_random_walk,
        ]);
    }
    let opts = NoiseFitOptions {
        start: st,
        held,
        ..NoiseFitOptions::default()
    };
    let mut fit = noise_fit::fit(&windows, &opts).map_err(|e| {
        CliError::Failed(format!(
            "{}: noise fit over {} windows: {e}",
            input.label(),
            windows.len()
        ))
    })?;
    if args.noise.is_none() {
        // "before" is at the EuRoC densities the fit did not start from.
        before_at(&mut fit, &windows, &start, &held);
    }
    Ok(NoiseRun {
        imu: input.label(),
        fit,
        skipped,
        rate_hz: 1e9 / dt,
        start,
    })
}

/// The χ²/dof per length at `noise` and the held ground-truth errors (0 when not given).
fn before_at(
    fit: &mut NoiseFit,
    windows: &[noise_fit::NoiseWindow],
    noise: &ImuNoise,
    held: &[Option<f64>; PARAMS],
) {
    let mut theta = nalgebra::SVector::<f64, PARAMS>::zeros();
    let d = [
        noise.gyro_noise_density,
        noise.acc_noise_density,
        noise.gyro_random_walk,
        noise.acc_random_walk,
    ];
    for k in 0..PARAMS {
        let v = if k < 4 { d[k] } else { held[k].unwrap_or(0.0) };
        theta[k] = v * v;
    }
    for l in &mut fit.per_length {
        let of = windows.iter().filter(|w| w.length_s == l.length_s);
        l.before = of.map(|w| noise_fit::chi2(w, &theta)).sum::<f64>() / (9.0 * l.count as f64);
    }
}

fn fit_of(r: &NoiseRun) -> Fit {
    let chi2: f64 = r.fit.per_length.iter().map(|l| l.chi2_after).sum();
    let dof: usize = r.fit.per_length.iter().map(|l| 9 * l.count).sum();
    Fit::new(chi2, dof).because(
        "the windows' residuals are not Gaussian with a covariance linear in the densities: \
         unmodelled errors (scale factors, misalignment, time offset, vibration) or a ground \
         truth whose errors are correlated in time",
    )
}

/// The noise model written by `--out`: fitted densities, withheld ones at their start value.
fn fitted_noise(r: &NoiseRun) -> ImuNoise {
    let p = &r.fit.params;
    let pick = |k: usize, start: f64| {
        if p[k].withheld.is_none() {
            p[k].value
        } else {
            start
        }
    };
    ImuNoise {
        gyro_noise_density: pick(0, r.start.gyro_noise_density),
        acc_noise_density: pick(1, r.start.acc_noise_density),
        gyro_random_walk: pick(2, r.start.gyro_random_walk),
        acc_random_walk: pick(3, r.start.acc_random_walk),
        update_rate_hz: r.rate_hz,
    }
}

fn to_json(r: &NoiseRun, written: Option<&std::path::Path>) -> Value {
    let (mut noise, mut truth, mut withheld) = (Map::new(), Map::new(), Vec::new());
    for (k, p) in r.fit.params.iter().enumerate() {
        let into = if k < 4 { &mut noise } else { &mut truth };
        match p.withheld {
            None | Some(Withheld::Held) => {
                into.insert(KEYS[k].into(), json!(p.value));
                into.insert(format!("{}_std", KEYS[k]), json!(p.std));
            }
            Some(w) => {
                let mut v = json!({"parameter": KEYS[k], "reason": w.reason(p.param.unit())});
                if let Withheld::AtBound { upper } = w {
                    v["upper_bound"] = json!(upper);
                }
                withheld.push(v);
            }
        }
        if p.withheld == Some(Withheld::Held) {
            withheld.push(json!({"parameter": KEYS[k], "reason": "held at the given value"}));
        }
    }
    let rows: Vec<Value> = r
        .fit
        .per_length
        .iter()
        .zip(&r.skipped)
        .map(|(l, (_, s))| {
            json!({"length_s": l.length_s, "count": l.count, "skipped": s,
                "chi2_dof_before": l.before, "chi2_dof_after": l.after})
        })
        .collect();
    let mut j = json!({
        "estimate": "noise",
        "noise": noise,
        "ground_truth_error": truth,
        "withheld": withheld,
        "per_length": rows,
        "iterations": r.fit.iterations,
        "log_likelihood": r.fit.log_likelihood,
        "update_rate_hz": r.rate_hz,
        "fit": fit_json(&fit_of(r)),
    });
    if let Some(p) = written {
        j["written"] = json!(p.display().to_string());
    }
    j
}

fn to_text(r: &NoiseRun, written: Option<&std::path::Path>) -> String {
    let mut h = String::new();
    let n: usize = r.fit.per_length.iter().map(|l| l.count).sum();
    let _ = writeln!(
        h,
        "{}: noise model by maximum likelihood over {n} ImuFactor windows at the ground truth \
         ({} Fisher-scoring iterations, log-likelihood {:.1}):",
        r.imu, r.fit.iterations, r.fit.log_likelihood
    );
    for (k, p) in r.fit.params.iter().enumerate() {
        let unit = p.param.unit();
        let line = match p.withheld {
            None => format!("{:.4e} ± {:.1e} {unit}", p.value, p.std),
            Some(Withheld::Held) => format!("{:.4e} {unit} (held at the given value)", p.value),
            Some(w) => w.reason(unit),
        };
        let _ = writeln!(h, "  {:<28} {line}", KEYS[k]);
    }
    let _ = writeln!(
        h,
        "{:>8} {:>6} {:>7} {:>14} {:>13}",
        "length s", "count", "skipped", "χ²/dof before", "χ²/dof after"
    );
    for (l, (_, s)) in r.fit.per_length.iter().zip(&r.skipped) {
        let _ = writeln!(
            h,
            "{:>8} {:>6} {:>7} {:>14.3} {:>13.3}",
            l.length_s, l.count, s, l.before, l.after
        );
    }
    h.push_str(&fit_text(&fit_of(r), "noise model over the windows"));
    if let Some(p) = written {
        let _ = writeln!(
            h,
            "noise model written to {} (Kalibr imu.yaml; withheld densities at their start value)",
            p.display()
        );
    }
    h
}

/// Runs `preint calibrate --estimate noise`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    if let Some(path) = &args.out {
        preint_io::write_kalibr_yaml(path, &fitted_noise(&r))?;
    }
    let out = args.out.as_deref();
    let output = Output {
        human: to_text(&r, out),
        json: to_json(&r, out),
    };
    strict(
        args.strict,
        output,
        &fit_of(&r),
        "noise model over the windows",
    )
}
