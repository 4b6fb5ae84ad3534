//! One sensor of a split recording: gyroscope and accelerometer published as separate streams
//! (RealSense: gyro at 200 Hz and accelerometer at 63 Hz on two topics), before
//! [`crate::split`] merges them into IMU samples.

use crate::error::{IoError, Location};
use nalgebra::Vector3;
use std::fmt;

/// Which sensor a channel carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sensor {
    /// Gyroscope: angular rate [rad/s].
    Gyro,
    /// Accelerometer: specific force [m/s²].
    Accel,
}

impl fmt::Display for Sensor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Sensor::Gyro => "gyro",
            Sensor::Accel => "accel",
        })
    }
}

/// One reading of one sensor, in SI units (rad/s or m/s²), body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelSample {
    /// Line or message it came from.
    pub at: Location,
    /// Timestamp \[ns\].
    pub t_ns: i64,
    /// The reading.
    pub value: Vector3<f64>,
}

/// The readings of one sensor, in file order.
pub type ChannelStream = Box<dyn Iterator<Item = Result<ChannelSample, IoError>> + Send>;
