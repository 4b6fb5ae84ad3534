//! The overlapping Allan deviation and the Kalibr noise figures (IEEE Std 952-1997, Annex C),
//! from numpy arrays or from a recording, as `preint allan` computes them
//! (`preint_calib::allan`: `AllanStream`, bounded memory; `StillnessMonitor`, the refusal of a
//! moving recording).
//!
//! Channel order `[ω_x, ω_y, ω_z, a_x, a_y, a_z]` (sensor frame); gyro channels in rad/s,
//! accelerometer channels in m/s². White-noise density N in u/√Hz (slope −½ line read at
//! τ = 1 s), random walk K in u/s/√Hz (slope +½ line read at τ = 3 s), bias instability B in u
//! (the curve's floor / 0.664), u = rad/s or m/s².

use crate::convert::samples;
use crate::errors::{Class, raise};
use crate::io::{ReadArgs, analysis_err};
use crate::params::PyNoise;
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2};
use preint_analysis::allan;
use preint_calib::allan::{AllanStream, ImuAllan, Stillness, StillnessMonitor, StillnessOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The curves and fits of `a` as a dict (layout in `_native.pyi`).
fn allan_dict<'py>(
    py: Python<'py>,
    a: &ImuAllan,
    samples: u64,
    block_len: usize,
    st: &Stillness,
) -> PyResult<Bound<'py, PyDict>> {
    let m = a.curves.iter().map(Vec::len).min().unwrap_or(0);
    let col = |f: fn(&preint_calib::allan::AllanPoint) -> f64| {
        Array2::from_shape_fn((m, 6), |(k, c)| f(&a.curves[c][k]))
    };
    let fit = |f: fn(&preint_calib::allan::NoiseFit) -> f64| {
        Array1::from_iter(a.fits.iter().map(f)).into_pyarray(py)
    };
    let flag = |f: fn(&preint_calib::allan::NoiseFit) -> bool| {
        Array1::from_iter(a.fits.iter().map(f)).into_pyarray(py)
    };
    let d = PyDict::new(py);
    d.set_item("samples", samples)?;
    d.set_item("dt", a.dt)?;
    d.set_item("tau0", a.tau0)?;
    d.set_item("block_len", block_len)?;
    d.set_item(
        "tau",
        Array1::from_iter(a.curves[0][..m].iter().map(|p| p.tau)).into_pyarray(py),
    )?;
    d.set_item(
        "clusters",
        Array1::from_iter(a.curves[0][..m].iter().map(|p| p.clusters)).into_pyarray(py),
    )?;
    d.set_item("adev", col(|p| p.adev).into_pyarray(py))?;
    d.set_item("adev_err", col(|p| p.adev_err).into_pyarray(py))?;
    d.set_item("white_density", fit(|f| f.white_density))?;
    d.set_item("white_density_err", fit(|f| f.white_density_err))?;
    d.set_item("white_density_is_bound", flag(|f| f.white_density_is_bound))?;
    d.set_item("random_walk", fit(|f| f.random_walk))?;
    d.set_item("random_walk_err", fit(|f| f.random_walk_err))?;
    d.set_item("random_walk_is_bound", flag(|f| f.random_walk_is_bound))?;
    d.set_item("bias_instability", fit(|f| f.bias_instability))?;
    d.set_item("bias_instability_tau", fit(|f| f.bias_instability_tau))?;
    d.set_item(
        "white_tau_range",
        Array2::from_shape_fn((6, 2), |(c, i)| {
            let r = a.fits[c].white_tau_range;
            [r.0, r.1][i]
        })
        .into_pyarray(py),
    )?;
    d.set_item(
        "random_walk_tau_range",
        Array2::from_shape_fn((6, 2), |(c, i)| {
            let r = a.fits[c].random_walk_tau_range;
            [r.0, r.1][i]
        })
        .into_pyarray(py),
    )?;
    d.set_item("noise", Py::new(py, PyNoise(a.to_imu_noise()))?)?;
    let s = PyDict::new(py);
    s.set_item("windows", st.windows)?;
    s.set_item("still_windows", st.still_windows)?;
    s.set_item("still_fraction", st.still_fraction())?;
    s.set_item("first_motion_s", st.first_motion_s)?;
    s.set_item("max_tilt_deg", st.max_tilt_deg)?;
    s.set_item("max_tilt_at_s", st.max_tilt_at_s)?;
    d.set_item("stillness", s)?;
    d.set_item(
        "channels",
        ["gyro x", "gyro y", "gyro z", "acc x", "acc y", "acc z"].to_vec(),
    )?;
    let u = PyDict::new(py);
    u.set_item("tau", "s")?;
    u.set_item("adev", "rad/s (gyro), m/s^2 (acc)")?;
    u.set_item(
        "white_density",
        "rad/s/sqrt(Hz) (gyro), m/s^2/sqrt(Hz) (acc)",
    )?;
    u.set_item(
        "random_walk",
        "rad/s^2/sqrt(Hz) (gyro), m/s^3/sqrt(Hz) (acc)",
    )?;
    u.set_item("bias_instability", "rad/s (gyro), m/s^2 (acc)")?;
    d.set_item("units", u)?;
    Ok(d)
}

/// allan_variance(t_ns, gyro, acc, *, per_decade=10, check_still=True)
///
/// Allan deviations and noise fits of arrays (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (t_ns, gyro, acc, *, per_decade=10, check_still=true))]
pub(crate) fn allan_variance<'py>(
    py: Python<'py>,
    t_ns: &Bound<'py, PyAny>,
    gyro: &Bound<'py, PyAny>,
    acc: &Bound<'py, PyAny>,
    per_decade: usize,
    check_still: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let s = samples(t_ns, gyro, acc)?;
    let per_decade = per_decade.max(1);
    let (a, block_len, st) = py
        .detach(|| {
            let mut stream = AllanStream::new();
            let mut still = StillnessMonitor::new(StillnessOptions::default());
            for x in &s {
                stream.push(x)?;
                still.push(x);
            }
            let st = still.finish();
            if check_still {
                st.verdict(&StillnessOptions::default())?;
            }
            let b = stream.block_len();
            Ok((stream.finish(per_decade)?, b, st))
        })
        .map_err(|e: preint_calib::allan::AllanError| raise(Class::Calibration, e))?;
    allan_dict(py, &a, s.len() as u64, block_len, &st)
}

/// allan_variance_file(path=None, *, gyro=None, accel=None, format=None, ..., check_still=True,
/// check_units=True)
///
/// `preint allan` on a recording (docs in `_native.pyi`).
#[pyfunction]
#[pyo3(signature = (path=None, *, gyro=None, accel=None, check_still=true, **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn allan_variance_file<'py>(
    py: Python<'py>,
    path: Option<PathBuf>,
    gyro: Option<PathBuf>,
    accel: Option<PathBuf>,
    check_still: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let input = ReadArgs::from_options(path, gyro, accel, options)?.imu_input()?;
    let opts = allan::Options {
        input,
        no_still_check: !check_still,
    };
    let r = py
        .detach(|| allan::compute(&opts))
        .map_err(|e| analysis_err(e, Class::Calibration))?;
    let d = allan_dict(py, &r.allan, r.samples as u64, r.block_len, &r.stillness)?;
    d.set_item("source", r.imu)?;
    d.set_item("units_checked", r.units_checked)?;
    Ok(d)
}
