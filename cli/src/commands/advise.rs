//! `preint advise`: the cheapest scheme and lowest rate whose discretisation error stays below
//! a fraction of the noise-induced standard deviation, estimated from the recording itself
//! (method: [`preint_analysis::advise`], after [`preint_analysis::denoise`]).
//!
//! Its fit (JSON `fit`, [`preint_analysis::advise::fit`]): the embedded truncation estimate's
//! χ² of the recommended (scheme, rate) against `χ²₉`, credible when p ≥ 1e-6; `--strict`
//! makes a fit that is not credible a refusal (exit 2, after the output). `--calibration`
//! applies only the file's intrinsics (every scheme is evaluated, so its scheme and time
//! offset do not enter).

use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output, scheme};
use preint::ImuSample;
use preint_analysis::advise::{
    Candidate, decimation_in_range, evaluate_input, gap_beyond_limit, recommend,
};
use preint_analysis::consistency::fit_json;
use preint_analysis::denoise::denoise;
use preint_analysis::input_class::{InputClass, exactness};
use preint_analysis::{checks, noise, stream};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Flags of `preint advise`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Kalibr imu.yaml with the noise densities.
    #[arg(long)]
    pub noise: PathBuf,
    /// Preintegration window (s).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub window: f64,
    /// Allowed discretisation error as a fraction of the noise σ.
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    pub fraction: f64,
    /// Analyse only samples with timestamps >= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Analyse only samples with timestamps <= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// What the input is between samples. smooth: point samples of a smooth signal,
    /// as a MEMS IMU delivers; no scheme is exact, the reference is hermite4 at the recording's
    /// rate. held: rate and specific force constant over each sample interval, as an
    /// integrating IMU (delta-angle/delta-velocity outputs) or a sample-and-hold stream
    /// delivers; galilean is exact for it and is the reference, lower rates average the samples.
    #[arg(long = "input", value_name = "CLASS", value_enum, default_value_t = InputClassArg::Smooth)]
    pub input_class: InputClassArg,
    /// An IMU calibration file (`calibrate --out`, OpenVINS kalibr_imu_chain.yaml or Kalibr
    /// imu.yaml): its intrinsics are applied to the raw samples before the analysis.
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<std::path::PathBuf>,
    /// Exit with status 2 (after printing the result) when the fit is not credible: the
    /// recommended (scheme, rate)'s own truncation error would make a factor at the true
    /// states inconsistent (χ² of the embedded estimate with p < 1e-6 against 9 dof).
    #[arg(long)]
    pub strict: bool,
}

/// `--input`: the [`InputClass`] as given on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum InputClassArg {
    /// Point samples of a smooth signal (a MEMS IMU): reference hermite4, Richardson-checked.
    #[default]
    Smooth,
    /// Rate and specific force constant over each sample interval (integrating IMUs,
    /// sample-and-hold streams): reference galilean, exact for this input.
    Held,
}

impl From<InputClassArg> for InputClass {
    fn from(c: InputClassArg) -> Self {
        match c {
            InputClassArg::Smooth => InputClass::Smooth,
            InputClassArg::Held => InputClass::Held,
        }
    }
}

/// The evaluation and the recommendation.
#[derive(Clone, Debug)]
pub struct Advice {
    /// The flags it ran with.
    pub args: Args,
    /// Number of samples in the recording.
    pub samples: usize,
    /// How the recording was read (`None` for samples given in memory).
    pub source: Option<preint_io::SourceInfo>,
    /// What the unit checks said.
    pub unit_check: preint_analysis::checks::UnitCheck,
    /// Low-pass cutoffs \[Hz\] chosen for (gyro, accelerometer); `None`: left unfiltered.
    pub cutoffs: [Option<f64>; 2],
    /// Every (scheme, rate) evaluated.
    pub candidates: Vec<Candidate>,
    /// Index of the recommended candidate, if any is acceptable.
    pub recommended: Option<usize>,
    /// Why the lower rates were not evaluated, when a gap of the recording widened by
    /// decimation stopped them ([`gap_note`]).
    pub rates_not_evaluated: Option<String>,
}

impl Advice {
    /// The recommended candidate, if any.
    pub fn recommendation(&self) -> Option<&Candidate> {
        self.recommended.map(|i| &self.candidates[i])
    }
}

/// Reads the recording, separates noise from motion and evaluates every scheme and rate.
pub fn compute(args: &Args) -> Result<Advice, CliError> {
    checks::window_order(args.from, args.to)?;
    checks::positive("--fraction", args.fraction)?;
    let input = args.input.to_input();
    let noise = noise::or_default(Some(&args.noise))?;
    let stream::Span {
        mut samples,
        source,
        unit_check,
    } = stream::read_span(&input, args.from, args.to, "advise")?;
    if let Some(path) = &args.calibration {
        let x = preint_analysis::calibration_file::read(path)?.intrinsics;
        if !x.is_identity() {
            let c = x.correction();
            samples.iter_mut().for_each(|s| *s = c.apply(s));
        }
    }
    // Held input is not low-passed: the filter would smear its steps (analysis::advise docs).
    let (signal, cutoffs) = match InputClass::from(args.input_class) {
        InputClass::Smooth => denoise(&samples, noise.gyro_noise_density, noise.acc_noise_density),
        InputClass::Held => (samples.clone(), [None, None]),
    };
    let candidates = evaluate_input(
        &signal,
        &noise,
        9.81,
        args.window,
        args.fraction,
        args.input_class.into(),
    )?;
    let recommended =
        recommend(&candidates).and_then(|r| candidates.iter().position(|c| std::ptr::eq(c, r)));
    let rates_not_evaluated = gap_note(args, &signal, &candidates);
    Ok(Advice {
        args: args.clone(),
        samples: samples.len(),
        source: Some(source),
        unit_check,
        cutoffs,
        candidates,
        recommended,
        rates_not_evaluated,
    })
}

/// When decimation stopped at a gap of the recording ([`gap_beyond_limit`]): which rates were
/// not evaluated and why, naming the file, the gap and the sample after it.
pub fn gap_note(args: &Args, samples: &[ImuSample], candidates: &[Candidate]) -> Option<String> {
    let (first, last) = (samples.first()?, samples.last()?);
    let dt_s = (last.t_ns - first.t_ns) as f64 * 1e-9 / (samples.len() - 1).max(1) as f64;
    let next = 2 * candidates.iter().map(|c| c.decimation).max()?;
    if !decimation_in_range(dt_s, next, args.window) {
        return None;
    }
    let (wide, gap, at) = gap_beyond_limit(samples, next)?;
    Some(format!(
        "rates of {:.2} Hz and below are not evaluated: the recording {} has an interval of \
         {:.6} s before sample {at} (t = {} ns), which the embedded estimate at that rate (one \
         sample in {}) widens to {:.6} s, above preintegration's gap limit of {} s",
        1.0 / (dt_s * next as f64),
        args.input.to_input().label(),
        gap as f64 * 1e-9,
        samples[at].t_ns,
        2 * next,
        wide as f64 * 1e-9,
        preint::params::DEFAULT_MAX_GAP_NS as f64 * 1e-9
    ))
}

/// `{rot_rad, vel_m_s, pos_m}`.
fn triple(e: &[f64; 3]) -> Value {
    json!({"rot_rad": e[0], "vel_m_s": e[1], "pos_m": e[2]})
}

/// The input class, its reference and exact scheme, and every scheme's order and exactness.
fn input_json(input: InputClass) -> Value {
    let schemes: serde_json::Map<String, Value> = scheme::ALL
        .iter()
        .map(|&s| {
            let e = exactness(s);
            let exact = input.exact_scheme() == Some(s);
            (
                scheme::label(s).to_string(),
                json!({"order_smooth": e.order_smooth, "exact_on": e.exact_on, "exact_for_input": exact}),
            )
        })
        .collect();
    json!({
        "input_class": input.label(),
        "reference_scheme": scheme::label(input.reference()),
        "exact_scheme": input.exact_scheme().map(scheme::label),
        "schemes": schemes,
    })
}

/// The JSON form: the recommendation, the cutoffs and every candidate.
pub fn to_json(a: &Advice) -> Value {
    let rec = a.recommendation();
    let input = InputClass::from(a.args.input_class);
    let rows: Vec<_> = a
        .candidates
        .iter()
        .map(|c| json!({"scheme": scheme::label(c.scheme), "rate": c.rate_hz, "decimation": c.decimation,
            "disc_err": triple(&c.disc_err),
            "ref_dist": c.ref_dist.as_ref().map(triple),
            "embedded_err": triple(&c.embedded_err),
            "embedded_chi2": if c.embedded_chi2.is_finite() { json!(c.embedded_chi2) } else { Value::Null },
            "reference": c.is_reference(),
            "noise_sigma": triple(&c.noise_sigma),
            "cost_ns_per_s": c.cost_ns_per_s, "acceptable": c.acceptable}))
        .collect();
    let mut out = json!({
        "recommended_scheme": rec.map(|c| scheme::label(c.scheme)),
        "recommended_rate": rec.map(|c| c.rate_hz),
        "recommended_exact": rec.is_some_and(|c| input.exact_scheme() == Some(c.scheme) && c.decimation == 1),
        "fraction": a.args.fraction, "window_s": a.args.window, "samples": a.samples,
        "denoise_cutoff_hz": {"gyro": a.cutoffs[0], "acc": a.cutoffs[1]},
        "candidates": rows,
        "tangent_order": ["dphi", "dv", "dp"],
        "method": method(input),
        "calibration": a.args.calibration.as_ref().map(|p| p.display().to_string()),
        "rates_not_evaluated": a.rates_not_evaluated,
        "fit": preint_analysis::advise::fit(&a.candidates, rec).as_ref().map(fit_json),
        "input": a.source.as_ref().map(|s| preint_analysis::recording::input_json(s, &a.unit_check)),
    });
    if let (Value::Object(o), Value::Object(i)) = (&mut out, input_json(input)) {
        o.extend(i);
    }
    out
}

/// The method in one sentence per input class.
fn method(input: InputClass) -> &'static str {
    match input {
        InputClass::Smooth => {
            "smooth input: white noise removed by a zero-phase low-pass whose cutoff makes the residual match the noise density; lower rates = every d-th sample; reference = hermite4 at the recording's rate; ref_dist = max over windows of the distance to it; embedded_err = max over windows of preint::truncation::estimate on the candidate's own samples, embedded_chi2 its e^T Sigma^-1 e; disc_err = the larger of the two per component (embedded_err alone for the reference); acceptable when disc_err < fraction * noise_sigma; noise_sigma = sqrt(trace) of each covariance block"
        }
        InputClass::Held => {
            "held input (constant over each sample interval), not filtered; lower rates = means of d consecutive samples held over their d intervals; reference = galilean at the recording's rate, exact for held input; ref_dist = max over windows of the distance to it; embedded_err = max over windows of the distance to galilean on the candidate's own samples (exact for them), embedded_chi2 its e^T Sigma^-1 e; disc_err = the larger of the two per component (embedded_err alone for the reference); acceptable when disc_err < fraction * noise_sigma; noise_sigma = sqrt(trace) of each covariance block"
        }
    }
}

/// The human summary: the input class and what is exact for it, the cutoffs, a table of every
/// candidate and the recommendation.
pub fn to_text(a: &Advice) -> String {
    let (window, fraction, input) = (
        a.args.window,
        a.args.fraction,
        InputClass::from(a.args.input_class),
    );
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} samples; window {window} s; threshold {fraction}·σ",
        a.args.input.to_input().path().display(),
        a.samples
    );
    h.push_str(&match &a.source {
        Some(s) => preint_analysis::recording::input_text(s, &a.unit_check),
        None => a.unit_check.text(),
    });
    h.push_str(&input_text(input));
    match input {
        InputClass::Smooth => {
            let fmt_cut = |c: Option<f64>| {
                c.map_or(
                    "none (residual is not white noise at any cutoff)".to_string(),
                    |c| format!("{c:.2} Hz"),
                )
            };
            let _ = writeln!(
                h,
                "signal/noise separation: zero-phase low-pass at gyro {}, accelerometer {}",
                fmt_cut(a.cutoffs[0]),
                fmt_cut(a.cutoffs[1])
            );
        }
        InputClass::Held => {
            let _ = writeln!(
                h,
                "held input: not low-passed; lower rates average d consecutive samples"
            );
        }
    }
    h.push_str(&table(&a.candidates));
    if let Some(note) = &a.rates_not_evaluated {
        let _ = writeln!(h, "note: {note}");
    }
    match a.recommendation() {
        Some(c) => {
            let exact = input.exact_scheme() == Some(c.scheme) && c.decimation == 1;
            let _ = writeln!(
                h,
                "recommended: {} at {:.1} Hz (cheapest whose discretisation error, reference distance and embedded estimate, < {fraction}·σ on rotation, velocity and position){}",
                scheme::label(c.scheme),
                c.rate_hz,
                if exact { "; exact for held input" } else { "" }
            );
        }
        None => {
            let _ = writeln!(
                h,
                "no scheme keeps the discretisation error below {fraction}·σ at these rates: {}",
                match input {
                    InputClass::Smooth => "use hermite4 at the full rate, or record faster",
                    InputClass::Held => "use galilean at the full rate (exact for held input)",
                }
            );
        }
    }
    if let Some(f) = preint_analysis::advise::fit(&a.candidates, a.recommendation()) {
        h.push_str(&fit_text(&f, "advice"));
    }
    if input == InputClass::Smooth && a.cutoffs.iter().any(Option::is_none) {
        let _ = writeln!(
            h,
            "note: the signal above the motion band is not white noise of the stated density (vibration, or a \
                             density set too low): the errors above include that high-frequency content."
        );
    }
    h
}

/// The input class, its reference, the scheme exact for it (if any) and each scheme's order.
fn input_text(input: InputClass) -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "input: {} (reference {} at the recording's rate); exact for this input: {}",
        input.label(),
        scheme::label(input.reference()),
        input
            .exact_scheme()
            .map_or("no scheme (hermite4 is 4th order)", scheme::label)
    );
    for &s in &scheme::ALL {
        let e = exactness(s);
        let _ = writeln!(
            h,
            "  {:<9} order {} on smooth input; {}",
            scheme::label(s),
            e.order_smooth,
            e.exact_on
        );
    }
    h
}

/// One line per candidate: per component the reference distance, the embedded estimate and σ;
/// the estimate's χ²; cost; `ok` when acceptable.
fn table(candidates: &[Candidate]) -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{:<9} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>10}",
        "scheme",
        "rate Hz",
        "rot ref",
        "rot est",
        "rot σ",
        "vel ref",
        "vel est",
        "vel σ",
        "pos ref",
        "pos est",
        "pos σ",
        "est χ²",
        "µs/s data"
    );
    let e = |x: f64| format!("{x:>9.2e}");
    for c in candidates {
        let r = |k: usize| c.ref_dist.map_or(format!("{:>9}", "(ref)"), |d| e(d[k]));
        let _ = writeln!(
            h,
            "{:<9} {:>8.1} {} {} {} {} {} {} {} {} {} {} {:>10.1}{}",
            scheme::label(c.scheme),
            c.rate_hz,
            r(0),
            e(c.embedded_err[0]),
            e(c.noise_sigma[0]),
            r(1),
            e(c.embedded_err[1]),
            e(c.noise_sigma[1]),
            r(2),
            e(c.embedded_err[2]),
            e(c.noise_sigma[2]),
            e(c.embedded_chi2),
            c.cost_ns_per_s * 1e-3,
            if c.acceptable { "  ok" } else { "" }
        );
    }
    let _ = writeln!(
        h,
        "ref: distance to the reference; est: embedded estimate from the candidate's own samples; est χ²: êᵀΣ⁻¹ê, tangent [δφ, δv, δp]"
    );
    h
}

/// Runs `preint advise`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let a = compute(args)?;
    let output = Output {
        human: to_text(&a),
        json: to_json(&a),
    };
    match preint_analysis::advise::fit(&a.candidates, a.recommendation()) {
        Some(f) => crate::fit::strict(args.strict, output, &f, "advice"),
        None => Ok(output),
    }
}
