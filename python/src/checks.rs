//! The value checks of the Python surface: what the command line refuses in a flag, refused in
//! an argument, before anything is computed or written. A bad value raises `PreintError` of
//! kind `"InvalidParameter"` (a `ValueError`) whose message names the argument, the value and
//! the fix; sample arrays are checked by `preint::check_samples` (kinds `NonFinite`,
//! `DuplicateTimestamp`, `DecreasingTimestamp`, naming the sample index).
//!
//! The rules:
//! - white-noise densities finite and > 0 (a zero density gives a singular covariance, which
//!   cannot weight a factor); bias random walks finite and ≥ 0 (zero is a constant bias, as in
//!   GTSAM's own tests; only `CombinedImuFactor` then refuses, its 15×15 covariance being
//!   singular); rates finite and > 0;
//! - gravity finite with `|g| ≤ 100` m/s² (the command line's `--gravity` range; 0 allowed);
//!   `omega_coriolis` finite with `|ω| < 100` rad/s;
//! - biases, states, lever arms finite; rotations within 1e-6 of a rotation
//!   (`crate::params::rotation`);
//! - every other `Params` field as `PreintParams::validate` says (finite symmetric
//!   covariances with a non-negative diagonal, positive thresholds and gap).

use crate::errors::{Class, new_err, preint_err};
use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise, ImuSample, PreintError, PreintParams};
use pyo3::prelude::*;

/// Largest `|g|` [m/s²] accepted (the command line's `--gravity` range is [0, 100]).
pub(crate) const MAX_GRAVITY: f64 = 100.0;
/// `|omega_coriolis|` [rad/s] must be below this (the Earth turns at 7.29e-5 rad/s).
pub(crate) const MAX_OMEGA: f64 = 100.0;

/// `PreintError` of kind `"InvalidParameter"` with message `msg`.
pub(crate) fn invalid(msg: impl Into<String>) -> PyErr {
    new_err(Class::Preint, "InvalidParameter", msg.into())
}

/// What is wrong with `n`, if anything: the field, its value and the fix.
pub(crate) fn noise_problem(n: &ImuNoise) -> Option<String> {
    let white = [
        ("gyro_noise_density", n.gyro_noise_density, "rad/s/√Hz"),
        ("acc_noise_density", n.acc_noise_density, "m/s²/√Hz"),
    ];
    for (name, v, unit) in white {
        if !(v.is_finite() && v > 0.0) {
            return Some(format!(
                "{name} must be a finite density > 0 [{unit}], got {v:?}; give the datasheet's \
                 or allan_variance's figure (a factor cannot be weighted with a zero white-noise \
                 density)"
            ));
        }
    }
    let walks = [
        ("gyro_random_walk", n.gyro_random_walk, "rad/s²/√Hz"),
        ("acc_random_walk", n.acc_random_walk, "m/s³/√Hz"),
    ];
    for (name, v, unit) in walks {
        if !(v.is_finite() && v >= 0.0) {
            return Some(format!(
                "{name} must be a finite density ≥ 0 [{unit}] (0: a constant bias), got {v:?}"
            ));
        }
    }
    let r = n.update_rate_hz;
    if !(r.is_finite() && r > 0.0) {
        return Some(format!(
            "update_rate_hz must be a finite rate > 0 [Hz], got {r:?}"
        ));
    }
    None
}

/// `n` as a valid `Noise` (`what` names where it came from in the error).
pub(crate) fn noise(what: &str, n: &ImuNoise) -> PyResult<()> {
    match noise_problem(n) {
        None => Ok(()),
        Some(m) => Err(invalid(format!("{what}: {m}"))),
    }
}

/// `v` finite, else an error naming `name` (`unit` its unit).
pub(crate) fn finite3(name: &str, v: &Vector3<f64>, unit: &str) -> PyResult<()> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(invalid(format!(
            "{name}[{i}] must be finite [{unit}], got {:?}",
            v[i]
        ))),
    }
}

/// `g` finite with `|g| ≤ MAX_GRAVITY` [m/s²].
pub(crate) fn gravity(name: &str, g: &Vector3<f64>) -> PyResult<()> {
    finite3(name, g, "m/s²")?;
    let n = g.norm();
    if n > MAX_GRAVITY {
        return Err(invalid(format!(
            "{name}: |g| = {n:?} m/s² is outside [0, {MAX_GRAVITY}] m/s² (the command line's \
             --gravity range); give gravity in m/s², e.g. (0, 0, -9.81)"
        )));
    }
    Ok(())
}

/// A gravity magnitude `g` [m/s²] finite within `[0, MAX_GRAVITY]`.
pub(crate) fn gravity_magnitude(name: &str, g: f64) -> PyResult<()> {
    if g.is_finite() && (0.0..=MAX_GRAVITY).contains(&g) {
        return Ok(());
    }
    Err(invalid(format!(
        "{name} must be a magnitude in [0, {MAX_GRAVITY}] m/s² (e.g. 9.81), got {g:?}"
    )))
}

/// A navigation-frame rotation rate `w` [rad/s] finite with `|w| < MAX_OMEGA`.
pub(crate) fn omega(name: &str, w: &Vector3<f64>) -> PyResult<()> {
    finite3(name, w, "rad/s")?;
    let n = w.norm();
    if n >= MAX_OMEGA {
        return Err(invalid(format!(
            "{name}: |ω| = {n:?} rad/s is not below {MAX_OMEGA} rad/s; give the frame's \
             rotation rate in rad/s (the Earth's is 7.292115e-5)"
        )));
    }
    Ok(())
}

/// A bias estimate with finite components.
pub(crate) fn bias(name: &str, b: &ImuBias) -> PyResult<()> {
    finite3(&format!("{name}.gyro"), &b.gyro, "rad/s")?;
    finite3(&format!("{name}.acc"), &b.acc, "m/s²")
}

/// `b` as `gyro [x, y, z] rad/s, acc [x, y, z] m/s²`.
pub(crate) fn show_bias(b: &ImuBias) -> String {
    let (g, a) = (&b.gyro, &b.acc);
    format!(
        "gyro [{:?}, {:?}, {:?}] rad/s, acc [{:?}, {:?}, {:?}] m/s²",
        g.x, g.y, g.z, a.x, a.y, a.z
    )
}

/// The Python name of a `PreintParams` field and the fix for a bad value.
fn params_field(rust: &str) -> (&'static str, &'static str) {
    const COV: &str = "give a finite symmetric 3×3 matrix with a non-negative diagonal, or a \
                       number s ≥ 0 meaning s·I";
    match rust {
        "gravity" => ("gravity", "give three finite numbers [m/s²]"),
        "omega_coriolis" => (
            "omega_coriolis",
            "give three finite numbers [rad/s] or None",
        ),
        "gyro_cov" => ("gyroscope_covariance", COV),
        "acc_cov" => ("accelerometer_covariance", COV),
        "gyro_bias_rw_cov" => ("bias_gyro_covariance", COV),
        "acc_bias_rw_cov" => ("bias_acc_covariance", COV),
        "integration_cov" => ("integration_covariance", COV),
        "reintegrate_gyro_threshold" => ("reintegrate_gyro_threshold", "give a number > 0 [rad/s]"),
        "reintegrate_acc_threshold" => ("reintegrate_acc_threshold", "give a number > 0 [m/s²]"),
        "max_gap_ns" => ("max_gap_ns", "give a positive number of nanoseconds"),
        "body_p_sensor" => (
            "body_p_sensor",
            "give a rotation and a finite translation [m]",
        ),
        _ => ("", "see Params.validate()"),
    }
}

/// `p` as `PreintParams::validate` and the ranges of gravity and `omega_coriolis` require;
/// the error names the `Params` property.
pub(crate) fn params(p: &PreintParams) -> PyResult<()> {
    if let Err(e) = p.validate() {
        return Err(match e {
            PreintError::InvalidParameter { name, reason } => {
                let (py_name, fix) = params_field(name);
                let py_name = if py_name.is_empty() { name } else { py_name };
                invalid(format!("Params.{py_name}: {reason}; {fix}"))
            }
            e => preint_err(e),
        });
    }
    gravity("Params.gravity", &p.gravity)?;
    if let Some(w) = &p.omega_coriolis {
        omega("Params.omega_coriolis", w)?;
    }
    Ok(())
}

/// Every sample finite, timestamps strictly increasing (the error names the index and time:
/// `PreintError` of kind `NonFinite`, `DuplicateTimestamp` or `DecreasingTimestamp`).
pub(crate) fn samples(s: &[ImuSample]) -> PyResult<()> {
    preint::check_samples(s, 0..s.len(), i64::MAX).map_err(preint_err)
}
