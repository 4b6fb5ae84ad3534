//! `preint factor`: an IMU factor evaluated at ground-truth states — is this IMU consistent
//! with this ground truth?
//!
//! The keyframes are the ground-truth rows nearest to `--from` and `--to` (the factor needs the
//! true state at the keyframe time; an interpolated state would add its own error). The window
//! between them is preintegrated with the ground truth's bias at keyframe i as the estimate,
//! and `ImuFactor` (or, with `--combined`, `CombinedImuFactor` with the ground truth's bias at
//! j as well) is evaluated at the two states. The weight is the covariance the factor uses
//! (`cov`, or `residual_cov15`), plus, when the ground truth's own errors are given
//! (`--pose-rot-std`, `--pose-pos-std`, `--vel-std`), their effect through the factor's
//! Jacobians at i and j: `Σ = Σ_factor + J_i S J_iᵀ + J_j S J_jᵀ` with
//! `S = diag(σ_R² I, σ_p² I, σ_v² I)` in the `NavState` tangent [δφ, δp, δv].
//!
//! Printed: the residual (order [r_φ, r_v, r_p] or [r_φ, r_v, r_p, r_bg, r_ba]), the whitened
//! residual `U r` (`UᵀU = Σ⁻¹`, `U` upper triangular), `χ² = ‖U r‖²` with its χ² quantiles, and
//! each block's marginal χ² (`r_bᵀ Σ_bb⁻¹ r_b`, 3 dof) to say which part disagrees.

use super::integrate::{noise_or_default, parse_scheme, scheme_name};
use super::{CliError, Output, list};
use crate::Command;
use nalgebra::{SMatrix, SVector, Vector3};
use preint::factor::sqrt_information;
use preint::io::{GroundTruthState, check_si_units, read_euroc_groundtruth, read_euroc_imu};
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, Level, NavState, PreintParams, PreintegratedImu,
    preintegrate,
};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

/// χ² quantiles (scipy.stats.chi2.ppf) for 3, 9 and 15 degrees of freedom: (0.95, 0.99).
fn chi2_quantiles(dof: usize) -> (f64, f64) {
    match dof {
        3 => (7.814_728, 11.344_867),
        9 => (16.918_978, 21.665_994),
        15 => (24.995_790, 30.577_914),
        _ => unreachable!("dof {dof}"),
    }
}

const BLOCKS: [&str; 5] = ["rotation", "velocity", "position", "gyro_bias", "acc_bias"];
const ORDER: [&str; 15] = [
    "r_phi_x", "r_phi_y", "r_phi_z", "r_v_x", "r_v_y", "r_v_z", "r_p_x", "r_p_y", "r_p_z",
    "r_bg_x", "r_bg_y", "r_bg_z", "r_ba_x", "r_ba_y", "r_ba_z",
];

/// The standard deviations of the ground truth's own errors (0: exact).
#[derive(Clone, Copy, Debug)]
struct TruthNoise {
    rot_rad: f64,
    pos_m: f64,
    vel_m_s: f64,
}

/// A factor evaluated at the ground truth, weighted.
struct Evaluation {
    residual: Vec<f64>,
    whitened: Vec<f64>,
    chi2: f64,
    /// Per 3-row block: `r_bᵀ Σ_bb⁻¹ r_b`.
    marginal_chi2: Vec<f64>,
}

fn evaluate<const R: usize>(
    r: SVector<f64, R>,
    jac_i: SMatrix<f64, R, 9>,
    jac_j: SMatrix<f64, R, 9>,
    cov: SMatrix<f64, R, R>,
    tn: TruthNoise,
) -> Result<Evaluation, CliError> {
    let mut s = SMatrix::<f64, 9, 9>::zeros();
    for k in 0..3 {
        s[(k, k)] = tn.rot_rad.powi(2);
        s[(3 + k, 3 + k)] = tn.pos_m.powi(2);
        s[(6 + k, 6 + k)] = tn.vel_m_s.powi(2);
    }
    let sigma = cov + jac_i * s * jac_i.transpose() + jac_j * s * jac_j.transpose();
    let u = sqrt_information(&sigma).map_err(|e| CliError::Failed(format!("weight: {e}")))?;
    let w = u * r;
    let marginal_chi2 = (0..R / 3)
        .map(|b| {
            let rb = r.fixed_rows::<3>(3 * b).into_owned();
            let sb = sigma.fixed_view::<3, 3>(3 * b, 3 * b).into_owned();
            sb.cholesky().map_or(f64::NAN, |c| rb.dot(&c.solve(&rb)))
        })
        .collect();
    Ok(Evaluation {
        residual: r.iter().copied().collect(),
        whitened: w.iter().copied().collect(),
        chi2: w.norm_squared(),
        marginal_chi2,
    })
}

/// The ground-truth row nearest to `t_ns`.
fn nearest(gt: &[GroundTruthState], t_ns: i64) -> &GroundTruthState {
    let k = gt.partition_point(|s| s.t_ns < t_ns);
    let candidates = [k.saturating_sub(1), k.min(gt.len() - 1)];
    let best = candidates
        .into_iter()
        .min_by_key(|&c| (gt[c].t_ns - t_ns).unsigned_abs())
        .unwrap();
    &gt[best]
}

fn nav(s: &GroundTruthState) -> NavState {
    NavState::new(s.rotation(), s.p, s.v)
}

fn state_json(s: &GroundTruthState) -> Value {
    json!({"t_ns": s.t_ns, "p": list(&s.p), "q_wxyz": [s.q.w, s.q.i, s.q.j, s.q.k], "v": list(&s.v),
           "bias_gyro": list(&s.bias.gyro), "bias_acc": list(&s.bias.acc)})
}

fn bias_json(b: &ImuBias) -> Value {
    json!({"gyro": list(&b.gyro), "acc": list(&b.acc)})
}

/// Everything `factor` computes.
struct FactorRun {
    scheme: &'static str,
    combined: bool,
    gi: GroundTruthState,
    gj: GroundTruthState,
    requested: (i64, i64),
    pim: PreintegratedImu,
    samples: usize,
    truth_noise: TruthNoise,
    ev: Evaluation,
}

fn compute(cmd: &Command) -> Result<FactorRun, CliError> {
    let Command::Factor {
        imu,
        poses,
        from,
        to,
        scheme,
        noise,
        gravity,
        combined,
        pose_rot_std,
        pose_pos_std,
        vel_std,
        no_unit_check,
    } = cmd
    else {
        unreachable!()
    };
    for (name, v) in [
        ("--pose-rot-std", pose_rot_std),
        ("--pose-pos-std", pose_pos_std),
        ("--vel-std", vel_std),
    ] {
        if !(v.is_finite() && *v >= 0.0) {
            return Err(CliError::Usage(format!(
                "{name} must be a non-negative number, got {v}"
            )));
        }
    }
    if !(gravity.is_finite() && *gravity >= 0.0) {
        return Err(CliError::Usage(format!(
            "--gravity must be a non-negative number, got {gravity}"
        )));
    }
    let scheme_v = parse_scheme(scheme)?;
    let noise = noise_or_default(noise.as_ref())?;
    let samples = read_euroc_imu(imu)?;
    if !no_unit_check {
        check_si_units(&samples, &imu.display().to_string())?;
    }
    let gt = read_euroc_groundtruth(poses)?;
    let (gi, gj) = (*nearest(&gt, *from), *nearest(&gt, *to));
    if gj.t_ns <= gi.t_ns {
        return Err(CliError::Usage(format!(
            "{}: the ground-truth rows nearest to --from {from} and --to {to} are at {} and {} ns; \
             they must be two different rows, the first earlier",
            poses.display(),
            gi.t_ns,
            gj.t_ns
        )));
    }
    let level = if *combined {
        Level::Combined
    } else {
        Level::Covariance
    };
    let params = PreintParams::from_noise(&noise)
        .with_scheme(scheme_v)
        .with_level(level)
        .with_gravity(Vector3::new(0.0, 0.0, -gravity));
    let pim = preintegrate(&params, &gi.bias, &samples, gi.t_ns, gj.t_ns)
        .map_err(|e| CliError::Failed(format!("{}: {e}", imu.display())))?;
    let n_used = samples
        .iter()
        .filter(|s| s.t_ns >= gi.t_ns && s.t_ns <= gj.t_ns)
        .count();
    let tn = TruthNoise {
        rot_rad: *pose_rot_std,
        pos_m: *pose_pos_std,
        vel_m_s: *vel_std,
    };
    let failed = |e: preint::FactorError| CliError::Failed(format!("{}: {e}", imu.display()));
    let (xi, xj) = (nav(&gi), nav(&gj));
    let ev = if *combined {
        let f = CombinedImuFactor::new(pim.clone()).map_err(failed)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias, &gj.bias);
        evaluate(r, j.state_i(), j.state_j(), pim.residual_cov15(), tn)?
    } else {
        let f = ImuFactor::new(pim.clone()).map_err(failed)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias);
        evaluate(r, j.state_i(), j.state_j(), pim.cov, tn)?
    };
    Ok(FactorRun {
        scheme: scheme_name(scheme_v),
        combined: *combined,
        gi,
        gj,
        requested: (*from, *to),
        pim,
        samples: n_used,
        truth_noise: tn,
        ev,
    })
}

fn to_json(f: &FactorRun) -> Value {
    let dof = f.ev.residual.len();
    let (q95, q99) = chi2_quantiles(dof);
    let (m95, m99) = chi2_quantiles(3);
    let marginal: serde_json::Map<String, Value> = BLOCKS
        .iter()
        .zip(&f.ev.marginal_chi2)
        .map(|(b, c)| ((*b).to_string(), json!(c)))
        .collect();
    json!({
        "factor": if f.combined { "CombinedImuFactor" } else { "ImuFactor" },
        "scheme": f.scheme,
        "requested_ns": [f.requested.0, f.requested.1],
        "t_i_ns": f.gi.t_ns,
        "t_j_ns": f.gj.t_ns,
        "delta_t": f.pim.delta_t,
        "samples": f.samples,
        "state_i": state_json(&f.gi),
        "state_j": state_json(&f.gj),
        "bias_hat": bias_json(&f.pim.bias_hat),
        "residual_order": &ORDER[..dof],
        "residual": f.ev.residual,
        "whitened_residual": f.ev.whitened,
        "chi2": f.ev.chi2,
        "dof": dof,
        "chi2_quantiles": {"0.95": q95, "0.99": q99},
        "consistent_at_0_99": f.ev.chi2 <= q99,
        "marginal_chi2": marginal,
        "marginal_chi2_quantiles": {"dof": 3, "0.95": m95, "0.99": m99},
        "ground_truth_noise": {"rot_rad": f.truth_noise.rot_rad, "pos_m": f.truth_noise.pos_m,
                               "vel_m_s": f.truth_noise.vel_m_s},
        "weight": if f.combined {
            "residual_cov15 (covariance of [r_phi, r_v, r_p, r_bg, r_ba]) + ground-truth noise through the Jacobians"
        } else {
            "cov (covariance of [r_phi, r_v, r_p]) + ground-truth noise through the Jacobians"
        },
        "units": {"residual": "rad, m/s, m (, rad/s, m/s^2) per block", "whitened_residual": "dimensionless",
                  "state": "p m (world), q body->world, v m/s (world), biases rad/s and m/s^2"},
    })
}

fn to_text(f: &FactorRun, imu: &Path) -> String {
    let dof = f.ev.residual.len();
    let (q95, q99) = chi2_quantiles(dof);
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} at the ground truth, scheme {}, keyframes {} → {} ns (nearest rows to {} and {}), \
         Δt = {:.6} s, {} samples",
        imu.display(),
        if f.combined {
            "CombinedImuFactor"
        } else {
            "ImuFactor"
        },
        f.scheme,
        f.gi.t_ns,
        f.gj.t_ns,
        f.requested.0,
        f.requested.1,
        f.pim.delta_t,
        f.samples
    );
    let r = &f.ev.residual;
    let names = [
        "r_φ (rad)",
        "r_v (m/s)",
        "r_p (m)",
        "r_bg (rad/s)",
        "r_ba (m/s²)",
    ];
    for (b, name) in names.iter().enumerate().take(dof / 3) {
        let _ = writeln!(
            h,
            "  {name:<13} [{:>12.4e} {:>12.4e} {:>12.4e}]   marginal χ²₃ = {:.3}",
            r[3 * b],
            r[3 * b + 1],
            r[3 * b + 2],
            f.ev.marginal_chi2[b]
        );
    }
    let verdict = if f.ev.chi2 <= q95 {
        "consistent"
    } else if f.ev.chi2 <= q99 {
        "above the 95 % quantile, below the 99 %"
    } else {
        "inconsistent at 99 %"
    };
    let _ = writeln!(
        h,
        "χ² = {:.3} with {dof} dof (95 % quantile {q95:.2}, 99 % {q99:.2}): {verdict}; marginal χ²₃ \
         quantiles 7.81 / 11.34",
        f.ev.chi2
    );
    let tn = f.truth_noise;
    if tn.rot_rad == 0.0 && tn.pos_m == 0.0 && tn.vel_m_s == 0.0 {
        let _ = writeln!(
            h,
            "weight: the factor's covariance only (the ground truth is taken as exact; give \
             --pose-rot-std, --pose-pos-std, --vel-std for its own errors)"
        );
    }
    h
}

pub fn run(cmd: &Command) -> Result<Output, CliError> {
    let Command::Factor { imu, .. } = cmd else {
        unreachable!()
    };
    let f = compute(cmd)?;
    Ok(Output {
        human: to_text(&f, imu),
        json: to_json(&f),
    })
}
