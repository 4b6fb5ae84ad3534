//! The Earth rate in a static recording: what of it can be told apart from the gyro bias.
//!
//! At rest in an east-north-up world frame at latitude φ the gyro reads
//! `ω_m = b_g + R_wbᵀ ω_ie` with `ω_ie = Ω_E (0, cos φ, sin φ)`, `Ω_E = 7.292115e-5` rad/s
//! (WGS-84), i.e. `R_wbᵀω_ie = Ω_E sin φ · u + Ω_E cos φ · n_b` with `u` the up direction and
//! `n_b` north, both in the body frame. A static recording gives `u` (from the accelerometer,
//! [`StaticCalibration::up_body`]) but not the heading, so:
//!
//! - the **vertical** part `Ω_E sin φ · u` is known and removed from the bias;
//! - the **horizontal** part, of known magnitude `Ω_E cos φ` but unknown direction in the
//!   plane ⟂ `u`, is not separable from the horizontal bias. Without a heading it stays in the
//!   estimate and is accounted for as an uncertainty: a direction uniform on the circle has
//!   covariance `½ (Ω_E cos φ)² (I − u uᵀ)`, which is added to the bias covariance (so each
//!   horizontal σ grows by up to `Ω_E cos φ/√2 ≈ 5.2e-5 cos φ` rad/s, reported in
//!   [`EarthRateInBody::unresolved`]);
//! - with a heading (azimuth of the body x axis, clockwise from north) the attitude is
//!   `R_wb = Rz(90° − heading)·Ry(pitch)·Rx(roll)` and the whole `R_wbᵀω_ie` is removed.
//!
//! The gyro-compassing alternative (estimating the heading from the horizontal rate) needs a
//! bias far below `Ω_E cos φ`, which a static calibration cannot assume.

use super::static_bias::StaticCalibration;
use super::tilt::attitude_from_roll_pitch;
use nalgebra::{Matrix3, Vector3};
use preint::earth::{EARTH_RATE_RAD_S, earth_rate_enu};
use preint_lie::SO3;

/// The Earth rate's share of a static gyro reading, in the body frame (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthRateInBody {
    /// Latitude \[deg\].
    pub latitude_deg: f64,
    /// Heading \[deg\] (body x axis, clockwise from north), if given.
    pub heading_deg: Option<f64>,
    /// Removed from the bias [rad/s, body frame]: `Ω_E sin φ · u`, or `R_wbᵀω_ie` with a
    /// heading.
    pub removed: Vector3<f64>,
    /// Magnitude of the Earth rate left in the bias [rad/s]: `Ω_E cos φ` without a heading,
    /// 0 with one.
    pub unresolved: f64,
    /// Covariance added to the bias [(rad/s)², body frame]: `½ (Ω_E cos φ)² (I − u uᵀ)` without
    /// a heading, zero with one.
    pub added_cov: Matrix3<f64>,
}

/// The Earth rate at `latitude_deg` \[deg\] for a body whose up direction is `up_body` (unit,
/// body frame) and, if known, whose attitude has roll/pitch `roll_pitch` \[rad\] and heading
/// `heading_deg` [deg, clockwise from north].
pub fn earth_rate_in_body(
    up_body: &Vector3<f64>,
    roll_pitch: (f64, f64),
    latitude_deg: f64,
    heading_deg: Option<f64>,
) -> EarthRateInBody {
    let (s, c) = latitude_deg.to_radians().sin_cos();
    let u = up_body.normalize();
    let (removed, unresolved, added_cov) = match heading_deg {
        Some(h) => {
            let yaw = SO3::exp(&Vector3::new(0.0, 0.0, (90.0 - h).to_radians()));
            let r_wb = yaw.compose(&attitude_from_roll_pitch(roll_pitch.0, roll_pitch.1));
            let w = r_wb.inverse().act(&earth_rate_enu(latitude_deg));
            (w, 0.0, Matrix3::zeros())
        }
        None => {
            let h = EARTH_RATE_RAD_S * c;
            let cov = (Matrix3::identity() - u * u.transpose()) * (0.5 * h * h);
            (u * (EARTH_RATE_RAD_S * s), h, cov)
        }
    };
    EarthRateInBody {
        latitude_deg,
        heading_deg,
        removed,
        unresolved,
        added_cov,
    }
}

/// `cal` with the Earth rate of `e` taken out of its gyro bias and its uncertainty added to
/// the bias σ (module docs).
pub fn remove_earth_rate(cal: &StaticCalibration, e: &EarthRateInBody) -> StaticCalibration {
    let mut out = cal.clone();
    out.gyro_bias = cal.gyro_bias - e.removed;
    out.gyro_bias_std =
        Vector3::from_fn(|i, _| (cal.gyro_bias_std[i].powi(2) + e.added_cov[(i, i)]).sqrt());
    out
}
