//! `preint calibrate --estimate noise`: the maximum-likelihood noise densities, bias random
//! walks and ground-truth errors from the `ImuFactor`s of back-to-back windows of several
//! lengths between the ground-truth states ([`preint_calib::noise_fit`], the windows of
//! [`crate::noise_windows`], cut as `factor --window` cuts them: [`crate::truth_windows`]).
//!
//! The densities start from `noise` (`--noise`; else a moment estimate); a ground-truth error
//! given (`--pose-rot-std`, `--pose-pos-std`, `--vel-std`, `--bias-gyro-std`,
//! `--bias-acc-std`) is held at that value, the others are fitted. The χ² per length "before"
//! is at the densities of `noise` (EuRoC's without it) and the given ground-truth errors (0
//! when not given). `out` writes a Kalibr `imu.yaml` (a withheld density keeps its start
//! value).
//!
//! The world gravity vector is fitted with them (the ground truth's frame need not be levelled)
//! and kept when the information criterion supports it; the χ² "after" is then at the fitted
//! gravity, which `factor --gravity-vector` takes.
//!
//! JSON: `{estimate: "noise", noise, ground_truth_error, withheld: [{parameter, reason,
//! upper_bound?}], per_length: [{length_s, count, skipped, chi2_dof_before, chi2_dof_after}],
//! gravity: {given, vector, vector_std, correction, magnitude, tilt_deg, tilt_deg_std,
//! supported, likelihood_ratio, bic_penalty, use}, ground_truth_time_correlation:
//! {per_length: [{length_s, pairs, observed, expected_independent, std_error, correlated}],
//! verdict}, iterations, log_likelihood, update_rate_hz, fit, written?}` (vectors in m/s²,
//! world frame; the correlation is [`noise_correlation`]'s).

use super::noise_correlation::{self, LagCorrelation};
use crate::consistency::fit_json;
use crate::noise_windows::{assign_blocks, noise_window_at};
use crate::truth_windows::{check_lengths, for_each_window, length_ns, overlap, read_window};
use crate::{Error, ImuInput, checks};
use nalgebra::Vector3;
use preint::{ImuNoise, Level, PreintParams};
use preint_calib::Fit;
use preint_calib::noise_fit::{self, NoiseFit, NoiseFitOptions, PARAMS, Withheld};
use preint_io::read_euroc_groundtruth;
use serde_json::{Map, Value, json};
use std::path::PathBuf;

/// The window lengths \[s\] when `window` is not given.
pub const DEFAULT_WINDOWS_S: [f64; 4] = [0.5, 1.0, 2.0, 4.0];

/// The JSON key of each parameter, in the order of [`preint_calib::noise_fit::Param::ALL`].
pub const KEYS: [&str; PARAMS] = [
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

/// What `calibrate --estimate noise` runs on (each field is the flag of the same name).
#[derive(Clone, Debug)]
pub struct NoiseOptions {
    /// The recording and how to read it.
    pub input: ImuInput,
    /// EuRoC ground truth with velocities and biases (`--poses`; required).
    pub poses: Option<PathBuf>,
    /// The window lengths \[s\] (`--window`; default [`DEFAULT_WINDOWS_S`]).
    pub window: Option<Vec<f64>>,
    /// Kalibr imu.yaml with the starting densities (`--noise`; else a moment estimate).
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G \[m/s²\] (`--gravity`).
    pub gravity: f64,
    /// Use only samples with timestamps ≥ this \[ns\] (`--from`).
    pub from: Option<i64>,
    /// Use only samples with timestamps ≤ this \[ns\] (`--to`).
    pub to: Option<i64>,
    /// The ground truth's attitude error \[rad\], held when given (`--pose-rot-std`).
    pub pose_rot_std: Option<f64>,
    /// The ground truth's position error \[m\], held when given (`--pose-pos-std`).
    pub pose_pos_std: Option<f64>,
    /// The ground truth's velocity error \[m/s\], held when given (`--vel-std`).
    pub vel_std: Option<f64>,
    /// The ground truth's gyroscope-bias error \[rad/s\], held when given (`--bias-gyro-std`).
    pub bias_gyro_std: Option<f64>,
    /// The ground truth's accelerometer-bias error \[m/s²\], held when given
    /// (`--bias-acc-std`).
    pub bias_acc_std: Option<f64>,
    /// Pose of the IMU in the body frame (`--body-p-sensor`).
    pub body_p_sensor: Option<preint::SensorPose>,
    /// The scheme the windows are preintegrated with (`--scheme`).
    pub scheme: preint::Scheme,
    /// Where to write the fitted noise model as a Kalibr imu.yaml (`--out`).
    pub out: Option<PathBuf>,
}

/// Everything `calibrate --estimate noise` computes.
#[derive(Clone, Debug)]
pub struct NoiseRun {
    /// The IMU file, as printed.
    pub imu: String,
    /// The fit.
    pub fit: NoiseFit,
    /// Windows skipped per length \[s\], in increasing length.
    pub skipped: Vec<(f64, usize)>,
    /// The recording's rate \[Hz\] (from the median sample interval).
    pub rate_hz: f64,
    /// The densities the fit started from (EuRoC's without `noise`).
    pub start: ImuNoise,
    /// The world gravity vector the windows were preintegrated with \[m/s²\], `(0, 0, −G)`.
    pub gravity_given: Vector3<f64>,
    /// Whether the ground truth's errors look correlated in time, per length
    /// ([`noise_correlation`]).
    pub time_correlation: Vec<LagCorrelation>,
    /// The Kalibr imu.yaml written to `out`, when given.
    pub written: Option<PathBuf>,
}

fn held(o: &NoiseOptions) -> Result<[Option<f64>; PARAMS], Error> {
    let given = [
        ("--pose-rot-std", o.pose_rot_std),
        ("--pose-pos-std", o.pose_pos_std),
        ("--vel-std", o.vel_std),
        ("--bias-gyro-std", o.bias_gyro_std),
        ("--bias-acc-std", o.bias_acc_std),
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

/// Reads the recording and the ground truth, fits the noise model over the windows (module
/// docs) and, with `out`, writes it.
pub fn compute(o: &NoiseOptions) -> Result<NoiseRun, Error> {
    let mut r = fit_windows(o)?;
    if let Some(path) = &o.out {
        preint_io::write_kalibr_yaml(path, &fitted_noise(&r))?;
        r.written = Some(path.clone());
    }
    Ok(r)
}

fn fit_windows(o: &NoiseOptions) -> Result<NoiseRun, Error> {
    let poses = o.poses.as_ref().ok_or_else(|| {
        Error::Usage(
            "--estimate noise needs --poses GT (EuRoC ground truth with velocities and biases)"
                .into(),
        )
    })?;
    let lengths: &[f64] = o.window.as_deref().unwrap_or(&DEFAULT_WINDOWS_S);
    check_lengths(lengths)?;
    checks::gravity("--gravity", o.gravity)?;
    let held = held(o)?;
    let start = crate::noise::or_default(o.noise.as_deref())?;
    let mut params = PreintParams {
        body_p_sensor: o.body_p_sensor,
        ..PreintParams::from_noise(&start)
            .with_scheme(o.scheme)
            .with_level(Level::Covariance)
            .with_gravity(Vector3::new(0.0, 0.0, -o.gravity))
    };
    let gt = read_euroc_groundtruth(poses)?;
    let (w, _, _) = read_window(&o.input, &start, &mut params, (o.from, o.to))?;
    let samples = w.samples.as_slice();
    let imu = o.input.label();
    let (span, dt) = overlap(samples, &gt, (&imu, poses), "--estimate noise")?;
    let mut sorted = lengths.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let (mut windows, mut ends, mut skipped) = (Vec::new(), Vec::new(), Vec::new());
    for &l in &sorted {
        let (ws, s) = for_each_window((samples, &gt), (span, dt), length_ns(l, span)?, |w, g| {
            noise_window_at(&params, w, g, l).ok()
        });
        for (w, e) in ws {
            windows.push(w);
            ends.push(e);
        }
        skipped.push((l, s));
    }
    let longest = length_ns(sorted[sorted.len() - 1], span)?;
    assign_blocks(&mut windows, &ends, span.0, longest);
    let mut st = [0.0; PARAMS];
    if o.noise.is_some() {
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
        fit_gravity: true,
        ..NoiseFitOptions::default()
    };
    let mut fit = noise_fit::fit(&windows, &opts).map_err(|e| {
        Error::Failed(format!(
            "{imu}: noise fit over {} windows: {e}",
            windows.len()
        ))
    })?;
    if o.noise.is_none() {
        // "before" is at the EuRoC densities the fit did not start from.
        before_at(&mut fit, &windows, &start, &held);
    }
    let time_correlation = noise_correlation::lag_one(&windows, &ends, &fit);
    Ok(NoiseRun {
        imu,
        fit,
        skipped,
        rate_hz: 1e9 / dt,
        start,
        gravity_given: params.gravity,
        time_correlation,
        written: None,
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

/// The fit of the whole set: the χ² after the fit summed over all windows against their
/// total dof.
pub fn fit(r: &NoiseRun) -> Fit {
    let chi2: f64 = r.fit.per_length.iter().map(|l| l.chi2_after).sum();
    let dof: usize = r.fit.per_length.iter().map(|l| 9 * l.count).sum();
    Fit::new(chi2, dof).because(
        "the windows' residuals are not Gaussian with a covariance linear in the densities: \
         unmodelled errors (scale factors, misalignment, time offset, vibration) or a ground \
         truth whose errors are correlated in time",
    )
}

/// The noise model written by `out`: fitted densities, withheld ones at their start value.
pub fn fitted_noise(r: &NoiseRun) -> ImuNoise {
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

/// The JSON form (module docs).
pub fn to_json(r: &NoiseRun) -> Value {
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
        "fit": fit_json(&fit(r)),
    });
    if let Some(g) = gravity_json(r) {
        j["gravity"] = g;
    }
    let rows: Vec<Value> = (r.time_correlation.iter())
        .map(|c| {
            json!({"length_s": c.length_s, "pairs": c.pairs, "observed": c.observed,
                "expected_independent": c.expected, "std_error": c.std_error,
                "correlated": c.correlated()})
        })
        .collect();
    j["ground_truth_time_correlation"] = json!({
        "per_length": rows,
        "verdict": noise_correlation::verdict(&r.time_correlation),
    });
    if let Some(p) = &r.written {
        j["written"] = json!(p.display().to_string());
    }
    j
}

/// The world gravity vector that fits \[m/s², world frame\] (given plus correction), when
/// the fit estimated one (supported or not: [`preint_calib::noise_fit::GravityEstimate`]).
pub fn fitted_gravity(r: &NoiseRun) -> Option<Vector3<f64>> {
    r.fit
        .gravity
        .as_ref()
        .map(|g| r.gravity_given + g.correction)
}

/// The world gravity vector the fit's χ² "after" is at \[m/s², world frame\]: the fitted one
/// when the information criterion supports it, else the given one.
pub fn gravity_in_use(r: &NoiseRun) -> Vector3<f64> {
    r.gravity_given + r.fit.gravity.map_or(Vector3::zeros(), |g| g.applied())
}

/// `gravity`: the world gravity vector that fits (module docs of [`preint_calib::noise_fit`])
/// beside the given one, its tilt from it, and whether the information criterion supports it.
fn gravity_json(r: &NoiseRun) -> Option<Value> {
    let g = r.fit.gravity.as_ref()?;
    let g0 = r.gravity_given;
    let v = fitted_gravity(r)?;
    let list = |x: &Vector3<f64>| json!([x[0], x[1], x[2]]);
    let std = g.std();
    Some(json!({
        "given": list(&g0),
        "vector": list(&v),
        "vector_std": list(&std),
        "correction": list(&g.correction),
        "magnitude": v.norm(),
        "tilt_deg": g.tilt_from(&g0).to_degrees(),
        "tilt_deg_std": g.tilt_std_from(&g0).to_degrees(),
        "supported": g.supported,
        "likelihood_ratio": g.lr,
        "bic_penalty": g.penalty,
        "use": if g.supported {
            format!("factor --gravity-vector={},{},{}", v[0], v[1], v[2])
        } else {
            "not supported by the windows: keep the given gravity".into()
        },
    }))
}
