//! [`TextSamples`]: IMU samples from delimited text, one line at a time.

use crate::error::{IoError, Location};
use crate::layout::TextLayout;
use crate::lines::LineReader;
use crate::number::{parse_finite, parse_scaled};
use crate::reader::Located;
use crate::units::TimeUnit;
use nalgebra::Vector3;
use preint::ImuSample;
use std::io::Read;

/// The samples of a text source laid out as `layout`. Blank and comment lines
/// ([`crate::lines::is_comment`]) are skipped; one header line (a first row whose time field is not a number) is
/// skipped; every other row must have exactly the layout's number of fields, a decimal
/// timestamp and finite readings, else the error names the line, column and value.
pub struct TextSamples<R> {
    lines: LineReader<R>,
    rows: RowParser,
}

impl<R: Read> TextSamples<R> {
    /// Samples of the lines of `lines`, laid out as `layout`.
    pub fn new(lines: LineReader<R>, layout: &TextLayout) -> Self {
        let rows = RowParser::new(layout, lines.name());
        Self { lines, rows }
    }
}

impl<R: Read> Iterator for TextSamples<R> {
    type Item = Result<Located, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        let rows = &mut self.rows;
        self.lines
            .next_row(|text, at| Ok(rows.parse(text, at)?.map(|sample| Located { at, sample })))
    }
}

/// Turns one row into a sample (see [`TextSamples`]).
struct RowParser {
    name: String,
    layout: TextLayout,
    /// For each column, the index in (t, wx, wy, wz, ax, ay, az), or `None`.
    role: Vec<Option<usize>>,
    gyro_factor: f64,
    acc_factor: f64,
    header_allowed: bool,
}

const WHAT: [&str; 7] = ["time", "wx", "wy", "wz", "ax", "ay", "az"];

impl RowParser {
    fn new(layout: &TextLayout, name: &str) -> Self {
        let pos = layout.positions();
        let role = (0..layout.columns.len())
            .map(|c| pos.iter().position(|&p| p == c))
            .collect();
        Self {
            name: name.to_string(),
            layout: layout.clone(),
            role,
            gyro_factor: layout.units.gyro.to_rad_per_s(),
            acc_factor: layout.units.accel.to_m_per_s2(),
            header_allowed: true,
        }
    }

    fn err(&self, at: Location, msg: String) -> IoError {
        IoError::parse(&self.name, at, msg)
    }

    /// The sample of row `text`, or `None` for the header row.
    #[inline]
    fn parse(&mut self, text: &str, at: Location) -> Result<Option<ImuSample>, IoError> {
        let mut f = [""; 7];
        let role = &self.role;
        let n = self.layout.delimiter.for_each_field(text, |i, s| {
            if let Some(Some(r)) = role.get(i) {
                f[*r] = s;
            }
        });
        let time = parse_scaled(f[0], self.layout.units.time.to_ns_exponent());
        if self.header_allowed && time.is_none() && f[0].parse::<f64>().is_err() {
            self.header_allowed = false;
            return Ok(None);
        }
        self.header_allowed = false;
        if n != self.layout.columns.len() {
            return Err(self.err(
                at,
                format!(
                    "expected {} columns ({}-separated: {}), found {n}",
                    self.layout.columns.len(),
                    self.layout.delimiter,
                    self.layout.columns_spec()
                ),
            ));
        }
        let t_ns = self.time(time, f[0], at)?;
        let mut v = [0.0; 6];
        for k in 0..6 {
            v[k] = parse_finite(f[k + 1]).map_err(|m| {
                let col = self.layout.positions()[k + 1] + 1;
                self.err(at, format!("column {col} ({}): {m}", WHAT[k + 1]))
            })?;
        }
        let (g, a) = (self.gyro_factor, self.acc_factor);
        Ok(Some(ImuSample::new(
            t_ns,
            Vector3::new(v[0], v[1], v[2]) * g,
            Vector3::new(v[3], v[4], v[5]) * a,
        )))
    }

    fn time(&self, time: Option<(i64, bool)>, field: &str, at: Location) -> Result<i64, IoError> {
        let unit = self.layout.units.time;
        match time {
            Some((t, true)) => Ok(t),
            Some((_, false)) if unit == TimeUnit::Ns => Err(self.err(
                at,
                format!(
                    "timestamp `{field}` has a fraction of a nanosecond; if the times are in \
                     seconds (or ms, µs), say so with --time-unit"
                ),
            )),
            Some((t, false)) => Ok(t),
            None if field.parse::<f64>().is_ok_and(f64::is_finite) => Err(self.err(
                at,
                format!("timestamp `{field}` [{unit}] is out of range for integer nanoseconds"),
            )),
            None => Err(self.err(at, format!("timestamp `{field}` is not a number [{unit}]"))),
        }
    }
}
