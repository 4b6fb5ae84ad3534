//! `preint advise`: the cheapest scheme and lowest rate whose discretisation error stays below
//! a fraction of the noise-induced standard deviation, estimated from the recording itself
//! (method: [`crate::analysis::advise`], after [`crate::analysis::denoise`]).

use crate::analysis::advise::{Candidate, evaluate, recommend};
use crate::analysis::denoise::denoise;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output, checks, noise, scheme, stream};
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
    #[arg(long, default_value_t = 1.0)]
    pub window: f64,
    /// Allowed discretisation error as a fraction of the noise σ.
    #[arg(long, default_value_t = 0.1)]
    pub fraction: f64,
    /// Analyse only samples with timestamps >= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Analyse only samples with timestamps <= this, in ns.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<i64>,
}

/// The evaluation and the recommendation.
#[derive(Clone, Debug)]
pub struct Advice {
    /// The flags it ran with.
    pub args: Args,
    /// Number of samples in the recording.
    pub samples: usize,
    /// Low-pass cutoffs \[Hz\] chosen for (gyro, accelerometer); `None`: left unfiltered.
    pub cutoffs: [Option<f64>; 2],
    /// Every (scheme, rate) evaluated.
    pub candidates: Vec<Candidate>,
    /// Index of the recommended candidate, if any is acceptable.
    pub recommended: Option<usize>,
}

impl Advice {
    /// The recommended candidate, if any.
    pub fn recommendation(&self) -> Option<&Candidate> {
        self.recommended.map(|i| &self.candidates[i])
    }
}

/// Reads the recording, separates noise from motion and evaluates every scheme and rate.
pub fn compute(args: &Args) -> Result<Advice, CliError> {
    checks::positive("--fraction", args.fraction)?;
    let noise = noise::or_default(Some(&args.noise))?;
    let samples = stream::read_span(&args.input, args.from, args.to, "advise")?;
    let (signal, cutoffs) = denoise(&samples, noise.gyro_noise_density, noise.acc_noise_density);
    let candidates = evaluate(&signal, &noise, 9.81, args.window, args.fraction)?;
    let recommended =
        recommend(&candidates).and_then(|r| candidates.iter().position(|c| std::ptr::eq(c, r)));
    Ok(Advice {
        args: args.clone(),
        samples: samples.len(),
        cutoffs,
        candidates,
        recommended,
    })
}

/// The JSON form: the recommendation, the cutoffs and every candidate.
pub fn to_json(a: &Advice) -> Value {
    let rec = a.recommendation();
    let rows: Vec<_> = a
        .candidates
        .iter()
        .map(|c| json!({"scheme": scheme::label(c.scheme), "rate": c.rate_hz, "decimation": c.decimation,
            "disc_err": {"rot_rad": c.disc_err[0], "vel_m_s": c.disc_err[1], "pos_m": c.disc_err[2]},
            "noise_sigma": {"rot_rad": c.noise_sigma[0], "vel_m_s": c.noise_sigma[1], "pos_m": c.noise_sigma[2]},
            "cost_ns_per_s": c.cost_ns_per_s, "acceptable": c.acceptable}))
        .collect();
    json!({
        "recommended_scheme": rec.map(|c| scheme::label(c.scheme)),
        "recommended_rate": rec.map(|c| c.rate_hz),
        "fraction": a.args.fraction, "window_s": a.args.window, "samples": a.samples,
        "denoise_cutoff_hz": {"gyro": a.cutoffs[0], "acc": a.cutoffs[1]},
        "candidates": rows,
        "method": "white noise removed by a zero-phase low-pass whose cutoff makes the residual match the noise density; reference = hermite4 at the recording's rate; disc_err = max over windows of the distance to it; noise_sigma = sqrt(trace) of each covariance block",
    })
}

/// The human summary: the cutoffs, a table of every candidate and the recommendation.
pub fn to_text(a: &Advice) -> String {
    let (window, fraction) = (a.args.window, a.args.fraction);
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{}: {} samples; window {window} s; threshold {fraction}·σ",
        a.args.input.path().display(),
        a.samples
    );
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
    h.push_str(&table(&a.candidates));
    match a.recommendation() {
        Some(c) => {
            let _ = writeln!(
                h,
                "recommended: {} at {:.1} Hz (cheapest whose discretisation error < {fraction}·σ on rotation, velocity and position)",
                scheme::label(c.scheme),
                c.rate_hz
            );
        }
        None => {
            let _ = writeln!(
                h,
                "no scheme keeps the discretisation error below {fraction}·σ at these rates: use hermite4 at the full rate, or record faster"
            );
        }
    }
    if a.cutoffs.iter().any(Option::is_none) {
        let _ = writeln!(
            h,
            "note: the signal above the motion band is not white noise of the stated density (vibration, or a \
                             density set too low): the errors above include that high-frequency content."
        );
    }
    h
}

/// One line per candidate: errors and σ per component, cost, `ok` when acceptable.
fn table(candidates: &[Candidate]) -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{:<9} {:>9} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>12}",
        "scheme",
        "rate Hz",
        "rot err",
        "rot σ",
        "vel err",
        "vel σ",
        "pos err",
        "pos σ",
        "µs/s data"
    );
    for c in candidates {
        let _ = writeln!(
            h,
            "{:<9} {:>9.1} {:>11.2e} {:>11.2e} {:>11.2e} {:>11.2e} {:>11.2e} {:>11.2e} {:>12.1}{}",
            scheme::label(c.scheme),
            c.rate_hz,
            c.disc_err[0],
            c.noise_sigma[0],
            c.disc_err[1],
            c.noise_sigma[1],
            c.disc_err[2],
            c.noise_sigma[2],
            c.cost_ns_per_s * 1e-3,
            if c.acceptable { "  ok" } else { "" }
        );
    }
    h
}

/// Runs `preint advise`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let a = compute(args)?;
    Ok(Output {
        human: to_text(&a),
        json: to_json(&a),
    })
}
