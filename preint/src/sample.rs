//! IMU samples and bias estimates.

use nalgebra::Vector3;

/// One IMU reading, in the IMU (body) frame, SI units.
///
/// - `t_ns`: timestamp in integer nanoseconds (durations are integer differences, so 1.4e18-ns
///   EuRoC stamps lose nothing).
/// - `gyro`: angular rate ω_m [rad/s].
/// - `acc`: specific force a_m [m/s²] (reads about +9.81 on the up axis at rest).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct ImuSample {
    /// Timestamp \[ns\].
    pub t_ns: i64,
    /// Gyroscope reading ω_m [rad/s], body frame.
    pub gyro: Vector3<f64>,
    /// Accelerometer reading a_m (specific force) [m/s²], body frame.
    pub acc: Vector3<f64>,
}

impl ImuSample {
    /// A sample from its timestamp \[ns\], gyro [rad/s] and accelerometer [m/s²] readings.
    pub fn new(t_ns: i64, gyro: Vector3<f64>, acc: Vector3<f64>) -> Self {
        Self { t_ns, gyro, acc }
    }
}

/// Duration between two integer-nanosecond timestamps, in seconds (`(t1 − t0)·1e-9`).
#[inline]
pub fn dt_seconds(t0_ns: i64, t1_ns: i64) -> f64 {
    (t1_ns - t0_ns) as f64 * 1e-9
}

/// `(t1 − t0)·1e-9` \[s\] computed in i128 when the i64 difference overflows, so any pair of
/// i64 timestamps is safe.
#[inline(always)]
pub(crate) fn span_s(t0_ns: i64, t1_ns: i64) -> f64 {
    // Same integer, same rounding: the i64 → f64 conversion is a single instruction, the
    // i128 one a library call.
    match t1_ns.checked_sub(t0_ns) {
        Some(d) => d as f64 * 1e-9,
        None => (t1_ns as i128 - t0_ns as i128) as f64 * 1e-9,
    }
}

/// IMU bias estimate. Tangent order everywhere in this project is **[b_g, b_a]**.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ImuBias {
    /// Gyroscope bias b_g [rad/s].
    pub gyro: Vector3<f64>,
    /// Accelerometer bias b_a [m/s²].
    pub acc: Vector3<f64>,
}

impl ImuBias {
    /// A bias from its gyroscope [rad/s] and accelerometer [m/s²] parts.
    pub fn new(gyro: Vector3<f64>, acc: Vector3<f64>) -> Self {
        Self { gyro, acc }
    }
    /// The zero bias.
    pub fn zero() -> Self {
        Self::default()
    }
}
