//! `integrate --calibration FILE`: the file's intrinsics applied to the raw samples, its
//! time offset moving the keyframes onto the IMU's clock and its IMU pose in the frame of the
//! poses (`preint_body_p_sensor`) applied as `--body-p-sensor`
//! ([`preint_analysis::calibration_file`]).

use preint::intrinsics::{AppliedIntrinsics, ImuIntrinsics};
use preint::{PreintParams, Scheme};
use preint_analysis::calibration_file;
use preint_analysis::format::rows;
use preint_io::ImuCalibration;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

/// The calibration file applied.
#[derive(Clone, Debug)]
pub struct AppliedCalibration {
    /// The file, as printed.
    pub file: String,
    /// Its intrinsics.
    pub intrinsics: ImuIntrinsics,
    /// Its time offset \[ns\], added to `--from`/`--to`.
    pub time_offset_ns: i64,
    /// The scheme its time offset was estimated for (`preint_scheme`).
    pub scheme: Option<Scheme>,
    /// Its IMU pose in the body frame (`preint_body_p_sensor`), applied as `--body-p-sensor`.
    pub body_p_sensor: Option<preint::SensorPose>,
    /// The line [`calibration_file::scheme_note`] prints when that scheme lags differently
    /// from the scheme used, or is unknown.
    pub scheme_note: Option<String>,
}

impl AppliedCalibration {
    /// The file at `path`, read; its intrinsics (unless the identity) set in `params`.
    pub fn read(
        path: &Path,
        params: &mut PreintParams,
    ) -> Result<(Self, ImuCalibration), crate::CliError> {
        let cal = calibration_file::read(path)?;
        if !cal.intrinsics.is_identity() {
            params.intrinsics = Some(AppliedIntrinsics::new(cal.intrinsics));
        }
        if let Some(x) = cal.body_p_sensor {
            if params.body_p_sensor.is_some() {
                return Err(preint_analysis::Error::Usage(format!(
                    "--body-p-sensor with --calibration {}, which holds the IMU's pose \
                     (preint_body_p_sensor): give one of them",
                    path.display()
                ))
                .into());
            }
            params.body_p_sensor = Some(x);
        }
        let applied = Self {
            file: path.display().to_string(),
            intrinsics: cal.intrinsics,
            time_offset_ns: calibration_file::time_offset_ns(&cal),
            body_p_sensor: cal.body_p_sensor,
            scheme: None,
            scheme_note: None,
        };
        Ok((applied, cal))
    }

    /// Records the file's scheme and the note on applying its time offset with `used`, for
    /// samples `dt_s` \[s\] apart.
    pub fn with_scheme(self, cal: &ImuCalibration, path: &Path, used: Scheme, dt_s: f64) -> Self {
        Self {
            scheme: cal.scheme,
            scheme_note: calibration_file::scheme_note(cal, path, used, dt_s),
            ..self
        }
    }

    /// `{file, time_offset_ns, model, Tw, R_IMUtoGYRO, Ta, R_IMUtoACC, Tg, note, scheme,
    /// scheme_note}`.
    pub fn to_json(&self) -> Value {
        let x = &self.intrinsics;
        json!({
            "file": self.file, "time_offset_ns": self.time_offset_ns, "model": x.model.name(),
            "Tw": rows(&x.t_w), "R_IMUtoGYRO": rows(&x.r_imu_to_gyro), "Ta": rows(&x.t_a),
            "R_IMUtoACC": rows(&x.r_imu_to_acc), "Tg": rows(&x.t_g),
            "note": "intrinsics applied to the raw samples (preint::intrinsics); t_i_ns and \
                     t_j_ns are on the IMU clock: --from/--to plus time_offset_ns",
            "scheme": self.scheme.map(crate::scheme::label),
            "scheme_note": self.scheme_note,
            "body_p_sensor": self.body_p_sensor.as_ref().map(preint_io::extrinsics::pose_vector),
        })
    }

    /// What was applied, and the scheme note.
    pub fn to_text(&self) -> String {
        let x = &self.intrinsics;
        let mut h = String::new();
        let _ = writeln!(
            h,
            "calibration {}: intrinsics ({} model{}) applied to the raw samples; keyframes \
             moved by the time offset {} ns onto the IMU clock",
            self.file,
            x.model.name(),
            if x.is_identity() { ", identity" } else { "" },
            self.time_offset_ns
        );
        if let Some(x) = &self.body_p_sensor {
            let _ = writeln!(
                h,
                "calibration {}: the IMU's pose in the body frame applied as --body-p-sensor {}",
                self.file,
                preint_io::extrinsics::body_p_sensor_flag(x)
            );
        }
        if let Some(n) = &self.scheme_note {
            let _ = writeln!(h, "{n}");
        }
        h
    }
}
