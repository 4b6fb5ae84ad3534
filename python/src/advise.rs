//! `preint advise` from Python: the cheapest scheme and lowest rate whose discretisation error
//! stays below a fraction of the noise σ, from numpy arrays or a recording. The computation and
//! the result are the command line's (`preint_analysis::advise`: `advise_samples`, `compute`,
//! `to_json`), so the dict equals `preint advise --json`.

use crate::calib::{check, noise_arg};
use crate::convert::samples;
use crate::errors::Class;
use crate::io::{ReadArgs, analysis_err, json_py};
use preint_analysis::advise::{self, Options};
use preint_analysis::checks::UnitCheck;
use preint_analysis::input_class::InputClass;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// The input class named `name` ("smooth" or "held", `preint advise --input`).
fn input_class(name: &str) -> PyResult<InputClass> {
    match name {
        "smooth" => Ok(InputClass::Smooth),
        "held" => Ok(InputClass::Held),
        _ => Err(crate::errors::shape_err(format!(
            "unknown input {name:?}: use \"smooth\" or \"held\""
        ))),
    }
}

/// advise(t_ns, gyro, acc, noise, *, window=1.0, fraction=0.1, input="smooth")
///
/// `preint advise` on arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(name = "advise", signature = (t_ns, gyro, acc, noise, *, window=1.0, fraction=0.1, input="smooth"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn advise_py<'py>(
    py: Python<'py>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    noise: &Bound<'py, PyAny>,
    window: f64,
    fraction: f64,
    input: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let class = input_class(input)?;
    // The command line's checks of --window and --fraction, named as the arguments.
    for (name, v) in [("window", window), ("fraction", fraction)] {
        preint_analysis::checks::positive(name, v)
            .map_err(|e| analysis_err(e, Class::Calibration))?;
    }
    let noise = noise_arg(Some(noise), false)?;
    let s = samples(t_ns, gyro, acc)?;
    check(&s)?;
    let label = Path::new("samples");
    let options = Options {
        input: ReadArgs {
            path: Some(label.into()),
            check_units: false,
            ..Default::default()
        }
        .imu_input()?,
        noise: PathBuf::from("(given)"),
        window,
        fraction,
        from: None,
        to: None,
        input_class: class,
        calibration: None,
    };
    let json = py
        .detach(|| {
            preint_analysis::checks::no_gaps(&s, label, preint::DEFAULT_MAX_GAP_NS)?;
            let a = advise::advise_samples(&options, &s, &noise, None, UnitCheck::Skipped)?;
            Ok(advise::to_json(&a))
        })
        .map_err(|e| analysis_err(e, Class::Calibration))?;
    json_py(py, &json)
}

/// advise_file(path=None, *, ..., noise, window=1.0, fraction=0.1, from_ns=None, to_ns=None,
/// input="smooth")
///
/// `preint advise --json` on a recording (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, noise, gyro=None, accel=None, window=1.0,
    fraction=0.1, from_ns=None, to_ns=None, input="smooth", **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn advise_file<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    noise: PathBuf,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    window: f64,
    fraction: f64,
    from_ns: Option<i64>,
    to_ns: Option<i64>,
    input: &str,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let input_class = input_class(input)?;
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    let options = Options {
        input_class,
        calibration: None,
        input,
        noise,
        window,
        fraction,
        from: from_ns,
        to: to_ns,
    };
    let json = py
        .detach(|| advise::compute(&options).map(|a| advise::to_json(&a)))
        .map_err(|e| analysis_err(e, Class::Calibration))?;
    json_py(py, &json)
}
