//! The flags that say where the IMU samples are and how to read them, shared by every
//! subcommand that reads a recording.

use crate::{CliError, checks};
use preint::ImuSample;
use preint_io::layout::{Column, parse_columns};
use preint_io::{
    AccelUnit, Delimiter, Format, GyroUnit, ImuReader, ReadOptions, SourceInfo, TimeUnit,
};
use serde_json::{Value, json};
use std::path::PathBuf;

/// The recording and how to read it. Whatever is not given is detected from the extension
/// and the first lines; what was decided is printed with the result.
#[derive(clap::Args, Clone, Debug)]
pub struct ImuArgs {
    /// IMU recording: EuRoC/TUM-VI CSV, UZH-FPV imu.txt, KITTI text, any delimited text (see
    /// --columns and the unit flags), ROS bag or MCAP (see --topic).
    #[arg(long)]
    pub imu: PathBuf,
    /// Format of --imu: euroc, tum-vi, uzh-fpv, kitti, delimited, bag, mcap, db3 (default:
    /// detected from the extension and the header).
    #[arg(long)]
    pub format: Option<Format>,
    /// Columns of a delimited file, e.g. t,ax,ay,az,wx,wy,wz (skip for unused columns;
    /// default: from the header's names).
    #[arg(long, value_parser = columns)]
    pub columns: Option<Vec<Column>>,
    /// Field delimiter of a text file: comma, semicolon, tab or whitespace (default: sniffed).
    #[arg(long)]
    pub delimiter: Option<Delimiter>,
    /// Unit of the timestamps: s, ms, us or ns (decimals allowed; converted to integer ns
    /// exactly).
    #[arg(long)]
    pub time_unit: Option<TimeUnit>,
    /// Unit of the gyroscope: rad/s or deg/s.
    #[arg(long)]
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of the accelerometer: m/s2 or g (1 g = 9.80665 m/s^2).
    #[arg(long)]
    pub accel_unit: Option<AccelUnit>,
    /// The sensor_msgs/Imu topic of a bag or MCAP file.
    #[arg(long)]
    pub topic: Option<String>,
    /// Skip the checks that the data looks like m/s^2, rad/s and the stated time unit.
    #[arg(long)]
    pub no_unit_check: bool,
}

/// Parses `--columns`.
fn columns(s: &str) -> Result<Vec<Column>, String> {
    parse_columns(s)
}

impl ImuArgs {
    /// The reader options these flags give.
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            format: self.format,
            columns: self.columns.clone(),
            delimiter: self.delimiter,
            time_unit: self.time_unit,
            gyro_unit: self.gyro_unit,
            accel_unit: self.accel_unit,
            topic: self.topic.clone(),
            ..ReadOptions::default()
        }
    }

    /// The recording's path, as printed.
    pub fn label(&self) -> String {
        self.imu.display().to_string()
    }

    /// A streaming reader of the recording.
    pub fn open(&self) -> Result<ImuReader, CliError> {
        Ok(ImuReader::open(&self.imu, &self.options())?)
    }

    /// Every sample of the recording, with the unit checks unless `--no-unit-check`; and how
    /// it was read.
    pub fn read_all(&self) -> Result<(Vec<ImuSample>, SourceInfo), CliError> {
        let reader = self.open()?;
        let info = reader.info().clone();
        let samples = reader.read_all()?;
        if !self.no_unit_check {
            checks::si_units(&samples, &self.imu)?;
        }
        Ok((samples, info))
    }
}

/// How a source was read, as JSON: format, units and the notes on how they were decided.
pub fn source_json(info: &SourceInfo) -> Value {
    json!({
        "format": info.format.name(),
        "read_as": info.describe(),
        "notes": info.notes,
    })
}
