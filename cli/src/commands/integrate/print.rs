//! The printed forms of `preint integrate`: the deltas, their covariances (with notes on what
//! each describes), the bias Jacobians, the noise used and the units; then what the flags
//! asked, each printed by its own type.

use super::Integration;
use crate::scheme;
use preint_analysis::format::{list, rows, text_matrix};
use preint_analysis::noise;
use preint_analysis::recording::input_json;
use serde_json::{Value, json};
use std::fmt::Write as _;

/// What each printed covariance describes, and how GTSAM's relate to them.
fn covariance_notes() -> Value {
    json!({
        "covariance": "covariance of the error [dphi, dv, dp] = measured minus true deltas \
            (dphi: DR_measured = DR_true Exp(dphi)); white measurement noise. It is also the \
            covariance of ImuFactor's residual [r_phi, r_v, r_p] (= -[dphi, dv, dp]).",
        "covariance15": "covariance of the error state [dphi, dv, dp, db_g, db_a], db = b_j - b_i, \
            with the bias random walk over the window; what merging windows composes. A gyro \
            bias that drifts up makes the measured rotation run ahead: the delta-bias blocks \
            are those of measured minus true.",
        "residual_covariance15": "covariance of CombinedImuFactor's residual [r_phi, r_v, r_p, \
            b_g,j - b_g,i, b_a,j - b_a,i] at the true states (the deltas' rows are true minus \
            measured): covariance15 with its 9x6 and 6x9 delta-bias blocks negated. Weight a \
            combined residual with this one.",
        "gtsam": "GTSAM 4.3 orders [rot, pos, vel, b_a, b_g] and expresses pos and vel errors \
            rotated by delta_R^T: with P the reordering and T = diag(I, delta_R^T, delta_R^T, I, I), \
            PreintegratedCombinedMeasurements::preintMeasCov() = T P covariance15 P^T T^T and \
            residualCovariance() = T P residual_covariance15 P^T T^T (tested to 1e-12 on \
            PreintegratedCombinedMeasurementsManifold, the euler scheme).",
    })
}

/// The JSON form: deltas, covariances (with notes on what each describes), bias Jacobians, the noise
/// used and the units.
pub fn to_json(r: &Integration) -> Value {
    let m = &r.pim;
    let jac = &m.jac;
    let mut noise = noise::densities_json(&r.noise);
    noise["source"] = json!(r.noise_source);
    noise["units"] = json!(
        "continuous-time densities: rad/s/sqrt(Hz), rad/s^2/sqrt(Hz), m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)"
    );
    let mut out = json!({
        "imu": r.imu,
        "input": input_json(&r.source, &r.unit_check),
        "scheme": scheme::label(r.scheme),
        "samples": r.samples,
        "t_i_ns": m.t_i_ns,
        "t_j_ns": m.t_j_ns,
        "delta_t": m.delta_t,
        "delta_R": rows(m.delta_r.matrix()),
        "delta_R_log": list(&m.delta_r.log()),
        "delta_v": list(&m.delta_v),
        "delta_p": list(&m.delta_p),
        "tangent_order": ["dphi_x", "dphi_y", "dphi_z", "dv_x", "dv_y", "dv_z", "dp_x", "dp_y", "dp_z"],
        "covariance": rows(&m.cov),
        "covariance15_order": "[dphi, dv, dp, db_g, db_a]",
        "covariance15": rows(&m.cov15),
        "residual_covariance15_order": "[r_phi, r_v, r_p, r_bg, r_ba]",
        "residual_covariance15": rows(&m.residual_cov15()),
        "covariance_notes": covariance_notes(),
        "bias_hat": {"gyro": list(&r.bias.gyro), "acc": list(&r.bias.acc)},
        "gravity": list(&m.gravity),
        "body_p_sensor": r.body_p_sensor.map(|p| json!({
            "translation": list(&p.translation),
            "rotation": rows(p.rotation.matrix()),
            "lever_arm": r.lever_arm.name(),
            "note": "IMU pose in the body: translation = IMU origin in body coordinates [m], \
                rotation = sensor-to-body; delta_R, delta_v, delta_p and their covariances are \
                the body's, biases the IMU's (its own axes)",
        })),
        "noise": noise,
        "units": {"delta_t": "s", "delta_v": "m/s (body frame i)", "delta_p": "m (body frame i)",
                  "covariance": "rad^2, (m/s)^2, m^2 blocks", "jacobians": "d(delta)/d(bias), bias order [b_g, b_a]"},
        "jacobians": {
            "dR_dbg": rows(&jac.d_r_d_bg), "dv_dbg": rows(&jac.d_v_d_bg), "dv_dba": rows(&jac.d_v_d_ba),
            "dp_dbg": rows(&jac.d_p_d_bg), "dp_dba": rows(&jac.d_p_d_ba),
        },
        "omega_coriolis": m.omega_coriolis.map(|w| list(&w)),
        "coriolis": m.omega_coriolis.map(|_| crate::earth_args::mode_label(m.coriolis)),
    });
    if !r.at.is_empty() {
        out["at"] = r.at.to_json();
    }
    if let Some(t) = &r.truncation {
        out["truncation"] = t.to_json();
    }
    if let Some(c) = &r.calibration {
        out["calibration"] = c.to_json();
    }
    if let Some(c) = &r.second_order {
        out["second_order"] = c.to_json(&r.pim);
    }
    if let Some(x) = &r.predicted {
        out["predicted"] = x.to_json();
    }
    out
}

/// The deltas, as printed: the window, how the recording was read, ΔR, Δv, Δp and the body
/// frame of `--body-p-sensor`.
fn deltas_text(r: &Integration) -> String {
    let m = &r.pim;
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{} (read as {}): {} samples, scheme {}, Δt = {:.9} s",
        r.imu,
        r.source.describe(),
        r.samples,
        scheme::label(r.scheme),
        m.delta_t
    );
    h.push_str(&preint_analysis::recording::input_text(
        &r.source,
        &r.unit_check,
    ));
    let phi = m.delta_r.log();
    let _ = writeln!(
        h,
        "ΔR = Exp([{:.9}, {:.9}, {:.9}]) (rotation vector, rad; |φ| = {:.6}°)",
        phi.x,
        phi.y,
        phi.z,
        phi.norm().to_degrees()
    );
    let _ = writeln!(
        h,
        "Δv = [{:.9}, {:.9}, {:.9}] m/s (body frame i, gravity excluded)",
        m.delta_v.x, m.delta_v.y, m.delta_v.z
    );
    let _ = writeln!(
        h,
        "Δp = [{:.9}, {:.9}, {:.9}] m (body frame i, gravity excluded)",
        m.delta_p.x, m.delta_p.y, m.delta_p.z
    );
    if let Some(pose) = &r.body_p_sensor {
        let t = pose.translation;
        let _ = writeln!(
            h,
            "body frame: IMU at [{:.4}, {:.4}, {:.4}] m in the body, rotated by {:.4}° (the deltas \
             are the body's, lever arm removed exactly; biases are the IMU's)",
            t.x,
            t.y,
            t.z,
            pose.rotation.log().norm().to_degrees()
        );
    }
    h
}

/// The noise densities used, the deltas' 1σ, the 9×9 covariance, the five bias Jacobians and
/// the rotating world frame.
fn covariance_text(r: &Integration) -> String {
    let (m, noise) = (&r.pim, &r.noise);
    let mut h = String::new();
    let sd: Vec<f64> = (0..9).map(|i| m.cov[(i, i)].sqrt()).collect();
    let _ = writeln!(
        h,
        "noise: {}: σ_g = {:.4e} rad/s/√Hz, σ_a = {:.4e} m/s²/√Hz, σ_bg = {:.4e} rad/s²/√Hz, σ_ba = {:.4e} m/s³/√Hz",
        r.noise_source,
        noise.gyro_noise_density,
        noise.acc_noise_density,
        noise.gyro_random_walk,
        noise.acc_random_walk
    );
    let _ = writeln!(
        h,
        "1σ (noise): φ [{:.3e} {:.3e} {:.3e}] rad, v [{:.3e} {:.3e} {:.3e}] m/s, p [{:.3e} {:.3e} {:.3e}] m",
        sd[0], sd[1], sd[2], sd[3], sd[4], sd[5], sd[6], sd[7], sd[8]
    );
    let _ = writeln!(h, "covariance, tangent order [δφ, δv, δp]:");
    h.push_str(&text_matrix(&m.cov, "  "));
    let jac = &m.jac;
    for (name, j) in [
        ("∂ΔR/∂b_g", &jac.d_r_d_bg),
        ("∂Δv/∂b_g", &jac.d_v_d_bg),
        ("∂Δv/∂b_a", &jac.d_v_d_ba),
        ("∂Δp/∂b_g", &jac.d_p_d_bg),
        ("∂Δp/∂b_a", &jac.d_p_d_ba),
    ] {
        let _ = writeln!(h, "{name}:");
        h.push_str(&text_matrix(j, "  "));
    }
    if let Some(w) = m.omega_coriolis {
        let _ = writeln!(
            h,
            "world frame rotating at ω = [{:e}, {:e}, {:e}] rad/s, Coriolis mode {}",
            w.x,
            w.y,
            w.z,
            crate::earth_args::mode_label(m.coriolis)
        );
    }
    h
}

/// The human summary: [`deltas_text`], [`covariance_text`], then what the flags asked, each
/// printed by its own type.
pub fn to_text(r: &Integration) -> String {
    let mut h = deltas_text(r) + &covariance_text(r);
    if let Some(t) = &r.truncation {
        h.push_str(&t.to_text(&r.pim));
    }
    if let Some(c) = &r.calibration {
        h.push_str(&c.to_text());
    }
    if let Some(c) = &r.second_order {
        h.push_str(&c.to_text(&r.pim));
    }
    if let Some(x) = &r.predicted {
        h.push_str(&x.to_text());
    }
    h.push_str(&r.at.to_text());
    h
}
