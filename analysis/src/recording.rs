//! The recording and how to read it, as every subcommand that reads one takes it (the
//! command line's `--imu`/`--gyro`/`--accel` and reader flags, the Python package's keyword
//! arguments), read whole with the unit checks ([`ImuInput::read_all_checked`]), and what every
//! command prints about its input ([`input_json`], [`input_text`]).

use crate::Error;
use crate::checks::{self, UnitCheck};
use preint::ImuSample;
use preint_io::layout::Column;
use preint_io::plausibility::limits;
use preint_io::split::{MergeHandle, MergeReport};
use preint_io::{
    AccelUnit, Delimiter, Format, GyroUnit, ImuReader, ReadOptions, SourceInfo, Stamp, TimeUnit,
};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The recording and how to read it. Whatever is not given is detected from the extension
/// and the first lines; what was decided is printed with the result. Each field is the
/// command-line flag of the same name.
#[derive(Clone, Debug, Default)]
pub struct ImuInput {
    /// IMU recording (`--imu`): EuRoC/TUM-VI CSV, UZH-FPV imu.txt, KITTI text, any delimited
    /// text, ROS 1 bag, MCAP or ROS 2 db3. `None` for a split recording.
    pub imu: Option<PathBuf>,
    /// A split recording's gyroscope file (`--gyro`, rows t, wx, wy, wz), with `accel`.
    pub gyro: Option<PathBuf>,
    /// A split recording's accelerometer file (`--accel`, rows t, ax, ay, az), with `gyro`.
    pub accel: Option<PathBuf>,
    /// Format of `imu` (`--format`; default: detected from the extension and the header).
    pub format: Option<Format>,
    /// Columns of a delimited file (`--columns`; default: from the header's names).
    pub columns: Option<Vec<Column>>,
    /// Field delimiter of a text file (`--delimiter`; default: sniffed).
    pub delimiter: Option<Delimiter>,
    /// Unit of the timestamps (`--time-unit`).
    pub time_unit: Option<TimeUnit>,
    /// Unit of the gyroscope (`--gyro-unit`).
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of the accelerometer (`--accel-unit`).
    pub accel_unit: Option<AccelUnit>,
    /// The sensor_msgs/Imu topic of a bag, MCAP or db3 file (`--topic`; default: its only one).
    pub topic: Option<String>,
    /// A split recording in a container: the topic whose angular velocity is used
    /// (`--gyro-topic`), with `accel_topic`.
    pub gyro_topic: Option<String>,
    /// The topic whose linear acceleration is used (`--accel-topic`), with `gyro_topic`.
    pub accel_topic: Option<String>,
    /// Time stamps of container messages (`--stamp`): header or record.
    pub stamp: Stamp,
    /// Skip the checks that the data looks like m/s², rad/s and the stated time unit
    /// (`--no-unit-check`; a reading beyond any IMU's range is refused regardless).
    pub no_unit_check: bool,
}

impl ImuInput {
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
            gyro_topic: self.gyro_topic.clone(),
            accel_topic: self.accel_topic.clone(),
            stamp: self.stamp,
            ..ReadOptions::default()
        }
    }

    /// The recording's file (the gyroscope file of a split recording), for messages.
    pub fn path(&self) -> &Path {
        match (&self.imu, &self.gyro) {
            (Some(p), _) | (None, Some(p)) => p,
            (None, None) => Path::new("(no --imu)"),
        }
    }

    /// The recording's path(s), as printed.
    pub fn label(&self) -> String {
        match (&self.imu, &self.gyro, &self.accel) {
            (None, Some(g), Some(a)) => format!("{} + {}", g.display(), a.display()),
            _ => self.path().display().to_string(),
        }
    }

    /// Whether the recording is split: a gyroscope file and an accelerometer file
    /// (`--gyro/--accel`) or two topics of a container (`--gyro-topic/--accel-topic`), merged
    /// with an effective accelerometer density ([`ImuInput::read_all_split`]).
    pub fn is_split(&self) -> bool {
        (self.imu.is_none() && self.gyro.is_some() && self.accel.is_some())
            || (self.gyro_topic.is_some() && self.accel_topic.is_some())
    }

    /// A streaming reader of the recording.
    pub fn open(&self) -> Result<ImuReader, Error> {
        self.open_with_report().map(|(r, _)| r)
    }

    /// As [`ImuInput::open`], with the handle of the merge report of a split recording
    /// (`--gyro`/`--accel` or `--gyro-topic`/`--accel-topic`; `None` otherwise).
    pub fn open_with_report(&self) -> Result<(ImuReader, Option<MergeHandle>), Error> {
        let opts = self.options();
        let container = || {
            let path = self.path();
            opts.format
                .or_else(|| Format::of_file(path))
                .filter(|f| f.is_container())
                .ok_or_else(|| {
                    Error::Usage(format!(
                        "--gyro-topic/--accel-topic need a bag, MCAP or db3 file; {} is not one",
                        path.display()
                    ))
                })
        };
        Ok(
            match (
                &self.imu,
                &self.gyro,
                &self.accel,
                &self.gyro_topic,
                &self.accel_topic,
            ) {
                (None, Some(g), Some(a), _, _) => {
                    let (r, h) = preint_io::split::open_split_with_report(g, a, &opts)?;
                    (r, Some(h))
                }
                (Some(p), _, _, Some(g), Some(a)) => {
                    let (r, h) = preint_io::containers::open_split(p, container()?, g, a, &opts)?;
                    (r, Some(h))
                }
                _ => (ImuReader::open(self.path(), &opts)?, None),
            },
        )
    }

    /// Every sample of the recording, with the unit checks unless `--no-unit-check`; and how
    /// it was read.
    pub fn read_all(&self) -> Result<(Vec<ImuSample>, SourceInfo), Error> {
        self.read_all_split().map(|(s, info, _)| (s, info))
    }

    /// As [`ImuInput::read_all`], also returning the merge report of a split recording
    /// (`--gyro`/`--accel` or `--gyro-topic`/`--accel-topic`), from which
    /// [`crate::noise::effective`] gives the noise densities to preintegrate the merged samples
    /// with. The report's summary and the accelerometer density factor are added to the
    /// source's notes.
    pub fn read_all_split(
        &self,
    ) -> Result<(Vec<ImuSample>, SourceInfo, Option<MergeReport>), Error> {
        self.read_all_checked()
            .map(|r| (r.samples, r.info, r.report))
    }

    /// As [`ImuInput::read_all_split`], with the unit checks' verdict (on every sample). Every
    /// sample is also refused when beyond the range of any IMU
    /// ([`preint_io::plausibility::limits`]).
    pub fn read_all_checked(&self) -> Result<Recording, Error> {
        let (mut reader, handle) = self.open_with_report()?;
        let mut info = reader.info().clone();
        let bar = crate::progress::ReadingBar::start(reader.progress(), "reading");
        let mut samples = Vec::new();
        while let Some(l) = reader.next_located() {
            if samples.len() == preint_io::reader::DEFAULT_MAX_SAMPLES {
                return Err(reader.too_many().into());
            }
            let l = l?;
            let index = samples.len() as u64;
            limits::check_reading(&l.sample, index, l.at, &info.source_name)?;
            samples.push(l.sample);
        }
        drop(bar);
        if samples.is_empty() {
            return Err(preint_io::IoError::Empty {
                source_name: info.source_name.clone(),
            }
            .into());
        }
        let report = handle.map(|h| h.report());
        if let Some(r) = &report {
            info.warnings.extend(r.shortening());
            info.notes.push(r.describe());
            info.notes.push(format!(
                "accelerometer white-noise density of the merged samples: sqrt(rho) = {:.5} \
                 times the given density, plus the interpolation term (docs/SPLIT_STREAMS.md)",
                r.white_ratio().sqrt()
            ));
        }
        let unit_check = if self.no_unit_check {
            UnitCheck::Skipped
        } else {
            UnitCheck::Checked {
                verdict: checks::si_units(&samples, self.path(), Some(info.units))?,
                samples: samples.len(),
            }
        };
        Ok(Recording {
            samples,
            info,
            report,
            unit_check,
        })
    }
}

/// A recording read whole ([`ImuInput::read_all_checked`]).
#[derive(Clone, Debug)]
pub struct Recording {
    /// Every sample, in order.
    pub samples: Vec<ImuSample>,
    /// How it was read.
    pub info: SourceInfo,
    /// The merge report of a split recording.
    pub report: Option<MergeReport>,
    /// The unit checks' verdict.
    pub unit_check: UnitCheck,
}

/// How a source was read, as JSON: format, units and the notes on how they were decided.
pub fn source_json(info: &SourceInfo) -> Value {
    json!({
        "format": info.format.name(),
        "read_as": info.describe(),
        "notes": info.notes,
        "warnings": info.warnings,
    })
}

/// What every command that reads a recording prints about its input: a `warning:` line per
/// [`SourceInfo::warnings`], then the unit checks' line ([`UnitCheck::text`]).
pub fn input_text(info: &SourceInfo, unit_check: &UnitCheck) -> String {
    let mut h: String = info
        .warnings
        .iter()
        .map(|w| format!("warning: {w}\n"))
        .collect();
    h.push_str(&unit_check.text());
    h
}

/// [`source_json`] with the unit checks' verdict under `unit_check` ([`UnitCheck::json`]): the
/// `input` object of every command that reads a recording.
pub fn input_json(info: &SourceInfo, unit_check: &UnitCheck) -> Value {
    let mut v = source_json(info);
    v["unit_check"] = unit_check.json();
    v
}
