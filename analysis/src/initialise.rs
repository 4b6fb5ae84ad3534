//! `preint initialise`: gravity, scale, keyframe velocities and biases from the keyframe poses
//! of a front end (up to scale or metric) and the IMU samples ([`preint_calib::init`]), with
//! the readiness verdict.

use crate::checks::{self, UnitCheck};
use crate::{Error, ImuInput, noise, stream};
use nalgebra::Vector3;
use preint::{ImuSample, PreintParams, Scheme, SensorPose};
use preint_calib::KnownPose;
use preint_calib::init::{COVARIANCE_ORDER, InitOptions, Initialisation, ScaleMode, initialise};
use preint_io::SourceInfo;
use preint_lie::SO3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// What `initialise` computes on.
#[derive(Clone, Debug)]
pub struct Options {
    /// The recording and how to read it.
    pub input: ImuInput,
    /// Keyframe poses (`--poses`): EuRoC ground truth or `t,x,y,z,qw,qx,qy,qz`, positions in
    /// their own unit.
    pub poses: PathBuf,
    /// Whether the positions are metric (`--scale`).
    pub scale: ScaleMode,
    /// Spacing of the keyframes used \[s\] (`--pose-spacing`).
    pub pose_spacing: f64,
    /// Kalibr imu.yaml with the noise densities (`--noise`).
    pub noise: Option<PathBuf>,
    /// |g| \[m/s²\] (`--gravity`).
    pub gravity: f64,
    /// Window bounds \[ns\] (`--from`, `--to`).
    pub from: Option<i64>,
    /// See `from`.
    pub to: Option<i64>,
    /// σ of the keyframe attitudes \[rad\] (`--pose-rot-std`).
    pub pose_rot_std: f64,
    /// σ of the keyframe positions \[unit of the poses\] (`--pose-pos-std`).
    pub pose_pos_std: f64,
    /// The IMU's pose in the frame of the poses (`--body-p-sensor`).
    pub body_p_sensor: Option<SensorPose>,
    /// The prior σ of the biases, gyro \[rad/s\] and accelerometer \[m/s²\]
    /// (`--bias-prior-std`).
    pub bias_prior_std: (f64, f64),
    /// The scheme of the windows (`--scheme`).
    pub scheme: Scheme,
}

/// The initialisation and how the recording was read.
#[derive(Clone, Debug)]
pub struct Initialised {
    /// The estimate and its verdict.
    pub init: Initialisation,
    /// The pose file, as printed.
    pub poses: String,
    /// How the recording was read.
    pub source: SourceInfo,
    /// The unit checks' verdict.
    pub unit_check: UnitCheck,
    /// Whether the scale was estimated.
    pub scale: ScaleMode,
}

/// The initialisation of `o` (module docs).
pub fn compute(o: &Options) -> Result<Initialised, Error> {
    checks::window_order(o.from, o.to)?;
    checks::non_negative("--pose-rot-std", o.pose_rot_std)?;
    checks::non_negative("--pose-pos-std", o.pose_pos_std)?;
    checks::positive("--pose-spacing", o.pose_spacing)?;
    checks::positive("--bias-prior-std (gyro)", o.bias_prior_std.0)?;
    checks::positive("--bias-prior-std (accelerometer)", o.bias_prior_std.1)?;
    checks::gravity("--gravity", o.gravity)?;
    let noise = noise::or_default(o.noise.as_deref())?;
    let span = stream::read_span(&o.input, o.from, o.to, "initialise")?;
    let poses = keyframes(&o.poses, &span.samples, o.pose_spacing)?;
    let mut opts = InitOptions::new(
        PreintParams::from_noise(&noise)
            .with_scheme(o.scheme)
            .with_gravity(Vector3::new(0.0, 0.0, -o.gravity)),
    );
    opts.scale = o.scale;
    opts.pose_rot_std = o.pose_rot_std;
    opts.pose_pos_std = o.pose_pos_std;
    opts.body_p_sensor = o.body_p_sensor;
    opts.bias_prior.gyro_std = o.bias_prior_std.0;
    opts.bias_prior.acc_std = o.bias_prior_std.1;
    let init = initialise(&span.samples, &poses, &opts)
        .map_err(|e| Error::failed_in(o.input.path(), e))?;
    Ok(Initialised {
        init,
        poses: o.poses.display().to_string(),
        source: span.source,
        unit_check: span.unit_check,
        scale: o.scale,
    })
}

/// The poses of `file` inside the samples' span, `spacing_s` apart; positions required.
fn keyframes(file: &Path, samples: &[ImuSample], spacing_s: f64) -> Result<Vec<KnownPose>, Error> {
    let rows = crate::calibrate::poses_in_span(file, samples, spacing_s, 0)?;
    rows.iter()
        .map(|r| {
            let p = r.p.ok_or_else(|| {
                Error::Failed(format!(
                    "{}: attitudes only; the initialisation needs positions (t,x,y,z,qw,qx,qy,qz)",
                    file.display()
                ))
            })?;
            Ok(KnownPose {
                t_ns: r.t_ns,
                r: SO3::from_quaternion(&r.q),
                p,
            })
        })
        .collect()
}

fn v3(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// The JSON form (`ready: false` is a result, not an error).
pub fn to_json(r: &Initialised) -> Value {
    let i = &r.init;
    let known = r.scale == ScaleMode::Known;
    let cov: Vec<Vec<f64>> = (0..10)
        .map(|a| (0..10).map(|b| i.covariance[(a, b)]).collect())
        .collect();
    json!({
        "command": "initialise",
        "input": crate::recording::input_json(&r.source, &r.unit_check),
        "poses": r.poses,
        "keyframes": i.keyframes,
        "window_s": i.window_s,
        "scale_mode": if known { "known" } else { "unknown" },
        "scale": i.scale,
        "scale_std": i.scale_std,
        "gravity": v3(&i.gravity),
        "gravity_std": v3(&i.gravity_std),
        "gravity_direction_std_deg": i.gravity_dir_std_rad.to_degrees(),
        "bias_gyro": v3(&i.bias.gyro),
        "bias_gyro_std": v3(&i.gyro_bias_std),
        "bias_acc": v3(&i.bias.acc),
        "bias_acc_std": v3(&i.acc_bias_std),
        "velocities": i.velocities.iter().zip(&i.velocity_std).map(|((t, v), s)| json!({
            "t_ns": t, "v": v3(v), "std": v3(s)
        })).collect::<Vec<_>>(),
        "covariance": cov,
        "covariance_order": COVARIANCE_ORDER,
        "std_factor": i.std_factor,
        "fit": crate::consistency::fit_json(&i.fit),
        "linear_start": {
            "scale": i.linear.scale,
            "gravity": v3(&i.linear.gravity),
            "bias_gyro": v3(&i.linear.gyro_bias),
        },
        "ready": i.ready,
        "reason": i.reason,
    })
}
