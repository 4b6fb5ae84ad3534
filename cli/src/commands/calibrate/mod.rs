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
//!
//! # Goodness of fit
//! Every estimate is printed with its fit ([`preint_calib::fit`]; JSON `fit`): the problem's
//! χ² against `χ²_dof`, credible or not and why. What the χ² is, per problem:
//! - known poses / attitudes: the whitened preintegration residuals of every window, the time
//!   offset and intrinsics included (`9(P − 1)` resp. `3(P − 1)` rows less the unknowns);
//! - multi-position: the whitened interval means and link rotations of the chosen model;
//! - static: the per-sample problem, the means' χ² plus the samples' scatter about them
//!   ([`preint_calib::bias::StaticCalibration::fit`]), which tests the noise densities.
//!
//! Not credible: a `warning:` line naming the likely cause (JSON `fit.why`). For known poses
//! the usual convention errors of a pose file are tried and the one that explains the misfit
//! is named ([`preint_calib::bias::known_poses::conventions`]). Every σ is printed as
//! modelled (from the noise densities and pose noise) and scaled by `√(χ²/dof)` (JSON `*_std`
//! and `*_std_scaled`): use the modelled σ when the fit is credible and the noise model
//! trusted, the scaled σ when the noise level itself is uncertain (a credible fit with χ²/dof
//! away from 1); with a fit that is not credible neither describes the error. `--strict` makes
//! a fit that is not credible a refusal (exit 2, after the output).
//!
//! # Scheme
//! `--scheme` (default midpoint) is the scheme the known-pose windows are preintegrated with:
//! the estimated time offset absorbs the scheme's own lag (euler and galilean hold each
//! interval's first sample, half a sample interval behind midpoint and hermite4), so estimate
//! with the scheme that will use the result. `--out` records it (`preint_scheme`).

mod known;
mod print;

pub use print::{to_json, to_text};

use crate::fit::strict;
use crate::imu_args::ImuArgs;
use crate::scheme::SchemeParser;
use crate::{CliError, Output};
use nalgebra::Vector3;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::{ImuNoise, ImuSample};
use preint_analysis::checks::UnitCheck;
use preint_analysis::{calibration_file, checks, noise, stream};
use preint_calib::Fit;
use preint_calib::bias::known_poses::KnownAttitudeCalibration;
use preint_calib::bias::known_poses::extras::Estimate;
use preint_calib::bias::{
    KnownPoseCalibration, MultiPoseCalibration, MultiPoseOptions, StaticCalibration, StaticOptions,
    StillInterval, StillOptions, calibrate_multi_pose, calibrate_static, detect_still_intervals,
    roll_pitch_of_up,
};
use preint_io::SourceInfo;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Flags of `preint calibrate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Known poses for the known-pose problem: EuRoC ground truth (17 columns),
    /// `t,x,y,z,qw,qx,qy,qz` (8) or attitudes only `t,qw,qx,qy,qz` (5: a gyroscope-only
    /// calibration); t in ns, quaternion body→world.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Known-pose problem: parameters estimated beside the biases, comma-separated, from
    /// time-offset, gyro-intrinsics, g-sensitivity, accel-intrinsics (OpenVINS' kalibr model:
    /// Tw and R_IMUtoGYRO, Tg, Ta). Each is printed with its σ, or withheld (not applied, not
    /// written) when the motion does not excite it.
    #[arg(long, value_name = "LIST", requires = "poses", value_parser = parse_estimate)]
    pub estimate: Option<Estimate>,
    /// Known-pose problem: spacing of the poses used, in s.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.5,
        requires = "poses",
        allow_hyphen_values = true
    )]
    pub pose_spacing: f64,
    /// Known-pose problem: a calibration file (as --out writes) whose intrinsics and time
    /// offset are applied, and are the starting point of those --estimate asks for.
    #[arg(long, value_name = "FILE", requires = "poses")]
    pub calibration: Option<PathBuf>,
    /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(long)]
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G (m/s^2, up to 100).
    #[arg(
        long,
        default_value_t = 9.81,
        value_parser = preint_analysis::parse::gravity,
        allow_hyphen_values = true
    )]
    pub gravity: f64,
    /// Use only samples (and poses) with timestamps >= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Use only samples (and poses) with timestamps <= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// Known-pose problem: standard deviation of the given attitudes in rad (0: exact).
    /// E.g. 1.75e-3 (0.1°) and --pose-pos-std 0.005 for motion capture such as EuRoC's.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub pose_rot_std: f64,
    /// Known-pose problem: standard deviation of the given positions in m (0: exact).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub pose_pos_std: f64,
    /// Pose of the IMU in the body frame, x,y,z,qw,qx,qy,qz (m; quaternion rotating sensor
    /// vectors into the body frame). Known-pose problem: the poses are the body's and the
    /// preintegration removes the lever arm. Static problem: roll and pitch are also given for
    /// the body. Biases are always the IMU's, in its own axes.
    #[arg(long, value_parser = preint_analysis::parse::sensor_pose, allow_hyphen_values = true)]
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
    /// Known-pose problem: the scheme the windows are preintegrated with, which should be the
    /// one that will use the result (euler, midpoint, hermite4 or galilean): the time offset
    /// absorbs its lag (euler and galilean are half a sample behind midpoint and hermite4).
    /// Recorded in --out's file (preint_scheme).
    #[arg(long, value_parser = SchemeParser, default_value = "midpoint", requires = "poses")]
    pub scheme: crate::scheme::Scheme,
    /// Exit with status 2 (after printing the result) when the fit is not credible: χ² far
    /// above its distribution (χ²/dof > 3 for dof ≥ 30, else p < 1e-6; see the module docs
    /// for what the χ² of each problem is).
    #[arg(long)]
    pub strict: bool,
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

/// A calibration, its goodness of fit and what the user must know about it.
#[derive(Clone, Debug)]
pub struct Calibrated {
    /// The problem solved and its estimates.
    pub calibration: Calibration,
    /// Its goodness of fit (with the likely cause in `why` when not credible).
    pub fit: Fit,
    /// Lines to print after the estimates, each starting with `warning:` or `note:` (the
    /// calibration file's scheme, a gravity estimate upside down).
    pub notes: Vec<String>,
    /// The scheme of the known-pose windows (`--scheme`).
    pub scheme: preint::Scheme,
}

impl Calibration {
    /// The problem's name in a sentence (`known-pose calibration`, …).
    pub fn problem(&self) -> &'static str {
        match self {
            Calibration::KnownPoses { .. } => "known-pose calibration",
            Calibration::KnownAttitudes { .. } => "known-attitude calibration",
            Calibration::MultiPose(_) => "multi-position calibration",
            Calibration::Static { .. } => "static calibration",
        }
    }
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
    Ok(stream::read_span(
        &args.input.to_input(),
        args.from,
        args.to,
        "calibrate",
    )?)
}

/// `--estimate`'s list.
fn parse_estimate(list: &str) -> Result<Estimate, String> {
    Estimate::parse(list)
}

/// Chooses the problem (module docs), solves it and tests its fit.
pub fn compute(args: &Args) -> Result<(Calibrated, (SourceInfo, UnitCheck)), CliError> {
    checks::window_order(args.from, args.to)?;
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
fn solve(args: &Args, samples: Vec<ImuSample>, noise: ImuNoise) -> Result<Calibrated, CliError> {
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
        return known::known_poses(args, pfile, &samples, &noise);
    }
    let input = args.input.to_input();
    let fail = fail_in(input.path());
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
        let fit = c.fit().because(
            "the noise densities (--noise) are too small for this sensor, the biases drift more \
             than their random walk (temperature), or the sensor has terms the chosen model \
             lacks",
        );
        return Ok(Calibrated {
            calibration: Calibration::MultiPose(Box::new(c)),
            fit,
            notes: Vec::new(),
            scheme: args.scheme.into(),
        });
    }
    let Some(used) = still.iter().max_by_key(|iv| iv.len()).copied() else {
        return Err(CliError::Failed(format!(
            "{}: no still interval (≥ {} s with gyro and accelerometer variances within 4× the \
             noise densities' white noise): a static calibration needs the sensor at rest. Give \
             --poses for a moving recording, or check --noise",
            input.label(),
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
    let fit = c.fit(&noise).because(&format!(
        "the samples scatter more than the noise densities say (measured white-noise densities \
         gyro {:.2e} rad/s/√Hz against {:.2e}, accelerometer {:.2e} m/s²/√Hz against {:.2e}): \
         give this sensor's densities with --noise (preint allan), or the interval is not still",
        c.measured_gyro_density.max(),
        noise.gyro_noise_density,
        c.measured_acc_density.max(),
        noise.acc_noise_density
    ));
    Ok(Calibrated {
        calibration: Calibration::Static {
            c: Box::new(c),
            used,
            still_s: (still_s, total_s),
            body_roll_pitch,
            earth,
        },
        fit,
        notes: Vec::new(),
        scheme: args.scheme.into(),
    })
}

/// Runs `preint calibrate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let (r, (source, units)) = compute(args)?;
    let (mut human, mut json) = (
        preint_analysis::recording::input_text(&source, &units) + &to_text(&r),
        to_json(&r),
    );
    json["input"] = preint_analysis::recording::input_json(&source, &units);
    if let Some(path) = &args.out {
        let (intrinsics, td, from) = match &r.calibration {
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
        // The scheme matters for what the windows estimated: the known-pose problem's.
        let scheme = matches!(
            r.calibration,
            Calibration::KnownPoses { .. } | Calibration::KnownAttitudes { .. }
        )
        .then_some(r.scheme);
        calibration_file::write(path, intrinsics, &noise, td, scheme)?;
        human.push_str(&format!(
            "calibration written to {} (OpenVINS kalibr_imu_chain.yaml: intrinsics{from}{}{}, \
             noise densities)\n",
            path.display(),
            if td.is_some() { ", time offset" } else { "" },
            scheme.map_or(String::new(), |s| format!(
                " for the {} scheme",
                crate::scheme::label(s)
            ))
        ));
        json["out"] = json!(path.display().to_string());
    }
    strict(
        args.strict,
        Output { human, json },
        &r.fit,
        r.calibration.problem(),
    )
}
