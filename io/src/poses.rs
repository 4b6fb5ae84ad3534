//! Known poses for calibration (`preint calibrate --poses`), one per row, comma-separated,
//! comment lines skipped as in every text reader ([`crate::lines::is_comment`]), in one of
//! three layouts told apart by the column count of the first row:
//! - 17 columns: EuRoC ground truth ([`crate::groundtruth`]; velocities and biases ignored);
//! - 8 columns: `timestamp [ns], p_x, p_y, p_z [m], q_w, q_x, q_y, q_z` (body→world);
//! - 5 columns: `timestamp [ns], q_w, q_x, q_y, q_z`: attitudes only (motion capture of
//!   orientation), for a gyroscope-only calibration.
//!
//! Timestamps are integer ns and strictly increasing, values finite, quaternions unit (norm
//! within 1e-3 of one, re-normalised); every row has the first row's column count. Errors name
//! the file, line and column.

use crate::error::{IoError, Location, read_text};
use crate::groundtruth::{timestamp, unit_quaternion};
use crate::lines::LineReader;
use crate::number::parse_finite;
use nalgebra::{UnitQuaternion, Vector3};
use std::path::Path;

/// One known pose: time, attitude (body→world) and, unless the file holds attitudes only, the
/// position \[m, world\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseRow {
    /// Timestamp \[ns\].
    pub t_ns: i64,
    /// Attitude body→world (Hamilton).
    pub q: UnitQuaternion<f64>,
    /// Position \[m\]; `None` in a 5-column file.
    pub p: Option<Vector3<f64>>,
}

/// Parses pose text (module docs).
pub fn parse_poses(text: &str, source_name: &str) -> Result<Vec<PoseRow>, IoError> {
    let mut out: Vec<PoseRow> = Vec::new();
    let mut width: Option<usize> = None;
    let mut lines = LineReader::new(text.as_bytes(), source_name);
    while let Some(parsed) = lines.next_row(|text, at| {
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        let layouts = "17 (EuRoC ground truth), 8 (timestamp [ns], p [m] ×3, q w,x,y,z) or 5 \
                       (timestamp [ns], q w,x,y,z)";
        let n = *width.get_or_insert(fields.len());
        if ![5, 8, 17].contains(&n) {
            return Err(IoError::parse(
                source_name,
                at,
                format!(
                    "the first row has {n} columns; a pose file has {layouts}, comma-separated"
                ),
            ));
        }
        if fields.len() != n {
            return Err(IoError::parse(
                source_name,
                at,
                format!(
                    "{} columns, where the first row has {n} (every row of a pose file has the \
                     same layout: {layouts})",
                    fields.len()
                ),
            ));
        }
        row(&fields, out.last().map(|r| r.t_ns), source_name, at).map(Some)
    }) {
        out.push(parsed?);
    }
    if out.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    Ok(out)
}

/// One data row of 5, 8 or 17 fields.
fn row(fields: &[&str], prev: Option<i64>, name: &str, at: Location) -> Result<PoseRow, IoError> {
    let t_ns = timestamp(fields[0], prev, name, at)?;
    let with_p = fields.len() != 5;
    let count = if with_p { 7 } else { 4 };
    // The values as p ×3 then q ×4 (p zero when absent), for `unit_quaternion`'s layout.
    let mut v = [0.0; 7];
    for k in 0..count {
        let slot = if with_p { k } else { k + 3 };
        v[slot] = parse_finite(fields[k + 1])
            .map_err(|m| IoError::parse(name, at, format!("column {}: {m}", k + 2)))?;
    }
    Ok(PoseRow {
        t_ns,
        q: unit_quaternion(&v, name, at)?,
        p: with_p.then(|| Vector3::new(v[0], v[1], v[2])),
    })
}

/// Reads a pose file (module docs).
pub fn read_poses(path: &Path) -> Result<Vec<PoseRow>, IoError> {
    parse_poses(&read_text(path)?, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_layouts_and_their_errors() {
        let q = "0.7071067811865476,0,0,0.7071067811865476";
        let att = parse_poses(&format!("#t,q\n100,{q}\n200,1,0,0,0\n"), "a.csv").unwrap();
        assert_eq!(att.len(), 2);
        assert_eq!(att[0].p, None);
        assert!((att[0].q.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let tp = parse_poses(&format!("100,1,2,3,{q}\n"), "b.csv").unwrap();
        assert_eq!(tp[0].p, Some(Vector3::new(1.0, 2.0, 3.0)));
        let euroc = format!("100,1,2,3,{q},0,0,0,0,0,0,0,0,0\n");
        assert_eq!(parse_poses(&euroc, "c.csv").unwrap()[0].p, tp[0].p);
        let msg = |t: &str| parse_poses(t, "d.csv").unwrap_err().to_string();
        assert!(msg(&format!("100,{q}\n200,1,2,3,{q}\n")).starts_with("d.csv:2: "));
        assert!(msg("100,1,0,0\n").contains("the first row has 4 columns"));
        let e = msg(&format!("100,1,2,3,{q}\n200,{q}\n"));
        assert!(
            e.starts_with("d.csv:2: 5 columns, where the first row has 8"),
            "{e}"
        );
        let e = msg("100,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15\n");
        assert!(
            e.contains("has 16 columns") && !e.contains("found 16"),
            "{e}"
        );
        assert!(msg(&format!("100,{q}\n100,{q}\n")).contains("duplicate"));
        assert!(msg("100,2,0,0,0\n").contains("norm"));
        assert!(msg("100,nan,0,0,1\n").contains("column 2"));
    }
}
