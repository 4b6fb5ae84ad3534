//! The JSON form of `preint calibrate`: every estimate with its modelled σ and its σ scaled by
//! `√(χ²/dof)` (`*_std` and `*_std_scaled`), the fit beside them, how the recording was read
//! and the file written.

use super::{CalibrateRun, Calibrated, Calibration};
use crate::consistency::fit_json;
use crate::format::{list, opt_list};
use nalgebra::Vector3;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint_calib::Fit;
use preint_calib::bias::MultiPoseCalibration;
use preint_calib::bias::known_poses::extras::ParameterEstimate;
use preint_calib::bias::known_poses::extrinsic::{ExtrinsicEstimate, ExtrinsicStart};
use serde_json::{Value, json};

/// `v·√(χ²/dof)` per component.
fn scaled(v: &Vector3<f64>, f: &Fit) -> Vector3<f64> {
    v * f.scale()
}

/// The JSON form of a run: [`calibrated_json`] with `input` (how the recording was read) and,
/// when a file was written, `out` (its path).
pub fn to_json(r: &CalibrateRun) -> Value {
    let mut json = calibrated_json(&r.calibrated);
    json["input"] = crate::recording::input_json(&r.source, &r.unit_check);
    if let Some(w) = &r.written {
        json["out"] = json!(w.path.display().to_string());
    }
    json
}

/// The JSON form: `model` names the problem; estimates with their standard deviations
/// (modelled `*_std`, scaled `*_std_scaled`), χ², units, the `fit` and the `notes`.
pub fn calibrated_json(r: &Calibrated) -> Value {
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
            "model": "known-poses", "poses": poses, "scheme": r.scheme.name(),
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
            "extrinsics": c.extrinsic.as_ref().map(|e| extrinsics_json(e, f)),
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
            "model": "known-attitudes", "poses": poses, "scheme": r.scheme.name(),
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

/// The tangent order of the extrinsic covariance, as printed beside it.
pub const EXTRINSIC_TANGENT: &str = "[dtheta_x, dtheta_y, dtheta_z] rad (right perturbation \
    R_bs*Exp(dtheta)), [dp_x, dp_y, dp_z] m (lever arm, frame of the poses)";

/// The IMU's pose in the frame of the poses: `body_p_sensor` as `[x, y, z, qw, qx, qy, qz]`,
/// its 6×6 covariance (modelled and scaled by χ²/dof; null rows and columns where withheld)
/// in the order `tangent`, σ, `excited` per part, where it started and how much the poses
/// rotate about each axis.
fn extrinsics_json(e: &ExtrinsicEstimate, f: &Fit) -> Value {
    let num = |v: f64| v.is_finite().then_some(v);
    let cov = |k: f64| -> Vec<Vec<Option<f64>>> {
        (0..6)
            .map(|i| (0..6).map(|j| num(e.covariance[(i, j)] * k)).collect())
            .collect()
    };
    let scale2 = f.scale() * f.scale();
    let std = e.std();
    json!({
        "body_p_sensor": preint_io::extrinsics::pose_vector(&e.body_p_sensor),
        "covariance": cov(1.0), "covariance_scaled": cov(scale2), "tangent": EXTRINSIC_TANGENT,
        "std": std.map(num), "std_scaled": std.map(|s| num(f.scaled(s))),
        "excited": {"rotation": e.rotation_excited, "lever_arm": e.lever_arm_excited},
        "start": match e.start {
            ExtrinsicStart::Given => "given",
            ExtrinsicStart::HandEye => "hand-eye",
            ExtrinsicStart::Identity => "identity",
        },
        "rotation_rms_rad_s": list(&e.rotation_rms_rad_s),
        "units": {"body_p_sensor": "m, Hamilton quaternion qw qx qy qz of R_bs (IMU -> frame of the poses)"},
    })
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

/// What `--latitude` did to the gyro bias.
fn earth_json(e: &preint_calib::bias::EarthRateInBody) -> Value {
    json!({"latitude_deg": e.latitude_deg, "heading_deg": e.heading_deg,
        "removed_body": list(&e.removed), "unresolved_horizontal": e.unresolved,
        "note": earth_note(e), "units": "rad/s, body frame"})
}

/// One sentence on the Earth rate's share of the bias.
pub fn earth_note(e: &preint_calib::bias::EarthRateInBody) -> String {
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

/// The multi-position calibration: estimates, σ (modelled and scaled), the models compared.
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
