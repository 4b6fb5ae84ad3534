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
//! `--residual component|logmap` picks the factor's [`ResidualMode`] (default: the library's,
//! [`ResidualMode::default`]); the weight is then the covariance of that residual
//! (`ImuFactor::residual_covariance`). `--second-order` adds the second-order covariance term
//! of `preint::second_order` to the measurement's covariance first. `--in-window-drift`
//! weights `ImuFactor` with the bias random walk's effect within the window
//! (`ImuFactor::with_in_window_drift`: `cov15`'s [δφ, δv, δp] block) instead of `cov`, which
//! leaves it out as GTSAM's `ImuFactor` does. `--gravity-vector` replaces `(0, 0, −G)` with
//! a world-frame vector (a ground-truth frame not levelled with gravity).
//!
//! Printed: the residual (order [r_φ, r_v, r_p] or [r_φ, r_v, r_p, r_bg, r_ba]), the whitened
//! residual `U r` (`UᵀU = Σ⁻¹`, `U` upper triangular), `χ² = ‖U r‖²` with its χ² quantiles, and
//! each block's marginal χ² (`r_bᵀ Σ_bb⁻¹ r_b`, 3 dof) to say which part disagrees.

//! The weighting and χ² are [`preint_analysis::consistency`].
//!
//! # Goodness of fit
//! The factor's fit (JSON `fit`, [`preint_calib::fit`]) is its χ² at the ground truth against
//! `χ²_dof` (9, or 15 with `--combined`): credible when the upper-tail p-value is ≥ 1e-6.
//! Not credible: a `warning:` line names the block whose marginal χ² is largest (the part that
//! disagrees); `--strict` makes it a refusal (exit 2, after the output).

pub(crate) mod evaluate;
pub mod windows;

use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::preint_args::PreintArgs;
use crate::scheme::{self};
use crate::{CliError, Output, input};
use evaluate::{in_window, keyframes, noise_params, truth_noise, window};
use preint::{ImuBias, PreintegratedImu, ResidualMode};
use preint_analysis::checks;
use preint_analysis::consistency::{Evaluation, TruthNoise, chi2_quantiles, fit_json};
use preint_analysis::factor_windows::evaluate_window;
use preint_analysis::format::list;
use preint_io::GroundTruthState;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Flags of `preint factor`: one window (`--from`, `--to`) or many (`--window`), exactly one
/// of the two.
#[derive(clap::Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("span").required(true).multiple(true).args(["from", "to", "window"])))]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Ground truth (EuRoC state_groundtruth_estimate0 format: p (m), q wxyz body->world,
    /// v (m/s), b_g (rad/s), b_a (m/s^2)), world frame z up.
    #[arg(help_heading = "Ground truth", long)]
    pub poses: PathBuf,
    /// Keyframe i: the ground-truth row nearest to this time (ns).
    #[arg(
        help_heading = "Window",
        long,
        allow_hyphen_values = true,
        requires = "to",
        conflicts_with = "window"
    )]
    pub from: Option<i64>,
    /// Keyframe j: the ground-truth row nearest to this time (ns).
    #[arg(
        help_heading = "Window",
        long,
        allow_hyphen_values = true,
        requires = "from",
        conflicts_with = "window"
    )]
    pub to: Option<i64>,
    /// Instead of --from/--to: back-to-back windows of each length (s, comma-separated) over
    /// the span where the recording and the ground truth overlap, keyframes at the ground-truth
    /// rows nearest to each window edge; per length the windows' χ² against χ²_dof (mean,
    /// median, fraction above the 0.99 quantile, Kolmogorov–Smirnov p-value, the share of each
    /// block) and a verdict on the noise model. The fit is the χ² summed over all windows of
    /// all lengths against their total dof.
    #[arg(
        help_heading = "Window",
        long,
        value_name = "S[,S…]",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub window: Option<Vec<f64>>,
    /// Scheme, noise densities and gravity.
    #[command(flatten)]
    pub preint: PreintArgs,
    /// Evaluate CombinedImuFactor (15-dim residual with the bias change b_j - b_i, weighted
    /// by the covariance with the bias random walk) instead of ImuFactor (9-dim).
    #[arg(help_heading = "Factor", long)]
    pub combined: bool,
    /// Weight ImuFactor (9-dim) with the covariance that includes the bias random walk within
    /// the window (the [dphi, dv, dp] block of the combined covariance; needs the random walks
    /// in --noise) instead of the white noise alone (GTSAM's ImuFactor).
    #[arg(help_heading = "Factor", long, conflicts_with = "combined")]
    pub in_window_drift: bool,
    /// Residual: `component` (Forster's [r_phi, r_v, r_p]) or `logmap` (the SE_2(3) logarithm
    /// of predicted^-1 * actual, GTSAM 4.3's default).
    #[arg(help_heading = "Factor", long, value_parser = parse_residual, default_value = ResidualMode::default().name())]
    pub residual: ResidualMode,
    /// Standard deviation of the ground truth's attitudes (rad), added to the weight.
    #[arg(
        help_heading = "Ground truth",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub pose_rot_std: f64,
    /// Standard deviation of the ground truth's positions (m), added to the weight.
    #[arg(
        help_heading = "Ground truth",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub pose_pos_std: f64,
    /// Standard deviation of the ground truth's velocities (m/s), added to the weight.
    #[arg(
        help_heading = "Ground truth",
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub vel_std: f64,
    /// Standard deviation (per axis) of the ground truth's gyroscope bias (rad/s), added to the
    /// weight through the measurement's bias Jacobian: Σ += J_bg σ² J_bgᵀ.
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "RAD_PER_S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub bias_gyro_std: f64,
    /// Standard deviation (per axis) of the ground truth's accelerometer bias (m/s^2), added to
    /// the weight through the measurement's bias Jacobian: Σ += J_ba σ² J_baᵀ.
    #[arg(
        help_heading = "Ground truth",
        long,
        value_name = "M_PER_S2",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub bias_acc_std: f64,
    /// Weight the factor with the second-order covariance (`preint::second_order`: the
    /// term the first-order covariance misses over long windows with noisy gyroscopes).
    #[arg(help_heading = "Factor", long)]
    pub second_order: bool,
    /// Exit with status 2 (after printing the result) when the fit is not credible: χ² at the
    /// ground truth with p < 1e-6 against χ² with 9 (15 with --combined) dof.
    #[arg(help_heading = "Output", long)]
    pub strict: bool,
}

fn parse_residual(s: &str) -> Result<ResidualMode, String> {
    ResidualMode::parse(s).ok_or_else(|| format!("unknown residual {s:?}: use component or logmap"))
}

const BLOCKS: [&str; 5] = ["rotation", "velocity", "position", "gyro_bias", "acc_bias"];
const ORDER: [&str; 15] = [
    "r_phi_x", "r_phi_y", "r_phi_z", "r_v_x", "r_v_y", "r_v_z", "r_p_x", "r_p_y", "r_p_z",
    "r_bg_x", "r_bg_y", "r_bg_z", "r_ba_x", "r_ba_y", "r_ba_z",
];

/// Everything `factor` computes.
#[derive(Clone, Debug)]
pub struct FactorRun {
    /// The IMU file, as printed.
    pub imu: String,
    /// How it was read.
    pub source: preint_io::SourceInfo,
    /// What the unit checks said.
    pub unit_check: preint_analysis::checks::UnitCheck,
    /// The scheme used.
    pub scheme: preint::Scheme,
    /// `CombinedImuFactor` (else `ImuFactor`).
    pub combined: bool,
    /// `ImuFactor` weighted with the in-window bias drift (`--in-window-drift`).
    pub in_window_drift: bool,
    /// The world gravity vector \[m/s²\] (`--gravity`, `--gravity-vector`).
    pub gravity: nalgebra::Vector3<f64>,
    /// The factor's residual.
    pub residual: ResidualMode,
    /// Weighted with the second-order covariance term (`--second-order`).
    pub second_order: bool,
    /// Ground truth at keyframe i.
    pub gi: GroundTruthState,
    /// Ground truth at keyframe j.
    pub gj: GroundTruthState,
    /// `--from` and `--to` as given (ns).
    pub requested: (i64, i64),
    /// The window, preintegrated with the ground truth's bias at i.
    pub pim: PreintegratedImu,
    /// Number of samples with timestamps in the window.
    pub samples: usize,
    /// The ground truth's own errors added to the weight.
    pub truth_noise: TruthNoise,
    /// The weighted residual.
    pub ev: Evaluation,
}

/// The factor's fit: its χ² against `χ²_dof`, with the block that disagrees most as the cause.
pub fn fit(f: &FactorRun) -> preint_calib::Fit {
    let (b, m) =
        f.ev.marginal_chi2
            .iter()
            .enumerate()
            .filter(|(_, m)| m.is_finite())
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(("rotation", f64::NAN), |(b, m)| (BLOCKS[b], *m));
    preint_calib::Fit::new(f.ev.chi2, f.ev.residual.len()).because(&format!(
        "the IMU and the ground truth disagree beyond the factor's covariance, most in the {b} \
         block (marginal χ²₃ = {m:.3}): the noise densities (--noise), the ground truth's own \
         errors (--pose-rot-std, --pose-pos-std, --vel-std, --bias-gyro-std, --bias-acc-std), \
         or the clocks"
    ))
}

/// Reads the files, preintegrates the window between the keyframes and evaluates the factor.
pub fn compute(args: &Args) -> Result<FactorRun, CliError> {
    let (Some(from), Some(to)) = (args.from, args.to) else {
        return Err(CliError::Usage(
            "give --from NS --to NS (one window) or --window S[,S…] (windows over the whole \
             recording)"
                .into(),
        ));
    };
    checks::window_order(Some(from), Some(to))?;
    let tn = truth_noise(args)?;
    let (noise, mut params) = noise_params(args)?;
    let (gi, gj) = keyframes(args, (from, to))?;
    let scheme = params.scheme;
    let input = args.input.to_input();
    let (w, source, unit_check) =
        window(&input, &noise, &mut params, (Some(gi.t_ns), Some(gj.t_ns)))?;
    let samples = w.samples.as_slice();
    let (pim, ev) = evaluate_window(&args.kind(), &params, samples, (&gi, &gj), tn)
        .map_err(|e| in_window(e, &input, &w))?;
    Ok(FactorRun {
        imu: input.label(),
        source,
        unit_check,
        scheme,
        combined: args.combined,
        in_window_drift: args.in_window_drift,
        gravity: params.gravity,
        residual: args.residual,
        second_order: args.second_order,
        gi,
        gj,
        requested: (from, to),
        samples: input::count_in(samples, gi.t_ns, gj.t_ns),
        pim,
        truth_noise: tn,
        ev,
    })
}

fn state_json(s: &GroundTruthState) -> Value {
    json!({"t_ns": s.t_ns, "p": list(&s.p), "q_wxyz": [s.q.w, s.q.i, s.q.j, s.q.k], "v": list(&s.v),
           "bias_gyro": list(&s.bias.gyro), "bias_acc": list(&s.bias.acc)})
}

/// The ground truth's own errors in the JSON: `{rot_rad, pos_m, vel_m_s, bias_gyro_rad_s,
/// bias_acc_m_s2}`.
pub(crate) fn truth_noise_json(t: &TruthNoise) -> Value {
    json!({"rot_rad": t.rot_rad, "pos_m": t.pos_m, "vel_m_s": t.vel_m_s,
           "bias_gyro_rad_s": t.bias_gyro_rad_s, "bias_acc_m_s2": t.bias_acc_m_s2})
}

fn bias_json(b: &ImuBias) -> Value {
    json!({"gyro": list(&b.gyro), "acc": list(&b.acc)})
}

pub(crate) fn factor_name(combined: bool) -> &'static str {
    if combined {
        "CombinedImuFactor"
    } else {
        "ImuFactor"
    }
}

/// The factor as printed: its name, and the weight's in-window drift when it has it.
pub(crate) fn factor_label(combined: bool, in_window_drift: bool) -> String {
    let name = factor_name(combined);
    if in_window_drift {
        format!("{name} weighted with the in-window bias drift")
    } else {
        name.to_string()
    }
}

/// The JSON form: keyframes, states, residual, whitened residual, χ² with quantiles, marginal
/// χ² per block, the weight used and the units.
pub fn to_json(f: &FactorRun) -> Value {
    let dof = f.ev.residual.len();
    let (q95, q99) = chi2_quantiles(dof);
    let (m95, m99) = chi2_quantiles(3);
    let marginal: serde_json::Map<String, Value> = BLOCKS
        .iter()
        .zip(&f.ev.marginal_chi2)
        .map(|(b, c)| ((*b).to_string(), json!(c)))
        .collect();
    json!({
        "input": preint_analysis::recording::input_json(&f.source, &f.unit_check),
        "factor": factor_name(f.combined),
        "in_window_drift": f.in_window_drift,
        "gravity": list(&f.gravity),
        "scheme": scheme::label(f.scheme),
        "residual_mode": f.residual.name(),
        "second_order": f.second_order,
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
        "ground_truth_noise": truth_noise_json(&f.truth_noise),
        "weight": match (f.combined, f.residual) {
            (true, ResidualMode::ComponentWise) => "residual_cov15 (covariance of [r_phi, r_v, r_p, r_bg, r_ba]) + ground-truth noise through the Jacobians",
            (false, ResidualMode::ComponentWise) if f.in_window_drift => "cov15[0..9, 0..9] (covariance of [r_phi, r_v, r_p] with the in-window bias drift) + ground-truth noise through the Jacobians",
            (false, ResidualMode::ComponentWise) => "cov (covariance of [r_phi, r_v, r_p]) + ground-truth noise through the Jacobians",
            (true, ResidualMode::Logmap) => "diag(T, I6) residual_cov15 diag(T, I6)^T, T = diag(I, dR^T, dR^T) (covariance of the Logmap residual) + ground-truth noise through the Jacobians",
            (false, ResidualMode::Logmap) if f.in_window_drift => "T C T^T, C = cov15[0..9, 0..9] (with the in-window bias drift), T = diag(I, dR^T, dR^T) (covariance of the Logmap residual) + ground-truth noise through the Jacobians",
            (false, ResidualMode::Logmap) => "T cov T^T, T = diag(I, dR^T, dR^T) (covariance of the Logmap residual [phi, Jl^-1 dR^T r_v, Jl^-1 dR^T r_p]) + ground-truth noise through the Jacobians",
        },
        "units": {"residual": "rad, m/s, m (, rad/s, m/s^2) per block", "whitened_residual": "dimensionless",
                  "state": "p m (world), q body->world, v m/s (world), biases rad/s and m/s^2"},
        "fit": fit_json(&fit(f)),
    })
}

/// The human summary: keyframes, residual blocks with their marginal χ², χ² and verdict.
pub fn to_text(f: &FactorRun) -> String {
    let dof = f.ev.residual.len();
    let (q95, q99) = chi2_quantiles(dof);
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} ({} residual{}) at the ground truth, scheme {}, keyframes {} → {} ns (nearest rows \
         to {} and {}), Δt = {:.6} s, {} samples",
        f.imu,
        factor_label(f.combined, f.in_window_drift),
        f.residual.name(),
        if f.second_order {
            ", second-order covariance"
        } else {
            ""
        },
        scheme::label(f.scheme),
        f.gi.t_ns,
        f.gj.t_ns,
        f.requested.0,
        f.requested.1,
        f.pim.delta_t,
        f.samples
    );
    h.push_str(&preint_analysis::recording::input_text(
        &f.source,
        &f.unit_check,
    ));
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
    h.push_str(&fit_text(&fit(f), "factor at the ground truth"));
    if f.truth_noise.is_exact() {
        let _ = writeln!(
            h,
            "weight: the factor's covariance only (the ground truth is taken as exact; give \
             --pose-rot-std, --pose-pos-std, --vel-std, --bias-gyro-std, --bias-acc-std for its \
             own errors)"
        );
    }
    h
}

/// Runs `preint factor`: one window (`--from`, `--to`) or many (`--window`,
/// [`windows`]).
pub fn run(args: &Args) -> Result<Output, CliError> {
    if let Some(lengths) = &args.window {
        return windows::run(args, lengths);
    }
    let f = compute(args)?;
    let output = Output {
        human: to_text(&f),
        json: to_json(&f),
    };
    crate::fit::strict(args.strict, output, &fit(&f), "factor at the ground truth")
}
