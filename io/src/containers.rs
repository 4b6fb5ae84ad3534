//! Container formats (ROS 1 bag, MCAP, ROS 2 `.db3`) carrying `sensor_msgs/Imu`.

use crate::detect::Format;
use crate::error::IoError;
use crate::reader::{ImuReader, ReadOptions};
use std::path::Path;

/// Opens the container `path` of format `format`.
pub fn open(path: &Path, format: Format, _opts: &ReadOptions) -> Result<ImuReader, IoError> {
    Err(IoError::format(
        &path.display().to_string(),
        format!("reading {format} files is not supported by this build"),
    ))
}
