//! Kalibr `imu.yaml`: the four continuous-time noise densities and the rate (see
//! [`ImuNoise`]).

use crate::error::{IoError, Location, read_text, write_text};
use crate::number::parse_finite;
use preint::ImuNoise;
use std::path::Path;

/// The Kalibr keys, in the order they are written.
const KALIBR_KEYS: [&str; 5] = [
    "gyroscope_noise_density",
    "gyroscope_random_walk",
    "accelerometer_noise_density",
    "accelerometer_random_walk",
    "update_rate",
];

/// Parses a Kalibr `imu.yaml` (flat `key: value` lines; `#` comments and unknown keys such as
/// `rostopic` are ignored). All five keys of `KALIBR_KEYS` are required; values must be finite
/// and non-negative (`update_rate` positive).
pub fn parse_kalibr_yaml(text: &str, source_name: &str) -> Result<ImuNoise, IoError> {
    let mut vals: [Option<f64>; 5] = [None; 5];
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some((k, v)) = line.split_once(':') else {
            continue;
        };
        let Some(idx) = KALIBR_KEYS.iter().position(|key| *key == k.trim()) else {
            continue;
        };
        let at = Location::Line(i as u64 + 1);
        let x = parse_finite(v.trim())
            .map_err(|m| IoError::parse(source_name, at, format!("{}: {m}", KALIBR_KEYS[idx])))?;
        if x < 0.0 || (idx == 4 && x == 0.0) {
            return Err(IoError::parse(
                source_name,
                at,
                format!("`{}` must be positive, got {x}", KALIBR_KEYS[idx]),
            ));
        }
        vals[idx] = Some(x);
    }
    let get = |i: usize| {
        vals[i].ok_or(IoError::MissingKey {
            source_name: source_name.to_string(),
            key: KALIBR_KEYS[i],
        })
    };
    Ok(ImuNoise {
        gyro_noise_density: get(0)?,
        gyro_random_walk: get(1)?,
        acc_noise_density: get(2)?,
        acc_random_walk: get(3)?,
        update_rate_hz: get(4)?,
    })
}

/// Reads a Kalibr `imu.yaml` (see [`parse_kalibr_yaml`]).
pub fn read_kalibr_yaml(path: &Path) -> Result<ImuNoise, IoError> {
    parse_kalibr_yaml(&read_text(path)?, &path.display().to_string())
}

/// Kalibr `imu.yaml` text for `noise`, with the units in comments (lossless).
pub fn kalibr_yaml_string(noise: &ImuNoise) -> String {
    format!(
        "# IMU noise model (Kalibr format): continuous-time densities, not per-sample std.\n\
         # per-sample white-noise std = density / sqrt(dt); bias step std = random_walk * sqrt(dt)\n\
         rostopic: /imu0\n\
         gyroscope_noise_density: {:?}      # [ rad / s / sqrt(Hz) ]\n\
         gyroscope_random_walk: {:?}        # [ rad / s^2 / sqrt(Hz) ]\n\
         accelerometer_noise_density: {:?}  # [ m / s^2 / sqrt(Hz) ]\n\
         accelerometer_random_walk: {:?}    # [ m / s^3 / sqrt(Hz) ]\n\
         update_rate: {:?}                  # [ Hz ]\n",
        noise.gyro_noise_density,
        noise.gyro_random_walk,
        noise.acc_noise_density,
        noise.acc_random_walk,
        noise.update_rate_hz
    )
}

/// Writes a Kalibr `imu.yaml`.
pub fn write_kalibr_yaml(path: &Path, noise: &ImuNoise) -> Result<(), IoError> {
    write_text(path, &kalibr_yaml_string(noise))
}
