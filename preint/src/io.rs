//! Readers and writers for the EuRoC / ASL formats and Kalibr's `imu.yaml`.
//!
//! - IMU (`mav0/imu0/data.csv`): a header line starting with `#`, then
//!   `timestamp [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s²]` (gyro first, body frame,
//!   accelerometer = specific force).
//! - Ground truth (`state_groundtruth_estimate0/data.csv`, also OpenVINS' vicon2gt files):
//!   `timestamp [ns], p_x, p_y, p_z [m], q_w, q_x, q_y, q_z (body→world), v_x, v_y, v_z [m/s],
//!   b_w_x, b_w_y, b_w_z [rad/s], b_a_x, b_a_y, b_a_z [m/s²]`.
//! - Kalibr `imu.yaml`: continuous-time densities (see [`ImuNoise`]).
//!
//! Every reader error names the source, the 1-based line and the problem. Writers print floats
//! in Rust's shortest round-trip form, so writing then reading is bit-exact.

use crate::noise::ImuNoise;
use crate::sample::{ImuBias, ImuSample};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint_lie::SO3;
use std::fmt::Write as _;
use std::path::Path;

/// Errors from reading or writing files.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    File {
        /// Path of the file.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A line is malformed.
    #[error("{source_name}:{line}: {msg}")]
    Parse {
        /// File name (or another label for in-memory text).
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// What is wrong.
        msg: String,
    },
    /// The file holds no data rows.
    #[error("{source_name}: no data rows")]
    Empty {
        /// File name.
        source_name: String,
    },
    /// A required key is missing (Kalibr yaml).
    #[error("{source_name}: missing key `{key}`")]
    MissingKey {
        /// File name.
        source_name: String,
        /// The key.
        key: &'static str,
    },
    /// The values look like they are in the wrong units.
    #[error("{source_name}: {msg}")]
    Units {
        /// File name.
        source_name: String,
        /// What looks wrong, and the likely fix.
        msg: String,
    },
}

fn read_text(path: &Path) -> Result<String, IoError> {
    std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.display().to_string(),
        source,
    })
}

fn write_text(path: &Path, text: &str) -> Result<(), IoError> {
    std::fs::write(path, text).map_err(|source| IoError::File {
        path: path.display().to_string(),
        source,
    })
}

/// Splits CSV text into data rows (1-based line number, fields), skipping blank lines and
/// lines starting with `#`.
fn data_rows(text: &str) -> impl Iterator<Item = (u64, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, l)| {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            None
        } else {
            Some((i as u64 + 1, l.split(',').map(str::trim).collect()))
        }
    })
}

struct RowCtx<'a> {
    source_name: &'a str,
    line: u64,
}

impl RowCtx<'_> {
    fn err(&self, msg: String) -> IoError {
        IoError::Parse {
            source_name: self.source_name.to_string(),
            line: self.line,
            msg,
        }
    }

    fn timestamp(&self, s: &str) -> Result<i64, IoError> {
        s.parse::<i64>().map_err(|_| {
            if s.parse::<f64>().is_ok() {
                self.err(format!(
                    "timestamp `{s}` is not an integer; expected integer nanoseconds \
                     (seconds would need converting: ns = s·1e9)"
                ))
            } else {
                self.err(format!("timestamp `{s}` is not an integer [ns]"))
            }
        })
    }

    fn finite(&self, s: &str, col: usize, what: &str) -> Result<f64, IoError> {
        let v: f64 = s
            .parse()
            .map_err(|_| self.err(format!("column {col} ({what}): `{s}` is not a number")))?;
        if !v.is_finite() {
            return Err(self.err(format!("column {col} ({what}): value `{s}` is not finite")));
        }
        Ok(v)
    }

    fn vec3(&self, f: &[&str], start: usize, what: &str) -> Result<Vector3<f64>, IoError> {
        Ok(Vector3::new(
            self.finite(f[start], start + 1, what)?,
            self.finite(f[start + 1], start + 2, what)?,
            self.finite(f[start + 2], start + 3, what)?,
        ))
    }

    fn increasing(&self, prev: Option<i64>, t: i64) -> Result<(), IoError> {
        match prev {
            Some(p) if t == p => Err(self.err(format!("duplicate timestamp {t} ns"))),
            Some(p) if t < p => {
                Err(self.err(format!("timestamp {t} ns decreases (previous row {p} ns)")))
            }
            _ => Ok(()),
        }
    }
}

/// Parses EuRoC IMU CSV text. `source_name` labels error messages (usually the path).
/// Rejects wrong column counts, non-numeric or non-finite values, non-integer timestamps and
/// duplicate or decreasing timestamps, naming the line.
pub fn parse_euroc_imu(text: &str, source_name: &str) -> Result<Vec<ImuSample>, IoError> {
    let mut out = Vec::new();
    let mut prev = None;
    for (line, f) in data_rows(text) {
        let ctx = RowCtx { source_name, line };
        if f.len() != 7 {
            return Err(ctx.err(format!(
                "expected 7 columns (timestamp [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s²]), found {}",
                f.len()
            )));
        }
        let t_ns = ctx.timestamp(f[0])?;
        ctx.increasing(prev, t_ns)?;
        prev = Some(t_ns);
        let gyro = ctx.vec3(&f, 1, "gyro [rad/s]")?;
        let acc = ctx.vec3(&f, 4, "accelerometer [m/s²]")?;
        out.push(ImuSample { t_ns, gyro, acc });
    }
    if out.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    Ok(out)
}

/// Reads an EuRoC IMU CSV file (see [`parse_euroc_imu`]).
pub fn read_euroc_imu(path: &Path) -> Result<Vec<ImuSample>, IoError> {
    parse_euroc_imu(&read_text(path)?, &path.display().to_string())
}

/// EuRoC IMU CSV text for `samples` (lossless).
pub fn euroc_imu_string(samples: &[ImuSample]) -> String {
    let mut s = String::with_capacity(samples.len() * 120 + 200);
    s.push_str(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],\
         a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
    );
    for x in samples {
        let (g, a) = (x.gyro, x.acc);
        let _ = writeln!(
            s,
            "{},{:?},{:?},{:?},{:?},{:?},{:?}",
            x.t_ns, g.x, g.y, g.z, a.x, a.y, a.z
        );
    }
    s
}

/// Writes an EuRoC IMU CSV file (lossless: reading it back gives identical samples).
pub fn write_euroc_imu(path: &Path, samples: &[ImuSample]) -> Result<(), IoError> {
    write_text(path, &euroc_imu_string(samples))
}

/// Checks that IMU samples look like SI units for an IMU near the Earth's surface: the median
/// accelerometer norm must lie in [4, 20] m/s² (data in g reads ≈ 1) and the median gyro norm
/// below 20 rad/s (data in deg/s of a moving IMU reads tens to hundreds).
pub fn check_si_units(samples: &[ImuSample], source_name: &str) -> Result<(), IoError> {
    if samples.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let acc = median(samples.iter().map(|s| s.acc.norm()).collect());
    let gyro = median(samples.iter().map(|s| s.gyro.norm()).collect());
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    if !(4.0..=20.0).contains(&acc) {
        return Err(units(format!(
            "median accelerometer norm is {acc:.4}; expected about 9.81 m/s² (specific force). \
             If the data is in g, multiply by 9.80665"
        )));
    }
    if gyro > 20.0 {
        return Err(units(format!(
            "median gyro norm is {gyro:.2}; expected rad/s. If the data is in deg/s, multiply by π/180"
        )));
    }
    Ok(())
}

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

/// Parses EuRoC ground-truth CSV text (17 columns, see the module docs). Quaternions must have a
/// norm within 1e-3 of one (they are re-normalised when off by more than 1e-12).
pub fn parse_euroc_groundtruth(
    text: &str,
    source_name: &str,
) -> Result<Vec<GroundTruthState>, IoError> {
    let mut out = Vec::new();
    let mut prev = None;
    for (line, f) in data_rows(text) {
        let ctx = RowCtx { source_name, line };
        if f.len() != 17 {
            return Err(ctx.err(format!(
                "expected 17 columns (timestamp [ns], p [m] ×3, q w,x,y,z, v [m/s] ×3, b_g [rad/s] ×3, \
                 b_a [m/s²] ×3), found {}",
                f.len()
            )));
        }
        let t_ns = ctx.timestamp(f[0])?;
        ctx.increasing(prev, t_ns)?;
        prev = Some(t_ns);
        let p = ctx.vec3(&f, 1, "position [m]")?;
        let qv = [
            ctx.finite(f[4], 5, "q_w")?,
            ctx.finite(f[5], 6, "q_x")?,
            ctx.finite(f[6], 7, "q_y")?,
            ctx.finite(f[7], 8, "q_z")?,
        ];
        let raw = Quaternion::new(qv[0], qv[1], qv[2], qv[3]);
        let n = raw.norm();
        if (n - 1.0).abs() > 1e-3 {
            return Err(ctx.err(format!(
                "quaternion (w,x,y,z) has norm {n}; expected a unit quaternion"
            )));
        }
        let q = if (n - 1.0).abs() > 1e-12 {
            UnitQuaternion::new_normalize(raw)
        } else {
            UnitQuaternion::new_unchecked(raw)
        };
        let v = ctx.vec3(&f, 8, "velocity [m/s]")?;
        let bg = ctx.vec3(&f, 11, "gyro bias [rad/s]")?;
        let ba = ctx.vec3(&f, 14, "accelerometer bias [m/s²]")?;
        out.push(GroundTruthState {
            t_ns,
            p,
            q,
            v,
            bias: ImuBias::new(bg, ba),
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

/// The Kalibr keys, in the order they are written.
const KALIBR_KEYS: [&str; 5] = [
    "gyroscope_noise_density",
    "gyroscope_random_walk",
    "accelerometer_noise_density",
    "accelerometer_random_walk",
    "update_rate",
];

/// Parses a Kalibr `imu.yaml` (flat `key: value` lines; `#` comments and unknown keys such as
/// `rostopic` are ignored). All five keys of `KALIBR_KEYS` are required; values must be finite
/// and non-negative (`update_rate` positive).
pub fn parse_kalibr_yaml(text: &str, source_name: &str) -> Result<ImuNoise, IoError> {
    let mut vals: [Option<f64>; 5] = [None; 5];
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some((k, v)) = line.split_once(':') else {
            continue;
        };
        let Some(idx) = KALIBR_KEYS.iter().position(|key| *key == k.trim()) else {
            continue;
        };
        let ctx = RowCtx {
            source_name,
            line: i as u64 + 1,
        };
        let x = ctx.finite(v.trim(), 2, KALIBR_KEYS[idx])?;
        if x < 0.0 || (idx == 4 && x == 0.0) {
            return Err(ctx.err(format!("`{}` must be positive, got {x}", KALIBR_KEYS[idx])));
        }
        vals[idx] = Some(x);
    }
    let get = |i: usize| {
        vals[i].ok_or(IoError::MissingKey {
            source_name: source_name.to_string(),
            key: KALIBR_KEYS[i],
        })
    };
    Ok(ImuNoise {
        gyro_noise_density: get(0)?,
        gyro_random_walk: get(1)?,
        acc_noise_density: get(2)?,
        acc_random_walk: get(3)?,
        update_rate_hz: get(4)?,
    })
}

/// Reads a Kalibr `imu.yaml` (see [`parse_kalibr_yaml`]).
pub fn read_kalibr_yaml(path: &Path) -> Result<ImuNoise, IoError> {
    parse_kalibr_yaml(&read_text(path)?, &path.display().to_string())
}

/// Kalibr `imu.yaml` text for `noise`, with the units in comments (lossless).
pub fn kalibr_yaml_string(noise: &ImuNoise) -> String {
    format!(
        "# IMU noise model (Kalibr format): continuous-time densities, not per-sample std.\n\
         # per-sample white-noise std = density / sqrt(dt); bias step std = random_walk * sqrt(dt)\n\
         rostopic: /imu0\n\
         gyroscope_noise_density: {:?}      # [ rad / s / sqrt(Hz) ]\n\
         gyroscope_random_walk: {:?}        # [ rad / s^2 / sqrt(Hz) ]\n\
         accelerometer_noise_density: {:?}  # [ m / s^2 / sqrt(Hz) ]\n\
         accelerometer_random_walk: {:?}    # [ m / s^3 / sqrt(Hz) ]\n\
         update_rate: {:?}                  # [ Hz ]\n",
        noise.gyro_noise_density,
        noise.gyro_random_walk,
        noise.acc_noise_density,
        noise.acc_random_walk,
        noise.update_rate_hz
    )
}

/// Writes a Kalibr `imu.yaml`.
pub fn write_kalibr_yaml(path: &Path, noise: &ImuNoise) -> Result<(), IoError> {
    write_text(path, &kalibr_yaml_string(noise))
}
