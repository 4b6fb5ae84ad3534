//! Readings no IMU can produce: an angular rate or a specific force beyond the range of every
//! inertial sensor made. Such a value is a corrupt row (a digit run together, an overflowed
//! field, a sentinel such as 1e308), not a measurement, and every result computed from it
//! would be wrong or infinite.
//!
//! The limits sit well above the widest ranges on the market, so that no real recording (and
//! no recording misread as rad/s when in deg/s at an everyday rate) reaches them:
//! - gyroscopes: MEMS IMUs read up to ±2000–4000 °/s (Bosch BMI088 ±2000 °/s; Analog Devices
//!   ADIS16448, EuRoC's IMU, ±1000 °/s); the widest gyroscope range is that of Analog
//!   Devices' ADXRS649, ±20 000 °/s = 349 rad/s, for spinning projectiles. The limit,
//!   [`MAX_GYRO_RAD_S`] = 1000 rad/s (57 300 °/s), is about three times that.
//! - accelerometers: navigation and MEMS IMUs read up to ±16–40 g (BMI088 ±24 g, ADIS16448
//!   ±18 g); high-g MEMS accelerometers ±200 g (Analog Devices ADXL375) and ±400 g
//!   (STMicroelectronics H3LIS331DL, 3923 m/s²). The limit, [`MAX_ACCEL_M_S2`] =
//!   10 000 m/s² (1020 g), is 2.5 times the widest.

use crate::error::{IoError, Location};
use preint::ImuSample;

/// Largest angular-rate norm any IMU reads \[rad/s\] (module docs).
pub const MAX_GYRO_RAD_S: f64 = 1000.0;

/// Largest specific-force norm any IMU reads \[m/s²\] (module docs).
pub const MAX_ACCEL_M_S2: f64 = 10_000.0;

/// What is impossible about the readings of `s`, if anything: the readings, their norm and
/// the limit it exceeds (a NaN is impossible too).
pub fn impossible(s: &ImuSample) -> Option<String> {
    // The largest component, not the norm, is printed: the norm of 1e308 overflows.
    let magnitude = |v: &nalgebra::Vector3<f64>| {
        let n = v.norm();
        if n.is_finite() || n.is_nan() {
            n
        } else {
            v.amax()
        }
    };
    let (w, a) = (magnitude(&s.gyro), magnitude(&s.acc));
    if w.is_nan() || w > MAX_GYRO_RAD_S {
        return Some(format!(
            "the gyro reads {:?} rad/s (|ω| ≥ {w:.4e}), beyond any IMU's range ({MAX_GYRO_RAD_S} \
             rad/s; the widest gyroscope reads ±349 rad/s)",
            [s.gyro.x, s.gyro.y, s.gyro.z]
        ));
    }
    if a.is_nan() || a > MAX_ACCEL_M_S2 {
        return Some(format!(
            "the accelerometer reads {:?} m/s² (|a| ≥ {a:.4e}), beyond any IMU's range \
             ({MAX_ACCEL_M_S2} m/s²; the widest IMU accelerometer reads ±400 g = 3923 m/s²)",
            [s.acc.x, s.acc.y, s.acc.z]
        ));
    }
    None
}

/// Refuses sample `index` (0-based) of `source_name` at `at` when its readings are beyond
/// any IMU's range ([`impossible`]); the error names the source, the line or message and the
/// sample.
pub fn check_reading(
    s: &ImuSample,
    index: u64,
    at: Location,
    source_name: &str,
) -> Result<(), IoError> {
    match impossible(s) {
        None => Ok(()),
        Some(why) => Err(IoError::parse(
            source_name,
            at,
            format!(
                "sample {index} (t = {} ns): {why}: a corrupt row? Correct or remove it",
                s.t_ns
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn limits_refuse_what_no_imu_reads_and_name_the_line() {
        let ok = ImuSample::new(
            0,
            Vector3::new(349.0, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 3923.0),
        );
        assert!(impossible(&ok).is_none());
        let spin = ImuSample::new(5, Vector3::new(800.0, 800.0, 0.0), Vector3::zeros());
        assert!(impossible(&spin).unwrap().contains("|ω| ≥ 1.1314e3"));
        let bad = ImuSample::new(7, Vector3::zeros(), Vector3::new(1e308, 0.0, 9.8));
        let e = check_reading(&bad, 1000, Location::Line(1002), "rec.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("rec.csv:1002: sample 1000 (t = 7 ns)") && e.contains("1.0000e308"),
            "{e}"
        );
        let nan = ImuSample::new(0, Vector3::new(f64::NAN, 0.0, 0.0), Vector3::zeros());
        assert!(impossible(&nan).is_some());
    }
}
