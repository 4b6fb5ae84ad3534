//! [`ImuReader`]: one streaming sample source over every format, validated, with progress.

use crate::detect::{Format, detect_text};
use crate::error::{IoError, Location};
use crate::layout::{Column, Delimiter, TextLayout};
use crate::lines::LineReader;
use crate::text::TextSamples;
use crate::units::{AccelUnit, GyroUnit, TimeUnit, Units};
use preint::ImuSample;
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Default bound on the samples [`ImuReader::read_all`] holds in memory: 50 million
/// (2.8 GB of [`ImuSample`]s; 69 h at 200 Hz). Streaming commands are not bounded by it.
pub const DEFAULT_MAX_SAMPLES: usize = 50_000_000;

/// A sample and where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    /// Line or message of the source.
    pub at: Location,
    /// The sample, in SI units and integer nanoseconds.
    pub sample: ImuSample,
}

/// How to read a source. Every field is optional: what is not given is detected from the
/// extension and the first lines, and reported in [`SourceInfo::notes`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReadOptions {
    /// The format (`--format`).
    pub format: Option<Format>,
    /// The columns of a delimited text source (`--columns`).
    pub columns: Option<Vec<Column>>,
    /// The delimiter of a text source (default: sniffed from the first data row).
    pub delimiter: Option<Delimiter>,
    /// Unit of the timestamps (`--time-unit`).
    pub time_unit: Option<TimeUnit>,
    /// Unit of the gyroscope (`--gyro-unit`).
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of the accelerometer (`--accel-unit`).
    pub accel_unit: Option<AccelUnit>,
    /// The `sensor_msgs/Imu` topic of a bag or MCAP file (`--topic`).
    pub topic: Option<String>,
    /// A split recording in a container: the topic whose angular velocity is used
    /// (`--gyro-topic`), with [`ReadOptions::accel_topic`].
    pub gyro_topic: Option<String>,
    /// The topic whose linear acceleration is used (`--accel-topic`).
    pub accel_topic: Option<String>,
    /// Which time stamps a container's samples carry (`--stamp`).
    pub stamp: Stamp,
    /// Bound of [`ImuReader::read_all`].
    pub max_samples: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            format: None,
            columns: None,
            delimiter: None,
            time_unit: None,
            gyro_unit: None,
            accel_unit: None,
            topic: None,
            gyro_topic: None,
            accel_topic: None,
            stamp: Stamp::Header,
            max_samples: DEFAULT_MAX_SAMPLES,
        }
    }
}

impl ReadOptions {
    /// Options that read EuRoC CSV without detection.
    pub fn euroc() -> Self {
        Self {
            format: Some(Format::Euroc),
            ..Self::default()
        }
    }
}

/// The time stamp of a message in a container.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Stamp {
    /// `header.stamp` of the `sensor_msgs/Imu` message: when the sensor sampled (default).
    #[default]
    Header,
    /// The time the recorder received the message (bag record time, MCAP log time).
    Record,
}

impl std::str::FromStr for Stamp {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "header" => Ok(Stamp::Header),
            "record" | "log" | "receive" => Ok(Stamp::Record),
            other => Err(format!(
                "unknown stamp `{other}`; expected header or record"
            )),
        }
    }
}

impl std::fmt::Display for Stamp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Stamp::Header => "header",
            Stamp::Record => "record",
        })
    }
}

/// What a source is and how it is read.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceInfo {
    /// The path or label.
    pub source_name: String,
    /// Its format.
    pub format: Format,
    /// The layout of a text source.
    pub layout: Option<TextLayout>,
    /// The units its values were converted from.
    pub units: Units,
    /// How the format, columns and units were decided.
    pub notes: Vec<String>,
    /// What a user must know about what was read (a split recording shortened to the streams'
    /// overlap), printed with every result as `warning:` lines and in the JSON's `input`.
    pub warnings: Vec<String>,
}

impl SourceInfo {
    /// One line: format, columns and units, e.g. `euroc (columns t,wx,wy,wz,ax,ay,az; time
    /// ns, gyro rad/s, accel m/s2)`.
    pub fn describe(&self) -> String {
        match &self.layout {
            Some(l) => format!(
                "{} ({} columns {}; {})",
                self.format,
                l.delimiter,
                l.columns_spec(),
                self.units
            ),
            None => format!("{} ({})", self.format, self.units),
        }
    }
}

/// How far reading has got: `done` of `total` bytes (or messages) of the source.
#[derive(Clone, Debug)]
pub struct Progress {
    done: Arc<AtomicU64>,
    total: u64,
}

impl Progress {
    /// Progress over `total` units, counted by `done`.
    pub fn new(done: Arc<AtomicU64>, total: u64) -> Self {
        Self { done, total }
    }
    /// Units consumed so far.
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }
    /// Units in the whole source (0 when unknown).
    pub fn total(&self) -> u64 {
        self.total
    }
}

/// The samples of one source, in order, validated: timestamps strictly increasing and values
/// finite, every error naming the source and the line or message. Streaming: memory does not
/// grow with the source unless [`ImuReader::read_all`] is called.
pub struct ImuReader {
    samples: Box<dyn Iterator<Item = Result<Located, IoError>> + Send>,
    info: SourceInfo,
    progress: Progress,
    max_samples: usize,
    prev: Option<Located>,
    failed: bool,
}

impl ImuReader {
    /// Opens `path` with `opts` (see [`ReadOptions`]).
    pub fn open(path: &Path, opts: &ReadOptions) -> Result<Self, IoError> {
        let format = opts.format.or_else(|| Format::of_file(path));
        if let Some(f) = format.filter(|f| f.is_container()) {
            return crate::containers::open(path, f, opts);
        }
        let name = path.display().to_string();
        let head = read_head(open_file(path)?, &name)?;
        let detection = detect_text(&head, opts, &name)?;
        let file = open_file(path)?;
        let total = file.metadata().map(|m| m.len()).unwrap_or(0);
        Ok(Self::text(file, &name, detection, total, opts))
    }

    /// Reads in-memory text labelled `source_name` (tests, and text already in memory).
    pub fn from_text(text: &str, source_name: &str, opts: &ReadOptions) -> Result<Self, IoError> {
        let head = read_head(text.as_bytes(), source_name)?;
        let detection = detect_text(&head, opts, source_name)?;
        let bytes = text.as_bytes().to_vec();
        Ok(Self::text(
            std::io::Cursor::new(bytes),
            source_name,
            detection,
            text.len() as u64,
            opts,
        ))
    }

    fn text<R: Read + Send + 'static>(
        inner: R,
        name: &str,
        detection: crate::detect::TextDetection,
        total: u64,
        opts: &ReadOptions,
    ) -> Self {
        let lines = LineReader::new(inner, name);
        let progress = Progress::new(lines.progress(), total);
        let info = SourceInfo {
            source_name: name.to_string(),
            format: detection.format,
            units: detection.layout.units,
            layout: Some(detection.layout.clone()),
            notes: detection.notes,
            warnings: Vec::new(),
        };
        let samples = TextSamples::new(lines, &detection.layout);
        Self::from_source(Box::new(samples), info, progress, opts.max_samples)
    }

    /// A reader over any source of located samples (containers, merged streams): adds the
    /// validation and the bound of [`ImuReader::read_all`].
    pub fn from_source(
        samples: Box<dyn Iterator<Item = Result<Located, IoError>> + Send>,
        info: SourceInfo,
        progress: Progress,
        max_samples: usize,
    ) -> Self {
        Self {
            samples,
            info,
            progress,
            max_samples,
            prev: None,
            failed: false,
        }
    }

    /// What the source is and how it is being read.
    pub fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// How far reading has got.
    pub fn progress(&self) -> &Progress {
        &self.progress
    }

    /// The next sample with its location (see the type docs for the checks).
    pub fn next_located(&mut self) -> Option<Result<Located, IoError>> {
        if self.failed {
            return None;
        }
        let item = self.samples.next()?.and_then(|s| self.check(s));
        self.failed = item.is_err();
        Some(item)
    }

    fn check(&mut self, s: Located) -> Result<Located, IoError> {
        let finite = |v: &nalgebra::Vector3<f64>| v.iter().all(|x| x.is_finite());
        let name = &self.info.source_name;
        if !finite(&s.sample.gyro) || !finite(&s.sample.acc) {
            return Err(IoError::parse(name, s.at, "a reading is not finite"));
        }
        if let Some(p) = &self.prev {
            let (t, tp) = (s.sample.t_ns, p.sample.t_ns);
            if t == tp {
                return Err(IoError::parse(
                    name,
                    s.at,
                    format!("duplicate timestamp {t} ns (same as {})", p.at),
                ));
            }
            if t < tp {
                return Err(IoError::parse(
                    name,
                    s.at,
                    format!("timestamp {t} ns decreases ({} has {tp} ns)", p.at),
                ));
            }
        }
        self.prev = Some(s);
        Ok(s)
    }

    /// Every sample, in memory; refuses sources with more than the options' `max_samples`
    /// (before allocating for them) and sources with no samples.
    pub fn read_all(mut self) -> Result<Vec<ImuSample>, IoError> {
        let mut out = Vec::new();
        while let Some(s) = self.next_located() {
            if out.len() == self.max_samples {
                return Err(self.too_many());
            }
            out.push(s?.sample);
        }
        if out.is_empty() {
            return Err(IoError::Empty {
                source_name: self.info.source_name.clone(),
            });
        }
        Ok(out)
    }

    /// The samples as the source gives them, without the ordering check (for audits that
    /// report duplicate and out-of-order samples instead of stopping at them); malformed rows
    /// are still errors. Also returns how the source is read and its progress counter.
    pub fn into_unvalidated(
        self,
    ) -> (
        Box<dyn Iterator<Item = Result<Located, IoError>> + Send>,
        SourceInfo,
        Progress,
    ) {
        (self.samples, self.info, self.progress)
    }

    /// The error for more samples than `max_samples`.
    pub fn too_many(&self) -> IoError {
        IoError::TooLarge {
            source_name: self.info.source_name.clone(),
            msg: format!(
                "more than {} samples ({:.1} GB in memory); select a window (--from/--to) or \
                 split the recording",
                self.max_samples,
                (self.max_samples * std::mem::size_of::<ImuSample>()) as f64 * 1e-9
            ),
        }
    }
}

impl Iterator for ImuReader {
    type Item = Result<ImuSample, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_located().map(|r| r.map(|l| l.sample))
    }
}

/// Number of lines detection looks at.
const HEAD_LINES: usize = 32;

/// The first [`HEAD_LINES`] lines of a text source.
fn read_head(inner: impl Read, name: &str) -> Result<Vec<String>, IoError> {
    let mut lines = LineReader::new(inner, name);
    let mut head = Vec::new();
    while head.len() < HEAD_LINES {
        match lines.next_line()? {
            Some(l) => head.push(l.text.to_string()),
            None => break,
        }
    }
    Ok(head)
}

fn open_file(path: &Path) -> Result<File, IoError> {
    File::open(path).map_err(|e| IoError::file(path, e))
}
