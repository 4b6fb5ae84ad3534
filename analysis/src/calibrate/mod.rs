//! `preint calibrate`'s numbers: bias estimation with Gauss-Newton, modelling only what the
//! data makes observable, its goodness of fit, the calibration file of `out` and the JSON.
//!
//! Model choice:
//! - `poses` (`--poses FILE`: EuRoC ground truth, `t,p,q` or attitudes only `t,q`;
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
//! a fit that is not credible a refusal (exit 2, after the output) on the command line.
//!
//! # Scheme
//! `--scheme` (default midpoint) is the scheme the known-pose windows are preintegrated with:
//! the estimated time offset absorbs the scheme's own lag (euler and galilean hold each
//! interval's first sample, half a sample interval behind midpoint and hermite4), so estimate
//! with the scheme that will use the result. `--out` records it (`preint_scheme`).

mod json;
mod known;
pub mod noise_correlation;
pub mod noise_model;

pub use json::{EXTRINSIC_TANGENT, calibrated_json, earth_note, to_json};
pub(crate) use known::poses_in_span;

use crate::checks::UnitCheck;
use crate::{Error, ImuInput, calibration_file, checks, noise, stream};
use nalgebra::Vector3;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::{ImuNoise, ImuSample};
use preint_calib::Fit;
use preint_calib::bias::known_poses::KnownAttitudeCalibration;
use preint_calib::bias::known_poses::extras::Estimate;
use preint_calib::bias::{
    KnownPoseCalibration, MultiPoseCalibration, MultiPoseOptions, StaticCalibration, StaticOptions,
    StillInterval, StillOptions, calibrate_multi_pose, calibrate_static, detect_still_intervals,
    roll_pitch_of_up,
};
use preint_io::SourceInfo;
use std::path::{Path, PathBuf};

/// What `calibrate` runs on (the flags of `preint calibrate` but `--strict`; each field is the
/// flag of the same name, whose help says what it does).
#[derive(Clone, Debug)]
pub struct Options {
    /// The recording and how to read it.
    pub input: ImuInput,
    /// Known poses (`--poses`): EuRoC ground truth, `t,x,y,z,qw,qx,qy,qz` or attitudes only
    /// `t,qw,qx,qy,qz`; t in ns, quaternion body→world.
    pub poses: Option<PathBuf>,
    /// Known-pose problem: parameters estimated beside the biases (`--estimate`).
    pub estimate: Option<Estimate>,
    /// Known-pose problem: spacing of the poses used \[s\] (`--pose-spacing`).
    pub pose_spacing: f64,
    /// Known-pose problem: a calibration file applied, and the starting point of what
    /// `estimate` asks for (`--calibration`).
    pub calibration: Option<PathBuf>,
    /// Kalibr imu.yaml with the noise densities (`--noise`; default: EuRoC figures).
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G \[m/s²\] (`--gravity`).
    pub gravity: f64,
    /// Use only samples (and poses) with timestamps ≥ this \[ns\] (`--from`).
    pub from: Option<i64>,
    /// Use only samples (and poses) with timestamps ≤ this \[ns\] (`--to`).
    pub to: Option<i64>,
    /// Known-pose problem: standard deviation of the given attitudes \[rad\] (`--pose-rot-std`).
    pub pose_rot_std: f64,
    /// Known-pose problem: standard deviation of the given positions \[m\] (`--pose-pos-std`).
    pub pose_pos_std: f64,
    /// Pose of the IMU in the body frame (`--body-p-sensor`).
    pub body_p_sensor: Option<preint::SensorPose>,
    /// Latitude \[deg\] of a static recording (`--latitude`).
    pub latitude: Option<f64>,
    /// Heading of the body x axis \[deg, clockwise from north\] (`--heading`, with `latitude`).
    pub heading: Option<f64>,
    /// Where to write the calibration as OpenVINS' kalibr_imu_chain.yaml (`--out`).
    pub out: Option<PathBuf>,
    /// Known-pose problem: the scheme the windows are preintegrated with (`--scheme`).
    pub scheme: preint::Scheme,
}

/// `--estimate`'s list: the known-pose problem's parameters, or `noise` alone (the noise
/// model of [`noise_model`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct EstimateList {
    /// The known-pose problem's parameters.
    pub extras: Estimate,
    /// The noise model (`noise`).
    pub noise: bool,
}

impl EstimateList {
    /// Parses a comma-separated list of [`Estimate`]'s names, or `noise` alone.
    pub fn parse(list: &str) -> Result<EstimateList, String> {
        let names: Vec<&str> = list.split(',').map(str::trim).collect();
        let noise = names.contains(&"noise");
        let rest: Vec<&str> = names.into_iter().filter(|n| *n != "noise").collect();
        let extras = Estimate::parse(&rest.join(",")).map_err(|e| format!("{e} or noise"))?;
        if noise && extras.any() {
            return Err(format!(
                "`noise` is estimated on its own (a fit of the noise model at the ground truth, \
                 not the known-pose problem): give --estimate noise, or --estimate {}",
                rest.join(",")
            ));
        }
        Ok(EstimateList { extras, noise })
    }
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
fn fail_in(imu: &Path) -> impl Fn(preint_calib::bias::BiasError) -> Error + '_ {
    move |e| Error::failed_in(imu, e)
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
/// [`preint::DEFAULT_MAX_GAP_NS`]).
pub const MAX_GAP_S: f64 = preint::DEFAULT_MAX_GAP_NS as f64 * 1e-9;

/// The calibration file written to `out` (OpenVINS kalibr_imu_chain.yaml).
#[derive(Clone, Debug)]
pub struct Written {
    /// Its path.
    pub path: PathBuf,
    /// Where its intrinsics come from, as printed after `intrinsics` (e.g. ` from the chosen
    /// model`).
    pub intrinsics_from: &'static str,
    /// Whether it holds a time offset.
    pub time_offset: bool,
    /// The scheme it records (`preint_scheme`): the known-pose problem's.
    pub scheme: Option<preint::Scheme>,
    /// Kalibr's `camchain-imucam.yaml` written beside it (`<stem>-camchain-imucam.yaml`), when
    /// the known-pose problem estimated or was given the IMU's pose in the frame of the poses.
    pub camchain: Option<PathBuf>,
}

/// A calibration, how its recording was read, and the file written.
#[derive(Clone, Debug)]
pub struct CalibrateRun {
    /// The calibration and its fit.
    pub calibrated: Calibrated,
    /// How the recording was read.
    pub source: SourceInfo,
    /// What the unit checks said.
    pub unit_check: UnitCheck,
    /// The file written to `out`, when given.
    pub written: Option<Written>,
}

/// Reads the recording, chooses the problem (module docs), solves it, tests its fit and, with
/// `out`, writes the calibration file.
pub fn compute(o: &Options) -> Result<CalibrateRun, Error> {
    let (calibrated, (source, unit_check, noise)) = calibrate(o)?;
    let written = match &o.out {
        Some(path) => Some(write(path, &calibrated, &noise)?),
        None => None,
    };
    Ok(CalibrateRun {
        calibrated,
        source,
        unit_check,
        written,
    })
}

/// Writes `r` to `path` as OpenVINS' kalibr_imu_chain.yaml: the intrinsics of the problem's
/// estimate (the identity where it has none), the time offset when estimated or given, the
/// noise densities, the known-pose problem's scheme and, when estimated or given, the IMU's
/// pose in the frame of the poses (also as Kalibr's `camchain-imucam.yaml` beside it).
fn write(path: &Path, r: &Calibrated, noise: &ImuNoise) -> Result<Written, Error> {
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
    // The scheme matters for what the windows estimated: the known-pose problem's.
    let scheme = matches!(
        r.calibration,
        Calibration::KnownPoses { .. } | Calibration::KnownAttitudes { .. }
    )
    .then_some(r.scheme);
    let extrinsic = match &r.calibration {
        Calibration::KnownPoses { c, .. } => c.extrinsic.map(|e| e.body_p_sensor),
        _ => None,
    };
    calibration_file::write(path, intrinsics, noise, (td, scheme), extrinsic)?;
    let camchain = match extrinsic {
        Some(x) => {
            let stem = path.file_stem().unwrap_or_default().to_string_lossy();
            let cc = path.with_file_name(format!("{stem}-camchain-imucam.yaml"));
            preint_io::extrinsics::write_kalibr_camchain(&cc, &x, td.unwrap_or(0.0))?;
            Some(cc)
        }
        None => None,
    };
    Ok(Written {
        path: path.to_path_buf(),
        intrinsics_from: from,
        time_offset: td.is_some(),
        scheme,
        camchain,
    })
}

/// Chooses the problem (module docs), solves it and tests its fit.
fn calibrate(args: &Options) -> Result<(Calibrated, (SourceInfo, UnitCheck, ImuNoise)), Error> {
    checks::window_order(args.from, args.to)?;
    checks::non_negative("--pose-rot-std", args.pose_rot_std)?;
    checks::non_negative("--pose-pos-std", args.pose_pos_std)?;
    checks::positive("--gravity", args.gravity)?;
    checks::gravity("--gravity", args.gravity)?;
    let noise = noise::or_default(args.noise.as_deref())?;
    let span = stream::read_span(&args.input, args.from, args.to, "calibrate")?;
    let c = solve(args, span.samples, noise)?;
    Ok((c, (span.source, span.unit_check, noise)))
}

/// [`compute`] on the samples read.
fn solve(args: &Options, samples: Vec<ImuSample>, noise: ImuNoise) -> Result<Calibrated, Error> {
    if let Some(h) = args.heading
        && !h.is_finite()
    {
        return Err(Error::Usage(format!(
            "--heading {h} is not a finite angle in degrees"
        )));
    }
    let earth_refused = |model: &str| {
        Error::Usage(format!(
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
        let fit = c.fit().because(
            "the noise densities (--noise) are too small for this sensor, the biases drift more \
             than their random walk (temperature), or the sensor has terms the chosen model \
             lacks",
        );
        return Ok(Calibrated {
            calibration: Calibration::MultiPose(Box::new(c)),
            fit,
            notes: Vec::new(),
            scheme: args.scheme,
        });
    }
    static_problem(args, &samples, &noise, &still, rate)
}

/// The single-attitude static problem on the longest of the still intervals `still` of
/// `samples` (recorded at `rate` Hz), with its fit; the Earth rate of `--latitude` removed.
fn static_problem(
    args: &Options,
    samples: &[ImuSample],
    noise: &ImuNoise,
    still: &[StillInterval],
    rate: f64,
) -> Result<Calibrated, Error> {
    let fail = fail_in(args.input.path());
    let g = Vector3::new(0.0, 0.0, -args.gravity);
    let n = samples.len();
    let Some(used) = still.iter().max_by_key(|iv| iv.len()).copied() else {
        return Err(Error::Failed(format!(
            "{}: no still interval (≥ {} s with gyro and accelerometer variances within 4× the \
             noise densities' white noise): a static calibration needs the sensor at rest. Give \
             --poses for a moving recording, or check --noise",
            args.input.label(),
            StillOptions::from_noise(noise, rate).min_duration_s
        )));
    };
    let opts = StaticOptions {
        gravity: g,
        ..Default::default()
    };
    let mut c = calibrate_static(&samples[used.start..used.end], noise, &opts).map_err(&fail)?;
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
    let fit = c.fit(noise).because(&format!(
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
        scheme: args.scheme,
    })
}
