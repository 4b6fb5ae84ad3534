//! Calibration from Python: static (one attitude) and multi-position bias calibration from
//! numpy arrays (`preint_calib::bias`), `preint calibrate` on a recording (the noise model from
//! ground truth with `estimate="noise"`), and the still-interval detector.
//!
//! Conventions (`preint_calib::bias`): world z up, gravity `(0, 0, −gravity)` m/s²; the
//! accelerometer measures specific force (+gravity on the up axis at rest); biases in the
//! sensor frame, gyro [rad/s], accelerometer [m/s²]; every estimate with its standard deviation
//! predicted from the noise densities, and the χ² that checks them (`chi2/dof ≈ 1`). A problem
//! the data cannot answer (no still interval, too few attitudes) raises `CalibrationError`
//! with the Rust message.

use crate::convert::{mat_py, samples, vec_py};
use crate::errors::{Class, new_err, raise};
use crate::io::{ReadArgs, analysis_err, json_py};
use crate::params::PyNoise;
use nalgebra::Vector3;
use numpy::IntoPyArray;
use numpy::ndarray::Array3;
use preint::{ImuNoise, ImuSample};
use preint_analysis::calibrate::{self, noise_model};
use preint_calib::bias::{
    AccBiasPrior, BiasError, MultiPoseCalibration, MultiPoseOptions, StaticCalibration,
    StaticOptions, StillInterval, StillOptions, calibrate_multi_pose, calibrate_static,
    detect_still_intervals, earth_rate_in_body, remove_earth_rate,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The noise densities of `obj`: a `Noise`, a path to a Kalibr `imu.yaml`, or `None` (the
/// EuRoC ADIS16448 figures when `default_euroc`, otherwise an error); checked as a `Noise` is
/// (`crate::checks::noise`).
pub(crate) fn noise_arg(obj: Option<&Bound<'_, PyAny>>, default_euroc: bool) -> PyResult<ImuNoise> {
    match obj {
        None if default_euroc => Ok(ImuNoise::euroc()),
        None => Err(new_err(
            Class::Shape,
            "Usage",
            "noise: give a preint.Noise or the path of a Kalibr imu.yaml".into(),
        )),
        Some(o) => {
            if let Ok(n) = o.extract::<PyRef<'_, PyNoise>>() {
                crate::checks::noise("noise", &n.0)?;
                return Ok(n.0);
            }
            let p: PathBuf = o.extract().map_err(|_| {
                new_err(
                    Class::Shape,
                    "Usage",
                    "noise: expected a preint.Noise or the path of a Kalibr imu.yaml".into(),
                )
            })?;
            crate::io::read_noise(&p)
        }
    }
}

/// `latitude` [deg] finite within [−90, 90] (the command line's check), `heading` [deg] finite
/// and only with a latitude; otherwise `ShapeError` (kind `"Usage"`).
fn earth_args(latitude: Option<f64>, heading: Option<f64>) -> PyResult<()> {
    let usage = |m: String| new_err(Class::Shape, "Usage", m);
    if let Some(lat) = latitude {
        preint_analysis::parse::latitude(&lat.to_string())
            .map_err(|m| usage(format!("latitude: {m}")))?;
    }
    match heading {
        Some(_) if latitude.is_none() => Err(usage("heading needs latitude".into())),
        Some(h) if !h.is_finite() => Err(usage(format!(
            "heading {h} is not a finite angle in degrees"
        ))),
        _ => Ok(()),
    }
}

/// At least two samples, finite, strictly increasing (the messages of `BiasError`).
pub(crate) fn check(s: &[ImuSample]) -> PyResult<()> {
    let err = |e: BiasError| raise(Class::Calibration, e);
    if s.len() < 2 {
        return Err(err(BiasError::TooFew {
            what: "samples",
            found: s.len(),
            needed: 2,
        }));
    }
    for (index, x) in s.iter().enumerate() {
        if !(x.gyro.iter().chain(x.acc.iter()).all(|v| v.is_finite())) {
            return Err(err(BiasError::NonFinite {
                index,
                t_ns: x.t_ns,
            }));
        }
        if index > 0 && x.t_ns <= s[index - 1].t_ns {
            return Err(err(BiasError::NotIncreasing {
                index,
                t_ns: x.t_ns,
            }));
        }
    }
    Ok(())
}

/// Mean sample rate \[Hz\] of at least two samples.
fn rate_hz(s: &[ImuSample]) -> f64 {
    let n = s.len();
    (n - 1) as f64 / ((s[n - 1].t_ns - s[0].t_ns) as f64 * 1e-9)
}

fn interval_dict<'py>(py: Python<'py>, iv: &StillInterval) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("start", iv.start)?;
    d.set_item("end", iv.end)?;
    d.set_item("t_start_ns", iv.t_start_ns)?;
    d.set_item("t_end_ns", iv.t_end_ns)?;
    d.set_item("duration_s", iv.duration_s())?;
    Ok(d)
}

/// detect_still_intervals(t_ns, gyro, acc, noise=None)
///
/// The still intervals of arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(name = "detect_still_intervals", signature = (t_ns, gyro, acc, noise=None))]
pub(crate) fn detect_still_intervals_py<'py>(
    py: Python<'py>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    noise: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let noise = noise_arg(noise, true)?;
    let s = samples(t_ns, gyro, acc)?;
    check(&s)?;
    let ivs = py
        .detach(|| detect_still_intervals(&s, &StillOptions::from_noise(&noise, rate_hz(&s))))
        .map_err(|e| raise(Class::Calibration, e))?;
    ivs.iter().map(|iv| interval_dict(py, iv)).collect()
}

fn static_dict<'py>(py: Python<'py>, c: &StaticCalibration) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("model", "static-single-attitude")?;
    d.set_item("gyro_bias", vec_py(py, &c.gyro_bias))?;
    d.set_item("gyro_bias_std", vec_py(py, &c.gyro_bias_std))?;
    d.set_item("acc_bias", c.acc_bias.map(|b| vec_py(py, &b)))?;
    d.set_item("acc_bias_std", c.acc_bias_std.map(|b| vec_py(py, &b)))?;
    d.set_item("acc_bias_note", c.acc_bias_note.clone())?;
    d.set_item("roll", c.roll)?;
    d.set_item("pitch", c.pitch)?;
    d.set_item("roll_std", c.roll_std)?;
    d.set_item("pitch_std", c.pitch_std)?;
    d.set_item("roll_pitch_cov", mat_py(py, &c.roll_pitch_cov))?;
    d.set_item("up_body", vec_py(py, &c.up_body))?;
    d.set_item("R_wb", mat_py(py, c.attitude.matrix()))?;
    d.set_item("unobservable", c.unobservable.clone())?;
    d.set_item("samples", c.samples)?;
    d.set_item("duration_s", c.duration_s)?;
    d.set_item(
        "measured_gyro_density",
        vec_py(py, &c.measured_gyro_density),
    )?;
    d.set_item("measured_acc_density", vec_py(py, &c.measured_acc_density))?;
    d.set_item("chi2", c.chi2)?;
    d.set_item("dof", c.dof)?;
    d.set_item("iterations", c.iterations)?;
    Ok(d)
}

/// calibrate_static(t_ns, gyro, acc, noise=None, *, gravity=9.81, acc_bias_prior=None,
/// latitude=None, heading=None, still_check=True)
///
/// Single-attitude static calibration of arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(name = "calibrate_static", signature = (t_ns, gyro, acc, noise=None, *, gravity=9.81, acc_bias_prior=None,
    latitude=None, heading=None, still_check=true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn calibrate_static_py<'py>(
    py: Python<'py>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    noise: Option<&Bound<'py, PyAny>>,
    gravity: f64,
    acc_bias_prior: Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    latitude: Option<f64>,
    heading: Option<f64>,
    still_check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    crate::checks::gravity_magnitude("gravity", gravity)?;
    let noise = noise_arg(noise, true)?;
    let prior = acc_bias_prior
        .map(|(m, s)| -> PyResult<AccBiasPrior> {
            Ok(AccBiasPrior {
                mean: crate::convert::vec3("acc_bias_prior mean", &m)?,
                std: crate::convert::vec3("acc_bias_prior std", &s)?,
            })
        })
        .transpose()?;
    earth_args(latitude, heading)?;
    let s = samples(t_ns, gyro, acc)?;
    check(&s)?;
    let opts = StaticOptions {
        gravity: Vector3::new(0.0, 0.0, -gravity),
        acc_bias_prior: prior,
        ..Default::default()
    };
    let n = s.len();
    let whole = StillInterval {
        start: 0,
        end: n,
        t_start_ns: s[0].t_ns,
        t_end_ns: s[n - 1].t_ns,
    };
    // Errors: (kind, message).
    let run = || -> Result<(StaticCalibration, StillInterval, f64), (String, String)> {
        let bias_err = |e: BiasError| (crate::errors::variant_name(&e), e.to_string());
        let (used, still_s) = if still_check {
            let so = StillOptions::from_noise(&noise, rate_hz(&s));
            let still = detect_still_intervals(&s, &so).map_err(bias_err)?;
            let still_s = still.iter().map(|iv| iv.duration_s()).sum();
            let used = still.iter().max_by_key(|iv| iv.len()).copied().ok_or((
                "NotStatic".to_string(),
                format!(
                    "no still interval (≥ {} s with gyro and accelerometer variances within 4× \
                     the noise densities' white noise): a static calibration needs the sensor at \
                     rest (or check the noise densities)",
                    so.min_duration_s
                ),
            ))?;
            (used, still_s)
        } else {
            (whole, whole.duration_s())
        };
        let mut c = calibrate_static(&s[used.start..used.end], &noise, &opts).map_err(bias_err)?;
        if let Some(lat) = latitude {
            let e = earth_rate_in_body(&c.up_body, (c.roll, c.pitch), lat, heading);
            c = remove_earth_rate(&c, &e);
        }
        Ok((c, used, still_s))
    };
    let (c, used, still_s) = py
        .detach(run)
        .map_err(|(kind, m)| new_err(Class::Calibration, &kind, m))?;
    let d = static_dict(py, &c)?;
    d.set_item("interval", interval_dict(py, &used)?)?;
    d.set_item("still_s", still_s)?;
    d.set_item("recording_s", whole.duration_s())?;
    Ok(d)
}

fn multi_pose_dict<'py>(py: Python<'py>, c: &MultiPoseCalibration) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("model", format!("multi-pose/{}", c.model.name()))?;
    d.set_item("reason", c.reason.clone())?;
    d.set_item("gyro_bias", vec_py(py, &c.gyro_bias))?;
    d.set_item("gyro_bias_std", vec_py(py, &c.gyro_bias_std))?;
    d.set_item("acc_bias", vec_py(py, &c.acc_bias))?;
    d.set_item("acc_bias_std", vec_py(py, &c.acc_bias_std))?;
    let opt = |v: &Option<Vector3<f64>>| v.map(|v| vec_py(py, &v));
    d.set_item("acc_scale", opt(&c.acc_scale))?;
    d.set_item("acc_scale_std", opt(&c.acc_scale_std))?;
    d.set_item("acc_misalignment", opt(&c.acc_misalignment))?;
    d.set_item("acc_misalignment_std", opt(&c.acc_misalignment_std))?;
    d.set_item("gyro_scale", opt(&c.gyro_scale))?;
    d.set_item("gyro_scale_std", opt(&c.gyro_scale_std))?;
    let opt6 = |v: &Option<nalgebra::SVector<f64, 6>>| v.map(|v| crate::convert::svec_py(py, &v));
    d.set_item("gyro_misalignment", opt6(&c.gyro_misalignment))?;
    d.set_item("gyro_misalignment_std", opt6(&c.gyro_misalignment_std))?;
    d.set_item("acc_scale_matrix", mat_py(py, &c.acc_scale_matrix()))?;
    d.set_item("gyro_scale_matrix", mat_py(py, &c.gyro_scale_matrix()))?;
    let ivs: PyResult<Vec<_>> = c.intervals.iter().map(|iv| interval_dict(py, iv)).collect();
    d.set_item("intervals", ivs?)?;
    let k = c.attitudes.len();
    let att = Array3::from_shape_fn((k, 3, 3), |(i, r, col)| c.attitudes[i].matrix()[(r, col)]);
    d.set_item("R_wb", att.into_pyarray(py))?;
    let fits: PyResult<Vec<_>> = c
        .fits
        .iter()
        .map(|f| {
            let x = PyDict::new(py);
            x.set_item("model", f.model.name())?;
            x.set_item("chi2", f.chi2)?;
            x.set_item("params", f.params)?;
            x.set_item("residuals", f.residuals)?;
            x.set_item("bic", f.bic)?;
            x.set_item("identifiable", f.identifiable)?;
            x.set_item("converged", f.converged)?;
            Ok(x)
        })
        .collect();
    d.set_item("model_selection", fits?)?;
    d.set_item("dof", c.dof)?;
    d.set_item("iterations", c.iterations)?;
    d.set_item("bias_reference_time_ns", c.reference_time_ns)?;
    d.set_item("random_walk_marginalised", c.random_walk_marginalised)?;
    Ok(d)
}

/// calibrate_multi_pose(t_ns, gyro, acc, noise=None, *, gravity=9.81)
///
/// Multi-position calibration of arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(name = "calibrate_multi_pose", signature = (t_ns, gyro, acc, noise=None, *, gravity=9.81))]
pub(crate) fn calibrate_multi_pose_py<'py>(
    py: Python<'py>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    noise: Option<&Bound<'py, PyAny>>,
    gravity: f64,
) -> PyResult<Bound<'py, PyDict>> {
    crate::checks::gravity_magnitude("gravity", gravity)?;
    let noise = noise_arg(noise, true)?;
    let s = samples(t_ns, gyro, acc)?;
    check(&s)?;
    let opts = MultiPoseOptions {
        gravity: Vector3::new(0.0, 0.0, -gravity),
        ..Default::default()
    };
    let c = py
        .detach(|| calibrate_multi_pose(&s, &noise, &opts))
        .map_err(|e| raise(Class::Calibration, e))?;
    multi_pose_dict(py, &c)
}

/// `estimate` as the command's comma-separated list: a string (`"noise"`,
/// `"time-offset,gyro-intrinsics"`) or a list of names (`["noise"]`).
fn estimate_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    if let Ok(s) = obj.extract::<String>() {
        return Ok(Some(s));
    }
    obj.extract::<Vec<String>>()
        .map(|v| Some(v.join(",")))
        .map_err(|_| {
            raise(
                Class::Input,
                "estimate: give a string (\"noise\", \"time-offset,gyro-intrinsics\") or a list \
                 of names ([\"noise\"])",
            )
        })
}

/// calibrate(path=None, *, gyro=None, accel=None, ..., noise=None, poses=None, gravity=9.81,
/// from_ns=None, to_ns=None, pose_rot_std=None, pose_pos_std=None, latitude=None, heading=None,
/// estimate=None, pose_spacing=0.5, calibration=None, out=None, scheme="midpoint", window=None,
/// vel_std=None, bias_gyro_std=None, bias_acc_std=None)
///
/// `preint calibrate --json` on a recording, as a dict (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, gyro=None, accel=None, noise=None, poses=None,
    gravity=9.81, from_ns=None, to_ns=None, pose_rot_std=None, pose_pos_std=None, latitude=None,
    heading=None, estimate=None, pose_spacing=0.5, calibration=None, out=None,
    scheme="midpoint", window=None, vel_std=None, bias_gyro_std=None, bias_acc_std=None,
    **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn calibrate_file<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    noise: Option<PathBuf>,
    poses: Option<PathBuf>,
    gravity: f64,
    from_ns: Option<i64>,
    to_ns: Option<i64>,
    pose_rot_std: Option<f64>,
    pose_pos_std: Option<f64>,
    latitude: Option<f64>,
    heading: Option<f64>,
    estimate: Option<&Bound<'py, PyAny>>,
    pose_spacing: f64,
    calibration: Option<PathBuf>,
    out: Option<PathBuf>,
    scheme: &str,
    window: Option<Vec<f64>>,
    vel_std: Option<f64>,
    bias_gyro_std: Option<f64>,
    bias_acc_std: Option<f64>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    crate::checks::gravity_magnitude("gravity", gravity)?;
    let scheme = crate::params::scheme_from(scheme)?;
    earth_args(latitude, heading)?;
    let estimate = estimate_arg(estimate)?;
    let needs_poses = estimate.is_some() || calibration.is_some();
    if needs_poses && poses.is_none() {
        return Err(raise(
            Class::Input,
            "estimate and calibration are options of the known-pose problem: give poses",
        ));
    }
    let estimate = estimate
        .map(|e| calibrate::EstimateList::parse(&e))
        .transpose()
        .map_err(|e| raise(Class::Input, e))?;
    let ground_truth = [
        ("window", window.is_some()),
        ("vel_std", vel_std.is_some()),
        ("bias_gyro_std", bias_gyro_std.is_some()),
        ("bias_acc_std", bias_acc_std.is_some()),
    ];
    if estimate.is_some_and(|e| e.noise) {
        let opts = noise_model::NoiseOptions {
            input,
            poses,
            window,
            noise,
            gravity,
            from: from_ns,
            to: to_ns,
            pose_rot_std,
            pose_pos_std,
            vel_std,
            bias_gyro_std,
            bias_acc_std,
            body_p_sensor: None,
            scheme,
            out,
        };
        let json = py
            .detach(|| noise_model::compute(&opts).map(|r| noise_model::to_json(&r)))
            .map_err(|e| analysis_err(e, Class::Calibration))?;
        return json_py(py, &json);
    }
    if let Some((name, _)) = ground_truth.iter().find(|(_, given)| *given) {
        return Err(raise(
            Class::Input,
            format!(
                "{name} is read by estimate=\"noise\" only; give poses=GT, estimate=\"noise\", \
                 or leave it out"
            ),
        ));
    }
    let opts = calibrate::Options {
        input,
        poses,
        noise,
        gravity,
        from: from_ns,
        to: to_ns,
        pose_rot_std: pose_rot_std.unwrap_or(0.0),
        pose_pos_std: pose_pos_std.unwrap_or(0.0),
        body_p_sensor: None,
        latitude,
        heading,
        out,
        estimate: estimate.map(|e| e.extras),
        pose_spacing,
        calibration,
        scheme,
    };
    let json = py
        .detach(|| calibrate::compute(&opts).map(|r| calibrate::to_json(&r)))
        .map_err(|e| analysis_err(e, Class::Calibration))?;
    json_py(py, &json)
}
