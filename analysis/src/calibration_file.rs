//! The IMU calibration file: what `calibrate --out` writes and `--calibration` reads.
//!
//! Written as OpenVINS' `kalibr_imu_chain.yaml` (`preint_io::write_openvins_imu_chain`): the
//! intrinsics `Tw`, `R_IMUtoGYRO`, `Ta`, `R_IMUtoACC`, `Tg` (`preint::intrinsics`), the noise
//! densities and rate, and, when known, `time_offset` \[s\]: the IMU clock reads
//! `t_imu = t_keyframe + time_offset` (Kalibr's `timeshift_cam_imu` convention), so the
//! keyframe window `[t_i, t_j]` is the IMU window `[t_i + time_offset, t_j + time_offset]`.
//! Read: that format, or Kalibr's `imu.yaml` with a `scale-misalignment` model (told apart by
//! Kalibr's `gyroscopes:` section).
//!
//! # What is refused
//! A file with nothing to apply (empty, or none of [`CALIBRATION_KEYS`]: `model:` and noise
//! densities alone) is refused naming it; one that states the identity explicitly (as
//! `calibrate --out` writes when the data supports no intrinsics) applies it. Refused too are
//! intrinsics far from the identity (`preint_io::intrinsics`,
//! "Plausibility": the file, line and key are named) and a time offset of a second or more.
//!
//! # Scheme
//! `preint_scheme` records the scheme the time offset was estimated for (`calibrate
//! --scheme`). Euler and galilean hold each interval's first sample: their windows lag those
//! of midpoint and hermite4 by half a sample interval, which an estimated time offset absorbs
//! (`calib/tests/broad_calibration.rs`: 5.82 ms with euler and galilean, 4.04 and 4.05 ms with
//! midpoint and hermite4, at 3.5 ms per sample). A command that applies the offset with a
//! scheme of the other kind warns with the size of that lag ([`scheme_note`]) and does not
//! convert it: `Δt/2` is the first-order lag of a held sample on smooth input, not an exact
//! relation (the estimates differ by 1.78 ms there, not 1.75), and it depends on the sample
//! interval of the recording it is applied to. A file with a time offset and no
//! `preint_scheme` gets a note that its scheme is unknown.
//!
//! The multi-position calibration's model (Tedaldi et al. 2014, `preint_calib::bias::multipose`)
//! maps exactly: `a_m = S_a a + b_a` with `S_a` lower triangular is OpenVINS' `kalibr` model
//! with `Ta = S_a`, `R_IMUtoACC = I`; `ω_m = S_g ω + b_g` with a full `S_g` becomes
//! `Tw R_IMUtoGYRO = S_g` by the RQ decomposition (`Tw` lower triangular with a positive
//! diagonal, `R_IMUtoGYRO` a rotation), `Tg = 0`.

use crate::Error;
use nalgebra::{Matrix3, SVector, Vector3};
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::{CellRule, ImuNoise, Scheme};
use preint_calib::bias::MultiPoseCalibration;
use preint_calib::bias::multipose::{acc_scale_matrix, gyro_scale_matrix};
use preint_io::ImuCalibration;
use std::path::Path;

/// The keys of which a calibration file must hold at least one: the intrinsics of both
/// formats and the time offset (a file of `model:` and noise densities alone calibrates
/// nothing; one that states the identity does, explicitly).
pub const CALIBRATION_KEYS: [&str; 9] = [
    "Tw",
    "Ta",
    "R_IMUtoGYRO",
    "R_IMUtoACC",
    "Tg",
    "time_offset",
    preint_io::extrinsics::BODY_P_SENSOR_KEY,
    "gyroscopes",
    "accelerometers",
];

/// Whether a line of `text` starts (after indentation) with one of [`CALIBRATION_KEYS`] and a
/// colon.
fn has_calibration_key(text: &str) -> bool {
    text.lines().any(|l| {
        let l = l.trim_start();
        CALIBRATION_KEYS.iter().any(|k| {
            l.strip_prefix(k)
                .is_some_and(|r| r.trim_start().starts_with(':'))
        })
    })
}

/// Reads a calibration file (module docs for the formats); the intrinsics are validated.
pub fn read(path: &Path) -> Result<ImuCalibration, Error> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::Usage(format!("--calibration {}: {e}", path.display())))?;
    let name = path.display().to_string();
    let cal = if text.contains("gyroscopes:") {
        preint_io::parse_kalibr_imu(&text, &name)?
    } else {
        preint_io::parse_openvins_imu_chain(&text, &name)?
    };
    cal.intrinsics
        .validate()
        .map_err(|e| Error::Usage(format!("--calibration {}: {e}", path.display())))?;
    if !has_calibration_key(&text) {
        return Err(Error::Usage(format!(
            "--calibration {}: the file holds none of the keys of a calibration ({}): nothing \
             to apply (is it the right file? `calibrate --out` writes one)",
            path.display(),
            CALIBRATION_KEYS.join(", ")
        )));
    }
    if let Some(t) = cal.time_offset_s
        && t.abs() >= 1.0
    {
        return Err(Error::Usage(format!(
            "--calibration {}: time_offset {t} s is not a clock offset between an IMU and its \
             keyframes (|t| < 1 s)",
            path.display()
        )));
    }
    Ok(cal)
}

/// The time offset of `cal` in integer nanoseconds (0 when the file has none).
pub fn time_offset_ns(cal: &ImuCalibration) -> i64 {
    time_offset_ns_of(cal.time_offset_s)
}

/// A time offset \[s\] in integer nanoseconds (0 for `None`).
pub fn time_offset_ns_of(t: Option<f64>) -> i64 {
    t.map_or(0, |t| (t * 1e9).round() as i64)
}

/// Writes `intrinsics`, `noise`, `time_offset_s`, the scheme they were estimated for and the
/// IMU's pose in the frame of the poses (`preint_body_p_sensor`) to `path` as OpenVINS'
/// `kalibr_imu_chain.yaml`.
pub fn write(
    path: &Path,
    intrinsics: ImuIntrinsics,
    noise: &ImuNoise,
    (time_offset_s, scheme): (Option<f64>, Option<Scheme>),
    body_p_sensor: Option<preint::SensorPose>,
) -> Result<(), Error> {
    let cal = ImuCalibration {
        intrinsics,
        noise: Some(*noise),
        time_offset_s,
        rostopic: None,
        scheme,
        body_p_sensor,
    };
    preint_io::write_openvins_imu_chain(path, &cal)?;
    Ok(())
}

/// Whether `a` and `b` place a window alike in time: both hold each interval's first sample
/// (euler, galilean) or both centre it (midpoint, hermite4).
pub fn same_lag(a: Scheme, b: Scheme) -> bool {
    a.cell_rule() == b.cell_rule()
}

/// The lag of `used` behind the scheme `recorded` \[s\] for samples `dt_s` apart: `+Δt/2` when
/// `used` holds samples and `recorded` centres them, `−Δt/2` the other way round, 0 alike.
pub fn scheme_lag_s(recorded: Scheme, used: Scheme, dt_s: f64) -> f64 {
    match (recorded.cell_rule(), used.cell_rule()) {
        (CellRule::Centered, CellRule::Held) => 0.5 * dt_s,
        (CellRule::Held, CellRule::Centered) => -0.5 * dt_s,
        _ => 0.0,
    }
}

/// The line to print when the file's time offset is applied with `used` (module docs,
/// "Scheme"): a `warning:` when the file's scheme lags differently (with the size of the lag
/// at `dt_s` \[s\] per sample), a `note:` when the file does not say, `None` when it agrees or
/// the file has no time offset.
pub fn scheme_note(cal: &ImuCalibration, path: &Path, used: Scheme, dt_s: f64) -> Option<String> {
    let td = cal.time_offset_s?;
    let name = Scheme::name;
    match cal.scheme {
        None => Some(format!(
            "note: {} does not record the scheme its time_offset ({:.3} ms) was estimated for \
             (preint_scheme): an offset estimated with euler or galilean is half a sample \
             interval ({:.3} ms here) larger than with midpoint or hermite4",
            path.display(),
            td * 1e3,
            0.5 * dt_s * 1e3
        )),
        Some(rec) if !same_lag(rec, used) => {
            let lag = scheme_lag_s(rec, used, dt_s);
            Some(format!(
                "warning: {}'s time_offset ({:.3} ms) was estimated for {}; {} places its windows \
                 {:.3} ms {} (half a sample interval), which the offset does not include: the \
                 offset for {} is ≈ {:.3} ms; re-estimate it with `calibrate --scheme {}`",
                path.display(),
                td * 1e3,
                name(rec),
                name(used),
                lag.abs() * 1e3,
                if lag > 0.0 { "earlier" } else { "later" },
                name(used),
                (td + lag) * 1e3,
                name(used)
            ))
        }
        Some(_) => None,
    }
}

/// The intrinsics of a multi-position calibration (module docs); the identity for the terms its
/// chosen model does not have.
pub fn intrinsics_of_multi_pose(c: &MultiPoseCalibration) -> Result<ImuIntrinsics, Error> {
    let z3 = Vector3::zeros();
    let s_a = acc_scale_matrix(
        &c.acc_scale.unwrap_or(z3),
        &c.acc_misalignment.unwrap_or(z3),
    );
    let s_g = gyro_scale_matrix(
        &c.gyro_scale.unwrap_or(z3),
        &c.gyro_misalignment.unwrap_or(SVector::zeros()),
    );
    let (t_w, r) = rq(&s_g).ok_or_else(|| {
        Error::Failed(format!(
            "the gyro scale/misalignment matrix {s_g} is not a rotation times a lower-triangular \
             matrix with a positive diagonal (det ≤ 0)"
        ))
    })?;
    Ok(ImuIntrinsics {
        t_w,
        r_imu_to_gyro: r,
        t_a: s_a,
        ..ImuIntrinsics::identity(IntrinsicsModel::Kalibr)
    })
}

/// `S = L Q` with `L` lower triangular with a positive diagonal and `Q` a rotation (the RQ
/// decomposition, from the QR decomposition of `Sᵀ`); `None` when `det S ≤ 0`.
pub fn rq(s: &Matrix3<f64>) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let det = s.determinant();
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let qr = s.transpose().qr();
    let (q1, r1) = (qr.q(), qr.r());
    let d = Matrix3::from_diagonal(&r1.diagonal().map(|x| if x < 0.0 { -1.0 } else { 1.0 }));
    // Sᵀ = Q₁R₁ ⇒ S = R₁ᵀQ₁ᵀ = (R₁ᵀD)(DQ₁ᵀ), D² = I.
    let (l, q) = (r1.transpose() * d, d * q1.transpose());
    (q.determinant() > 0.0).then_some((l, q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rq_recomposes_a_scale_misalignment_matrix() {
        let s = gyro_scale_matrix(
            &Vector3::new(0.01, -0.02, 0.005),
            &SVector::<f64, 6>::from_column_slice(&[0.002, -0.001, 0.003, 0.0015, -0.002, 0.001]),
        );
        let (l, q) = rq(&s).unwrap();
        assert!((l * q - s).norm() < 1e-15);
        assert!((q * q.transpose() - Matrix3::identity()).norm() < 1e-15);
        assert!((q.determinant() - 1.0).abs() < 1e-15);
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            assert_eq!(l[(i, j)], 0.0);
        }
        assert!(l.diagonal().iter().all(|x| *x > 0.0));
        assert!(rq(&-Matrix3::<f64>::identity()).is_none());
    }
}
