//! `preint advise`: the cheapest scheme and lowest rate whose discretisation error stays below
//! a fraction of the noise-induced standard deviation, estimated from the recording itself
//! (the computation, its fit and its JSON: [`preint_analysis::advise`]); `--strict` makes a fit
//! that is not credible a refusal (exit 2, after the output).

use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output, scheme};
use preint_analysis::advise::{Advice, Candidate, Options};
use preint_analysis::input_class::{InputClass, exactness};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Flags of `preint advise`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Kalibr imu.yaml with the noise densities.
    #[arg(help_heading = "Analysis", long)]
    pub noise: PathBuf,
    /// Preintegration window (s).
    #[arg(
        help_heading = "Analysis",
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub window: f64,
    /// Allowed discretisation error as a fraction of the noise σ.
    #[arg(
        help_heading = "Analysis",
        long,
        default_value_t = 0.1,
        allow_hyphen_values = true
    )]
    pub fraction: f64,
    /// Analyse only samples with timestamps >= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Analyse only samples with timestamps <= this, in ns.
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// What the input is between samples. smooth: point samples of a smooth signal,
    /// as a MEMS IMU delivers; no scheme is exact, the reference is hermite4 at the recording's
    /// rate. held: rate and specific force constant over each sample interval, as an
    /// integrating IMU (delta-angle/delta-velocity outputs) or a sample-and-hold stream
    /// delivers; galilean is exact for it and is the reference, lower rates average the samples.
    #[arg(help_heading = "Analysis", long = "input", value_name = "CLASS", value_enum, default_value_t = InputClassArg::Smooth)]
    pub input_class: InputClassArg,
    /// An IMU calibration file (`calibrate --out`, OpenVINS kalibr_imu_chain.yaml or Kalibr
    /// imu.yaml): its intrinsics are applied to the raw samples before the analysis.
    #[arg(help_heading = "Input", long, value_name = "FILE")]
    pub calibration: Option<std::path::PathBuf>,
    /// Exit with status 2 (after printing the result) when the fit is not credible: the
    /// recommended (scheme, rate)'s own truncation error would make a factor at the true
    /// states inconsistent (χ² of the embedded estimate with p < 1e-6 against 9 dof).
    #[arg(help_heading = "Output", long)]
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

impl Args {
    /// What the library computes on.
    pub fn options(&self) -> Options {
        Options {
            input: self.input.to_input(),
            noise: self.noise.clone(),
            window: self.window,
            fraction: self.fraction,
            from: self.from,
            to: self.to,
            input_class: self.input_class.into(),
            calibration: self.calibration.clone(),
        }
    }
}

/// The human summary: the input class and what is exact for it, the cutoffs, a table of every
/// candidate and the recommendation.
pub fn to_text(a: &Advice) -> String {
    let (window, fraction, input) = (a.options.window, a.options.fraction, a.options.input_class);
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} samples; window {window} s; threshold {fraction}·σ",
        a.options.input.path().display(),
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
    if let Some(f) = a.fit() {
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
    let a = preint_analysis::advise::compute(&args.options())?;
    let output = Output {
        human: to_text(&a),
        json: preint_analysis::advise::to_json(&a),
    };
    match a.fit() {
        Some(f) => crate::fit::strict(args.strict, output, &f, "advice"),
        None => Ok(output),
    }
}
