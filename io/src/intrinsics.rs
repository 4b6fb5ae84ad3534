//! IMU intrinsics files: OpenVINS' `kalibr_imu_chain.yaml` and Kalibr's `imu.yaml` of the
//! `scale-misalignment` model, read into [`preint::intrinsics::ImuIntrinsics`] (its module
//! docs state the model, frames and units) with the noise densities the file holds.
//!
//! # OpenVINS (`config/*/kalibr_imu_chain.yaml`, `ov_msckf/src/core/VioManagerOptions.h`)
//!
//! Under `imu0`: `Tw` (gyro axes → reading, `ω_m = Tw R_IMUtoGYRO ω_I + Tg a_I + b_g`), `Ta`
//! (accelerometer axes → reading, `a_m = Ta R_IMUtoACC a_I + b_a`), `R_IMUtoGYRO` and
//! `R_IMUtoACC` (rotate IMU-frame vectors into the sensor's axes), `Tg` (g-sensitivity
//! [(rad/s)/(m/s²)], IMU-frame specific force), `model: kalibr | calibrated | rpng`
//! (`kalibr`: `Tw`, `Ta` lower triangular, `rpng`: upper), each matrix as three rows
//! `- [ x, y, z ]`; a missing matrix is OpenVINS' default (identity, `Tg = 0`). OpenVINS uses
//! only the model's triangle of `Tw⁻¹`, `Ta⁻¹`, so a matrix outside it is refused here rather
//! than read as something OpenVINS would not use. The noise densities
//! (`gyroscope_noise_density` …) and `update_rate` are read as in Kalibr's `imu.yaml`;
//! `time_offset` \[s\] and `rostopic` are kept as the file holds them.
//!
//! `preint_scheme` (this crate's key: `euler`, `midpoint`, `hermite4` or `galilean`) names the
//! preintegration scheme the time offset was estimated for: a scheme that holds each
//! interval's first sample (euler, galilean) lags the centred ones (midpoint, hermite4) by
//! half a sample interval, which an estimated offset absorbs. OpenVINS and Kalibr read their
//! keys by name (OpenVINS' `YamlParser::parse_external(…, "imu0", key, …)`, Kalibr's
//! `ImuParameters` dictionary look-ups), so they never see it.
//!
//! # Plausibility
//! Intrinsics far from the identity are refused, naming the file, line and key: a scale
//! (diagonal of `Tw`, `Ta`) outside [`SCALE_RANGE`], a misalignment (off-diagonal entry over
//! its diagonal) or sensor-axis rotation (`R_IMUtoGYRO`, `R_IMUtoACC`) above
//! [`MAX_AXIS_ANGLE_DEG`], or a g-sensitivity entry above [`MAX_G_SENSITIVITY`]. MEMS
//! datasheets give scale errors of a few % and cross-axis sensitivities of 1–2 % (≈ 1°)
//! before calibration, and gyro g-sensitivities of 0.01–0.1 °/s/g; a file ten (a hundred for
//! `Tg`) times beyond is a unit, layout or sign error, not a sensor (`preint audit
//! --calibration` warns from closer limits: 10 % scale, 0.1 rad, 0.01 (rad/s)/(m/s²)). `preint_unusual_intrinsics: true` under
//! `imu0` accepts such a file for a sensor that really is that far from nominal.
//!
//! # Kalibr (`IccSensors.py`, `IccScaledMisalignedImu`)
//!
//! Under `imu0` (or at the top level): `model: scale-misalignment`, `gyroscopes: {M, A,
//! C_gyro_i}`, `accelerometers: {M}`, with `ω_m = M_w C_gyro_i ω_I + A C_gyro_i a_I + b_g`,
//! `a_m = M_a a_I + b_a`: `Tw = M_w`, `R_IMUtoGYRO = C_gyro_i`, `Ta = M_a`, `R_IMUtoACC = I`,
//! `Tg = A C_gyro_i`. `model: calibrated` (or no model) is the identity.

use crate::error::{IoError, Location, read_text, write_text};
use crate::number::parse_finite;
use crate::yaml::{Node, parse};
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::nalgebra::Matrix3;
use preint::{ImuNoise, Scheme};
use std::path::Path;

/// An IMU calibration file's content.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuCalibration {
    /// The intrinsics.
    pub intrinsics: ImuIntrinsics,
    /// The noise densities and rate, when the file holds all five Kalibr keys.
    pub noise: Option<ImuNoise>,
    /// `time_offset` \[s\], as the file holds it (its sign convention is the file's producer's).
    pub time_offset_s: Option<f64>,
    /// `rostopic`.
    pub rostopic: Option<String>,
    /// `preint_scheme`: the scheme the time offset was estimated for (module docs); `None`
    /// when the file does not say.
    pub scheme: Option<Scheme>,
    /// `preint_body_p_sensor`: the IMU's pose in the frame of the poses it was calibrated
    /// against ([`crate::extrinsics`]).
    pub body_p_sensor: Option<preint::SensorPose>,
}

/// Accepted range of a scale factor (a diagonal entry of `Tw`, `Ta`): ±20–25 %.
pub const SCALE_RANGE: (f64, f64) = (0.8, 1.25);
/// Largest accepted misalignment or sensor-axis rotation \[deg\].
pub const MAX_AXIS_ANGLE_DEG: f64 = 10.0;
/// Largest accepted `|Tg|` entry \[(rad/s)/(m/s²)\]: 11 °/s/g, a hundred times the 0.1 °/s/g
/// of consumer MEMS gyroscopes' datasheets (`preint audit --calibration` warns from half of it).
pub const MAX_G_SENSITIVITY: f64 = 0.02;
/// The key that accepts intrinsics beyond the plausible ranges (module docs).
pub const UNUSUAL_KEY: &str = "preint_unusual_intrinsics";

const NOISE_KEYS: [&str; 5] = [
    "gyroscope_noise_density",
    "gyroscope_random_walk",
    "accelerometer_noise_density",
    "accelerometer_random_walk",
    "update_rate",
];

/// Reading context: the file name and the key path for messages.
struct Ctx<'a> {
    source: &'a str,
}

impl Ctx<'_> {
    /// The file's content: `x` checked, and the keys both formats share.
    /// `keys`: where each matrix was read, `(name, key path, line)` (the map's line for a
    /// matrix the file does not give), for the plausibility messages.
    fn calibration(
        &self,
        x: ImuIntrinsics,
        map: &Node,
        path: &str,
        keys: &[(&str, String, u64)],
    ) -> Result<ImuCalibration, IoError> {
        let intrinsics = self.checked(x, map.line(), path)?;
        if !self.flag(map, path, UNUSUAL_KEY)? {
            self.plausible(&intrinsics, keys, path)?;
        }
        let (time_offset_s, rostopic) = self.common(map, path)?;
        Ok(ImuCalibration {
            intrinsics,
            noise: self.noise(map, path)?,
            time_offset_s,
            rostopic,
            scheme: self.scheme(map, path)?,
            body_p_sensor: crate::extrinsics::read_body_p_sensor(map, path, self.source)?,
        })
    }

    /// `preint_scheme`, if given.
    fn scheme(&self, map: &Node, path: &str) -> Result<Option<Scheme>, IoError> {
        match map.get("preint_scheme") {
            None => Ok(None),
            Some(Node::Scalar(s, l)) => Scheme::from_name(s).map(Some).ok_or_else(|| {
                self.err(
                    *l,
                    format!(
                        "`{path}preint_scheme`: `{s}` is not euler, midpoint, hermite4 or \
                         galilean"
                    ),
                )
            }),
            Some(n) => Err(self.err(n.line(), format!("`{path}preint_scheme`: expected a name"))),
        }
    }

    /// A `true`/`false` key (absent: false).
    fn flag(&self, map: &Node, path: &str, key: &str) -> Result<bool, IoError> {
        match map.get(key) {
            None => Ok(false),
            Some(Node::Scalar(s, _)) if s == "true" => Ok(true),
            Some(Node::Scalar(s, _)) if s == "false" => Ok(false),
            Some(n) => Err(self.err(n.line(), format!("`{path}{key}`: expected true or false"))),
        }
    }

    /// The plausibility limits of the module docs, the first violation named by its key and
    /// line.
    fn plausible(
        &self,
        x: &ImuIntrinsics,
        keys: &[(&str, String, u64)],
        path: &str,
    ) -> Result<(), IoError> {
        let at = |name: &str| {
            keys.iter()
                .find(|k| k.0 == name)
                .map_or((format!("{path}{name}"), 0), |k| (k.1.clone(), k.2))
        };
        let fix = format!(
            "if this sensor really is that far from nominal, add `{UNUSUAL_KEY}: true` under \
             imu0"
        );
        let refuse = |name: &str, what: String| {
            let (key, line) = at(name);
            Err(self.err(line, format!("`{key}` {what}; {fix}")))
        };
        let tan = MAX_AXIS_ANGLE_DEG.to_radians().tan();
        for (name, m) in [("Tw", &x.t_w), ("Ta", &x.t_a)] {
            for i in 0..3 {
                let d = m[(i, i)];
                if !(SCALE_RANGE.0..=SCALE_RANGE.1).contains(&d) {
                    return refuse(
                        name,
                        format!(
                            "entry ({i}, {i}) is {d}: a scale factor outside [{}, {}] is not an \
                             IMU's (a unit, layout or sign error?)",
                            SCALE_RANGE.0, SCALE_RANGE.1
                        ),
                    );
                }
            }
            for (i, j) in [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)] {
                let a = m[(i, j)] / m[(j, j)];
                if a.abs() > tan {
                    return refuse(
                        name,
                        format!(
                            "entry ({i}, {j}) is {}: a misalignment of {:.1}° (above \
                             {MAX_AXIS_ANGLE_DEG}°) is not an IMU's",
                            m[(i, j)],
                            a.atan().to_degrees().abs()
                        ),
                    );
                }
            }
        }
        for (name, r) in [
            ("R_IMUtoGYRO", &x.r_imu_to_gyro),
            ("R_IMUtoACC", &x.r_imu_to_acc),
        ] {
            let angle = ((r.trace() - 1.0) / 2.0)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            if angle > MAX_AXIS_ANGLE_DEG {
                return refuse(
                    name,
                    format!(
                        "rotates the sensor axes by {angle:.1}° (above {MAX_AXIS_ANGLE_DEG}°): \
                         the sensors' axes of an IMU agree to about a degree"
                    ),
                );
            }
        }
        let g = x.t_g.amax();
        if g > MAX_G_SENSITIVITY {
            return refuse(
                "Tg",
                format!(
                    "has an entry of {g} (rad/s)/(m/s²) ({:.2} °/s/g), above \
                     {MAX_G_SENSITIVITY} (11 °/s/g, a hundred times a MEMS datasheet's)",
                    g.to_degrees() * 9.80665
                ),
            );
        }
        Ok(())
    }

    fn err(&self, line: u64, msg: impl Into<String>) -> IoError {
        IoError::parse(self.source, Location::Line(line), msg)
    }

    fn number(&self, node: &Node, field: &str) -> Result<f64, IoError> {
        match node {
            Node::Scalar(s, l) => {
                parse_finite(s).map_err(|m| self.err(*l, format!("`{field}`: {m}")))
            }
            other => Err(self.err(other.line(), format!("`{field}`: expected a number"))),
        }
    }

    /// A 3×3 matrix given as three rows of three numbers.
    fn matrix(&self, node: &Node, field: &str) -> Result<Matrix3<f64>, IoError> {
        let shape = || {
            self.err(
                node.line(),
                format!("`{field}`: expected 3 rows of 3 numbers"),
            )
        };
        let Node::Seq(rows, _) = node else {
            return Err(shape());
        };
        if rows.len() != 3 {
            return Err(shape());
        }
        let mut m = Matrix3::zeros();
        for (i, row) in rows.iter().enumerate() {
            match row {
                Node::Seq(xs, _) if xs.len() == 3 => {
                    for (j, x) in xs.iter().enumerate() {
                        m[(i, j)] = self.number(x, &format!("{field}[{i}][{j}]"))?;
                    }
                }
                _ => return Err(shape()),
            }
        }
        Ok(m)
    }

    fn optional_matrix(
        &self,
        map: &Node,
        path: &str,
        key: &str,
        default: Matrix3<f64>,
    ) -> Result<Matrix3<f64>, IoError> {
        match map.get(key) {
            Some(n) => self.matrix(n, &format!("{path}{key}")),
            None => Ok(default),
        }
    }

    /// The five noise keys: all, none, or an error naming the first missing one.
    fn noise(&self, map: &Node, path: &str) -> Result<Option<ImuNoise>, IoError> {
        let mut v = [0.0; 5];
        let mut found = 0;
        for (i, key) in NOISE_KEYS.iter().enumerate() {
            if let Some(n) = map.get(key) {
                let x = self.number(n, &format!("{path}{key}"))?;
                if x < 0.0 || (i == 4 && x == 0.0) {
                    return Err(
                        self.err(n.line(), format!("`{path}{key}` must be positive, got {x}"))
                    );
                }
                v[i] = x;
                found += 1;
            }
        }
        if found == 0 {
            return Ok(None);
        }
        if let Some(missing) = NOISE_KEYS.iter().find(|k| map.get(k).is_none()) {
            return Err(IoError::MissingKey {
                source_name: self.source.to_string(),
                key: missing,
            });
        }
        Ok(Some(ImuNoise {
            gyro_noise_density: v[0],
            gyro_random_walk: v[1],
            acc_noise_density: v[2],
            acc_random_walk: v[3],
            update_rate_hz: v[4],
        }))
    }

    fn common(&self, map: &Node, path: &str) -> Result<(Option<f64>, Option<String>), IoError> {
        let offset = match map.get("time_offset") {
            Some(n) => Some(self.number(n, &format!("{path}time_offset"))?),
            None => None,
        };
        let topic = match map.get("rostopic") {
            Some(Node::Scalar(s, _)) => Some(s.clone()),
            Some(n) => return Err(self.err(n.line(), format!("`{path}rostopic`: expected a name"))),
            None => None,
        };
        Ok((offset, topic))
    }

    /// The intrinsics checked: the model's triangle, invertible, rotations orthonormal.
    fn checked(&self, x: ImuIntrinsics, line: u64, path: &str) -> Result<ImuIntrinsics, IoError> {
        let free = x.model.free_entries();
        for (name, m) in [("Tw", &x.t_w), ("Ta", &x.t_a)] {
            for r in 0..3 {
                for c in 0..3 {
                    if m[(r, c)] != 0.0 && !free.contains(&(r, c)) {
                        let shape = match x.model {
                            IntrinsicsModel::Kalibr => "lower",
                            IntrinsicsModel::Rpng => "upper",
                        };
                        return Err(self.err(
                            line,
                            format!(
                                "`{path}{name}` must be {shape} triangular for model `{}`: entry ({r}, {c}) is {}",
                                x.model.name(),
                                m[(r, c)]
                            ),
                        ));
                    }
                }
            }
        }
        x.validate()
            .map_err(|e| self.err(line, format!("`{path}`: {e}")))?;
        Ok(x)
    }
}

/// The `imu0` mapping (or the root when there is none) and its key prefix.
fn imu_map(root: &Node) -> (&Node, &'static str) {
    match root.get("imu0") {
        Some(m @ Node::Map(..)) => (m, "imu0."),
        _ => (root, ""),
    }
}

/// Parses an OpenVINS `kalibr_imu_chain.yaml` (module docs).
pub fn parse_openvins_imu_chain(text: &str, source_name: &str) -> Result<ImuCalibration, IoError> {
    let root = parse(text, source_name)?;
    let cx = Ctx {
        source: source_name,
    };
    let (map, path) = imu_map(&root);
    let model = match map.get("model") {
        Some(Node::Scalar(s, l)) => IntrinsicsModel::parse(s).ok_or_else(|| {
            cx.err(
                *l,
                format!("`{path}model`: `{s}` is not kalibr, calibrated or rpng"),
            )
        })?,
        Some(n) => return Err(cx.err(n.line(), format!("`{path}model`: expected a name"))),
        None => IntrinsicsModel::Kalibr,
    };
    let i = Matrix3::identity();
    let keys: Vec<(&str, String, u64)> = ["Tw", "Ta", "R_IMUtoGYRO", "R_IMUtoACC", "Tg"]
        .into_iter()
        .map(|k| {
            let line = map.get(k).map_or(map.line(), Node::line);
            (k, format!("{path}{k}"), line)
        })
        .collect();
    let x = ImuIntrinsics {
        model,
        t_w: cx.optional_matrix(map, path, "Tw", i)?,
        t_a: cx.optional_matrix(map, path, "Ta", i)?,
        r_imu_to_gyro: cx.optional_matrix(map, path, "R_IMUtoGYRO", i)?,
        r_imu_to_acc: cx.optional_matrix(map, path, "R_IMUtoACC", i)?,
        t_g: cx.optional_matrix(map, path, "Tg", Matrix3::zeros())?,
    };
    cx.calibration(x, map, path, &keys)
}

/// Parses Kalibr's `imu.yaml` with the `scale-misalignment` (or `calibrated`) model (module
/// docs).
pub fn parse_kalibr_imu(text: &str, source_name: &str) -> Result<ImuCalibration, IoError> {
    let root = parse(text, source_name)?;
    let cx = Ctx {
        source: source_name,
    };
    let (map, path) = imu_map(&root);
    let mut x = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    let mut keys: Vec<(&str, String, u64)> = Vec::new();
    match map.get("model") {
        None => {}
        Some(Node::Scalar(s, _)) if s == "calibrated" => {}
        Some(Node::Scalar(s, _)) if s == "scale-misalignment" => {
            let section = |key: &'static str| {
                map.get(key).ok_or(IoError::MissingKey {
                    source_name: source_name.to_string(),
                    key,
                })
            };
            let (g, a) = (section("gyroscopes")?, section("accelerometers")?);
            let get = |sec: &Node, name: &str, key: &'static str| match sec.get(key) {
                Some(n) => cx.matrix(n, &format!("{path}{name}.{key}")),
                None => Err(IoError::MissingKey {
                    source_name: source_name.to_string(),
                    key,
                }),
            };
            x.t_w = get(g, "gyroscopes", "M")?;
            x.r_imu_to_gyro = get(g, "gyroscopes", "C_gyro_i")?;
            x.t_g = get(g, "gyroscopes", "A")? * x.r_imu_to_gyro;
            x.t_a = get(a, "accelerometers", "M")?;
            let line = |sec: &Node, key: &str| sec.get(key).map_or(sec.line(), Node::line);
            keys = vec![
                ("Tw", format!("{path}gyroscopes.M"), line(g, "M")),
                (
                    "R_IMUtoGYRO",
                    format!("{path}gyroscopes.C_gyro_i"),
                    line(g, "C_gyro_i"),
                ),
                ("Tg", format!("{path}gyroscopes.A"), line(g, "A")),
                ("Ta", format!("{path}accelerometers.M"), line(a, "M")),
            ];
        }
        Some(n) => {
            return Err(cx.err(
                n.line(),
                format!("`{path}model`: only `calibrated` and `scale-misalignment` are read"),
            ));
        }
    }
    cx.calibration(x, map, path, &keys)
}

/// Reads an OpenVINS `kalibr_imu_chain.yaml`.
pub fn read_openvins_imu_chain(path: &Path) -> Result<ImuCalibration, IoError> {
    parse_openvins_imu_chain(&read_text(path)?, &path.display().to_string())
}

/// Reads a Kalibr `imu.yaml` with intrinsics.
pub fn read_kalibr_imu(path: &Path) -> Result<ImuCalibration, IoError> {
    parse_kalibr_imu(&read_text(path)?, &path.display().to_string())
}

fn matrix_lines(out: &mut String, key: &str, m: &Matrix3<f64>, indent: &str) {
    out.push_str(&format!("{indent}{key}:\n"));
    for r in 0..3 {
        out.push_str(&format!(
            "{indent}  - [ {:?}, {:?}, {:?} ]\n",
            m[(r, 0)],
            m[(r, 1)],
            m[(r, 2)]
        ));
    }
}

fn header_lines(out: &mut String, cal: &ImuCalibration) {
    if let Some(n) = &cal.noise {
        out.push_str(&format!(
            "  accelerometer_noise_density: {:?}  # [ m / s^2 / sqrt(Hz) ]\n  \
             accelerometer_random_walk: {:?}  # [ m / s^3 / sqrt(Hz) ]\n  \
             gyroscope_noise_density: {:?}  # [ rad / s / sqrt(Hz) ]\n  \
             gyroscope_random_walk: {:?}  # [ rad / s^2 / sqrt(Hz) ]\n  \
             update_rate: {:?}  # [ Hz ]\n",
            n.acc_noise_density,
            n.acc_random_walk,
            n.gyro_noise_density,
            n.gyro_random_walk,
            n.update_rate_hz
        ));
    }
    if let Some(t) = &cal.rostopic {
        out.push_str(&format!("  rostopic: {t}\n"));
    }
    if let Some(t) = cal.time_offset_s {
        out.push_str(&format!("  time_offset: {t:?}  # [ s ]\n"));
    }
    if let Some(s) = cal.scheme {
        out.push_str(&format!(
            "  preint_scheme: \"{}\"  # the preint scheme time_offset was estimated for\n",
            s.name()
        ));
    }
    if let Some(x) = &cal.body_p_sensor {
        out.push_str(&crate::extrinsics::body_p_sensor_line(x));
    }
}

/// OpenVINS `kalibr_imu_chain.yaml` text for `cal` (every number written exactly).
pub fn openvins_imu_chain_string(cal: &ImuCalibration) -> String {
    let x = &cal.intrinsics;
    let mut out = String::from("%YAML:1.0\n\nimu0:\n");
    header_lines(&mut out, cal);
    out.push_str(&format!("  model: \"{}\"\n", x.model.name()));
    matrix_lines(&mut out, "Tw", &x.t_w, "  ");
    matrix_lines(&mut out, "R_IMUtoGYRO", &x.r_imu_to_gyro, "  ");
    matrix_lines(&mut out, "Ta", &x.t_a, "  ");
    matrix_lines(&mut out, "R_IMUtoACC", &x.r_imu_to_acc, "  ");
    matrix_lines(&mut out, "Tg", &x.t_g, "  ");
    out
}

/// Kalibr `imu.yaml` text (`scale-misalignment`) for `cal`; an error when the intrinsics are
/// not of that model (`rpng`, or `R_IMUtoACC ≠ I`), naming `name` as the destination.
pub fn kalibr_imu_string(cal: &ImuCalibration, name: &str) -> Result<String, IoError> {
    let x = &cal.intrinsics;
    if x.model != IntrinsicsModel::Kalibr || x.r_imu_to_acc != Matrix3::identity() {
        return Err(IoError::format(
            name,
            "Kalibr's scale-misalignment model has lower-triangular matrices and no \
             accelerometer rotation: write an OpenVINS file for these intrinsics",
        ));
    }
    let mut out = String::from("imu0:\n");
    header_lines(&mut out, cal);
    out.push_str("  model: scale-misalignment\n  gyroscopes:\n");
    matrix_lines(&mut out, "M", &x.t_w, "    ");
    matrix_lines(
        &mut out,
        "A",
        &(x.t_g * x.r_imu_to_gyro.transpose()),
        "    ",
    );
    matrix_lines(&mut out, "C_gyro_i", &x.r_imu_to_gyro, "    ");
    out.push_str("  accelerometers:\n");
    matrix_lines(&mut out, "M", &x.t_a, "    ");
    Ok(out)
}

/// Writes an OpenVINS `kalibr_imu_chain.yaml`.
pub fn write_openvins_imu_chain(path: &Path, cal: &ImuCalibration) -> Result<(), IoError> {
    write_text(path, &openvins_imu_chain_string(cal))
}

/// Writes a Kalibr `imu.yaml` ([`kalibr_imu_string`]).
pub fn write_kalibr_imu(path: &Path, cal: &ImuCalibration) -> Result<(), IoError> {
    write_text(path, &kalibr_imu_string(cal, &path.display().to_string())?)
}
