//! `preint integrate`: preintegrate a window of a EuRoC IMU file.

use super::{CliError, Output, fmt_matrix, list, rows};
use crate::Command;
use nalgebra::Vector3;
use preint::io::{check_si_units, read_euroc_imu, read_kalibr_yaml};
use preint::{ImuBias, ImuNoise, Level, PreintParams, Scheme, preintegrate};
use serde_json::json;
use std::fmt::Write as _;

/// Parses a scheme name.
pub fn parse_scheme(s: &str) -> Result<Scheme, CliError> {
    match s {
        "euler" => Ok(Scheme::Euler),
        "midpoint" => Ok(Scheme::Midpoint),
        "rk4" | "high-order" => Ok(Scheme::Hermite4),
        _ => Err(CliError::Usage(format!(
            "unknown scheme `{s}`: expected euler, midpoint or rk4"
        ))),
    }
}

/// Scheme name as printed.
pub fn scheme_name(s: Scheme) -> &'static str {
    match s {
        Scheme::Euler => "euler",
        Scheme::Midpoint => "midpoint",
        Scheme::Hermite4 => "rk4",
    }
}

/// Reads the noise file, or the EuRoC figures when none is given.
pub fn noise_or_default(path: Option<&std::path::PathBuf>) -> Result<ImuNoise, CliError> {
    Ok(match path {
        Some(p) => read_kalibr_yaml(p)?,
        None => ImuNoise::euroc(),
    })
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Integrate {
        imu,
        scheme,
        noise,
        gravity,
        bias_gyro,
        bias_acc,
        from,
        to,
        no_unit_check,
    } = cmd
    else {
        unreachable!()
    };
    let scheme = parse_scheme(scheme)?;
    if !(gravity.is_finite() && *gravity >= 0.0) {
        return Err(CliError::Usage(format!(
            "--gravity must be a non-negative number, got {gravity}"
        )));
    }
    let noise_source = match noise {
        Some(p) => p.display().to_string(),
        None => "EuRoC / ADIS16448 defaults (no --noise)".to_string(),
    };
    let noise = noise_or_default(noise.as_ref())?;
    let samples = read_euroc_imu(imu)?;
    if !no_unit_check {
        check_si_units(&samples, &imu.display().to_string())?;
    }
    let t_i = from.unwrap_or(samples[0].t_ns);
    let t_j = to.unwrap_or(samples[samples.len() - 1].t_ns);
    let bias = ImuBias::new(bias_gyro.unwrap_or_default(), bias_acc.unwrap_or_default());
    let params = PreintParams::from_noise(&noise)
        .with_scheme(scheme)
        .with_level(Level::Combined)
        .with_gravity(Vector3::new(0.0, 0.0, -gravity));
    let m = preintegrate(&params, &bias, &samples, t_i, t_j)
        .map_err(|e| CliError::Failed(format!("{}: {e}", imu.display())))?;
    let n_used = samples
        .iter()
        .filter(|s| s.t_ns >= t_i && s.t_ns <= t_j)
        .count();
    let jac = &m.jac;
    let json = json!({
        "scheme": scheme_name(scheme),
        "samples": n_used,
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
        "covariance_notes": {
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
        },
        "bias_hat": {"gyro": list(&bias.gyro), "acc": list(&bias.acc)},
        "gravity": list(&m.gravity),
        "noise": {
            "source": noise_source,
            "gyroscope_noise_density": noise.gyro_noise_density,
            "gyroscope_random_walk": noise.gyro_random_walk,
            "accelerometer_noise_density": noise.acc_noise_density,
            "accelerometer_random_walk": noise.acc_random_walk,
            "units": "continuous-time densities: rad/s/sqrt(Hz), rad/s^2/sqrt(Hz), m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)",
        },
        "units": {"delta_t": "s", "delta_v": "m/s (body frame i)", "delta_p": "m (body frame i)",
                  "covariance": "rad^2, (m/s)^2, m^2 blocks", "jacobians": "d(delta)/d(bias), bias order [b_g, b_a]"},
        "jacobians": {
            "dR_dbg": rows(&jac.d_r_d_bg), "dv_dbg": rows(&jac.d_v_d_bg), "dv_dba": rows(&jac.d_v_d_ba),
            "dp_dbg": rows(&jac.d_p_d_bg), "dp_dba": rows(&jac.d_p_d_ba),
        },
    });
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} samples, scheme {}, Δt = {:.9} s",
        imu.display(),
        n_used,
        scheme_name(scheme),
        m.delta_t
    );
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
    let sd: Vec<f64> = (0..9).map(|i| m.cov[(i, i)].sqrt()).collect();
    let _ = writeln!(
        h,
        "noise: {noise_source}: σ_g = {:.4e} rad/s/√Hz, σ_a = {:.4e} m/s²/√Hz, σ_bg = {:.4e} rad/s²/√Hz, σ_ba = {:.4e} m/s³/√Hz",
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
    h.push_str(&fmt_matrix(&m.cov, "  "));
    for (name, j) in [
        ("∂ΔR/∂b_g", &jac.d_r_d_bg),
        ("∂Δv/∂b_g", &jac.d_v_d_bg),
        ("∂Δv/∂b_a", &jac.d_v_d_ba),
        ("∂Δp/∂b_g", &jac.d_p_d_bg),
        ("∂Δp/∂b_a", &jac.d_p_d_ba),
    ] {
        let _ = writeln!(h, "{name}:");
        h.push_str(&fmt_matrix(j, "  "));
    }
    Ok(Output { human: h, json })
}
