//! Container formats (ROS 1 bag, MCAP, ROS 2 `.db3`) carrying `sensor_msgs/Imu`.

use crate::channel::{ChannelStream, Sensor};
use crate::detect::Format;
use crate::error::IoError;
use crate::reader::{ImuReader, ReadOptions};
use std::path::Path;

/// Opens the container `path` of format `format`: the `sensor_msgs/Imu` messages of
/// `opts.topic`, or the gyro of `opts.gyro_topic` merged with the accelerometer of
/// `opts.accel_topic`.
pub fn open(path: &Path, format: Format, _opts: &ReadOptions) -> Result<ImuReader, IoError> {
    Err(IoError::format(
        &path.display().to_string(),
        format!("reading {format} files is not supported by this build"),
    ))
}

/// The readings of one sensor (`sensor`) from the `sensor_msgs/Imu` messages of `topic`.
pub fn open_channel(
    path: &Path,
    format: Format,
    topic: &str,
    sensor: Sensor,
    _opts: &ReadOptions,
) -> Result<ChannelStream, IoError> {
    Err(IoError::format(
        &path.display().to_string(),
        format!(
            "reading the {sensor} of topic {topic} from {format} files is not supported by this build"
        ),
    ))
}
