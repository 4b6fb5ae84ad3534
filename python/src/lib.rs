//! Python bindings of `preint` (the `preint._native` extension module; the Python package
//! `preint` re-exports it). One file per area: parameters, preintegration, the measurement,
//! factors and prediction, readers, Allan variance and calibration.

mod convert;
mod errors;
mod factor;
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
    m.add_function(wrap_pyfunction!(window::states_at, m)?)?;
    m.add_function(wrap_pyfunction!(window::deskew_points, m)?)?;
    m.add_class::<navstate::PyNavState>()?;
    m.add_function(wrap_pyfunction!(navstate::predict, m)?)?;
    m.add_class::<factor::PyImuFactor>()?;
    m.add_class::<factor::PyCombinedImuFactor>()?;
    m.add(
        "SCHEMES",
        preint::Scheme::ALL
            .iter()
            .map(|s| s.name())
            .collect::<Vec<_>>(),
    )?;
    Ok(())
}
