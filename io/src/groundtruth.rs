//! EuRoC ground truth (`state_groundtruth_estimate0/data.csv`, also OpenVINS' vicon2gt files):
//! `timestamp [ns], p_x, p_y, p_z [m], q_w, q_x, q_y, q_z (body→world), v_x, v_y, v_z [m/s],
//! b_w_x, b_w_y, b_w_z [rad/s], b_a_x, b_a_y, b_a_z [m/s²]`.

use crate::error::{IoError, Location, read_text, write_text};
use crate::lines::LineReader;
use crate::number::{parse_finite, parse_scaled};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint::ImuBias;
use preint_lie::SO3;
use std::fmt::Write as _;
use std::path::Path;

/// One row of an EuRoC ground-truth file: the full state of the body at `t_ns`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundTruthState {
    /// Timestamp \[ns\].
    pub t_ns: i64,
    /// Position of the body in the world frame \[m\].
    pub p: Vector3<f64>,
    /// Attitude, body→world (Hamilton; `v_world = q v_body q⁻¹`).
    pub q: UnitQuaternion<f64>,
    /// Velocity in the world frame [m/s].
    pub v: Vector3<f64>,
    /// IMU biases at this time (gyro [rad/s], accelerometer [m/s²]).
    pub bias: ImuBias,
}

impl GroundTruthState {
    /// The attitude as a rotation matrix (body→world).
    pub fn rotation(&self) -> SO3 {
        SO3::from_quaternion(&self.q)
    }
}

const WHAT: [&str; 17] = [
    "timestamp [ns]",
    "p_x [m]",
    "p_y [m]",
    "p_z [m]",
    "q_w",
    "q_x",
    "q_y",
    "q_z",
    "v_x [m/s]",
    "v_y [m/s]",
    "v_z [m/s]",
    "b_g_x [rad/s]",
    "b_g_y [rad/s]",
    "b_g_z [rad/s]",
    "b_a_x [m/s²]",
    "b_a_y [m/s²]",
    "b_a_z [m/s²]",
];

/// One data row's 16 values after the timestamp, or the error naming line and column.
fn row_values(fields: &[&str], name: &str, at: Location) -> Result<[f64; 16], IoError> {
    let mut v = [0.0; 16];
    for (k, x) in v.iter_mut().enumerate() {
        *x = parse_finite(fields[k + 1]).map_err(|m| {
            IoError::parse(name, at, format!("column {} ({}): {m}", k + 2, WHAT[k + 1]))
        })?;
    }
    Ok(v)
}

/// The unit quaternion of `v[3..7]` (w, x, y, z; `v` holds at least 7 values); norm within 1e-3 of one (re-normalised
/// when off by more than 1e-12).
pub(crate) fn unit_quaternion(
    v: &[f64],
    name: &str,
    at: Location,
) -> Result<UnitQuaternion<f64>, IoError> {
    let raw = Quaternion::new(v[3], v[4], v[5], v[6]);
    let n = raw.norm();
    if (n - 1.0).abs() > 1e-3 {
        return Err(IoError::parse(
            name,
            at,
            format!("quaternion (w,x,y,z) has norm {n}; expected a unit quaternion"),
        ));
    }
    Ok(if (n - 1.0).abs() > 1e-12 {
        UnitQuaternion::new_normalize(raw)
    } else {
        UnitQuaternion::new_unchecked(raw)
    })
}

/// The integer-ns timestamp of a row, strictly after the previous row's `prev`; the error
/// names the line.
pub(crate) fn timestamp(
    field: &str,
    prev: Option<i64>,
    name: &str,
    at: Location,
) -> Result<i64, IoError> {
    let t_ns = match parse_scaled(field, 0) {
        Some((t, true)) => t,
        _ => {
            return Err(IoError::parse(
                name,
                at,
                format!("timestamp `{field}` is not an integer [ns]"),
            ));
        }
    };
    if let Some(prev) = prev.filter(|&p| t_ns <= p) {
        let what = if t_ns == prev {
            "duplicate"
        } else {
            "decreasing"
        };
        return Err(IoError::parse(
            name,
            at,
            format!("{what} timestamp {t_ns} ns (previous row {prev} ns)"),
        ));
    }
    Ok(t_ns)
}

/// Parses EuRoC ground-truth CSV text (17 columns, see the module docs): `#` lines are
/// comments, timestamps are integer ns and strictly increasing, values finite, quaternions
/// unit (norm within 1e-3 of one, re-normalised when off by more than 1e-12).
pub fn parse_euroc_groundtruth(
    text: &str,
    source_name: &str,
) -> Result<Vec<GroundTruthState>, IoError> {
    let mut out: Vec<GroundTruthState> = Vec::new();
    let mut lines = LineReader::new(text.as_bytes(), source_name);
    while let Some(line) = lines.next_line()? {
        let (at, text) = (line.at, line.text.trim());
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != 17 {
            return Err(IoError::parse(
                source_name,
                at,
                format!(
                    "expected 17 columns (timestamp [ns], p [m] ×3, q w,x,y,z, v [m/s] ×3, \
                     b_g [rad/s] ×3, b_a [m/s²] ×3), found {}",
                    fields.len()
                ),
            ));
        }
        let t_ns = timestamp(fields[0], out.last().map(|s| s.t_ns), source_name, at)?;
        let v = row_values(&fields, source_name, at)?;
        out.push(GroundTruthState {
            t_ns,
            p: Vector3::new(v[0], v[1], v[2]),
            q: unit_quaternion(&v, source_name, at)?,
            v: Vector3::new(v[7], v[8], v[9]),
            bias: ImuBias::new(
                Vector3::new(v[10], v[11], v[12]),
                Vector3::new(v[13], v[14], v[15]),
            ),
        });
    }
    if out.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    Ok(out)
}

/// Reads an EuRoC ground-truth CSV file (see [`parse_euroc_groundtruth`]).
pub fn read_euroc_groundtruth(path: &Path) -> Result<Vec<GroundTruthState>, IoError> {
    parse_euroc_groundtruth(&read_text(path)?, &path.display().to_string())
}

/// EuRoC ground-truth CSV text (lossless).
pub fn euroc_groundtruth_string(states: &[GroundTruthState]) -> String {
    let mut s = String::with_capacity(states.len() * 300 + 400);
    s.push_str(
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], \
         q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], \
         b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], \
         b_a_RS_S_z [m s^-2]\n",
    );
    for x in states {
        let q = x.q.quaternion();
        let vals = [
            x.p.x,
            x.p.y,
            x.p.z,
            q.w,
            q.i,
            q.j,
            q.k,
            x.v.x,
            x.v.y,
            x.v.z,
            x.bias.gyro.x,
            x.bias.gyro.y,
            x.bias.gyro.z,
            x.bias.acc.x,
            x.bias.acc.y,
            x.bias.acc.z,
        ];
        let _ = write!(s, "{}", x.t_ns);
        for v in vals {
            let _ = write!(s, ",{v:?}");
        }
        s.push('\n');
    }
    s
}

/// Writes an EuRoC ground-truth CSV file (lossless).
pub fn write_euroc_groundtruth(path: &Path, states: &[GroundTruthState]) -> Result<(), IoError> {
    write_text(path, &euroc_groundtruth_string(states))
}
