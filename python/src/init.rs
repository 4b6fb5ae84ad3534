//! `initialise_file`: `preint initialise --json` on a recording and a keyframe pose file
//! ([`preint_analysis::initialise`]).

use crate::errors::{Class, raise};
use crate::io::{ReadArgs, analysis_err, json_py};
use preint_analysis::initialise::{self, Options};
use preint_calib::init::ScaleMode;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// initialise_file(path=None, *, poses, scale="unknown", ...)
///
/// `preint initialise --json` on a recording, as a dict (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, poses, gyro=None, accel=None, scale="unknown", noise=None,
    gravity=9.81, from_ns=None, to_ns=None, pose_rot_std=0.0, pose_pos_std=0.0,
    pose_spacing=0.1, body_p_sensor=None, bias_prior_std=None, scheme="midpoint",
    **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn initialise_file<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    poses: PathBuf,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    scale: &str,
    noise: Option<PathBuf>,
    gravity: f64,
    from_ns: Option<i64>,
    to_ns: Option<i64>,
    pose_rot_std: f64,
    pose_pos_std: f64,
    pose_spacing: f64,
    body_p_sensor: Option<Vec<f64>>,
    bias_prior_std: Option<(f64, f64)>,
    scheme: &str,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    crate::checks::gravity_magnitude("gravity", gravity)?;
    let scale = match scale {
        "unknown" => ScaleMode::Unknown,
        "known" => ScaleMode::Known,
        other => {
            return Err(raise(
                Class::Input,
                format!("scale {other:?}: expected \"unknown\" or \"known\""),
            ));
        }
    };
    let body_p_sensor = body_p_sensor
        .map(|v| {
            let text: Vec<String> = v.iter().map(f64::to_string).collect();
            preint_analysis::parse::sensor_pose(&text.join(","))
                .map_err(|e| raise(Class::Input, format!("body_p_sensor: {e}")))
        })
        .transpose()?;
    let opts = Options {
        input,
        poses,
        scale,
        pose_spacing,
        noise,
        gravity,
        from: from_ns,
        to: to_ns,
        pose_rot_std,
        pose_pos_std,
        body_p_sensor,
        bias_prior_std: bias_prior_std.unwrap_or((0.05, 0.2)),
        scheme: crate::params::scheme_from(scheme)?,
    };
    let json = py
        .detach(|| initialise::compute(&opts).map(|r| initialise::to_json(&r)))
        .map_err(|e| analysis_err(e, Class::Calibration))?;
    json_py(py, &json)
}
