//! `preint factor --window S[,S…]`: the IMU factor at the ground truth over a whole recording,
//! back-to-back windows of each length: is the noise model consistent with this IMU and this
//! ground truth, and from which window length on does it fail?
//!
//! The windows are [`preint_analysis::truth_windows`]' and their factors
//! [`preint_analysis::factor_windows`]' (back-to-back over the span where the
//! recording and the ground truth overlap, keyframes at the ground-truth rows nearest to their
//! edges), and each window's factor is evaluated as the one-window form does ([`super`]: 9-dof
//! `ImuFactor`, 15-dof `CombinedImuFactor` with `--combined`, the same weight). A window is
//! skipped (and counted) when it cannot be cut ([`preint_analysis::truth_windows`]: no
//! ground-truth row within `L/2` of an edge, two edges on the same row, fewer than 2 samples,
//! a gap of more than [`GAP_FACTOR`](preint_analysis::truth_windows::GAP_FACTOR) median
//! sample intervals) or a preintegration or weight fails.
//!
//! The statistics per length and the verdict are [`preint_analysis::chi2_windows`]. The fit
//! (JSON `fit`) is the χ² summed over all windows of all lengths against their total dof.

use super::evaluate::{noise_params, truth_noise, window};
use super::{Args, truth_noise_json};
use crate::{CliError, Output};
use preint_analysis::chi2_windows::{self, LengthSummary, Verdict, length_json, verdict_json};
use preint_analysis::consistency::{TruthNoise, fit_json};
use preint_analysis::factor_windows::per_length;
use preint_analysis::truth_windows::{check_lengths, overlap};
use preint_io::read_euroc_groundtruth;
use serde_json::{Value, json};
use std::fmt::Write as _;

/// Everything `factor --window` computes.
#[derive(Clone, Debug)]
pub struct WindowsRun {
    /// The IMU file, as printed.
    pub imu: String,
    /// The span where the recording and the ground truth overlap [ns].
    pub span_ns: (i64, i64),
    /// One summary per `--window` length, in the order given.
    pub lengths: Vec<LengthSummary>,
    /// What they say about the noise model.
    pub verdict: Verdict,
    /// The ground truth's own errors added to the weight.
    pub truth_noise: TruthNoise,
    /// `CombinedImuFactor` (else `ImuFactor`).
    pub combined: bool,
    /// `ImuFactor` weighted with the in-window bias drift (`--in-window-drift`).
    pub in_window_drift: bool,
    /// The world gravity vector \[m/s²\] (`--gravity`, `--gravity-vector`).
    pub gravity: nalgebra::Vector3<f64>,
}

/// Reads the files and evaluates the factor over back-to-back windows of every length.
pub fn compute(args: &Args, lengths: &[f64]) -> Result<WindowsRun, CliError> {
    check_lengths(lengths)?;
    let tn = truth_noise(args)?;
    let (noise, mut params) = noise_params(args)?;
    let gt = read_euroc_groundtruth(&args.poses)?;
    let input = args.input.to_input();
    let (w, _, _) = window(&input, &noise, &mut params, (None, None))?;
    let samples = w.samples.as_slice();
    let (span, dt) = overlap(samples, &gt, (&input.label(), &args.poses), "--window")?;
    let summaries = per_length(
        &args.kind(),
        &params,
        (samples, &gt),
        (span, dt),
        lengths,
        tn,
    )?;
    Ok(WindowsRun {
        imu: input.label(),
        span_ns: span,
        verdict: chi2_windows::verdict(&summaries),
        lengths: summaries,
        truth_noise: tn,
        combined: args.combined,
        in_window_drift: args.in_window_drift,
        gravity: params.gravity,
    })
}

/// The fit of the whole set: the χ² summed over all windows of all lengths against their
/// total dof.
pub fn fit(r: &WindowsRun) -> preint_calib::Fit {
    let chi2: f64 = r.lengths.iter().map(|l| l.chi2_sum).sum();
    let dof: usize = r.lengths.iter().map(|l| l.count * l.dof).sum();
    preint_calib::Fit::new(chi2, dof).because(&format!(
        "the IMU and the ground truth disagree beyond the factor's covariance over the windows \
         ({}): the noise densities (--noise), the ground truth's own errors (--pose-rot-std, \
         --pose-pos-std, --vel-std, --bias-gyro-std, --bias-acc-std), or the clocks",
        r.verdict.text()
    ))
}

/// The JSON form: `{windows: [...], verdict, span_ns, factor, in_window_drift, gravity
/// (m/s², world frame), ground_truth_noise, fit}`.
pub fn to_json(r: &WindowsRun) -> Value {
    json!({
        "factor": super::factor_name(r.combined),
        "in_window_drift": r.in_window_drift,
        "gravity": [r.gravity[0], r.gravity[1], r.gravity[2]],
        "span_ns": [r.span_ns.0, r.span_ns.1],
        "windows": r.lengths.iter().map(length_json).collect::<Vec<_>>(),
        "verdict": verdict_json(&r.verdict),
        "ground_truth_noise": truth_noise_json(&r.truth_noise),
        "fit": fit_json(&fit(r)),
    })
}

/// The human summary: one row per length, then the verdict.
pub fn to_text(r: &WindowsRun) -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} at the ground truth over {:.3} s ({} → {} ns), back-to-back windows",
        r.imu,
        super::factor_label(r.combined, r.in_window_drift),
        (r.span_ns.1 - r.span_ns.0) as f64 * 1e-9,
        r.span_ns.0,
        r.span_ns.1
    );
    let _ = writeln!(
        h,
        "{:>8} {:>6} {:>7} {:>10} {:>10} {:>8} {:>9} {:>9}  share rot / vel / pos{}",
        "length s",
        "count",
        "skipped",
        "mean χ²",
        "median χ²",
        "χ²/dof",
        ">p99",
        "KS p",
        if r.combined { " / bg / ba" } else { "" }
    );
    for l in &r.lengths {
        let head = format!("{:>8} {:>6} {:>7}", l.length_s, l.count, l.skipped);
        let Some(s) = &l.stats else {
            let _ = writeln!(h, "{head}  fewer than 2 windows: no statistics");
            continue;
        };
        let shares: Vec<String> = s.block_share.iter().map(|x| format!("{x:.3}")).collect();
        let _ = writeln!(
            h,
            "{head} {:>10.3} {:>10.3} {:>8.3} {:>8.1} % {:>9}  {}",
            s.mean,
            s.median,
            s.mean / l.dof as f64,
            100.0 * s.fraction_above_p99,
            s.ks_p_value.map_or("—".into(), |p| format!("{p:.2e}")),
            shares.join(" / ")
        );
    }
    let _ = writeln!(h, "verdict: {}", r.verdict.text());
    h.push_str(&crate::fit::fit_text(&fit(r), "factor over the windows"));
    h
}

/// Runs `preint factor --window`.
pub fn run(args: &Args, lengths: &[f64]) -> Result<Output, CliError> {
    let r = compute(args, lengths)?;
    let output = Output {
        human: to_text(&r),
        json: to_json(&r),
    };
    crate::fit::strict(args.strict, output, &fit(&r), "factor over the windows")
}
