//! The printed forms of `preint calibrate`: every estimate with its modelled σ and its σ scaled
//! by `√(χ²/dof)` (`*_std` and `*_std_scaled` in JSON), and the fit beside them.

use super::{Calibrated, Calibration};
use crate::fit::fit_text;
use crate::scheme;
use nalgebra::Vector3;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint_analysis::consistency::fit_json;
use preint_analysis::format::{list, opt_list};
use preint_calib::Fit;
use preint_calib::bias::MultiPoseCalibration;
use preint_calib::bias::known_poses::extras::ParameterEstimate;
use serde_json::{Value, json};

/// `v·√(χ²/dof)` per component.
fn scaled(v: &Vector3<f64>, f: &Fit) -> Vector3<f64> {
    v * f.scale()
}

/// The JSON form: `model` names the problem; estimates with their standard deviations
/// (modelled `*_std`, scaled `*_std_scaled`), χ², units, the `fit` and the `notes`.
pub fn to_json(r: &Calibrated) -> Value {
    let f = &r.fit;
    let s = |v: &Vector3<f64>| list(&scaled(v, f));
    let mut out = match &r.calibration {
        Calibration::KnownPoses {
            poses,
            pose_std,
            c,
            time_offset,
            ..
        } => json!({
            "model": "known-poses", "poses": poses, "scheme": scheme::label(r.scheme),
            "parameters": parameters_json(&c.parameters, c.intrinsics.model, f),
            "time_offset_s": time_offset.then_some(c.time_offset_s),
            "intrinsics": intrinsics_json(&c.intrinsics),
            "gyro_bias": list(&c.bias.gyro), "gyro_bias_std": list(&c.gyro_bias_std),
            "gyro_bias_std_scaled": s(&c.gyro_bias_std),
            "acc_bias": list(&c.bias.acc), "acc_bias_std": list(&c.acc_bias_std),
            "acc_bias_std_scaled": s(&c.acc_bias_std),
            "gravity": list(&c.gravity), "gravity_std": list(&c.gravity_std),
            "gravity_std_scaled": s(&c.gravity_std), "gravity_tilt_deg": c.gravity_tilt.to_degrees(),
            "pose_rot_std": pose_std.0, "pose_pos_std": pose_std.1,
            "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "gravity": "m/s^2"},
        }),
        Calibration::KnownAttitudes {
            poses,
            pose_rot_std,
            c,
            time_offset,
            ..
        } => json!({
            "model": "known-attitudes", "poses": poses, "scheme": scheme::label(r.scheme),
            "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
            "gyro_bias_std_scaled": s(&c.gyro_bias_std),
            "parameters": parameters_json(&c.parameters, c.intrinsics.model, f),
            "time_offset_s": time_offset.then_some(c.time_offset_s),
            "intrinsics": intrinsics_json(&c.intrinsics),
            "pose_rot_std": pose_rot_std,
            "iterations": c.iterations, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s"},
        }),
        Calibration::MultiPose(c) => multi_pose_json(c, f),
        Calibration::Static {
            c,
            used,
            still_s,
            body_roll_pitch,
            earth,
        } => json!({
            "model": "static-single-attitude",
            "interval_ns": [used.t_start_ns, used.t_end_ns], "still_s": still_s.0, "recording_s": still_s.1,
            "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
            "gyro_bias_std_scaled": s(&c.gyro_bias_std),
            "acc_bias": opt_list(c.acc_bias), "acc_bias_std": opt_list(c.acc_bias_std),
            "acc_bias_std_scaled": opt_list(c.acc_bias_std.map(|v| scaled(&v, f))),
            "acc_bias_note": c.acc_bias_note,
            "roll": c.roll, "pitch": c.pitch, "roll_std": c.roll_std, "pitch_std": c.pitch_std,
            "roll_std_scaled": f.scaled(c.roll_std), "pitch_std_scaled": f.scaled(c.pitch_std),
            "body_roll": body_roll_pitch.map(|b| b.0), "body_pitch": body_roll_pitch.map(|b| b.1),
            "unobservable": c.unobservable, "measured_gyro_density": list(&c.measured_gyro_density),
            "measured_acc_density": list(&c.measured_acc_density),
            "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s", "roll": "rad", "pitch": "rad", "densities": "rad/s/sqrt(Hz), m/s^2/sqrt(Hz)"},
            "earth_rate": earth.as_ref().map(earth_json),
        }),
    };
    out["fit"] = fit_json(f);
    out["notes"] = json!(r.notes);
    out
}

/// The `--estimate` parameters: name, unit, whether excited, the estimate (`value`, null when
/// withheld), the value kept (`kept`: the estimate, or the initial value when withheld) and σ,
/// modelled and scaled (null when the motion does not move the parameter at all).
fn parameters_json(ps: &[ParameterEstimate], model: IntrinsicsModel, f: &Fit) -> Value {
    ps.iter()
        .map(|e| {
            let std = e.std.is_finite().then_some(e.std);
            json!({"name": e.param.name(model), "unit": e.param.unit(), "excited": e.excited,
                "value": e.excited.then_some(e.value), "kept": e.value,
                "std": std, "std_scaled": std.map(|s| f.scaled(s))})
        })
        .collect()
}

/// The intrinsics' matrices, row by row.
fn intrinsics_json(x: &ImuIntrinsics) -> Value {
    let rows = |m: &nalgebra::Matrix3<f64>| -> Vec<Vec<f64>> {
        (0..3)
            .map(|r| (0..3).map(|c| m[(r, c)]).collect())
            .collect()
    };
    json!({"model": x.model.name(), "Tw": rows(&x.t_w), "R_IMUtoGYRO": rows(&x.r_imu_to_gyro),
        "Ta": rows(&x.t_a), "R_IMUtoACC": rows(&x.r_imu_to_acc), "Tg": rows(&x.t_g)})
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

/// What `--latitude` did to the gyro bias.
fn earth_json(e: &preint_calib::bias::EarthRateInBody) -> Value {
    json!({"latitude_deg": e.latitude_deg, "heading_deg": e.heading_deg,
        "removed_body": list(&e.removed), "unresolved_horizontal": e.unresolved,
        "note": earth_note(e), "units": "rad/s, body frame"})
}

/// One sentence on the Earth rate's share of the bias.
fn earth_note(e: &preint_calib::bias::EarthRateInBody) -> String {
    if e.heading_deg.is_some() {
        "the Earth rate R_wb^T w_ie (from latitude, roll, pitch and heading) is removed from b_g"
            .into()
    } else {
        format!(
            "the vertical Earth rate is removed from b_g; its horizontal part ({:.3e} rad/s, \
             direction unknown without --heading) is not separable from b_g and is included in \
             the b_g sigma",
            e.unresolved
        )
    }
}

fn multi_pose_json(c: &MultiPoseCalibration, f: &Fit) -> Value {
    let fits: Vec<Value> = c
        .fits
        .iter()
        .map(|f| {
            json!({"model": format!("{:?}", f.model), "chi2": f.chi2,
        "params": f.params, "bic": f.bic, "identifiable": f.identifiable, "converged": f.converged})
        })
        .collect();
    let chosen = c.fits.iter().find(|f| f.model == c.model);
    let s = |v: Option<Vector3<f64>>| opt_list(v.map(|v| scaled(&v, f)));
    json!({
        "model": format!("multi-pose/{:?}", c.model), "still_intervals": c.intervals.len(),
        "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
        "gyro_bias_std_scaled": s(Some(c.gyro_bias_std)),
        "acc_bias": list(&c.acc_bias), "acc_bias_std": list(&c.acc_bias_std),
        "acc_bias_std_scaled": s(Some(c.acc_bias_std)),
        "acc_scale": opt_list(c.acc_scale), "acc_scale_std": opt_list(c.acc_scale_std),
        "acc_scale_std_scaled": s(c.acc_scale_std),
        "gyro_scale": opt_list(c.gyro_scale), "gyro_scale_std": opt_list(c.gyro_scale_std),
        "gyro_scale_std_scaled": s(c.gyro_scale_std),
        "model_selection": fits, "reason": c.reason,
        "bias_reference_time_ns": c.reference_time_ns, "random_walk_marginalised": c.random_walk_marginalised,
        "iterations": c.iterations, "cost": chosen.map(|f| 0.5 * f.chi2), "chi2": c.chi2, "dof": c.dof,
        "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "scale": "dimensionless (1 = ideal)"},
    })
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

/// The human summary: the problem solved, its estimates with their standard deviations
/// (modelled, then scaled by √(χ²/dof)), the fit, and its warnings and notes.
pub fn to_text(r: &Calibrated) -> String {
    let f = &r.fit;
    let body = match &r.calibration {
        Calibration::KnownPoses {
            source, poses, c, ..
        } => format!(
            "known-pose calibration ({poses} poses from {source}, scheme {}):\n{}{}{}  gravity \
             tilt {:.3}°, χ²/dof = {:.2}, {} iterations\n",
            scheme::label(r.scheme),
            gyro_line(&c.bias.gyro, &c.gyro_bias_std, f),
            acc_line(&c.bias.acc, &c.acc_bias_std, f),
            parameter_lines(&c.parameters, c.intrinsics.model, f),
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
        } => format!(
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
                .as_ref()
                .map(|e| format!("  Earth rate at {}°: {}\n", e.latitude_deg, earth_note(e)))
                .unwrap_or_default()
        ),
    };
    let mut h = body;
    h.push_str(&fit_text(f, r.calibration.problem()));
    for n in &r.notes {
        h.push_str(n);
        h.push('\n');
    }
    h
}
