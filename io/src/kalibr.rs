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

/// Largest value of each key of `KALIBR_KEYS`, in its unit: 1 rad/s/√Hz, 1 rad/s²/√Hz,
/// 10 m/s²/√Hz, 10 m/s³/√Hz, 1 MHz. The noisiest MEMS gyroscopes have white-noise densities
/// near 0.1 °/s/√Hz (1.7e-3 rad/s/√Hz) and accelerometers near 1 mg/√Hz (0.01 m/s²/√Hz);
/// random walks are smaller still (EuRoC's ADIS16448: 1.9e-5 rad/s²/√Hz, 3e-3 m/s³/√Hz). The
/// limits are hundreds of times beyond them: a larger value is a unit slip (a per-sample
/// standard deviation, a variance, deg for rad) or a corrupt file, and would give a
/// covariance of no sensor.
pub const MAX_VALUES: [f64; 5] = [1.0, 1.0, 10.0, 10.0, 1e6];

/// The units of [`KALIBR_KEYS`], as printed.
const UNITS: [&str; 5] = [
    "rad/s/sqrt(Hz)",
    "rad/s^2/sqrt(Hz)",
    "m/s^2/sqrt(Hz)",
    "m/s^3/sqrt(Hz)",
    "Hz",
];

/// Parses a Kalibr `imu.yaml` (flat `key: value` lines; `#` comments and unknown keys such as
/// `rostopic` are ignored). All five keys of `KALIBR_KEYS` are required; values must be
/// finite, non-negative and at most [`MAX_VALUES`] (`update_rate` positive); an error names
/// the line and the key.
pub fn parse_kalibr_yaml(text: &str, source_name: &str) -> Result<ImuNoise, IoError> {
    parse_located(text, source_name).map(|(n, _)| n)
}

/// [`parse_kalibr_yaml`], with the line of each key.
fn parse_located(text: &str, source_name: &str) -> Result<(ImuNoise, [u64; 5]), IoError> {
    let mut vals: [Option<(f64, u64)>; 5] = [None; 5];
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some((k, v)) = line.split_once(':') else {
            continue;
        };
        let Some(idx) = KALIBR_KEYS.iter().position(|key| *key == k.trim()) else {
            continue;
        };
        let at = Location::Line(i as u64 + 1);
        let key = KALIBR_KEYS[idx];
        let x = parse_finite(v.trim())
            .map_err(|m| IoError::parse(source_name, at, format!("{key}: {m}")))?;
        if x < 0.0 || (idx == 4 && x == 0.0) {
            return Err(IoError::parse(
                source_name,
                at,
                format!("`{key}` must be positive, got {x}"),
            ));
        }
        if x > MAX_VALUES[idx] {
            return Err(IoError::parse(
                source_name,
                at,
                format!(
                    "`{key}` is {x:e} {}, beyond any IMU's (at most {}): a per-sample standard \
                     deviation, a variance or degrees instead of a continuous-time density in \
                     {}?",
                    UNITS[idx], MAX_VALUES[idx], UNITS[idx]
                ),
            ));
        }
        vals[idx] = Some((x, i as u64 + 1));
    }
    let get = |i: usize| {
        vals[i].ok_or(IoError::MissingKey {
            source_name: source_name.to_string(),
            key: KALIBR_KEYS[i],
        })
    };
    let v = [get(0)?, get(1)?, get(2)?, get(3)?, get(4)?];
    let noise = ImuNoise {
        gyro_noise_density: v[0].0,
        gyro_random_walk: v[1].0,
        acc_noise_density: v[2].0,
        acc_random_walk: v[3].0,
        update_rate_hz: v[4].0,
    };
    Ok((noise, v.map(|x| x.1)))
}

/// Reads a Kalibr `imu.yaml` (see [`parse_kalibr_yaml`]).
pub fn read_kalibr_yaml(path: &Path) -> Result<ImuNoise, IoError> {
    parse_kalibr_yaml(&read_text(path)?, &path.display().to_string())
}

/// Parses a Kalibr `imu.yaml` whose densities weight preintegrated measurements and factors:
/// as [`parse_kalibr_yaml`], and a white-noise density of zero (`gyroscope_noise_density`,
/// `accelerometer_noise_density`) is refused naming its line and key. A noise-free model
/// gives a singular covariance, which cannot weight a factor. (Zero random walks, a constant
/// bias, are accepted: [`parse_kalibr_bias_model`] refuses them too.)
pub fn parse_kalibr_noise_model(text: &str, source_name: &str) -> Result<ImuNoise, IoError> {
    let (noise, lines) = parse_located(text, source_name)?;
    refuse_zero(
        &noise,
        &lines,
        source_name,
        &[0, 2],
        "a noise-free model gives a singular covariance, which cannot weight a factor",
    )?;
    Ok(noise)
}

/// As [`parse_kalibr_noise_model`], the random walks (`gyroscope_random_walk`,
/// `accelerometer_random_walk`) positive too: a factor that weights the bias change between
/// its keyframes (GTSAM's `CombinedImuFactor`) has a singular covariance without them.
pub fn parse_kalibr_bias_model(text: &str, source_name: &str) -> Result<ImuNoise, IoError> {
    let noise = parse_kalibr_noise_model(text, source_name)?;
    let (_, lines) = parse_located(text, source_name)?;
    refuse_zero(
        &noise,
        &lines,
        source_name,
        &[1, 3],
        "a bias without random walk gives the combined factor's bias blocks a singular \
         covariance",
    )?;
    Ok(noise)
}

/// Refuses a zero value among `keys` (indices of [`KALIBR_KEYS`]) of `noise`, naming the line
/// and the key, and saying `why`.
fn refuse_zero(
    noise: &ImuNoise,
    lines: &[u64; 5],
    source_name: &str,
    keys: &[usize],
    why: &str,
) -> Result<(), IoError> {
    let values = [
        noise.gyro_noise_density,
        noise.gyro_random_walk,
        noise.acc_noise_density,
        noise.acc_random_walk,
        noise.update_rate_hz,
    ];
    match keys.iter().find(|&&k| values[k] == 0.0) {
        None => Ok(()),
        Some(&k) => Err(IoError::parse(
            source_name,
            Location::Line(lines[k]),
            format!(
                "`{}` is 0: {why}; give the sensor's value in {} (`preint allan` measures it \
                 from a still recording)",
                KALIBR_KEYS[k], UNITS[k]
            ),
        )),
    }
}

/// Reads a Kalibr `imu.yaml` to weight measurements with ([`parse_kalibr_noise_model`]).
pub fn read_kalibr_noise_model(path: &Path) -> Result<ImuNoise, IoError> {
    parse_kalibr_noise_model(&read_text(path)?, &path.display().to_string())
}

/// Reads a Kalibr `imu.yaml` for a factor that weights the bias change
/// ([`parse_kalibr_bias_model`]).
pub fn read_kalibr_bias_model(path: &Path) -> Result<ImuNoise, IoError> {
    parse_kalibr_bias_model(&read_text(path)?, &path.display().to_string())
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

#[cfg(test)]
mod tests {
    use super::*;

    const EUROC: &str = "gyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\n\
        accelerometer_noise_density: 2.0e-03\naccelerometer_random_walk: 3.0e-03\n\
        update_rate: 200.0\n";

    fn with(key: &str, value: &str) -> String {
        (EUROC.lines())
            .map(|l| {
                if l.starts_with(key) {
                    format!("{key}: {value}\n")
                } else {
                    format!("{l}\n")
                }
            })
            .collect()
    }

    #[test]
    fn values_beyond_any_imu_and_zero_white_noise_are_refused_naming_line_and_key() {
        assert!(parse_kalibr_noise_model(EUROC, "imu.yaml").is_ok());
        let e = parse_kalibr_yaml(&with("accelerometer_noise_density", "1e308"), "imu.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("imu.yaml:3: `accelerometer_noise_density` is 1e308"),
            "{e}"
        );
        let e = parse_kalibr_yaml(&with("gyroscope_random_walk", "1.5"), "imu.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("imu.yaml:2: `gyroscope_random_walk`"), "{e}");
        assert!(parse_kalibr_yaml(&with("update_rate", "2e6"), "imu.yaml").is_err());
        // Zero white noise: a noise-free simulation may read it, a factor's weight may not.
        let zero = with("gyroscope_noise_density", "0");
        assert_eq!(
            parse_kalibr_yaml(&zero, "imu.yaml")
                .unwrap()
                .gyro_noise_density,
            0.0
        );
        let e = parse_kalibr_noise_model(&zero, "imu.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("imu.yaml:1: `gyroscope_noise_density` is 0"),
            "{e}"
        );
        // Zero random walk: a constant bias, refused only where the bias change is weighted.
        let walk = with("accelerometer_random_walk", "0");
        assert!(parse_kalibr_noise_model(&walk, "imu.yaml").is_ok());
        let e = parse_kalibr_bias_model(&walk, "imu.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("imu.yaml:4: `accelerometer_random_walk` is 0"),
            "{e}"
        );
    }
}
