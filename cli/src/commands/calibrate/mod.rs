//! `preint calibrate`: bias estimation with Gauss-Newton, modelling only what the data makes
//! observable (the problems, their fits and the calibration file of `--out`:
//! [`preint_analysis::calibrate`]); `--strict` makes a fit that is not credible a refusal
//! (exit 2, after the output).

mod noise;
mod text;

pub use text::to_text;

use crate::fit::strict;
use crate::imu_args::ImuArgs;
use crate::scheme::SchemeParser;
use crate::{CliError, Output};
use preint_analysis::calibrate::{EstimateList, Options};
use std::path::PathBuf;

/// Flags of `preint calibrate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Known poses for the known-pose problem: EuRoC ground truth (17 columns),
    /// `t,x,y,z,qw,qx,qy,qz` (8) or attitudes only `t,qw,qx,qy,qz` (5: a gyroscope-only
    /// calibration); t in ns, quaternion body→world.
    #[arg(help_heading = "Known poses", long)]
    pub poses: Option<PathBuf>,
    /// Known-pose problem: parameters estimated beside the biases, comma-separated, from
    /// time-offset, gyro-intrinsics, g-sensitivity, accel-intrinsics (OpenVINS' kalibr model:
    /// Tw and R_IMUtoGYRO, Tg, Ta), extrinsic-rotation and lever-arm (the IMU's pose in the
    /// frame of the poses, as --body-p-sensor takes it; started at the hand-eye rotation
    /// unless --body-p-sensor or --calibration gives one). Each is printed with its σ, or
    /// withheld (not applied, not written) when the motion does not excite it. `noise` (alone): the maximum-likelihood
    /// noise densities, bias random walks and the ground truth's own errors from ImuFactors
    /// over back-to-back windows (--window) between EuRoC ground-truth states (--poses).
    #[arg(help_heading = "Known poses", long, value_name = "LIST", requires = "poses", value_parser = EstimateList::parse)]
    pub estimate: Option<EstimateList>,
    /// `--estimate noise`: the window lengths (s, comma-separated; default 0.5,1,2,4),
    /// back-to-back windows of each; several lengths separate white noise, random walk and the
    /// ground truth's error.
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "S[,S…]",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub window: Option<Vec<f64>>,
    /// `--estimate noise`: the ground truth's velocity error in m/s, held (not fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M/S",
        allow_hyphen_values = true
    )]
    pub vel_std: Option<f64>,
    /// `--estimate noise`: the ground truth's gyroscope-bias error in rad/s, held (not fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "RAD/S",
        allow_hyphen_values = true
    )]
    pub bias_gyro_std: Option<f64>,
    /// `--estimate noise`: the ground truth's accelerometer-bias error in m/s², held (not
    /// fitted).
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M/S2",
        allow_hyphen_values = true
    )]
    pub bias_acc_std: Option<f64>,
    /// Known-pose problem: spacing of the poses used, in s.
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "S",
        default_value_t = 0.5,
        requires = "poses",
        allow_hyphen_values = true
    )]
    pub pose_spacing: f64,
    /// Known-pose problem: a calibration file (as --out writes) whose intrinsics and time
    /// offset are applied, and are the starting point of those --estimate asks for.
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "FILE",
        requires = "poses"
    )]
    pub calibration: Option<PathBuf>,
    /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(help_heading = "Sensor model", long)]
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G (m/s^2, up to 100).
    #[arg(
        help_heading = "Sensor model",
        long,
        default_value_t = 9.81,
        value_parser = preint_analysis::parse::gravity,
        allow_hyphen_values = true
    )]
    pub gravity: f64,
    /// Use only samples (and poses) with timestamps >= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Use only samples (and poses) with timestamps <= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// Known-pose problem: standard deviation of the given attitudes in rad (default 0:
    /// exact). E.g. 1.75e-3 (0.1°) and --pose-pos-std 0.005 for motion capture such as
    /// EuRoC's. With `--estimate noise`: held at this value (else fitted).
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "RAD",
        allow_hyphen_values = true
    )]
    pub pose_rot_std: Option<f64>,
    /// Known-pose problem: standard deviation of the given positions in m (default 0: exact).
    /// With `--estimate noise`: held at this value (else fitted).
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "M",
        allow_hyphen_values = true
    )]
    pub pose_pos_std: Option<f64>,
    /// Pose of the IMU in the body frame, x,y,z,qw,qx,qy,qz (m; quaternion rotating sensor
    /// vectors into the body frame). Known-pose problem: the poses are the body's and the
    /// preintegration removes the lever arm; with --estimate it is applied to the poses and is
    /// the start of extrinsic-rotation and lever-arm. Static problem: roll and pitch are also given for
    /// the body. Biases are always the IMU's, in its own axes.
    #[arg(help_heading = "Sensor model", long, value_parser = preint_analysis::parse::sensor_pose, allow_hyphen_values = true)]
    pub body_p_sensor: Option<preint::SensorPose>,
    /// Latitude (deg) of a static recording: the Earth rate's vertical part (Ω_E sin φ along
    /// up) is removed from the gyro bias; its horizontal part (Ω_E cos φ, direction unknown
    /// without --heading) is added to the bias σ. Single-attitude static model only.
    #[arg(help_heading = "Earth rotation", long, value_name = "DEG", allow_hyphen_values = true,
          value_parser = crate::earth_args::latitude)]
    pub latitude: Option<f64>,
    /// Heading of the body x axis (deg, clockwise from north): with --latitude, the whole
    /// Earth rate is removed from the gyro bias.
    #[arg(
        help_heading = "Earth rotation",
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        requires = "latitude"
    )]
    pub heading: Option<f64>,
    /// Write the calibration as OpenVINS' kalibr_imu_chain.yaml: the intrinsics (Tw,
    /// R_IMUtoGYRO, Ta, R_IMUtoACC, Tg; from the multi-position model BIC chose, or the
    /// known-pose estimate, else the identity), the time offset when estimated, the noise
    /// densities and the IMU's pose in the frame of the poses when estimated
    /// (preint_body_p_sensor; also as Kalibr's camchain-imucam.yaml, T_cam_imu and
    /// timeshift_cam_imu, in <stem>-camchain-imucam.yaml beside it). `integrate --calibration
    /// FILE` applies it.
    #[arg(help_heading = "Output", long, value_name = "FILE")]
    pub out: Option<std::path::PathBuf>,
    /// Known-pose problem: the scheme the windows are preintegrated with, which should be the
    /// one that will use the result (euler, midpoint, hermite4 or galilean): the time offset
    /// absorbs its lag (euler and galilean are half a sample behind midpoint and hermite4).
    /// Recorded in --out's file (preint_scheme).
    #[arg(help_heading = "Known poses", long, value_parser = SchemeParser, default_value = "midpoint", requires = "poses")]
    pub scheme: crate::scheme::Scheme,
    /// Exit with status 2 (after printing the result) when the fit is not credible: χ² far
    /// above its distribution (χ²/dof > 3 for dof ≥ 30, else p < 1e-6; see the module docs
    /// for what the χ² of each problem is).
    #[arg(help_heading = "Output", long)]
    pub strict: bool,
}

impl Args {
    /// What the library computes on.
    pub fn options(&self) -> Options {
        Options {
            input: self.input.to_input(),
            poses: self.poses.clone(),
            estimate: self.estimate.map(|e| e.extras),
            pose_spacing: self.pose_spacing,
            calibration: self.calibration.clone(),
            noise: self.noise.clone(),
            gravity: self.gravity,
            from: self.from,
            to: self.to,
            pose_rot_std: self.pose_rot_std.unwrap_or(0.0),
            pose_pos_std: self.pose_pos_std.unwrap_or(0.0),
            body_p_sensor: self.body_p_sensor,
            latitude: self.latitude,
            heading: self.heading,
            out: self.out.clone(),
            scheme: self.scheme,
        }
    }
}

/// Flags that only `--estimate noise` reads: refused without it.
fn check_noise_flags(args: &Args) -> Result<(), CliError> {
    let noise = args.estimate.is_some_and(|e| e.noise);
    let only = [
        ("--window", args.window.is_some()),
        ("--vel-std", args.vel_std.is_some()),
        ("--bias-gyro-std", args.bias_gyro_std.is_some()),
        ("--bias-acc-std", args.bias_acc_std.is_some()),
    ];
    for (flag, given) in only {
        if given && !noise {
            return Err(CliError::Usage(format!(
                "{flag} is read by --estimate noise only; give --poses GT --estimate noise, \
                 or leave it out"
            )));
        }
    }
    Ok(())
}

/// Runs `preint calibrate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    check_noise_flags(args)?;
    if args.estimate.is_some_and(|e| e.noise) {
        return noise::run(args);
    }
    let r = preint_analysis::calibrate::compute(&args.options())?;
    let output = Output {
        human: to_text(&r),
        json: preint_analysis::calibrate::to_json(&r),
    };
    let c = &r.calibrated;
    strict(args.strict, output, &c.fit, c.calibration.problem())
}
