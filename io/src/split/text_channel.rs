//! One sensor's readings from delimited text: rows `t, x, y, z`.

use crate::channel::{ChannelSample, Sensor};
use crate::error::{IoError, Location};
use crate::layout::{Delimiter, words};
use crate::lines::{LineReader, is_comment};
use crate::number::{parse_finite, parse_scaled, parse_scaled_integer};
use crate::reader::ReadOptions;
use crate::units::{AccelUnit, GyroUnit, TimeUnit};
use nalgebra::Vector3;
use std::io::Read;

/// How a channel file is read: delimiter, time unit, value factor to SI, and how each was
/// decided.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelLayout {
    /// Field separator.
    pub delimiter: Delimiter,
    /// Unit of the timestamps.
    pub time: TimeUnit,
    /// Factor from the file's unit to rad/s (gyro) or m/s² (accelerometer).
    pub factor: f64,
    /// Unit of a gyro file (rad/s for an accelerometer file).
    pub gyro: GyroUnit,
    /// Unit of an accelerometer file (m/s² for a gyro file).
    pub accel: AccelUnit,
    /// How the units were decided.
    pub notes: Vec<String>,
}

fn header_time_unit(field: &str) -> Option<TimeUnit> {
    let w = words(field);
    let has = |s: &str| w.iter().skip(1).any(|x| x == s);
    [
        ("ns", TimeUnit::Ns),
        ("us", TimeUnit::Us),
        ("ms", TimeUnit::Ms),
        ("s", TimeUnit::S),
        ("sec", TimeUnit::S),
    ]
    .into_iter()
    .find_map(|(n, u)| has(n).then_some(u))
}

/// The unit a header's value fields name.
fn header_value_unit(fields: &[&str], sensor: Sensor) -> Option<Unit> {
    let has = |s: &str| {
        fields
            .iter()
            .any(|f| words(f).iter().skip(1).any(|x| x == s))
    };
    match sensor {
        Sensor::Gyro if has("deg") || has("dps") => Some(unit(GyroUnit::DegPerS)),
        Sensor::Gyro if has("rad") => Some(unit(GyroUnit::RadPerS)),
        Sensor::Accel if has("g") => Some(aunit(AccelUnit::G)),
        Sensor::Accel if has("m") => Some(aunit(AccelUnit::MPerS2)),
        _ => None,
    }
}

/// A gyro or accelerometer unit.
#[derive(Clone, Copy)]
enum Unit {
    Gyro(GyroUnit),
    Accel(AccelUnit),
}

fn unit(u: GyroUnit) -> Unit {
    Unit::Gyro(u)
}

fn aunit(u: AccelUnit) -> Unit {
    Unit::Accel(u)
}

/// Decides the layout of a channel file from its first lines (`head`) and the options: the
/// delimiter from `--delimiter` or the first data row; the time unit from `--time-unit`, the
/// header (`t_s`, `timestamp [ns]`), or integer nanoseconds since an epoch (first stamp above
/// 10¹²), else an error asking for `--time-unit`; the value unit from `--gyro-unit` /
/// `--accel-unit`, the header, else rad/s or m/s² (noted as assumed).
pub fn detect_channel(
    head: &[String],
    opts: &ReadOptions,
    name: &str,
    sensor: Sensor,
) -> Result<ChannelLayout, IoError> {
    if opts.columns.is_some() {
        return Err(IoError::format(
            name,
            "--columns describes an IMU file; a --gyro or --accel file has the rows t, x, y, z",
        ));
    }
    let lines: Vec<&str> = head
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect();
    let first_field = |l: &str| {
        let mut f = "";
        Delimiter::sniff(l).for_each_field(l, |i, s| {
            if i == 0 {
                f = s;
            }
        });
        f.to_string()
    };
    let data = lines
        .iter()
        .position(|l| !is_comment(l) && first_field(l).parse::<f64>().is_ok_and(f64::is_finite))
        .ok_or_else(|| IoError::Empty {
            source_name: name.to_string(),
        })?;
    let delimiter = opts
        .delimiter
        .unwrap_or_else(|| Delimiter::sniff(lines[data]));
    let mut header: Vec<&str> = Vec::new();
    if data > 0 {
        let h = lines[data - 1].trim_start_matches('#');
        delimiter.for_each_field(h, |_, f| header.push(f));
    }
    let mut notes = Vec::new();
    let time = match (
        opts.time_unit,
        header.first().and_then(|f| header_time_unit(f)),
    ) {
        (Some(t), _) => (t, "flag"),
        (None, Some(t)) => (t, "header"),
        (None, None)
            if parse_scaled_integer(&first_field(lines[data]), 0)
                .is_some_and(|t| t > 1_000_000_000_000) =>
        {
            (TimeUnit::Ns, "integer stamps since an epoch")
        }
        (None, None) => {
            return Err(IoError::format(
                name,
                "the time unit is not stated (no unit in the header); give --time-unit s, ms, \
                 us or ns",
            ));
        }
    };
    let flag = match sensor {
        Sensor::Gyro => opts.gyro_unit.map(unit),
        Sensor::Accel => opts.accel_unit.map(aunit),
    };
    let from_header = header.get(1..).and_then(|f| header_value_unit(f, sensor));
    let (u, how) = match (flag, from_header) {
        (Some(u), _) => (u, "flag"),
        (None, Some(u)) => (u, "header"),
        (None, None) if sensor == Sensor::Gyro => (unit(GyroUnit::RadPerS), "assumed"),
        (None, None) => (aunit(AccelUnit::MPerS2), "assumed"),
    };
    let (factor, uname, gyro, accel) = match u {
        Unit::Gyro(g) => (g.to_rad_per_s(), g.to_string(), g, AccelUnit::MPerS2),
        Unit::Accel(a) => (a.to_m_per_s2(), a.to_string(), GyroUnit::RadPerS, a),
    };
    notes.push(format!(
        "{name}: {sensor} rows t,x,y,z ({delimiter}-separated); time {} ({}), {sensor} {uname} \
         ({how})",
        time.0, time.1
    ));
    Ok(ChannelLayout {
        delimiter,
        time: time.0,
        factor,
        gyro,
        accel,
        notes,
    })
}

/// The samples of a channel file laid out as [`ChannelLayout`]: comments (`#`, `%`) and
/// blank lines skipped, one header row skipped, every other row exactly four fields with a
/// decimal timestamp and finite readings.
pub struct TextChannel<R> {
    lines: LineReader<R>,
    rows: RowParser,
}

/// Turns one row into a sample.
struct RowParser {
    name: String,
    layout: ChannelLayout,
    sensor: Sensor,
    header_allowed: bool,
}

impl<R: Read> TextChannel<R> {
    /// Rows of `lines` read as `layout`.
    pub fn new(lines: LineReader<R>, layout: ChannelLayout, sensor: Sensor) -> Self {
        let rows = RowParser {
            name: lines.name().to_string(),
            layout,
            sensor,
            header_allowed: true,
        };
        Self { lines, rows }
    }
}

impl RowParser {
    fn row(&mut self, text: &str, at: Location) -> Result<Option<ChannelSample>, IoError> {
        let mut f = [""; 4];
        let n = self.layout.delimiter.for_each_field(text, |i, s| {
            if i < 4 {
                f[i] = s;
            }
        });
        let exp = self.layout.time.to_ns_exponent();
        let time = parse_scaled(f[0], exp);
        let name = self.name.as_str();
        if std::mem::take(&mut self.header_allowed)
            && time.is_none()
            && f[0].parse::<f64>().is_err()
        {
            return Ok(None);
        }
        if n != 4 {
            return Err(IoError::parse(
                name,
                at,
                format!(
                    "expected 4 columns ({}-separated: t, {s}_x, {s}_y, {s}_z), found {n}",
                    self.layout.delimiter,
                    s = self.sensor
                ),
            ));
        }
        let unit = self.layout.time;
        let t_ns = match time {
            Some((t, exact)) if exact || unit != TimeUnit::Ns => t,
            Some(_) => {
                return Err(IoError::parse(
                    name,
                    at,
                    format!(
                        "timestamp `{}` has a fraction of a nanosecond; if the times are in \
                         seconds (or ms, µs), say so with --time-unit",
                        f[0]
                    ),
                ));
            }
            None => {
                return Err(IoError::parse(
                    name,
                    at,
                    format!("timestamp `{}` is not a number of {unit} in range", f[0]),
                ));
            }
        };
        let mut v = [0.0; 3];
        for k in 0..3 {
            v[k] = parse_finite(f[k + 1]).map_err(|m| {
                IoError::parse(name, at, format!("column {} ({}): {m}", k + 2, self.sensor))
            })?;
        }
        Ok(Some(ChannelSample {
            at,
            t_ns,
            value: Vector3::new(v[0], v[1], v[2]) * self.layout.factor,
        }))
    }
}

impl<R: Read> Iterator for TextChannel<R> {
    type Item = Result<ChannelSample, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        let rows = &mut self.rows;
        self.lines.next_row(|text, at| rows.row(text, at))
    }
}
