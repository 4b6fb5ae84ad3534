//! Are these readings plausible for an IMU on Earth in the units they were read as? Checks
//! that catch data in g, deg/s or the wrong time unit before it gives a confident wrong answer.

use crate::error::IoError;
use preint::ImuSample;

/// Checks that IMU samples look like SI units for an IMU near the Earth's surface: the median
/// accelerometer norm must lie in [4, 20] m/s² (data in g reads ≈ 1) and the median gyro norm
/// below 20 rad/s (data in deg/s of a moving IMU reads tens to hundreds).
pub fn check_si_units(samples: &[ImuSample], source_name: &str) -> Result<(), IoError> {
    if samples.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let acc = median(samples.iter().map(|s| s.acc.norm()).collect());
    let gyro = median(samples.iter().map(|s| s.gyro.norm()).collect());
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    if !(4.0..=20.0).contains(&acc) {
        return Err(units(format!(
            "median accelerometer norm is {acc:.4}; expected about 9.81 m/s² (specific force). \
             If the data is in g, multiply by 9.80665"
        )));
    }
    if gyro > 20.0 {
        return Err(units(format!(
            "median gyro norm is {gyro:.2}; expected rad/s. If the data is in deg/s, multiply by π/180"
        )));
    }
    Ok(())
}
