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
//! of `preint::second_order` to the measurement's covariance first.
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

use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::preint_args::PreintArgs;
use crate::scheme::{self};
use crate::{CliError, Output, input};
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, Level, NavState, PreintParams,
    PreintegratedImu, ResidualMode, preintegrate,
};
use preint_analysis::checks::UnitCheck;
use preint_analysis::consistency::{
    Evaluation, ResidualJacobians, TruthNoise, chi2_quantiles, evaluate, fit_json,
};
use preint_analysis::format::list;
use preint_analysis::stream::{self, StreamWindow};
use preint_analysis::{ImuInput, checks};
use preint_io::{GroundTruthState, SourceInfo, read_euroc_groundtruth};
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

fn nav(s: &GroundTruthState) -> NavState {
    NavState::new(s.rotation(), s.p, s.v)
}

/// The ground-truth rows nearest to `--from` and `--to`: two different rows, the first
/// earlier.
fn keyframes(
    args: &Args,
    (from, to): (i64, i64),
) -> Result<(GroundTruthState, GroundTruthState), CliError> {
    let gt = read_euroc_groundtruth(&args.poses)?;
    let (gi, gj) = (*input::nearest_row(&gt, from), *input::nearest_row(&gt, to));
    if gj.t_ns <= gi.t_ns {
        return Err(CliError::Usage(format!(
            "{}: the ground-truth rows nearest to --from {} and --to {} are at {} and {} ns; \
             they must be two different rows, the first earlier",
            args.poses.display(),
            from,
            to,
            gi.t_ns,
            gj.t_ns
        )));
    }
    Ok((gi, gj))
}

/// The window `[t_i, t_j]` of the recording, how it was read and its unit checks. Only the
/// part the window needs is read; a split recording is merged whole, and the effective
/// accelerometer density of its merged samples is set in `params`.
/// `None` for `t_i` and `t_j`: the whole recording.
pub(crate) fn window(
    input: &ImuInput,
    noise: &ImuNoise,
    params: &mut PreintParams,
    (t_i, t_j): (Option<i64>, Option<i64>),
) -> Result<(StreamWindow, SourceInfo, UnitCheck), CliError> {
    if input.is_split() {
        let (w, source, split, units) = stream::split_window(input, t_i, t_j)?;
        preint_analysis::noise::apply_split(noise, split.as_ref(), params);
        return Ok((w, source, units));
    }
    let stream = stream::open_checked_until(input, t_j)?;
    let (source, units) = (stream.info().clone(), stream.unit_check().clone());
    let _bar = preint_analysis::progress::ReadingBar::start(stream.progress(), "factor");
    let w = stream::cut_window(stream, t_i, t_j)?;
    Ok((w, source, units))
}

/// The ground truth's own errors (`--pose-rot-std`, `--pose-pos-std`, `--vel-std`,
/// `--bias-gyro-std`, `--bias-acc-std`), each checked finite and non-negative.
pub(crate) fn truth_noise(args: &Args) -> Result<TruthNoise, CliError> {
    let tn = TruthNoise {
        rot_rad: args.pose_rot_std,
        pos_m: args.pose_pos_std,
        vel_m_s: args.vel_std,
        bias_gyro_rad_s: args.bias_gyro_std,
        bias_acc_m_s2: args.bias_acc_std,
    };
    checks::non_negative("--pose-rot-std", tn.rot_rad)?;
    checks::non_negative("--pose-pos-std", tn.pos_m)?;
    checks::non_negative("--vel-std", tn.vel_m_s)?;
    checks::non_negative("--bias-gyro-std", tn.bias_gyro_rad_s)?;
    checks::non_negative("--bias-acc-std", tn.bias_acc_m_s2)?;
    Ok(tn)
}

/// The noise model and parameters at the factor's level (the bias random walk with
/// `--combined`, whose noise file must hold it).
pub(crate) fn noise_params(args: &Args) -> Result<(ImuNoise, PreintParams), CliError> {
    let level = if args.combined {
        Level::Combined
    } else {
        Level::Covariance
    };
    let (noise, params) = args.preint.params(level)?;
    if let (true, Some(path)) = (args.combined, &args.preint.noise) {
        preint_io::read_kalibr_bias_model(path)?;
    }
    Ok((noise, params))
}

/// Why a window could not be evaluated: preintegration (indices in `samples`), the factor or
/// its weight.
#[derive(Debug)]
pub(crate) enum WindowError {
    Preint(preint::PreintError),
    Factor(preint::FactorError),
    Weight(preint_analysis::Error),
}

impl std::fmt::Display for WindowError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WindowError::Preint(e) => write!(f, "{e}"),
            WindowError::Factor(e) => write!(f, "{e}"),
            WindowError::Weight(e) => write!(f, "{e}"),
        }
    }
}

/// The error of a window of `w`, in the recording's terms (sample indices of the stream).
fn in_window(e: WindowError, input: &ImuInput, w: &StreamWindow) -> CliError {
    match e {
        WindowError::Preint(e) => CliError::failed_in(input.path(), w.in_stream(e)),
        WindowError::Factor(e) => CliError::failed_in(input.path(), e),
        WindowError::Weight(e) => e.into(),
    }
}

/// The window `[gi, gj]` of `samples` preintegrated with the ground truth's bias at i (and the
/// second-order term with `--second-order`), its factor evaluated at the ground truth.
pub(crate) fn evaluate_window(
    args: &Args,
    params: &PreintParams,
    samples: &[preint::ImuSample],
    (gi, gj): (&GroundTruthState, &GroundTruthState),
    tn: TruthNoise,
) -> Result<(PreintegratedImu, Evaluation), WindowError> {
    use WindowError as E;
    let mut pim = preintegrate(params, &gi.bias, samples, gi.t_ns, gj.t_ns).map_err(E::Preint)?;
    if args.second_order {
        let term = preint::second_order::covariance(params, samples, &pim).map_err(E::Preint)?;
        pim = preint::second_order::inflate(&pim, &term);
    }
    let (xi, xj) = (nav(gi), nav(gj));
    let ev = if args.combined {
        let f = CombinedImuFactor::with_mode(pim.clone(), args.residual).map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias, &gj.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    } else {
        let f = ImuFactor::with_mode(pim.clone(), args.residual).map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    }
    .map_err(E::Weight)?;
    Ok((pim, ev))
}

fn jacobians<const R: usize>(j: &preint::FactorJacobians<R>) -> ResidualJacobians<R> {
    ResidualJacobians {
        state_i: j.state_i(),
        state_j: j.state_j(),
        bias_i: j.bias_i(),
    }
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
    let (pim, ev) = evaluate_window(args, &params, samples, (&gi, &gj), tn)
        .map_err(|e| in_window(e, &input, &w))?;
    Ok(FactorRun {
        imu: input.label(),
        source,
        unit_check,
        scheme,
        combined: args.combined,
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

fn factor_name(combined: bool) -> &'static str {
    if combined {
        "CombinedImuFactor"
    } else {
        "ImuFactor"
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
            (false, ResidualMode::ComponentWise) => "cov (covariance of [r_phi, r_v, r_p]) + ground-truth noise through the Jacobians",
            (true, ResidualMode::Logmap) => "diag(T, I6) residual_cov15 diag(T, I6)^T, T = diag(I, dR^T, dR^T) (covariance of the Logmap residual) + ground-truth noise through the Jacobians",
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
        factor_name(f.combined),
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
/// [`super::factor_windows`]).
pub fn run(args: &Args) -> Result<Output, CliError> {
    if let Some(lengths) = &args.window {
        return super::factor_windows::run(args, lengths);
    }
    let f = compute(args)?;
    let output = Output {
        human: to_text(&f),
        json: to_json(&f),
    };
    crate::fit::strict(args.strict, output, &fit(&f), "factor at the ground truth")
}
