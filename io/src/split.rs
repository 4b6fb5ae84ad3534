//! Split recordings: a gyroscope stream and an accelerometer stream with their own timestamps,
//! merged into IMU samples.

use crate::channel::{ChannelStream, Sensor};
use crate::error::IoError;
use crate::reader::{ImuReader, ReadOptions, SourceInfo};
use std::path::Path;

/// The readings of one sensor from a text file `path` (`t, x, y, z` rows).
pub fn open_text_channel(
    path: &Path,
    sensor: Sensor,
    _opts: &ReadOptions,
) -> Result<ChannelStream, IoError> {
    Err(IoError::format(
        &path.display().to_string(),
        format!("reading a separate {sensor} file is not supported by this build"),
    ))
}

/// IMU samples from a gyroscope stream and an accelerometer stream.
pub fn merge(
    _gyro: ChannelStream,
    _accel: ChannelStream,
    info: SourceInfo,
    _opts: &ReadOptions,
) -> Result<ImuReader, IoError> {
    Err(IoError::format(
        &info.source_name,
        "merging split gyro and accelerometer streams is not supported by this build",
    ))
}

/// IMU samples from a gyroscope file and an accelerometer file.
pub fn open_split(gyro: &Path, accel: &Path, opts: &ReadOptions) -> Result<ImuReader, IoError> {
    let g = open_text_channel(gyro, Sensor::Gyro, opts)?;
    let a = open_text_channel(accel, Sensor::Accel, opts)?;
    let info = SourceInfo {
        source_name: format!("{} + {}", gyro.display(), accel.display()),
        format: crate::Format::Delimited,
        layout: None,
        units: crate::Units::SI_NS,
        notes: Vec::new(),
    };
    merge(g, a, info, opts)
}
