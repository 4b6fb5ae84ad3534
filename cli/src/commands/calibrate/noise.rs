//! `preint calibrate --estimate noise`: the flags as
//! [`NoiseOptions`](preint_analysis::calibrate::noise_model::NoiseOptions) and the human
//! summary; the fit, the file of `--out` and the JSON are
//! [`preint_analysis::calibrate::noise_model`]'s.

use super::Args;
use crate::fit::{fit_text, strict};
use crate::{CliError, Output};
use preint_analysis::calibrate::noise_correlation;
use preint_analysis::calibrate::noise_model::{self, KEYS, NoiseOptions, NoiseRun};
use preint_calib::noise_fit::Withheld;
use std::fmt::Write as _;

/// What the library computes on.
fn options(args: &Args) -> NoiseOptions {
    NoiseOptions {
        input: args.input.to_input(),
        poses: args.poses.clone(),
        window: args.window.clone(),
        noise: args.noise.clone(),
        gravity: args.gravity,
        from: args.from,
        to: args.to,
        pose_rot_std: args.pose_rot_std,
        pose_pos_std: args.pose_pos_std,
        vel_std: args.vel_std,
        bias_gyro_std: args.bias_gyro_std,
        bias_acc_std: args.bias_acc_std,
        body_p_sensor: args.body_p_sensor,
        scheme: args.scheme,
        out: args.out.clone(),
    }
}

fn to_text(r: &NoiseRun) -> String {
    let mut h = String::new();
    let n: usize = r.fit.per_length.iter().map(|l| l.count).sum();
    let _ = writeln!(
        h,
        "{}: noise model by maximum likelihood over {n} ImuFactor windows at the ground truth \
         ({} Fisher-scoring iterations, log-likelihood {:.1}):",
        r.imu, r.fit.iterations, r.fit.log_likelihood
    );
    for (k, p) in r.fit.params.iter().enumerate() {
        let unit = p.param.unit();
        let line = match p.withheld {
            None => format!("{:.4e} ± {:.1e} {unit}", p.value, p.std),
            Some(Withheld::Held) => format!("{:.4e} {unit} (held at the given value)", p.value),
            Some(w) => w.reason(unit),
        };
        let _ = writeln!(h, "  {:<28} {line}", KEYS[k]);
    }
    if let (Some(g), Some(v)) = (&r.fit.gravity, noise_model::fitted_gravity(r)) {
        let g0 = r.gravity_given;
        let std = g.std().max();
        let _ = writeln!(
            h,
            "  world gravity                ({:.4}, {:.4}, {:.4}) ± {std:.1e} m/s², tilted \
             {:.3} ± {:.3}° from ({}, {}, {}): {} (2Δℓ = {:.1}, BIC penalty {:.1})",
            v[0],
            v[1],
            v[2],
            g.tilt_from(&g0).to_degrees(),
            g.tilt_std_from(&g0).to_degrees(),
            g0[0],
            g0[1],
            g0[2],
            if g.supported {
                format!(
                    "fitted; give factor --gravity-vector={},{},{}",
                    v[0], v[1], v[2]
                )
            } else {
                "not supported by the windows; the given gravity kept".to_string()
            },
            g.lr,
            g.penalty
        );
    }
    let _ = writeln!(
        h,
        "  ground truth in time         {}",
        noise_correlation::verdict(&r.time_correlation)
    );
    let _ = writeln!(
        h,
        "{:>8} {:>6} {:>7} {:>14} {:>13}",
        "length s", "count", "skipped", "χ²/dof before", "χ²/dof after"
    );
    for (l, (_, s)) in r.fit.per_length.iter().zip(&r.skipped) {
        let _ = writeln!(
            h,
            "{:>8} {:>6} {:>7} {:>14.3} {:>13.3}",
            l.length_s, l.count, s, l.before, l.after
        );
    }
    h.push_str(&fit_text(
        &noise_model::fit(r),
        "noise model over the windows",
    ));
    if let Some(p) = &r.written {
        let _ = writeln!(
            h,
            "noise model written to {} (Kalibr imu.yaml; withheld densities at their start value)",
            p.display()
        );
    }
    if r.fit.params[2..4].iter().any(|p| p.withheld.is_none()) {
        h.push_str(
            "the χ² after includes the bias random walk within each window: a 9-dim ImuFactor \
             is weighted with it by `factor --in-window-drift` (ImuFactor::with_in_window_drift); \
             CombinedImuFactor always is\n",
        );
    }
    h
}

/// Runs `preint calibrate --estimate noise`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = noise_model::compute(&options(args))?;
    let output = Output {
        human: to_text(&r),
        json: noise_model::to_json(&r),
    };
    strict(
        args.strict,
        output,
        &noise_model::fit(&r),
        "noise model over the windows",
    )
}
