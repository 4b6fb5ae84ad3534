//! The IMU calibration file from Python: what `calibrate --out` writes and `--calibration`
//! reads (OpenVINS `kalibr_imu_chain.yaml` or Kalibr `imu.yaml`), read into numpy, and its
//! intrinsics applied to sample arrays exactly as the Rust preintegrator applies them.

use crate::convert::{SampleArrays, mat_py};
use crate::errors::{Class, new_err};
use crate::io::analysis_err;
use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use preint::ImuSample;
use preint_analysis::calibration_file;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The file, every failure an `InputError` naming it.
fn read(path: &std::path::Path) -> PyResult<preint_io::ImuCalibration> {
    calibration_file::read(path).map_err(|e| match e {
        preint_analysis::Error::Usage(m) => new_err(Class::Input, "Failed", m),
        e => analysis_err(e, Class::Input),
    })
}

/// read_calibration(path)
///
/// The calibration file as a dict (docs in `_native.pyi`).
#[pyfunction]
pub(crate) fn read_calibration<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<Bound<'py, PyDict>> {
    let cal = read(&path)?;
    let x = &cal.intrinsics;
    let d = PyDict::new(py);
    d.set_item("source", path.display().to_string())?;
    d.set_item("model", x.model.name())?;
    d.set_item("Tw", mat_py(py, &x.t_w))?;
    d.set_item("R_IMUtoGYRO", mat_py(py, &x.r_imu_to_gyro))?;
    d.set_item("Ta", mat_py(py, &x.t_a))?;
    d.set_item("R_IMUtoACC", mat_py(py, &x.r_imu_to_acc))?;
    d.set_item("Tg", mat_py(py, &x.t_g))?;
    d.set_item("time_offset_s", cal.time_offset_s)?;
    if let Some(m) = cal.noise.as_ref().and_then(crate::checks::noise_problem) {
        return Err(new_err(
            Class::Input,
            "Parse",
            format!("{}: {m}", path.display()),
        ));
    }
    d.set_item("noise", cal.noise.map(crate::params::PyNoise))?;
    Ok(d)
}

/// apply_intrinsics(calibration, t_ns, gyro, acc)
///
/// The samples corrected by a calibration file's intrinsics (docs in `_native.pyi`).
#[pyfunction]
pub(crate) fn apply_intrinsics<'py>(
    py: Python<'py>,
    calibration: PathBuf,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let cal = read(&calibration)?;
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let v = arrays.views();
    let mut src: Vec<ImuSample> = Vec::with_capacity(v.len());
    v.fill(0..v.len(), &mut src);
    crate::checks::samples(&src)?;
    let c = cal.intrinsics.correction();
    let mut out = src.clone();
    c.apply_all(&src, &mut out);
    let n = out.len();
    let g = Array2::from_shape_fn((n, 3), |(k, i)| out[k].gyro[i]);
    let a = Array2::from_shape_fn((n, 3), |(k, i)| out[k].acc[i]);
    Ok((g.into_pyarray(py).into_any(), a.into_pyarray(py).into_any()))
}
