//! Input validation shared by the bias problems: every check names the input at fault
//! ([`BiasError`]), so that bad input is a typed error and never a panic.

use super::BiasError;
use nalgebra::Vector3;
use preint::{ImuNoise, ImuSample};

/// Checks finite values and strictly increasing timestamps; needs at least `min` samples.
pub(crate) fn check_samples(samples: &[ImuSample], min: usize) -> Result<(), BiasError> {
    if samples.len() < min {
        return Err(BiasError::TooFew {
            what: "samples",
            found: samples.len(),
            needed: min,
        });
    }
    for (i, s) in samples.iter().enumerate() {
        if !(s.gyro.iter().all(|v| v.is_finite()) && s.acc.iter().all(|v| v.is_finite())) {
            return Err(BiasError::NonFinite {
                index: i,
                t_ns: s.t_ns,
            });
        }
        if i > 0 && s.t_ns <= samples[i - 1].t_ns {
            return Err(BiasError::NotIncreasing {
                index: i,
                t_ns: s.t_ns,
            });
        }
    }
    Ok(())
}

/// Checks that `v` is finite and > 0.
pub(crate) fn check_positive(name: &'static str, v: f64) -> Result<(), BiasError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(BiasError::InvalidParameter {
            name,
            reason: format!("must be finite and > 0, got {v}"),
        })
    }
}

/// Checks that `v` is finite and ≥ 0.
pub(crate) fn check_non_negative(name: &'static str, v: f64) -> Result<(), BiasError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(BiasError::InvalidParameter {
            name,
            reason: format!("must be finite and ≥ 0, got {v}"),
        })
    }
}

/// Checks that the white-noise densities are finite and > 0 and the random walks finite ≥ 0.
pub(crate) fn check_noise(noise: &ImuNoise) -> Result<(), BiasError> {
    check_positive("gyro_noise_density", noise.gyro_noise_density)?;
    check_positive("acc_noise_density", noise.acc_noise_density)?;
    check_non_negative("gyro_random_walk", noise.gyro_random_walk)?;
    check_non_negative("acc_random_walk", noise.acc_random_walk)
}

/// Checks that the gravity vector `g` (named `name`) is finite and non-zero; returns `|g|`.
pub(crate) fn check_gravity(name: &'static str, g: &Vector3<f64>) -> Result<f64, BiasError> {
    let n = g.norm();
    if !(n.is_finite() && n > 0.0) {
        return Err(BiasError::InvalidParameter {
            name,
            reason: format!("must be finite and non-zero, got {g:?}"),
        });
    }
    Ok(n)
}
