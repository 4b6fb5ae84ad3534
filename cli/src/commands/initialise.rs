//! `preint initialise`: gravity, scale, keyframe velocities and biases from a front end's
//! keyframe poses ([`preint_analysis::initialise`]), with the readiness verdict. A window that
//! is not ready is a result (exit 0, `ready: false`), not an error.

use crate::imu_args::ImuArgs;
use crate::scheme::SchemeParser;
use crate::{CliError, Output};
use preint_analysis::initialise::{Initialised, Options, compute, to_json};
use preint_calib::init::ScaleMode;
use std::fmt::Write;
use std::path::PathBuf;

/// Whether the poses' positions are metric.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Known up to scale (a monocular front end): the scale is estimated.
    Unknown,
    /// Metric positions.
    Known,
}

/// Flags of `preint initialise`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Keyframe poses of the front end: EuRoC ground truth (17 columns) or
    /// `t,x,y,z,qw,qx,qy,qz` (t in ns, quaternion frame→world, positions in the poses' own
    /// unit).
    #[arg(help_heading = "Known poses", long)]
    pub poses: PathBuf,
    /// Whether the positions are metric (known) or known up to scale (unknown: the scale is
    /// estimated, in metres per unit of the poses).
    #[arg(
        help_heading = "Known poses",
        long,
        value_enum,
        default_value = "unknown"
    )]
    pub scale: Scale,
    /// Spacing of the keyframes used, in s.
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "S",
        default_value_t = 0.1,
        allow_hyphen_values = true
    )]
    pub pose_spacing: f64,
    /// Standard deviation of the keyframe attitudes in rad (0: exact).
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "RAD",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub pose_rot_std: f64,
    /// Standard deviation of the keyframe positions, in the poses' unit (0: exact).
    #[arg(
        help_heading = "Known poses",
        long,
        value_name = "UNIT",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub pose_pos_std: f64,
    /// Pose of the IMU in the frame of the poses, x,y,z,qw,qx,qy,qz (m; quaternion rotating
    /// IMU vectors into that frame), as `calibrate --estimate extrinsic-rotation,lever-arm`
    /// prints it.
    #[arg(help_heading = "Sensor model", long, value_parser = preint_analysis::parse::sensor_pose, allow_hyphen_values = true)]
    pub body_p_sensor: Option<preint::SensorPose>,
    /// Prior standard deviations of the biases, gyro (rad/s) and accelerometer (m/s^2), zero
    /// mean: the maximum-a-posteriori refinement's prior.
    #[arg(
        help_heading = "Sensor model",
        long,
        value_name = "RAD/S,M/S2",
        default_value = "0.05,0.2",
        value_parser = two_numbers,
        allow_hyphen_values = true
    )]
    pub bias_prior_std: (f64, f64),
    /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(help_heading = "Sensor model", long)]
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G (m/s^2, up to 100).
    #[arg(help_heading = "Sensor model", long, default_value_t = 9.81, value_parser = preint_analysis::parse::gravity, allow_hyphen_values = true)]
    pub gravity: f64,
    /// Use only samples (and keyframes) with timestamps >= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Use only samples (and keyframes) with timestamps <= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// The scheme the windows between keyframes are preintegrated with.
    #[arg(help_heading = "Known poses", long, value_parser = SchemeParser, default_value = "midpoint")]
    pub scheme: crate::scheme::Scheme,
}

impl Args {
    /// What the library computes on.
    pub fn options(&self) -> Options {
        Options {
            input: self.input.to_input(),
            poses: self.poses.clone(),
            scale: match self.scale {
                Scale::Unknown => ScaleMode::Unknown,
                Scale::Known => ScaleMode::Known,
            },
            pose_spacing: self.pose_spacing,
            noise: self.noise.clone(),
            gravity: self.gravity,
            from: self.from,
            to: self.to,
            pose_rot_std: self.pose_rot_std,
            pose_pos_std: self.pose_pos_std,
            body_p_sensor: self.body_p_sensor,
            bias_prior_std: self.bias_prior_std,
            scheme: self.scheme,
        }
    }
}

/// Two comma-separated numbers (`--bias-prior-std`).
fn two_numbers(s: &str) -> Result<(f64, f64), String> {
    let [g, a] = preint_analysis::parse::numbers::<2>(
        s,
        "two comma-separated numbers, gyro (rad/s) and accelerometer (m/s^2)",
    )?;
    Ok((g, a))
}

/// The text form.
pub fn to_text(r: &Initialised) -> String {
    let i = &r.init;
    let mut s = String::new();
    let v =
        |x: &nalgebra::Vector3<f64>, p: usize| format!("[{:.p$}, {:.p$}, {:.p$}]", x.x, x.y, x.z);
    let _ = writeln!(
        s,
        "initialisation from {} keyframes over {:.2} s of {}",
        i.keyframes, i.window_s, r.poses
    );
    if r.scale == ScaleMode::Unknown {
        let _ = writeln!(
            s,
            "scale       {:.6} ± {:.6} m per unit of the poses ({:.2} %)",
            i.scale,
            i.scale_std,
            100.0 * i.scale_std / i.scale
        );
    } else {
        let _ = writeln!(s, "scale       1 (metric poses)");
    }
    let _ = writeln!(
        s,
        "gravity     {} ± {} m/s², world frame of the poses (direction σ {:.3}°)",
        v(&i.gravity, 4),
        v(&i.gravity_std, 4),
        i.gravity_dir_std_rad.to_degrees()
    );
    let _ = writeln!(
        s,
        "bias_gyro   {} ± {} rad/s",
        v(&i.bias.gyro, 5),
        v(&i.gyro_bias_std, 5)
    );
    let _ = writeln!(
        s,
        "bias_acc    {} ± {} m/s²",
        v(&i.bias.acc, 4),
        v(&i.acc_bias_std, 4)
    );
    if let (Some((t, v0)), Some(sd)) = (i.velocities.first(), i.velocity_std.first()) {
        let _ = writeln!(
            s,
            "velocity at the first keyframe (t {t} ns) {} ± {} m/s, world (all in the JSON)",
            v(v0, 4),
            v(sd, 4)
        );
    }
    let _ = writeln!(
        s,
        "linear start: scale {:.6}, gravity {} m/s²",
        i.linear.scale,
        v(&i.linear.gravity, 4)
    );
    let _ = writeln!(
        s,
        "fit: χ²/dof {:.3} (dof {}); σ above multiplied by {:.3}",
        i.fit.chi2_dof, i.fit.dof, i.std_factor
    );
    let _ = writeln!(s, "{}", i.reason);
    s
}

/// Runs `preint initialise`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(&args.options())?;
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}
