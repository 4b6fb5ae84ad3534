//! `preint calibrate`: bias estimation with Gauss-Newton, modelling only what the data makes
//! observable.
//!
//! Model choice:
//! - `--poses FILE` (EuRoC ground-truth format, or any pose source written in it): the
//!   known-pose problem (biases, velocities, gravity direction) on poses ≥ 0.5 s apart;
//! - otherwise, still intervals are detected; with at least three of them at distinct
//!   attitudes (> 20° apart) the multi-position problem (Tedaldi et al. 2014) estimates both
//!   biases, the attitudes and, if BIC supports it, scale factors;
//! - otherwise the single-attitude static problem: gyro bias and roll/pitch; the accelerometer
//!   bias is not separable from tilt and is reported as unobservable (`acc_bias: null`).

use super::integrate::noise_or_default;
use super::{CliError, Output, list};
use crate::Command;
use nalgebra::Vector3;
use preint::io::{check_si_units, read_euroc_groundtruth, read_euroc_imu};
use preint::{ImuSample, PreintParams, Scheme};
use preint_calib::bias::{
    KnownPose, KnownPoseOptions, MultiPoseOptions, StaticOptions, StillOptions,
    calibrate_known_poses, calibrate_multi_pose, calibrate_static, detect_still_intervals,
};
use serde_json::{Value, json};

/// A solver error, prefixed with the IMU file it came from.
fn fail_in(imu: &std::path::Path) -> impl Fn(preint_calib::bias::BiasError) -> CliError + '_ {
    move |e| CliError::Failed(format!("{}: {e}", imu.display()))
}

fn opt3(v: Option<Vector3<f64>>) -> Value {
    v.map_or(Value::Null, |v| list(&v))
}

/// Number of still intervals whose mean specific-force directions differ pairwise by > 20°.
fn distinct_attitudes(samples: &[ImuSample], ivs: &[preint_calib::bias::StillInterval]) -> usize {
    let mut dirs: Vec<Vector3<f64>> = Vec::new();
    for iv in ivs {
        let m: Vector3<f64> = samples[iv.start..iv.end]
            .iter()
            .map(|s| s.acc)
            .sum::<Vector3<f64>>();
        let d = m.normalize();
        if dirs.iter().all(|e| e.dot(&d) < 20f64.to_radians().cos()) {
            dirs.push(d);
        }
    }
    dirs.len()
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Calibrate {
        imu,
        poses,
        noise,
        gravity,
        from,
        to,
        pose_rot_std,
        pose_pos_std,
    } = cmd
    else {
        unreachable!()
    };
    let fail = fail_in(imu);
    for (name, v) in [
        ("--pose-rot-std", pose_rot_std),
        ("--pose-pos-std", pose_pos_std),
    ] {
        if !(v.is_finite() && *v >= 0.0) {
            return Err(CliError::Usage(format!(
                "{name} must be a non-negative number, got {v}"
            )));
        }
    }
    if !(gravity.is_finite() && *gravity > 0.0) {
        return Err(CliError::Usage(format!(
            "--gravity must be a positive number, got {gravity}"
        )));
    }
    let noise = noise_or_default(noise.as_ref())?;
    let mut samples = read_euroc_imu(imu)?;
    let (lo, hi) = (from.unwrap_or(i64::MIN), to.unwrap_or(i64::MAX));
    samples.retain(|s| s.t_ns >= lo && s.t_ns <= hi);
    if samples.len() < 2 {
        return Err(CliError::Failed(format!(
            "{}: fewer than two samples with timestamps in [{lo}, {hi}] ns",
            imu.display()
        )));
    }
    check_si_units(&samples, &imu.display().to_string())?;
    let g = Vector3::new(0.0, 0.0, -gravity);
    let n = samples.len();
    let rate = (n - 1) as f64 / ((samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9);

    if let Some(pfile) = poses {
        let gt = read_euroc_groundtruth(pfile)?;
        let (t0, t1) = (samples[0].t_ns, samples[n - 1].t_ns);
        let mut kp: Vec<KnownPose> = Vec::new();
        for s in gt.iter().filter(|s| s.t_ns >= t0 && s.t_ns <= t1) {
            if kp.last().is_none_or(|l| s.t_ns - l.t_ns >= 500_000_000) {
                kp.push(KnownPose {
                    t_ns: s.t_ns,
                    r: s.rotation(),
                    p: s.p,
                });
            }
        }
        if kp.len() < 3 {
            return Err(CliError::Failed(format!(
                "{}: fewer than three poses inside the IMU time span (poses ≥ 0.5 s apart are used)",
                pfile.display()
            )));
        }
        let params = PreintParams::from_noise(&noise)
            .with_scheme(Scheme::Midpoint)
            .with_gravity(g);
        let opts = KnownPoseOptions {
            pose_rot_std: *pose_rot_std,
            pose_pos_std: *pose_pos_std,
            ..KnownPoseOptions::new(params)
        };
        let c = calibrate_known_poses(&samples, &kp, &opts).map_err(&fail)?;
        let json = json!({
            "model": "known-poses", "poses": kp.len(),
            "gyro_bias": list(&c.bias.gyro), "gyro_bias_std": list(&c.gyro_bias_std),
            "acc_bias": list(&c.bias.acc), "acc_bias_std": list(&c.acc_bias_std),
            "gravity": list(&c.gravity), "gravity_std": list(&c.gravity_std), "gravity_tilt_deg": c.gravity_tilt.to_degrees(),
            "pose_rot_std": pose_rot_std, "pose_pos_std": pose_pos_std,
            "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
            "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "gravity": "m/s^2"},
        });
        let human = format!(
            "known-pose calibration ({} poses from {}):\n  b_g = [{:.6}, {:.6}, {:.6}] ± [{:.1e}, {:.1e}, {:.1e}] rad/s\n  b_a = [{:.4}, {:.4}, {:.4}] ± [{:.1e}, {:.1e}, {:.1e}] m/s²\n  gravity tilt {:.3}°, χ²/dof = {:.2}, {} iterations\n",
            kp.len(),
            pfile.display(),
            c.bias.gyro.x,
            c.bias.gyro.y,
            c.bias.gyro.z,
            c.gyro_bias_std.x,
            c.gyro_bias_std.y,
            c.gyro_bias_std.z,
            c.bias.acc.x,
            c.bias.acc.y,
            c.bias.acc.z,
            c.acc_bias_std.x,
            c.acc_bias_std.y,
            c.acc_bias_std.z,
            c.gravity_tilt.to_degrees(),
            c.chi2 / c.dof.max(1) as f64,
            c.iterations
        );
        return Ok(Output { human, json });
    }

    let still =
        detect_still_intervals(&samples, &StillOptions::from_noise(&noise, rate)).map_err(&fail)?;
    if distinct_attitudes(&samples, &still) >= 3 {
        let opts = MultiPoseOptions {
            gravity: g,
            ..Default::default()
        };
        let c = calibrate_multi_pose(&samples, &noise, &opts).map_err(&fail)?;
        let fits: Vec<Value> = c.fits.iter().map(|f| json!({"model": format!("{:?}", f.model), "chi2": f.chi2,
            "params": f.params, "bic": f.bic, "identifiable": f.identifiable, "converged": f.converged})).collect();
        let chosen = c.fits.iter().find(|f| f.model == c.model);
        let json = json!({
            "model": format!("multi-pose/{:?}", c.model), "still_intervals": c.intervals.len(),
            "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
            "acc_bias": list(&c.acc_bias), "acc_bias_std": list(&c.acc_bias_std),
            "acc_scale": opt3(c.acc_scale), "acc_scale_std": opt3(c.acc_scale_std),
            "gyro_scale": opt3(c.gyro_scale), "gyro_scale_std": opt3(c.gyro_scale_std),
            "model_selection": fits, "reason": c.reason,
            "bias_reference_time_ns": c.reference_time_ns, "random_walk_marginalised": c.random_walk_marginalised,
            "iterations": c.iterations, "cost": chosen.map(|f| 0.5 * f.chi2),
            "units": {"gyro_bias": "rad/s", "acc_bias": "m/s^2", "scale": "dimensionless (1 = ideal)"},
        });
        let human = format!(
            "multi-position calibration: {} still intervals; model {:?} ({})\n  b_g = [{:.6}, {:.6}, {:.6}] ± [{:.1e}, {:.1e}, {:.1e}] rad/s\n  b_a = [{:.4}, {:.4}, {:.4}] ± [{:.1e}, {:.1e}, {:.1e}] m/s²\n",
            c.intervals.len(),
            c.model,
            c.reason,
            c.gyro_bias.x,
            c.gyro_bias.y,
            c.gyro_bias.z,
            c.gyro_bias_std.x,
            c.gyro_bias_std.y,
            c.gyro_bias_std.z,
            c.acc_bias.x,
            c.acc_bias.y,
            c.acc_bias.z,
            c.acc_bias_std.x,
            c.acc_bias_std.y,
            c.acc_bias_std.z
        );
        return Ok(Output { human, json });
    }

    let c = calibrate_static(
        &samples,
        &noise,
        &StaticOptions {
            gravity: g,
            ..Default::default()
        },
    )
    .map_err(&fail)?;
    let json = json!({
        "model": "static-single-attitude",
        "gyro_bias": list(&c.gyro_bias), "gyro_bias_std": list(&c.gyro_bias_std),
        "acc_bias": opt3(c.acc_bias), "acc_bias_std": opt3(c.acc_bias_std), "acc_bias_note": c.acc_bias_note,
        "roll": c.roll, "pitch": c.pitch, "roll_std": c.roll_std, "pitch_std": c.pitch_std,
        "unobservable": c.unobservable, "measured_gyro_density": list(&c.measured_gyro_density),
        "measured_acc_density": list(&c.measured_acc_density),
        "iterations": c.iterations, "cost": 0.5 * c.chi2, "chi2": c.chi2, "dof": c.dof,
        "units": {"gyro_bias": "rad/s", "roll": "rad", "pitch": "rad", "densities": "rad/s/sqrt(Hz), m/s^2/sqrt(Hz)"},
    });
    let human = format!(
        "static calibration (one attitude, {:.1} s):\n  b_g = [{:.6}, {:.6}, {:.6}] ± [{:.1e}, {:.1e}, {:.1e}] rad/s\n  roll {:.4}° ± {:.1e}°, pitch {:.4}° ± {:.1e}°\n  b_a: not estimated ({})\n",
        c.duration_s,
        c.gyro_bias.x,
        c.gyro_bias.y,
        c.gyro_bias.z,
        c.gyro_bias_std.x,
        c.gyro_bias_std.y,
        c.gyro_bias_std.z,
        c.roll.to_degrees(),
        c.roll_std.to_degrees(),
        c.pitch.to_degrees(),
        c.pitch_std.to_degrees(),
        c.acc_bias_note
    );
    Ok(Output { human, json })
}
