//! `preint calibrate`: bias estimation with Gauss-Newton, modelling only what the data makes
//! observable.
//!
//! Model choice:
//! - `--poses FILE` (EuRoC ground truth, `t,p,q` or attitudes only `t,q`;
//!   [`preint_io::poses`]): the known-pose problem (biases, velocities, gravity direction) on
//!   poses `--pose-spacing` apart, or with attitudes only the gyroscope problem (gyro bias);
//!   `--estimate` adds the time offset, gyroscope intrinsics, g-sensitivity and accelerometer
//!   intrinsics, each with its σ or withheld when the motion does not excite it
//!   ([`preint_calib::bias::known_poses::extras`]); JSON `parameters`: `[{name, unit,
//!   excited, value` (null when withheld), `kept` (the value applied and written), `std}]`,
//!   `time_offset_s` (null unless estimated or given) and `intrinsics` (`Tw`, `R_IMUtoGYRO`,
//!   `Ta`, `R_IMUtoACC`, `Tg` row by row);
//! - otherwise, still intervals are detected; with at least three of them at distinct
//!   attitudes (> 20° apart) the multi-position problem (Tedaldi et al. 2014) estimates both
//!   biases, the attitudes and, if BIC supports it, scale factors;
//! - otherwise the single-attitude static problem on the longest still interval: gyro bias and
//!   roll/pitch; the accelerometer bias is not separable from tilt and is reported as
//!   unobservable (`acc_bias: null`). Without a still interval there is nothing a static
//!   method can answer: the command refuses (exit 2) and says what would work.
//!
//! The samples must be continuous: a gap longer than [`MAX_GAP_S`] (and ten sample intervals)
//! is refused, naming where it is.

use crate::checks::UnitCheck;
use crate::format::{list, opt_list};
use crate::imu_args::ImuArgs;
use crate::{CliError, Output, calibration_file, checks, noise, stream};
use nalgebra::Vector3;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::{ImuNoise, ImuSample, PreintParams, Scheme};
use preint_calib::bias::known_poses::extras::{Estimate, ParameterEstimate};
use preint_calib::bias::known_poses::{
    KnownAttitude, KnownAttitudeCalibration, calibrate_known_attitudes,
};
use preint_calib::bias::{
    KnownPose, KnownPoseCalibration, KnownPoseOptions, MultiPoseCalibration, MultiPoseOptions,
    StaticCalibration, StaticOptions, StillInterval, StillOptions, calibrate_known_poses,
    calibrate_multi_pose, calibrate_static, detect_still_intervals, roll_pitch_of_up,
};
use preint_io::SourceInfo;
use preint_lie::SO3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Flags of `preint calibrate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Known poses for the known-pose problem: EuRoC ground truth (17 columns), `t,x,y,z,qw,qx,
    /// qy,qz` (8) or attitudes only `t,qw,qx,qy,qz` (5: a gyroscope-only calibration); t in ns,
    /// quaternion body→world.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Known-pose problem: parameters estimated beside the biases, comma-separated, from
    /// time-offset, gyro-intrinsics, g-sensitivity, accel-intrinsics (OpenVINS' kalibr model:
    /// Tw and R_IMUtoGYRO, Tg, Ta). Each is printed with its σ, or withheld (not applied, not
    /// written) when the motion does not excite it.
    #[arg(long, value_name = "LIST", requires = "poses", value_parser = parse_estimate)]
    pub estimate: Option<Estimate>,
    /// Known-pose problem: spacing of the poses used, in s.
    #[arg(long, value_name = "S", default_value_t = 0.5, requires = "poses")]
    pub pose_spacing: f64,
    /// Known-pose problem: a calibration file (as --out writes) whose intrinsics and time
    /// offset are applied, and are the starting point of those --estimate asks for.
    #[arg(long, value_name = "FILE", requires = "poses")]
    pub calibration: Option<PathBuf>,
    /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(long)]
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G (m/s^2, up to 100).
    #[arg(long, default_value_t = 9.81, value_parser = crate::parse::gravity)]
    pub gravity: f64,
    /// Use only samples (and poses) with timestamps >= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Use only samples (and poses) with timestamps <= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// Known-pose problem: standard deviation of the given attitudes in rad (0: exact).
    /// E.g. 1.75e-3 (0.1°) and --pose-pos-std 0.005 for motion capture such as EuRoC's.
    #[arg(long, default_value_t = 0.0)]
    pub pose_rot_std: f64,
    /// Known-pose problem: standard deviation of the given positions in m (0: exact).
    #[arg(long, default_value_t = 0.0)]
    pub pose_pos_std: f64,
    /// Pose of the IMU in the body frame, x,y,z,qw,qx,qy,qz (m; quaternion rotating sensor
    /// vectors into the body frame). Known-pose problem: the poses are the body's and the
    /// preintegration removes the lever arm. Static problem: roll and pitch are also given for
    /// the body. Biases are always the IMU's, in its own axes.
    #[arg(long, value_parser = crate::parse::sensor_pose, allow_hyphen_values = true)]
    pub body_p_sensor: Option<preint::SensorPose>,
    /// Latitude (deg) of a static recording: the Earth rate's vertical part (Ω_E sin φ along
    /// up) is removed from the gyro bias; its horizontal part (Ω_E cos φ, direction unknown
    /// without --heading) is added to the bias σ. Single-attitude static model only.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true,
          value_parser = crate::earth_args::latitude)]
    pub latitude: Option<f64>,
    /// Heading of the body x axis (deg, clockwise from north): with --latitude, the whole
    /// Earth rate is removed from the gyro bias.
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "latitude"
    )]
    pub heading: Option<f64>,
    /// Write the calibration as OpenVINS' kalibr_imu_chain.yaml: the intrinsics (Tw,
    /// R_IMUtoGYRO, Ta, R_IMUtoACC, Tg; from the multi-position model BIC chose, or the
    /// known-pose estimate, else the identity), the time offset when estimated, and the noise
    /// densities. `integrate --calibration FILE` applies it.
    #[arg(long, value_name = "FILE")]
    pub out: Option<std::path::PathBuf>,
}

/// The problem solved and its estimates.
#[derive(Clone, Debug)]
pub enum Calibration {
    /// Known poses: biases, velocities and the gravity direction (and what `--estimate` asks).
    KnownPoses {
        /// The pose file, as printed.
        source: String,
        /// Number of poses used (`--pose-spacing` apart, inside the IMU time span).
        poses: usize,
        /// The stated pose noise: attitude \[rad\], position \[m\].
        pose_std: (f64, f64),
        /// The estimates.
        c: Box<KnownPoseCalibration>,
        /// Whether the time offset was asked for or given (then it is written by `--out`).
        time_offset: bool,
    },
    /// Known attitudes only: the gyro bias (and what `--estimate` asks of the gyroscope).
    KnownAttitudes {
        /// The pose file, as printed.
        source: String,
        /// Number of attitudes used.
        poses: usize,
        /// The stated attitude noise \[rad\].
        pose_rot_std: f64,
        /// The estimates.
        c: Box<KnownAttitudeCalibration>,
        /// Whether the time offset was asked for or given.
        time_offset: bool,
    },
    /// Still intervals at ≥ 3 distinct attitudes: both biases, scale factors if BIC says so.
    MultiPose(Box<MultiPoseCalibration>),
    /// One attitude: gyro bias, roll and pitch, on the longest still interval.
    Static {
        /// The estimates.
        c: Box<StaticCalibration>,
        /// The still interval used.
        used: StillInterval,
        /// Total still time found \[s\] and duration of the recording \[s\].
        still_s: (f64, f64),
        /// With `--body-p-sensor`: the body's roll and pitch \[rad\] (the IMU's "up" rotated
        /// into the body frame).
        body_roll_pitch: Option<(f64, f64)>,
        /// The Earth rate taken out of the gyro bias (`--latitude`).
        earth: Option<preint_calib::bias::EarthRateInBody>,
    },
}

/// A solver error, prefixed with the IMU file it came from.
fn fail_in(imu: &Path) -> impl Fn(preint_calib::bias::BiasError) -> CliError + '_ {
    move |e| CliError::failed_in(imu, e)
}

/// Number of still intervals whose mean specific-force directions differ pairwise by > 20°.
fn distinct_attitudes(samples: &[ImuSample], ivs: &[StillInterval]) -> usize {
    let mut dirs: Vec<Vector3<f64>> = Vec::new();
    for iv in ivs {
        let m: Vector3<f64> = samples[iv.start..iv.end]
            .iter()
            .map(|s| s.acc)
            .sum::<Vector3<f64>>();
        let d = m.normalize();
        if dirs.iter().all(|e| e.dot(&d) < 20f64.to_radians().cos()) {
            dirs.push(d);
        }
    }
    dirs.len()
}

/// Longest accepted interval between consecutive samples \[s\] (that of preintegration,
/// [`preint::params::DEFAULT_MAX_GAP_NS`]).
pub const MAX_GAP_S: f64 = preint::params::DEFAULT_MAX_GAP_NS as f64 * 1e-9;

/// Reads the samples in `[--from, --to]` (only those are held, at most
/// [`stream::MAX_HELD_SAMPLES`]; reading stops after `--to`) and checks their units and that
/// they have no gap.
fn read_samples(args: &Args) -> Result<stream::Span, CliError> {
    stream::read_span(&args.input, args.from, args.to, "calibrate")
}

/// `--estimate`'s list.
fn parse_estimate(list: &str) -> Result<Estimate, String> {
    Estimate::parse(list)
}

/// Largest time offset `--estimate time-offset` looks for \[ns\]: poses within this of the
/// recording's ends are not used, so that every shifted window stays inside the samples.
const MAX_TIME_OFFSET_NS: i64 = 100_000_000;

/// The poses of `pfile` inside the samples' time span (less a margin for the time offset),
/// `--pose-spacing` apart.
fn select_poses(
    args: &Args,
    pfile: &Path,
    samples: &[ImuSample],
    margin_ns: i64,
) -> Result<Vec<preint_io::PoseRow>, CliError> {
    let rows = preint_io::read_poses(pfile)?;
    let (t0, t1) = (
        samples[0].t_ns + margin_ns,
        samples[samples.len() - 1].t_ns - margin_ns,
    );
    let spacing = (args.pose_spacing * 1e9).round() as i64;
    let mut kp: Vec<preint_io::PoseRow> = Vec::new();
    for s in rows.iter().filter(|s| s.t_ns >= t0 && s.t_ns <= t1) {
        if kp.last().is_none_or(|l| s.t_ns - l.t_ns >= spacing) {
            kp.push(*s);
        }
    }
    if kp.len() < 3 {
        return Err(CliError::Failed(format!(
            "{}: fewer than three poses inside the IMU time span (poses ≥ {} s apart{} are \
             used)",
            pfile.display(),
            args.pose_spacing,
            if margin_ns > 0 {
                format!(", ≥ {} s from its ends", margin_ns as f64 * 1e-9)
            } else {
                String::new()
            }
        )));
    }
    Ok(kp)
}

/// The known-pose problem on the poses of `pfile` inside the samples' time span (attitudes
/// only when the file has no positions).
fn known_poses(
    args: &Args,
    pfile: &Path,
    samples: &[ImuSample],
    noise: &ImuNoise,
) -> Result<Calibration, CliError> {
    checks::positive("--pose-spacing", args.pose_spacing)?;
    let estimate = args.estimate.unwrap_or_default();
    if estimate.any() && args.body_p_sensor.is_some() {
        return Err(CliError::Usage(
            "--estimate with --body-p-sensor: the calibration parameters are estimated in the \
             IMU's frame; give poses of the IMU instead"
                .into(),
        ));
    }
    let file = args
        .calibration
        .as_deref()
        .map(calibration_file::read)
        .transpose()?;
    let td0 = file.as_ref().and_then(|f| f.time_offset_s);
    let time_offset = estimate.time_offset || td0.is_some();
    let margin = if time_offset {
        MAX_TIME_OFFSET_NS + calibration_file::time_offset_ns_of(td0).abs()
    } else {
        0
    };
    let rows = select_poses(args, pfile, samples, margin)?;
    let params = PreintParams {
        body_p_sensor: args.body_p_sensor,
        ..PreintParams::from_noise(noise)
            .with_scheme(Scheme::Midpoint)
            .with_gravity(Vector3::new(0.0, 0.0, -args.gravity))
    };
    let mut opts = KnownPoseOptions {
        pose_rot_std: args.pose_rot_std,
        pose_pos_std: args.pose_pos_std,
        estimate,
        initial_time_offset_s: td0.unwrap_or(0.0),
        ..KnownPoseOptions::new(params)
    };
    if let Some(f) = &file {
        opts.initial_intrinsics = f.intrinsics;
    }
    let source = pfile.display().to_string();
    let fail = fail_in(args.input.path());
    if rows.iter().any(|r| r.p.is_none()) {
        let atts: Vec<KnownAttitude> = rows
            .iter()
            .map(|r| KnownAttitude {
                t_ns: r.t_ns,
                r: SO3::from_quaternion(&r.q),
            })
            .collect();
        let c = calibrate_known_attitudes(samples, &atts, &opts).map_err(fail)?;
        return Ok(Calibration::KnownAttitudes {
            source,
            poses: atts.len(),
            pose_rot_std: args.pose_rot_std,
            c: Box::new(c),
            time_offset,
        });
    }
    let kp: Vec<KnownPose> = rows
        .iter()
        .map(|r| KnownPose {
            t_ns: r.t_ns,
            r: SO3::from_quaternion(&r.q),
            p: r.p.unwrap_or_default(),
        })
        .collect();
    let c = calibrate_known_poses(samples, &kp, &opts).map_err(fail)?;
    Ok(Calibration::KnownPoses {
        source,
        poses: kp.len(),
        pose_std: (args.pose_rot_std, args.pose_pos_std),
        c: Box::new(c),
        time_offset,
    })
}

/// Chooses the problem (module docs) and solves it; also returns how the recording was read
/// and what its unit checks said.
pub fn compute(args: &Args) -> Result<(Calibration, (SourceInfo, UnitCheck)), CliError> {
    checks::non_negative("--pose-rot-std", args.pose_rot_std)?;
    checks::non_negative("--pose-pos-std", args.pose_pos_std)?;
    checks::positive("--gravity", args.gravity)?;
    checks::gravity("--gravity", args.gravity)?;
    let noise = noise::or_default(args.noise.as_deref())?;
    let span = read_samples(args)?;
    let c = solve(args, span.samples, noise)?;
    Ok((c, (span.source, span.unit_check)))
}

/// [`compute`] on the samples read.
fn solve(args: &Args, samples: Vec<ImuSample>, noise: ImuNoise) -> Result<Calibration, CliError> {
    if let Some(h) = args.heading
        && !h.is_finite()
    {
        return Err(CliError::Usage(format!(
            "--heading {h} is not a finite angle in degrees"
        )));
    }
    let earth_refused = |model: &str| {
        CliError::Usage(format!(
            "--latitude is applied by the single-attitude static model; the {model} model does \
             not model Earth rotation (drop --latitude, or calibrate one still interval with \
             --from/--to)"
        ))
    };
    if let Some(pfile) = &args.poses {
        if args.latitude.is_some() {
            return Err(earth_refused("known-pose"));
        }
        return known_poses(args, pfile, &samples, &noise);
    }
    let fail = fail_in(args.input.path());
    let g = Vector3::new(0.0, 0.0, -args.gravity);
    let n = samples.len();
    let rate = (n - 1) as f64 / ((samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9);
    let still =
        detect_still_intervals(&samples, &StillOptions::from_noise(&noise, rate)).map_err(&fail)?;
    if distinct_attitudes(&samples, &still) >= 3 {
        if args.latitude.is_some() {
            return Err(earth_refused("multi-position"));
        }
        let opts = MultiPoseOptions {
            gravity: g,
            ..Default::default()
        };
        let c = calibrate_multi_pose(&samples, &noise, &opts).map_err(&fail)?;
        return Ok(Calibration::MultiPose(Box::new(c)));
    }
    let Some(used) = still.iter().max_by_key(|iv| iv.len()).copied() else {
        return Err(CliError::Failed(format!(
            "{}: no still interval (≥ {} s with gyro and accelerometer variances within 4× the \
             noise densities' white noise): a static calibration needs the sensor at rest. Give \
             --poses for a moving recording, or check --noise",
            args.input.label(),
            StillOptions::from_noise(&noise, rate).min_duration_s
        )));
    };
    let opts = StaticOptions {
        gravity: g,
        ..Default::default()
    };
    let mut c = calibrate_static(&samples[used.start..used.end], &noise, &opts).map_err(&fail)?;
    let earth = args.latitude.map(|lat| {
        preint_calib::bias::earth_rate_in_body(&c.up_body, (c.roll, c.pitch), lat, args.heading)
    });
    if let Some(e) = &earth {
        c = preint_calib::bias::remove_earth_rate(&c, e);
    }
    let total_s = (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9;
    let still_s = still.iter().map(|iv| iv.duration_s()).sum();
    let body_roll_pitch = args.body_p_sensor.map(|pose| {
        let (roll, pitch, _) = roll_pitch_of_up(&pose.rotation.act(&c.up_body));
        (roll, pitch)
    });
    Ok(Calibration::Static {
        c: Box::new(c),
        used,
        still_s: (still_s, total_s),
        body_roll_pitch,
        earth,
    })
}

/// The JSON form: `model` names the problem; estimates with standard deviations, χ², units.
pub fn to_json(cal: &Calibration) -> Value {
    match cal {
        Calibration::KnownPoses {
            poses,
            pose_std,
            c,
            time_offset,
            ..
        } => json!({
            "model": "known-poses", "poses": poses,
            "parameters": parameters_json(&c.parameters, c.intrinsics.model),
            "time_offset_s": time_offset.then_some(c.time_offset_s),
            "intrinsics": intrinsics_json(&c.intrinsics),
            "gyro_bias": list(&c.bias.gyro), "gyro_bias_std": list(&c.gyro_bias_std),
            "acc_bias": list(&c.bias.acc), "acc_bias_std": list(&c.acc_bias_std),
            "gravity": list(&c.gravity), "gravity_std": list(&c.gravity_std), "gravity_tilt_deg": c.gravity_tilt.to_degrees(),
            "pose_rot_std": pose_std.0, "pose_pos_std": pose_std.1,
            "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "gravity": "m/s^2"},
        }),
        Calibration::KnownAttitudes {
            poses,
            pose_rot_std,
            c,
            time_offset,
            ..
        } => json!({
            "model": "known-attitudes", "poses": poses,
            "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
            "parameters": parameters_json(&c.parameters, c.intrinsics.model),
            "time_offset_s": time_offset.then_some(c.time_offset_s),
            "intrinsics": intrinsics_json(&c.intrinsics),
            "pose_rot_std": pose_rot_std,
            "iterations": c.iterations, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s"},
        }),
        Calibration::MultiPose(c) => multi_pose_json(c),
        Calibration::Static {
            c,
            used,
            still_s,
            body_roll_pitch,
            earth,
        } => json!({
            "model": "static-single-attitude",
            "interval_ns": [used.t_start_ns, used.t_end_ns], "still_s": still_s.0, "recording_s": still_s.1,
            "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
            "acc_bias": opt_list(c.acc_bias), "acc_bias_std": opt_list(c.acc_bias_std), "acc_bias_note": c.acc_bias_note,
            "roll": c.roll, "pitch": c.pitch, "roll_std": c.roll_std, "pitch_std": c.pitch_std,
            "body_roll": body_roll_pitch.map(|b| b.0), "body_pitch": body_roll_pitch.map(|b| b.1),
            "unobservable": c.unobservable, "measured_gyro_density": list(&c.measured_gyro_density),
            "measured_acc_density": list(&c.measured_acc_density),
            "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s", "roll": "rad", "pitch": "rad", "densities": "rad/s/sqrt(Hz), m/s^2/sqrt(Hz)"},
            "earth_rate": earth.as_ref().map(earth_json),
        }),
    }
}

/// The `--estimate` parameters: name, unit, whether excited, the estimate (`value`, null when
/// withheld), the value kept (`kept`: the estimate, or the initial value when withheld) and σ
/// (null when the motion does not move the parameter at all).
fn parameters_json(ps: &[ParameterEstimate], model: IntrinsicsModel) -> Value {
    ps.iter()
        .map(|e| {
            json!({"name": e.param.name(model), "unit": e.param.unit(), "excited": e.excited,
                "value": e.excited.then_some(e.value), "kept": e.value,
                "std": e.std.is_finite().then_some(e.std)})
        })
        .collect()
}

/// The intrinsics' matrices, row by row.
fn intrinsics_json(x: &ImuIntrinsics) -> Value {
    let rows = |m: &nalgebra::Matrix3<f64>| -> Vec<Vec<f64>> {
        (0..3)
            .map(|r| (0..3).map(|c| m[(r, c)]).collect())
            .collect()
    };
    json!({"model": x.model.name(), "Tw": rows(&x.t_w), "R_IMUtoGYRO": rows(&x.r_imu_to_gyro),
        "Ta": rows(&x.t_a), "R_IMUtoACC": rows(&x.r_imu_to_acc), "Tg": rows(&x.t_g)})
}

/// The `--estimate` parameters, one line each: value ± σ, or why withheld.
fn parameter_lines(ps: &[ParameterEstimate], model: IntrinsicsModel) -> String {
    ps.iter()
        .map(|e| {
            let name = e.param.name(model);
            let unit = e.param.unit();
            if e.excited {
                format!("  {name} = {:+.6e} ± {:.1e} {unit}\n", e.value, e.std)
            } else {
                format!(
                    "  {name}: not excited by the motion (σ {:.1e} {unit}): kept at {:+.6e}\n",
                    e.std, e.value
                )
            }
        })
        .collect()
}

/// What `--latitude` did to the gyro bias.
fn earth_json(e: &preint_calib::bias::EarthRateInBody) -> Value {
    json!({"latitude_deg": e.latitude_deg, "heading_deg": e.heading_deg,
        "removed_body": list(&e.removed), "unresolved_horizontal": e.unresolved,
        "note": earth_note(e), "units": "rad/s, body frame"})
}

/// One sentence on the Earth rate's share of the bias.
fn earth_note(e: &preint_calib::bias::EarthRateInBody) -> String {
    if e.heading_deg.is_some() {
        "the Earth rate R_wb^T w_ie (from latitude, roll, pitch and heading) is removed from b_g"
            .into()
    } else {
        format!(
            "the vertical Earth rate is removed from b_g; its horizontal part ({:.3e} rad/s, \
             direction unknown without --heading) is not separable from b_g and is included in \
             the b_g sigma",
            e.unresolved
        )
    }
}

fn multi_pose_json(c: &MultiPoseCalibration) -> Value {
    let fits: Vec<Value> = c
        .fits
        .iter()
        .map(|f| {
            json!({"model": format!("{:?}", f.model), "chi2": f.chi2,
        "params": f.params, "bic": f.bic, "identifiable": f.identifiable, "converged": f.converged})
        })
        .collect();
    let chosen = c.fits.iter().find(|f| f.model == c.model);
    json!({
        "model": format!("multi-pose/{:?}", c.model), "still_intervals": c.intervals.len(),
        "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
        "acc_bias": list(&c.acc_bias), "acc_bias_std": list(&c.acc_bias_std),
        "acc_scale": opt_list(c.acc_scale), "acc_scale_std": opt_list(c.acc_scale_std),
        "gyro_scale": opt_list(c.gyro_scale), "gyro_scale_std": opt_list(c.gyro_scale_std),
        "model_selection": fits, "reason": c.reason,
        "bias_reference_time_ns": c.reference_time_ns, "random_walk_marginalised": c.random_walk_marginalised,
        "iterations": c.iterations, "cost": chosen.map(|f| 0.5 * f.chi2),
        "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "scale": "dimensionless (1 = ideal)"},
    })
}

/// `  b_g = [x, y, z] ± [σx, σy, σz] rad/s`.
fn gyro_line(b: &Vector3<f64>, s: &Vector3<f64>) -> String {
    format!(
        "  b_g = [{:.6}, {:.6}, {:.6}] ± [{:.1e}, {:.1e}, {:.1e}] rad/s\n",
        b.x, b.y, b.z, s.x, s.y, s.z
    )
}

/// `  b_a = [x, y, z] ± [σx, σy, σz] m/s²`.
fn acc_line(b: &Vector3<f64>, s: &Vector3<f64>) -> String {
    format!(
        "  b_a = [{:.4}, {:.4}, {:.4}] ± [{:.1e}, {:.1e}, {:.1e}] m/s²\n",
        b.x, b.y, b.z, s.x, s.y, s.z
    )
}

/// The human summary: the problem solved and its estimates with standard deviations.
pub fn to_text(cal: &Calibration) -> String {
    match cal {
        Calibration::KnownPoses {
            source, poses, c, ..
        } => format!(
            "known-pose calibration ({poses} poses from {source}):\n{}{}{}  gravity tilt {:.3}°, \
             χ²/dof = {:.2}, {} iterations\n",
            gyro_line(&c.bias.gyro, &c.gyro_bias_std),
            acc_line(&c.bias.acc, &c.acc_bias_std),
            parameter_lines(&c.parameters, c.intrinsics.model),
            c.gravity_tilt.to_degrees(),
            c.chi2 / c.dof.max(1) as f64,
            c.iterations
        ),
        Calibration::KnownAttitudes {
            source, poses, c, ..
        } => format!(
            "known-attitude (gyroscope) calibration ({poses} attitudes from {source}):\n{}{}  \
             χ²/dof = {:.2}, {} iterations\n",
            gyro_line(&c.gyro_bias, &c.gyro_bias_std),
            parameter_lines(&c.parameters, c.intrinsics.model),
            c.chi2_per_dof(),
            c.iterations
        ),
        Calibration::MultiPose(c) => format!(
            "multi-position calibration: {} still intervals; model {:?} ({})\n{}{}",
            c.intervals.len(),
            c.model,
            c.reason,
            gyro_line(&c.gyro_bias, &c.gyro_bias_std),
            acc_line(&c.acc_bias, &c.acc_bias_std)
        ),
        Calibration::Static {
            c,
            used,
            still_s,
            body_roll_pitch,
            earth,
        } => format!(
            "static calibration (one attitude) on the longest still interval, {:.1} s from {} to \
             {} ns ({:.1} s still of {:.1} s recorded):\n{}  roll {:.4}° ± {:.1e}°, pitch \
             {:.4}° ± {:.1e}° (IMU axes){}\n  b_a: not estimated ({})\n{}",
            c.duration_s,
            used.t_start_ns,
            used.t_end_ns,
            still_s.0,
            still_s.1,
            gyro_line(&c.gyro_bias, &c.gyro_bias_std),
            c.roll.to_degrees(),
            c.roll_std.to_degrees(),
            c.pitch.to_degrees(),
            c.pitch_std.to_degrees(),
            body_roll_pitch.map_or(String::new(), |(r, p)| format!(
                "; body roll {:.4}°, pitch {:.4}°",
                r.to_degrees(),
                p.to_degrees()
            )),
            c.acc_bias_note,
            earth
                .as_ref()
                .map(|e| format!("  Earth rate at {}°: {}\n", e.latitude_deg, earth_note(e)))
                .unwrap_or_default()
        ),
    }
}

/// Runs `preint calibrate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let (c, (source, units)) = compute(args)?;
    let (mut human, mut json) = (units.text() + &to_text(&c), to_json(&c));
    json["input"] = crate::imu_args::input_json(&source, &units);

    if let Some(path) = &args.out {
        let (intrinsics, td, from) = match &c {
            Calibration::MultiPose(m) => (
                calibration_file::intrinsics_of_multi_pose(m)?,
                None,
                " from the chosen model",
            ),
            Calibration::KnownPoses { c, time_offset, .. } => (
                c.intrinsics,
                time_offset.then_some(c.time_offset_s),
                " as estimated (withheld parameters at their initial value)",
            ),
            Calibration::KnownAttitudes { c, time_offset, .. } => (
                c.intrinsics,
                time_offset.then_some(c.time_offset_s),
                " as estimated (withheld parameters at their initial value)",
            ),
            Calibration::Static { .. } => (
                ImuIntrinsics::identity(IntrinsicsModel::Kalibr),
                None,
                " identity: this problem does not estimate them",
            ),
        };
        let noise = noise::or_default(args.noise.as_deref())?;
        calibration_file::write(path, intrinsics, &noise, td)?;
        human.push_str(&format!(
            "calibration written to {} (OpenVINS kalibr_imu_chain.yaml: intrinsics{from}{}, \
             noise densities)\n",
            path.display(),
            if td.is_some() { ", time offset" } else { "" }
        ));
        json["out"] = json!(path.display().to_string());
    }
    Ok(Output { human, json })
}
