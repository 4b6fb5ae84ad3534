//! Python bindings of `preint` (the `preint._native` extension module; the Python package
//! `preint` re-exports it). One file per area: parameters, preintegration, the measurement,
//! factors and prediction, readers, Allan variance and calibration.

mod advise;
mod allan;
mod calib;
mod calibration;
mod checks;
mod convert;
mod errors;
mod factor;
mod init;
mod io;
mod measurement;
mod navstate;
mod params;
mod preintegration;
mod state;
mod window;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<params::PyNoise>()?;
    m.add_class::<params::PyBias>()?;
    m.add_class::<params::PyParams>()?;
    m.add_class::<measurement::PyMeasurement>()?;
    m.add_class::<preintegration::PyPreintegrator>()?;
    m.add_function(wrap_pyfunction!(preintegration::preintegrate, m)?)?;
    m.add_function(wrap_pyfunction!(preintegration::preintegrate_windows, m)?)?;
    m.add_function(wrap_pyfunction!(preintegration::merge, m)?)?;
    m.add_function(wrap_pyfunction!(window::deltas_at, m)?)?;
    m.add_function(wrap_pyfunction!(window::truncation_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(window::inflate, m)?)?;
    m.add_function(wrap_pyfunction!(window::second_order_covariance, m)?)?;
    m.add_function(wrap_pyfunction!(window::add_covariance, m)?)?;
    m.add_function(wrap_pyfunction!(window::states_at, m)?)?;
    m.add_function(wrap_pyfunction!(window::deskew_points, m)?)?;
    m.add_class::<navstate::PyNavState>()?;
    m.add_function(wrap_pyfunction!(navstate::predict, m)?)?;
    m.add_class::<factor::PyImuFactor>()?;
    m.add_class::<factor::PyCombinedImuFactor>()?;
    // io and calibration: readers, Allan variance, calibration, advise
    m.add_function(wrap_pyfunction!(io::read_imu, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_groundtruth, m)?)?;
    m.add_function(wrap_pyfunction!(io::audit, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_kalibr_yaml, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_kalibr_yaml, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_euroc_imu, m)?)?;
    m.add_function(wrap_pyfunction!(allan::allan_variance, m)?)?;
    m.add_function(wrap_pyfunction!(allan::allan_variance_file, m)?)?;
    m.add_function(wrap_pyfunction!(calib::detect_still_intervals_py, m)?)?;
    m.add_function(wrap_pyfunction!(calib::calibrate_static_py, m)?)?;
    m.add_function(wrap_pyfunction!(calib::calibrate_multi_pose_py, m)?)?;
    m.add_function(wrap_pyfunction!(calib::calibrate_file, m)?)?;
    m.add_function(wrap_pyfunction!(init::initialise_file, m)?)?;
    m.add_function(wrap_pyfunction!(calibration::read_calibration, m)?)?;
    m.add_function(wrap_pyfunction!(calibration::apply_intrinsics, m)?)?;
    m.add_function(wrap_pyfunction!(advise::advise_py, m)?)?;
    m.add_function(wrap_pyfunction!(advise::advise_file, m)?)?;
    m.add(
        "SCHEMES",
        preint::Scheme::ALL
            .iter()
            .map(|s| s.name())
            .collect::<Vec<_>>(),
    )?;
    Ok(())
}
