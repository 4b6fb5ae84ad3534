//! The flags every preintegrating subcommand shares: scheme, noise densities, gravity, sensor
//! pose, bias correction.

use crate::CliError;
use crate::scheme::{Scheme, SchemeParser};
use nalgebra::Vector3;
use preint::{ImuNoise, Level, PreintParams};
use preint_analysis::{checks, noise};
use std::path::PathBuf;

/// Scheme, noise file and gravity of a preintegration.
#[derive(clap::Args, Clone, Debug)]
pub struct PreintArgs {
    /// Integration scheme: the registry's (`crate::scheme::flag_help`).
    #[arg(
        help_heading = "Preintegration",
        long,
        value_parser = SchemeParser,
        default_value = "midpoint",
        help = crate::scheme::flag_help()
    )]
    pub scheme: Scheme,
    /// Kalibr imu.yaml with the noise densities (default: EuRoC figures).
    #[arg(help_heading = "Preintegration", long)]
    pub noise: Option<PathBuf>,
    /// Gravity magnitude G (m/s^2, from 0 to 100); gravity is (0, 0, -G).
    #[arg(help_heading = "Preintegration", long, default_value_t = 9.81, value_parser = preint_analysis::parse::gravity, allow_hyphen_values = true)]
    pub gravity: f64,
    /// Gravity as a world-frame vector x,y,z (m/s^2, norm at most 100), for a world frame not
    /// levelled with gravity (a motion-capture frame; `calibrate --estimate noise` prints the
    /// vector that fits as gravity.vector). Replaces (0, 0, -G) of --gravity.
    #[arg(help_heading = "Preintegration", long, value_name = "X,Y,Z", value_parser = preint_analysis::parse::gravity_vector, allow_hyphen_values = true)]
    pub gravity_vector: Option<Vector3<f64>>,
    /// Pose of the IMU in the body frame, x,y,z,qw,qx,qy,qz: sensor origin in body coordinates
    /// (m) and the unit quaternion rotating sensor vectors into the body frame. The output is
    /// then the body's motion (lever arm and rotation removed exactly); biases stay the IMU's.
    #[arg(help_heading = "Preintegration", long, value_parser = preint_analysis::parse::sensor_pose, allow_hyphen_values = true)]
    pub body_p_sensor: Option<preint::SensorPose>,
    /// How the lever arm of --body-p-sensor is removed: exact (closed form from the window's
    /// end rates, whatever the angular acceleration) or centripetal (GTSAM's per-sample
    /// ω×(ω×r), exact only at a constant rate; for GTSAM's numbers).
    #[arg(help_heading = "Preintegration", long, value_parser = parse_lever_arm, default_value = preint::LeverArm::default().name())]
    pub lever_arm: preint::LeverArm,
    /// How the deltas are corrected for a bias change (prediction and factors): additive
    /// (Forster eq. 44, GTSAM's Manifold/Tangent backends) or group (right-applied on the
    /// group, GTSAM's Galilean backend). Default: group for galilean, additive otherwise.
    #[arg(help_heading = "Preintegration", long, value_parser = parse_bias_correction)]
    pub bias_correction: Option<preint::BiasCorrection>,
}

fn parse_bias_correction(s: &str) -> Result<preint::BiasCorrection, String> {
    preint::BiasCorrection::parse(s)
        .ok_or_else(|| format!("unknown bias correction {s:?}: use additive or group"))
}

fn parse_lever_arm(s: &str) -> Result<preint::LeverArm, String> {
    preint::LeverArm::parse(s)
        .ok_or_else(|| format!("unknown lever-arm model {s:?}: use exact or centripetal"))
}

impl PreintArgs {
    /// The noise densities (from the file, or the EuRoC figures) and the preintegration
    /// parameters at `level`, after checking `--gravity` (set by other means than the flag).
    pub fn params(&self, level: Level) -> Result<(ImuNoise, PreintParams), CliError> {
        checks::gravity("--gravity", self.gravity)?;
        let noise = noise::or_default(self.noise.as_deref())?;
        let params = PreintParams::from_noise(&noise)
            .with_scheme(self.scheme)
            .with_level(level)
            .with_gravity(
                self.gravity_vector
                    .unwrap_or(Vector3::new(0.0, 0.0, -self.gravity)),
            );
        let params = PreintParams {
            body_p_sensor: self.body_p_sensor,
            lever_arm: self.lever_arm,
            bias_correction: self.bias_correction,
            ..params
        };
        Ok((noise, params))
    }

    /// Where the noise densities came from (the file, or the defaults).
    pub fn noise_source(&self) -> String {
        noise::source(self.noise.as_deref())
    }
}
