//! EuRoC / ASL IMU CSV (`mav0/imu0/data.csv`, also TUM-VI): a header line starting with `#`,
//! then `timestamp [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s²]` (gyro first, body frame,
//! accelerometer = specific force). Writers print floats in Rust's shortest round-trip form, so
//! writing then reading is bit-exact.

use crate::error::{IoError, write_text};
use crate::reader::{ImuReader, ReadOptions};
use preint::ImuSample;
use std::fmt::Write as _;
use std::path::Path;

/// Parses EuRoC IMU CSV text ([`ImuReader::from_text`] with the EuRoC format): rejects wrong
/// column counts, non-numeric or non-finite values, fractional-ns timestamps and duplicate or
/// decreasing timestamps, naming the line.
pub fn parse_euroc_imu(text: &str, source_name: &str) -> Result<Vec<ImuSample>, IoError> {
    ImuReader::from_text(text, source_name, &ReadOptions::euroc())?.read_all()
}

/// Reads an EuRoC IMU CSV file (see [`parse_euroc_imu`]).
pub fn read_euroc_imu(path: &Path) -> Result<Vec<ImuSample>, IoError> {
    ImuReader::open(path, &ReadOptions::euroc())?.read_all()
}

/// The EuRoC IMU header line (with its line end).
pub const EUROC_IMU_HEADER: &str = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],\
w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";

/// Appends one EuRoC IMU row for `x` to `s` (lossless).
pub fn push_euroc_row(s: &mut String, x: &ImuSample) {
    let (g, a) = (x.gyro, x.acc);
    let _ = writeln!(
        s,
        "{},{:?},{:?},{:?},{:?},{:?},{:?}",
        x.t_ns, g.x, g.y, g.z, a.x, a.y, a.z
    );
}

/// Writes the samples of `samples` as EuRoC IMU CSV to `out` as they come (bounded memory);
/// returns the number written. The first reader error stops it.
pub fn write_euroc_stream(
    out: &mut impl std::io::Write,
    samples: impl Iterator<Item = Result<ImuSample, IoError>>,
    out_name: &str,
) -> Result<u64, IoError> {
    let file_err = |e| IoError::File {
        path: out_name.to_string(),
        source: e,
    };
    out.write_all(EUROC_IMU_HEADER.as_bytes())
        .map_err(file_err)?;
    let (mut n, mut row) = (0u64, String::with_capacity(160));
    for s in samples {
        let s = s?;
        let finite = s.gyro.iter().chain(s.acc.iter()).all(|v| v.is_finite());
        if !finite {
            return Err(IoError::NotFinite {
                path: out_name.to_string(),
                line: n as usize + 2,
                text: format!(
                    "sample {n} (t = {} ns): gyro [{}, {}, {}], acc [{}, {}, {}]",
                    s.t_ns, s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z
                ),
            });
        }
        row.clear();
        push_euroc_row(&mut row, &s);
        out.write_all(row.as_bytes()).map_err(file_err)?;
        n += 1;
    }
    out.flush().map_err(file_err)?;
    Ok(n)
}

/// EuRoC IMU CSV text for `samples` (lossless).
pub fn euroc_imu_string(samples: &[ImuSample]) -> String {
    let mut s = String::with_capacity(samples.len() * 120 + 200);
    s.push_str(EUROC_IMU_HEADER);
    for x in samples {
        push_euroc_row(&mut s, x);
    }
    s
}

/// Writes an EuRoC IMU CSV file (lossless: reading it back gives identical samples).
pub fn write_euroc_imu(path: &Path, samples: &[ImuSample]) -> Result<(), IoError> {
    write_text(path, &euroc_imu_string(samples))
}
