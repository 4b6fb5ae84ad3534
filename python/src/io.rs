//! The input layer from Python: IMU recordings (EuRoC/TUM-VI CSV, UZH-FPV, KITTI, any delimited
//! text in any units, ROS 1 bag, MCAP, ROS 2 `.db3`, split gyro/accelerometer recordings) and
//! EuRoC ground truth as numpy arrays, and the recording audit as a dict.
//!
//! Every reader is the Rust one (`preint_io`, driven by `preint_analysis::ImuInput` as the
//! command line's reader flags drive it, so the options, detection, unit checks and messages
//! are those of `preint --imu ...`): samples in SI
//! units (rad/s, m/s², sensor frame) with integer-nanosecond timestamps, validated (finite,
//! strictly increasing), a bad file raising `preint.InputError` whose message names the file and
//! the line (text) or message (containers). `read_imu` holds at most the Rust reader's bound of
//! samples (`preint_io::reader::DEFAULT_MAX_SAMPLES`, refused before allocating); the GIL is
//! released while Rust reads.

use crate::errors::{Class, new_err, raise};
use crate::params::PyNoise;
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2};
use preint::ImuSample;
use preint_analysis::{Error, ImuInput};
use preint_io::layout::parse_columns;
use preint_io::{Format, GroundTruthState, SourceInfo, read_euroc_groundtruth};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// An analysis error as a typed exception: a reader error as `InputError` (kind: the
/// `IoError` variant), an invalid option as `ShapeError` (kind `"Usage"`), a failed
/// computation as `failed` (kind `"Failed"`).
pub(crate) fn analysis_err(e: Error, failed: Class) -> PyErr {
    match e {
        Error::Io(e) => raise(Class::Input, e),
        Error::Usage(m) => new_err(Class::Shape, "Usage", m),
        Error::Failed(m) => new_err(failed, "Failed", m),
    }
}

/// A JSON value (as the command line prints it) as the equal Python object (dict, list, float,
/// int, str, bool, None), through the standard library's `json.loads`.
pub(crate) fn json_py<'py>(
    py: Python<'py>,
    v: &impl std::fmt::Display,
) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

/// The options that choose how a recording is read (the command line's `--imu`/`--gyro`/
/// `--accel`, `--format`, `--columns`, `--delimiter`, the unit flags, `--topic`,
/// `--gyro-topic`/`--accel-topic`, `--stamp`, `--no-unit-check`).
#[derive(Default)]
pub(crate) struct ReadArgs {
    pub path: Option<PathBuf>,
    pub gyro: Option<PathBuf>,
    pub accel: Option<PathBuf>,
    pub format: Option<String>,
    pub columns: Option<String>,
    pub delimiter: Option<String>,
    pub time_unit: Option<String>,
    pub gyro_unit: Option<String>,
    pub accel_unit: Option<String>,
    pub topic: Option<String>,
    pub gyro_topic: Option<String>,
    pub accel_topic: Option<String>,
    pub stamp: Option<String>,
    pub check_units: bool,
}

/// `name`'s value parsed by `FromStr`, an unknown one raising `ShapeError` with the choices.
fn parse_opt<T: std::str::FromStr<Err = String>>(
    name: &str,
    v: &Option<String>,
) -> PyResult<Option<T>> {
    v.as_deref()
        .map(|s| {
            s.parse::<T>()
                .map_err(|e| new_err(Class::Shape, "Usage", format!("{name}: {e}")))
        })
        .transpose()
}

/// The reader options a function taking a recording accepts as keyword arguments besides
/// `path`, `gyro` and `accel` (the command line's reader flags; documented in `_native.pyi`).
const READER_OPTIONS: [&str; 11] = [
    "format",
    "columns",
    "delimiter",
    "time_unit",
    "gyro_unit",
    "accel_unit",
    "topic",
    "gyro_topic",
    "accel_topic",
    "stamp",
    "check_units",
];

impl ReadArgs {
    /// The recording `path` (or the split pair `gyro`, `accel`) and the keyword options
    /// `options` (names in [`READER_OPTIONS`]; an unknown name or a value of the wrong type
    /// raises `ShapeError` of kind "Usage").
    pub(crate) fn from_options(
        path: Option<PathBuf>,
        gyro: Option<PathBuf>,
        accel: Option<PathBuf>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let usage = |m: String| new_err(Class::Shape, "Usage", m);
        let mut a = ReadArgs {
            path,
            gyro,
            accel,
            format: None,
            columns: None,
            delimiter: None,
            time_unit: None,
            gyro_unit: None,
            accel_unit: None,
            topic: None,
            gyro_topic: None,
            accel_topic: None,
            stamp: None,
            check_units: true,
        };
        let Some(options) = options else {
            return Ok(a);
        };
        for (k, v) in options.iter() {
            let key: String = k.extract()?;
            if key == "check_units" {
                a.check_units = v
                    .extract()
                    .map_err(|_| usage("check_units: expected True or False".into()))?;
                continue;
            }
            let value: Option<String> = v
                .extract()
                .map_err(|_| usage(format!("{key}: expected a string or None")))?;
            let slot = match key.as_str() {
                "format" => &mut a.format,
                "columns" => &mut a.columns,
                "delimiter" => &mut a.delimiter,
                "time_unit" => &mut a.time_unit,
                "gyro_unit" => &mut a.gyro_unit,
                "accel_unit" => &mut a.accel_unit,
                "topic" => &mut a.topic,
                "gyro_topic" => &mut a.gyro_topic,
                "accel_topic" => &mut a.accel_topic,
                "stamp" => &mut a.stamp,
                _ => {
                    return Err(usage(format!(
                        "unknown keyword argument {key:?}; the reader options are {}",
                        READER_OPTIONS.join(", ")
                    )));
                }
            };
            *slot = value;
        }
        Ok(a)
    }

    /// The recording and how to read it for these options (the same checks as the command
    /// line's flags).
    pub(crate) fn imu_input(&self) -> PyResult<ImuInput> {
        let usage = |m: &str| new_err(Class::Shape, "Usage", m.to_string());
        match (&self.path, &self.gyro, &self.accel) {
            (Some(_), None, None) | (None, Some(_), Some(_)) => {}
            _ => {
                return Err(usage(
                    "give either path, or gyro and accel (a split recording), not both",
                ));
            }
        }
        if self.gyro_topic.is_some() != self.accel_topic.is_some() {
            return Err(usage("gyro_topic and accel_topic go together"));
        }
        if self.topic.is_some() && self.gyro_topic.is_some() {
            return Err(usage("topic excludes gyro_topic/accel_topic"));
        }
        let columns = self
            .columns
            .as_deref()
            .map(parse_columns)
            .transpose()
            .map_err(|e| new_err(Class::Shape, "Usage", format!("columns: {e}")))?;
        Ok(ImuInput {
            imu: self.path.clone(),
            gyro: self.gyro.clone(),
            accel: self.accel.clone(),
            format: parse_opt::<Format>("format", &self.format)?,
            columns,
            delimiter: parse_opt("delimiter", &self.delimiter)?,
            time_unit: parse_opt("time_unit", &self.time_unit)?,
            gyro_unit: parse_opt("gyro_unit", &self.gyro_unit)?,
            accel_unit: parse_opt("accel_unit", &self.accel_unit)?,
            topic: self.topic.clone(),
            gyro_topic: self.gyro_topic.clone(),
            accel_topic: self.accel_topic.clone(),
            stamp: parse_opt("stamp", &self.stamp)?.unwrap_or_default(),
            no_unit_check: !self.check_units,
        })
    }
}

/// The samples as numpy arrays: `t_ns` int64[N], `gyro` float64[N, 3], `acc` float64[N, 3].
pub(crate) fn samples_dict<'py>(
    py: Python<'py>,
    samples: &[ImuSample],
) -> PyResult<Bound<'py, PyDict>> {
    let n = samples.len();
    let t = Array1::from_iter(samples.iter().map(|s| s.t_ns));
    let g = Array2::from_shape_fn((n, 3), |(k, i)| samples[k].gyro[i]);
    let a = Array2::from_shape_fn((n, 3), |(k, i)| samples[k].acc[i]);
    let d = PyDict::new(py);
    d.set_item("t_ns", t.into_pyarray(py))?;
    d.set_item("gyro", g.into_pyarray(py))?;
    d.set_item("acc", a.into_pyarray(py))?;
    Ok(d)
}

/// How a source was read, into `d`: `source`, `format`, `read_as`, `units`, `columns`,
/// `delimiter`, `notes`.
fn info_into(d: &Bound<'_, PyDict>, label: &str, info: &SourceInfo) -> PyResult<()> {
    let py = d.py();
    d.set_item("source", label)?;
    d.set_item("format", info.format.name())?;
    d.set_item("read_as", info.describe())?;
    let u = PyDict::new(py);
    u.set_item("time", info.units.time.to_string())?;
    u.set_item("gyro", info.units.gyro.to_string())?;
    u.set_item("accel", info.units.accel.to_string())?;
    d.set_item("units", u)?;
    d.set_item("columns", info.layout.as_ref().map(|l| l.columns_spec()))?;
    d.set_item(
        "delimiter",
        info.layout.as_ref().map(|l| l.delimiter.to_string()),
    )?;
    d.set_item("notes", info.notes.clone())?;
    Ok(())
}

/// read_imu(path=None, *, gyro=None, accel=None, format=None, columns=None, delimiter=None,
/// time_unit=None, gyro_unit=None, accel_unit=None, topic=None, gyro_topic=None,
/// accel_topic=None, stamp="header", check_units=True)
///
/// Reads an IMU recording into numpy arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, gyro=None, accel=None, **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn read_imu<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    let (samples, info, report) = py
        .detach(|| input.read_all_split())
        .map_err(|e| analysis_err(e, Class::Input))?;
    let d = samples_dict(py, &samples)?;
    drop(samples);
    info_into(&d, &input.label(), &info)?;
    d.set_item("split", report.is_some())?;
    d.set_item(
        "accel_white_ratio",
        report.as_ref().map(|r| r.white_ratio()),
    )?;
    Ok(d)
}

/// read_groundtruth(path)
///
/// Reads an EuRoC ground-truth CSV (docs in `_native.pyi`).
#[pyfunction]
pub(crate) fn read_groundtruth<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<Bound<'py, PyDict>> {
    let gt: Vec<GroundTruthState> = py
        .detach(|| read_euroc_groundtruth(&path))
        .map_err(|e| raise(Class::Input, e))?;
    let n = gt.len();
    let v3 = |f: fn(&GroundTruthState) -> nalgebra::Vector3<f64>| {
        Array2::from_shape_fn((n, 3), |(k, i)| f(&gt[k])[i])
    };
    let q = Array2::from_shape_fn((n, 4), |(k, i)| {
        let q = gt[k].q.quaternion();
        [q.w, q.i, q.j, q.k][i]
    });
    let d = PyDict::new(py);
    d.set_item("source", path.display().to_string())?;
    d.set_item(
        "t_ns",
        Array1::from_iter(gt.iter().map(|s| s.t_ns)).into_pyarray(py),
    )?;
    d.set_item("p", v3(|s| s.p).into_pyarray(py))?;
    d.set_item("q_wxyz", q.into_pyarray(py))?;
    d.set_item("v", v3(|s| s.v).into_pyarray(py))?;
    d.set_item("bias_gyro", v3(|s| s.bias.gyro).into_pyarray(py))?;
    d.set_item("bias_acc", v3(|s| s.bias.acc).into_pyarray(py))?;
    Ok(d)
}

/// audit(path=None, *, gyro=None, accel=None, format=None, ..., check_units=True,
/// calibration=None)
///
/// The `preint audit --json` report as a dict (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, gyro=None, accel=None, calibration=None, **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn audit<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    calibration: Option<PathBuf>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    let opts = preint_analysis::audit::Options { input, calibration };
    let no_unit_check = opts.input.no_unit_check;
    let json = py
        .detach(|| {
            preint_analysis::audit::compute(&opts)
                .map(|r| preint_analysis::audit::to_json(&r, no_unit_check))
        })
        .map_err(|e| analysis_err(e, Class::Input))?;
    json_py(py, &json)
}

/// read_kalibr_yaml(path)
///
/// The noise densities of a Kalibr `imu.yaml` as a `Noise` (docs in `_native.pyi`).
#[pyfunction]
pub(crate) fn read_kalibr_yaml(path: PathBuf) -> PyResult<PyNoise> {
    read_noise(&path).map(PyNoise)
}

/// The Kalibr `imu.yaml` at `path`, read by `preint_io` and checked as a `Noise` is
/// (`crate::checks::noise_problem`); every failure an `InputError` naming the file.
pub(crate) fn read_noise(path: &std::path::Path) -> PyResult<preint::ImuNoise> {
    let n = preint_io::read_kalibr_yaml(path).map_err(|e| raise(Class::Input, e))?;
    match crate::checks::noise_problem(&n) {
        None => Ok(n),
        Some(m) => Err(new_err(
            Class::Input,
            "Parse",
            format!("{}: {m}", path.display()),
        )),
    }
}

/// write_kalibr_yaml(path, noise)
///
/// Writes a `Noise` as a Kalibr `imu.yaml` (docs in `_native.pyi`); a noise a `Noise` could
/// not be built from (e.g. a fit that found no white noise) is refused before the file is
/// opened.
#[pyfunction]
pub(crate) fn write_kalibr_yaml(path: PathBuf, noise: PyRef<'_, PyNoise>) -> PyResult<()> {
    crate::checks::noise("noise", &noise.0)?;
    preint_io::write_kalibr_yaml(&path, &noise.0).map_err(|e| raise(Class::Input, e))
}

/// write_euroc_imu(path, t_ns, gyro, acc)
///
/// Writes arrays as a EuRoC imu0 CSV (docs in `_native.pyi`); non-finite values and
/// timestamps out of order are refused before the file is opened (the readers would refuse
/// the file).
#[pyfunction]
pub(crate) fn write_euroc_imu(
    py: Python<'_>,
    path: PathBuf,
    t_ns: &Bound<'_, PyAny>,
    gyro: &Bound<'_, PyAny>,
    acc: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let s = crate::convert::samples(t_ns, gyro, acc)?;
    crate::checks::samples(&s)?;
    py.detach(|| preint_io::write_euroc_imu(&path, &s))
        .map_err(|e| raise(Class::Input, e))
}
