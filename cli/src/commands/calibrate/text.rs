//! The human summary of `preint calibrate`: every estimate with its modelled σ and its σ
//! scaled by `√(χ²/dof)`, the fit beside them, and the file written.

use crate::fit::fit_text;
use crate::scheme;
use nalgebra::Vector3;
use preint::intrinsics::IntrinsicsModel;
use preint_analysis::calibrate::{CalibrateRun, Calibrated, Calibration, earth_note};
use preint_calib::Fit;
use preint_calib::bias::known_poses::extras::ParameterEstimate;
use preint_calib::bias::known_poses::extrinsic::{ExtrinsicEstimate, ExtrinsicStart};
use preint_calib::bias::{EarthRateInBody, StaticCalibration, StillInterval};

/// `v·√(χ²/dof)` per component.
fn scaled(v: &Vector3<f64>, f: &Fit) -> Vector3<f64> {
    v * f.scale()
}

/// ` (± σ' scaled by √(χ²/dof) = s)`.
fn scaled_note(value: String, f: &Fit) -> String {
    format!(" (± {value} scaled by √(χ²/dof) = {:.3})", f.scale())
}

/// The `--estimate` parameters, one line each: value ± σ (and scaled), or why withheld.
fn parameter_lines(ps: &[ParameterEstimate], model: IntrinsicsModel, f: &Fit) -> String {
    ps.iter()
        .map(|e| {
            let name = e.param.name(model);
            let unit = e.param.unit();
            if e.excited {
                format!(
                    "  {name} = {:+.6e} ± {:.1e} {unit}{}\n",
                    e.value,
                    e.std,
                    scaled_note(format!("{:.1e}", f.scaled(e.std)), f)
                )
            } else {
                let sigma = if e.std.is_finite() {
                    format!("σ {:.1e} {unit}", e.std)
                } else {
                    "σ unbounded: the motion holds no information on it".to_string()
                };
                format!(
                    "  {name}: not excited by the motion ({sigma}): kept at {:+.6e}\n",
                    e.value
                )
            }
        })
        .collect()
}

/// `  name = [x, y, z] ± [σx, σy, σz] unit (± [σ'…] scaled by √(χ²/dof) = s)`, the values with
/// `digits` decimals.
fn vector_line(
    name: &str,
    b: &Vector3<f64>,
    s: &Vector3<f64>,
    unit: &str,
    digits: usize,
    f: &Fit,
) -> String {
    let ss = scaled(s, f);
    format!(
        "  {name} = [{:.digits$}, {:.digits$}, {:.digits$}] ± [{:.1e}, {:.1e}, {:.1e}] {unit}{}\n",
        b.x,
        b.y,
        b.z,
        s.x,
        s.y,
        s.z,
        scaled_note(format!("[{:.1e}, {:.1e}, {:.1e}]", ss.x, ss.y, ss.z), f)
    )
}

fn gyro_line(b: &Vector3<f64>, s: &Vector3<f64>, f: &Fit) -> String {
    vector_line("b_g", b, s, "rad/s", 6, f)
}

fn acc_line(b: &Vector3<f64>, s: &Vector3<f64>, f: &Fit) -> String {
    vector_line("b_a", b, s, "m/s²", 4, f)
}

/// The static problem's estimates: the interval used, b_g, roll and pitch (of the IMU, and of
/// the body with `--body-p-sensor`), why b_a is not estimated, and the Earth rate removed.
fn static_text(
    c: &StaticCalibration,
    used: &StillInterval,
    still_s: (f64, f64),
    body_roll_pitch: Option<(f64, f64)>,
    earth: Option<&EarthRateInBody>,
    f: &Fit,
) -> String {
    format!(
        "static calibration (one attitude) on the longest still interval, {:.1} s from {} to \
         {} ns ({:.1} s still of {:.1} s recorded):\n{}  roll {:.4}° ± {:.1e}°, pitch \
         {:.4}° ± {:.1e}° (IMU axes){}{}\n  b_a: not estimated ({})\n{}",
        c.duration_s,
        used.t_start_ns,
        used.t_end_ns,
        still_s.0,
        still_s.1,
        gyro_line(&c.gyro_bias, &c.gyro_bias_std, f),
        c.roll.to_degrees(),
        c.roll_std.to_degrees(),
        c.pitch.to_degrees(),
        c.pitch_std.to_degrees(),
        scaled_note(
            format!(
                "{:.1e}°, {:.1e}°",
                f.scaled(c.roll_std).to_degrees(),
                f.scaled(c.pitch_std).to_degrees()
            ),
            f
        ),
        body_roll_pitch.map_or(String::new(), |(r, p)| format!(
            "; body roll {:.4}°, pitch {:.4}°",
            r.to_degrees(),
            p.to_degrees()
        )),
        c.acc_bias_note,
        earth
            .map(|e| format!("  Earth rate at {}°: {}\n", e.latitude_deg, earth_note(e)))
            .unwrap_or_default()
    )
}

/// The IMU's pose in the frame of the poses: as `--body-p-sensor` takes it, where it started,
/// what was withheld and how much the poses rotate (the lever arm needs rotation).
fn extrinsic_lines(e: &ExtrinsicEstimate) -> String {
    let start = match e.start {
        ExtrinsicStart::Given => "the given transform",
        ExtrinsicStart::HandEye => "the hand-eye rotation",
        ExtrinsicStart::Identity => "the identity (the motion turns about one axis only)",
    };
    let part = |excited: bool| {
        if excited {
            "estimated"
        } else {
            "not all excited"
        }
    };
    let w = e.rotation_rms_rad_s;
    let mut out = format!(
        "  IMU in the frame of the poses: --body-p-sensor {} (rotation {}, lever arm {}; \
         started at {start})\n  covariance order {}\n",
        preint_io::extrinsics::body_p_sensor_flag(&e.body_p_sensor),
        part(e.rotation_excited),
        part(e.lever_arm_excited),
        preint_analysis::calibrate::EXTRINSIC_TANGENT
    );
    if !e.lever_arm_excited {
        out.push_str(&format!(
            "  the poses turn at RMS {:.3}, {:.3}, {:.3} rad/s about their x, y, z axes: a \
             lever-arm component needs rotation about the two other axes\n",
            w.x, w.y, w.z
        ));
    }
    out
}

/// The human summary: the problem solved, its estimates with their standard deviations
/// (modelled, then scaled by √(χ²/dof)), the fit, and its warnings and notes.
pub fn calibrated_text(r: &Calibrated) -> String {
    let f = &r.fit;
    let body = match &r.calibration {
        Calibration::KnownPoses {
            source, poses, c, ..
        } => format!(
            "known-pose calibration ({poses} poses from {source}, scheme {}):\n{}{}{}{}  gravity \
             tilt {:.3}°, χ²/dof = {:.2}, {} iterations\n",
            scheme::label(r.scheme),
            gyro_line(&c.bias.gyro, &c.gyro_bias_std, f),
            acc_line(&c.bias.acc, &c.acc_bias_std, f),
            parameter_lines(&c.parameters, c.intrinsics.model, f),
            c.extrinsic.as_ref().map_or(String::new(), extrinsic_lines),
            c.gravity_tilt.to_degrees(),
            c.chi2 / c.dof.max(1) as f64,
            c.iterations
        ),
        Calibration::KnownAttitudes {
            source, poses, c, ..
        } => format!(
            "known-attitude (gyroscope) calibration ({poses} attitudes from {source}, scheme \
             {}):\n{}{}  χ²/dof = {:.2}, {} iterations\n",
            scheme::label(r.scheme),
            gyro_line(&c.gyro_bias, &c.gyro_bias_std, f),
            parameter_lines(&c.parameters, c.intrinsics.model, f),
            c.chi2_per_dof(),
            c.iterations
        ),
        Calibration::MultiPose(c) => format!(
            "multi-position calibration: {} still intervals; model {:?} ({})\n{}{}",
            c.intervals.len(),
            c.model,
            c.reason,
            gyro_line(&c.gyro_bias, &c.gyro_bias_std, f),
            acc_line(&c.acc_bias, &c.acc_bias_std, f)
        ),
        Calibration::Static {
            c,
            used,
            still_s,
            body_roll_pitch,
            earth,
        } => static_text(c, used, *still_s, *body_roll_pitch, earth.as_ref(), f),
    };
    let mut h = body;
    h.push_str(&fit_text(f, r.calibration.problem()));
    for n in &r.notes {
        h.push_str(n);
        h.push('\n');
    }
    h
}

/// The human summary of a run: how the recording was read, [`calibrated_text`] and the file
/// written.
pub fn to_text(r: &CalibrateRun) -> String {
    let mut human = preint_analysis::recording::input_text(&r.source, &r.unit_check)
        + &calibrated_text(&r.calibrated);
    if let Some(w) = &r.written {
        human.push_str(&format!(
            "calibration written to {} (OpenVINS kalibr_imu_chain.yaml: intrinsics{}{}{}, \
             noise densities)\n",
            w.path.display(),
            w.intrinsics_from,
            if w.time_offset { ", time offset" } else { "" },
            w.scheme.map_or(String::new(), |s| format!(
                " for the {} scheme",
                scheme::label(s)
            ))
        ));
        if let Some(cc) = &w.camchain {
            human.push_str(&format!(
                "extrinsics written to {} (Kalibr camchain-imucam.yaml: T_cam_imu, \
                 timeshift_cam_imu)\n",
                cc.display()
            ));
        }
    }
    human
}
