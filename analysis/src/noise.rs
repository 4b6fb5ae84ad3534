//! Noise densities: read from a Kalibr `imu.yaml`, or the EuRoC figures when none is given.

use crate::Error;
use preint::ImuNoise;
use preint_io::read_kalibr_noise_model;
use preint_io::split::MergeReport;
use serde_json::{Value, json};
use std::path::Path;

/// What [`source`] prints when no noise file is given.
pub const DEFAULT_SOURCE: &str = "EuRoC / ADIS16448 defaults (no --noise)";

/// Reads the Kalibr `imu.yaml` at `path` to weight measurements with (white-noise densities
/// positive, every value within an IMU's range: [`preint_io::read_kalibr_noise_model`]), or
/// returns the EuRoC (ADIS16448) figures ([`ImuNoise::euroc`]) when there is none.
pub fn or_default(path: Option<&Path>) -> Result<ImuNoise, Error> {
    Ok(match path {
        Some(p) => read_kalibr_noise_model(p)?,
        None => ImuNoise::euroc(),
    })
}

/// Where the densities came from: the file's path, or [`DEFAULT_SOURCE`].
pub fn source(path: Option<&Path>) -> String {
    path.map_or(DEFAULT_SOURCE.to_string(), |p| p.display().to_string())
}

/// The four continuous-time densities under their Kalibr names: gyroscope_noise_density
/// [rad/s/√Hz], gyroscope_random_walk [rad/s²/√Hz], accelerometer_noise_density [m/s²/√Hz],
/// accelerometer_random_walk [m/s³/√Hz].
pub fn densities_json(n: &ImuNoise) -> Value {
    json!({
        "gyroscope_noise_density": n.gyro_noise_density,
        "gyroscope_random_walk": n.gyro_random_walk,
        "accelerometer_noise_density": n.acc_noise_density,
        "accelerometer_random_walk": n.acc_random_walk,
    })
}

/// The densities to preintegrate with: `noise` itself, or for the merged samples of a split
/// recording (`report`) the effective densities of [`preint_io::split::effective_noise`]
/// (accelerometer white noise `σ_a,eff = √(ρ σ_a² + q_int)`, everything else unchanged).
pub fn effective(noise: &ImuNoise, report: Option<&MergeReport>) -> ImuNoise {
    report.map_or(*noise, |r| preint_io::split::effective_noise(noise, r))
}

/// Sets the accelerometer white-noise covariance of `params` to the effective density of a
/// split recording's merged samples ([`effective`]; nothing changes without a `report`) and
/// returns the densities used.
pub fn apply_split(
    noise: &ImuNoise,
    report: Option<&MergeReport>,
    params: &mut preint::PreintParams,
) -> ImuNoise {
    let eff = effective(noise, report);
    if report.is_some() {
        params.acc_cov = nalgebra::Matrix3::identity() * eff.acc_noise_density.powi(2);
    }
    eff
}

/// The effective densities as JSON ([`densities_json`]) with the merge's white-noise ratio
/// `rho` and interpolation density `q_int` [m²/s³], for a split recording.
pub fn effective_json(noise: &ImuNoise, report: &MergeReport) -> Value {
    let mut v = densities_json(&effective(noise, Some(report)));
    v["split_white_ratio_rho"] = json!(report.white_ratio());
    v["split_interpolation_psd"] = json!(preint_io::split::interpolation_psd(
        report,
        noise.acc_noise_density
    ));
    v
}
