//! The flags that say where the IMU samples are and how to read them, shared by every
//! subcommand that reads a recording; [`ImuArgs::to_input`] hands them to the library as an
//! [`ImuInput`].

use preint_analysis::ImuInput;
use preint_io::layout::{Column, parse_columns};
use preint_io::{AccelUnit, Delimiter, Format, GyroUnit, Stamp, TimeUnit};
use std::path::PathBuf;

/// The recording and how to read it. Whatever is not given is detected from the extension
/// and the first lines; what was decided is printed with the result.
#[derive(clap::Args, Clone, Debug)]
pub struct ImuArgs {
    /// IMU recording: EuRoC/TUM-VI CSV, UZH-FPV imu.txt, KITTI text, any delimited text (see
    /// --columns and the unit flags), ROS 1 bag, MCAP or ROS 2 db3 (see --topic).
    // Required unless `--gyro` (which requires `--accel`): one `unless` id, so that a command
    // whose recording is optional can lift the requirement (`report`).
    #[arg(help_heading = "Input", long, required_unless_present = "gyro", conflicts_with_all = ["gyro", "accel"])]
    pub imu: Option<PathBuf>,
    /// A split recording's gyroscope file (rows t, wx, wy, wz), with --accel.
    #[arg(help_heading = "Input", long, requires = "accel")]
    pub gyro: Option<PathBuf>,
    /// A split recording's accelerometer file (rows t, ax, ay, az), with --gyro.
    #[arg(help_heading = "Input", long, requires = "gyro")]
    pub accel: Option<PathBuf>,
    /// Format of --imu: euroc, tum-vi, uzh-fpv, kitti, delimited, bag, mcap, db3 (default:
    /// detected from the extension and the header).
    #[arg(help_heading = "Input", long)]
    pub format: Option<Format>,
    /// Columns of a delimited file, e.g. t,ax,ay,az,wx,wy,wz (skip for unused columns;
    /// default: from the header's names).
    // One value, the whole list: `std::vec::Vec` (not `Vec`) keeps clap's derive from reading
    // the field as a list of values, each a `Column`, which is not what `columns` returns.
    #[arg(help_heading = "Input", long, value_parser = columns)]
    pub columns: Option<std::vec::Vec<Column>>,
    /// Field delimiter of a text file: comma, semicolon, tab or whitespace (default: sniffed).
    #[arg(help_heading = "Input", long)]
    pub delimiter: Option<Delimiter>,
    /// Unit of the timestamps: s, ms, us or ns (decimals allowed; converted to integer ns
    /// exactly).
    #[arg(help_heading = "Input", long)]
    pub time_unit: Option<TimeUnit>,
    /// Unit of the gyroscope: rad/s or deg/s.
    #[arg(help_heading = "Input", long)]
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of the accelerometer: m/s2 or g (1 g = 9.80665 m/s^2).
    #[arg(help_heading = "Input", long)]
    pub accel_unit: Option<AccelUnit>,
    /// The sensor_msgs/Imu topic of a bag, MCAP or db3 file (default: its only one).
    #[arg(help_heading = "Input", long, conflicts_with_all = ["gyro_topic", "accel_topic"])]
    pub topic: Option<String>,
    /// A split recording in a bag, MCAP or db3 file: the topic whose angular velocity is used.
    #[arg(help_heading = "Input", long, requires = "accel_topic")]
    pub gyro_topic: Option<String>,
    /// The topic whose linear acceleration is used, with --gyro-topic.
    #[arg(help_heading = "Input", long, requires = "gyro_topic")]
    pub accel_topic: Option<String>,
    /// Time stamps of bag, MCAP or db3 messages: header (header.stamp, when the sensor sampled) or
    /// record (when the recorder received the message).
    #[arg(help_heading = "Input", long, default_value = "header")]
    pub stamp: Stamp,
    /// Skip the checks that the data looks like m/s^2, rad/s and the stated time unit (a
    /// reading beyond any IMU's range, 1000 rad/s or 10000 m/s^2, is refused regardless).
    #[arg(help_heading = "Input", long)]
    pub no_unit_check: bool,
}

/// Parses `--columns`.
fn columns(s: &str) -> Result<Vec<Column>, String> {
    parse_columns(s)
}

impl ImuArgs {
    /// The recording and how to read it, as the library takes it.
    pub fn to_input(&self) -> ImuInput {
        ImuInput {
            imu: self.imu.clone(),
            gyro: self.gyro.clone(),
            accel: self.accel.clone(),
            format: self.format,
            columns: self.columns.clone(),
            delimiter: self.delimiter,
            time_unit: self.time_unit,
            gyro_unit: self.gyro_unit,
            accel_unit: self.accel_unit,
            topic: self.topic.clone(),
            gyro_topic: self.gyro_topic.clone(),
            accel_topic: self.accel_topic.clone(),
            stamp: self.stamp,
            no_unit_check: self.no_unit_check,
        }
    }
}
