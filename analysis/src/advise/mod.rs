//! `preint advise`: the cheapest scheme and lowest rate whose discretisation error stays below
//! a fraction of the noise-induced standard deviation, estimated from the recording itself:
//! every (scheme, rate) evaluated ([`candidates`], after [`crate::denoise`]), the
//! recommendation and its JSON.
//!
//! Its fit (JSON `fit`, [`candidates::fit`]): the embedded truncation estimate's χ² of the
//! recommended (scheme, rate) against `χ²₉`, credible when p ≥ 1e-6. `calibration` applies
//! only the file's intrinsics (every scheme is evaluated, so its scheme and time offset do not
//! enter).

pub mod candidates;

pub use candidates::*;

use crate::checks::UnitCheck;
use crate::consistency::fit_json;
use crate::denoise::denoise;
use crate::input_class::{InputClass, exactness};
use crate::{Error, ImuInput, checks, noise, stream};
use preint::{ImuNoise, ImuSample, Scheme};
use serde_json::{Value, json};
use std::path::PathBuf;

/// What `advise` runs on (the flags of `preint advise` but `--strict`).
#[derive(Clone, Debug)]
pub struct Options {
    /// The recording and how to read it.
    pub input: ImuInput,
    /// Kalibr imu.yaml with the noise densities (`--noise`; read by [`compute`]).
    pub noise: PathBuf,
    /// Preintegration window \[s\] (`--window`).
    pub window: f64,
    /// Allowed discretisation error as a fraction of the noise σ (`--fraction`).
    pub fraction: f64,
    /// Analyse only samples with timestamps ≥ this \[ns\] (`--from`).
    pub from: Option<i64>,
    /// Analyse only samples with timestamps ≤ this \[ns\] (`--to`).
    pub to: Option<i64>,
    /// What the input is between samples (`--input`).
    pub input_class: InputClass,
    /// An IMU calibration file whose intrinsics are applied to the raw samples first
    /// (`--calibration`).
    pub calibration: Option<PathBuf>,
}

/// The evaluation and the recommendation.
#[derive(Clone, Debug)]
pub struct Advice {
    /// The options it ran with.
    pub options: Options,
    /// Number of samples in the recording.
    pub samples: usize,
    /// How the recording was read (`None` for samples given in memory).
    pub source: Option<preint_io::SourceInfo>,
    /// What the unit checks said.
    pub unit_check: crate::checks::UnitCheck,
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

    /// The advice's fit ([`candidates::fit`]), `None` without a candidate.
    pub fn fit(&self) -> Option<preint_calib::Fit> {
        candidates::fit(&self.candidates, self.recommendation())
    }
}

/// Reads the recording (the span `[from, to]`, its units checked), applies the calibration
/// file's intrinsics and advises on the samples ([`advise_samples`]).
pub fn compute(o: &Options) -> Result<Advice, Error> {
    checks::window_order(o.from, o.to)?;
    checks::positive("--fraction", o.fraction)?;
    let noise = noise::or_default(Some(&o.noise))?;
    let stream::Span {
        mut samples,
        source,
        unit_check,
    } = stream::read_span(&o.input, o.from, o.to, "advise")?;
    if let Some(path) = &o.calibration {
        let x = crate::calibration_file::read(path)?.intrinsics;
        if !x.is_identity() {
            let c = x.correction();
            samples.iter_mut().for_each(|s| *s = c.apply(s));
        }
    }
    advise_samples(o, &samples, &noise, Some(source), unit_check)
}

/// Separates noise from motion (smooth input), evaluates every scheme and rate on `samples`
/// (read, checked and corrected as [`compute`] does) and recommends one. `noise` replaces
/// `o.noise`; `source` is how the recording was read (`None` for samples given in memory).
pub fn advise_samples(
    o: &Options,
    samples: &[ImuSample],
    noise: &ImuNoise,
    source: Option<preint_io::SourceInfo>,
    unit_check: UnitCheck,
) -> Result<Advice, Error> {
    // Held input is not low-passed: the filter would smear its steps (candidates' docs).
    let (signal, cutoffs) = match o.input_class {
        InputClass::Smooth => denoise(samples, noise.gyro_noise_density, noise.acc_noise_density),
        InputClass::Held => (samples.to_vec(), [None, None]),
    };
    let candidates = evaluate_input(&signal, noise, 9.81, o.window, o.fraction, o.input_class)?;
    let recommended =
        recommend(&candidates).and_then(|r| candidates.iter().position(|c| std::ptr::eq(c, r)));
    let rates_not_evaluated = gap_note(o, &signal, &candidates);
    Ok(Advice {
        options: o.clone(),
        samples: samples.len(),
        source,
        unit_check,
        cutoffs,
        candidates,
        recommended,
        rates_not_evaluated,
    })
}

/// When decimation stopped at a gap of the recording ([`gap_beyond_limit`]): which rates were
/// not evaluated and why, naming the file, the gap and the sample after it.
pub fn gap_note(o: &Options, samples: &[ImuSample], candidates: &[Candidate]) -> Option<String> {
    let (first, last) = (samples.first()?, samples.last()?);
    let dt_s = (last.t_ns - first.t_ns) as f64 * 1e-9 / (samples.len() - 1).max(1) as f64;
    let next = 2 * candidates.iter().map(|c| c.decimation).max()?;
    if !decimation_in_range(dt_s, next, o.window) {
        return None;
    }
    let (wide, gap, at) = gap_beyond_limit(samples, next)?;
    Some(format!(
        "rates of {:.2} Hz and below are not evaluated: the recording {} has an interval of \
         {:.6} s before sample {at} (t = {} ns), which the embedded estimate at that rate (one \
         sample in {}) widens to {:.6} s, above preintegration's gap limit of {} s",
        1.0 / (dt_s * next as f64),
        o.input.label(),
        gap as f64 * 1e-9,
        samples[at].t_ns,
        2 * next,
        wide as f64 * 1e-9,
        preint::DEFAULT_MAX_GAP_NS as f64 * 1e-9
    ))
}

/// `{rot_rad, vel_m_s, pos_m}`.
fn triple(e: &[f64; 3]) -> Value {
    json!({"rot_rad": e[0], "vel_m_s": e[1], "pos_m": e[2]})
}

/// The input class, its reference and exact scheme, and every scheme's order and exactness.
fn input_class_json(input: InputClass) -> Value {
    let schemes: serde_json::Map<String, Value> = Scheme::ALL
        .iter()
        .map(|&s| {
            let e = exactness(s);
            let exact = input.exact_scheme() == Some(s);
            (
                s.name().to_string(),
                json!({"order_smooth": e.order_smooth, "exact_on": e.exact_on, "exact_for_input": exact}),
            )
        })
        .collect();
    json!({
        "input_class": input.label(),
        "reference_scheme": input.reference().name(),
        "exact_scheme": input.exact_scheme().map(Scheme::name),
        "schemes": schemes,
    })
}

/// The JSON form: the recommendation, the cutoffs and every candidate.
pub fn to_json(a: &Advice) -> Value {
    let rec = a.recommendation();
    let input = a.options.input_class;
    let rows: Vec<_> = a
        .candidates
        .iter()
        .map(|c| json!({"scheme": c.scheme.name(), "rate": c.rate_hz, "decimation": c.decimation,
            "disc_err": triple(&c.disc_err),
            "ref_dist": c.ref_dist.as_ref().map(triple),
            "embedded_err": triple(&c.embedded_err),
            "embedded_chi2": if c.embedded_chi2.is_finite() { json!(c.embedded_chi2) } else { Value::Null },
            "reference": c.is_reference(),
            "noise_sigma": triple(&c.noise_sigma),
            "cost_ns_per_s": c.cost_ns_per_s, "acceptable": c.acceptable}))
        .collect();
    let mut out = json!({
        "recommended_scheme": rec.map(|c| c.scheme.name()),
        "recommended_rate": rec.map(|c| c.rate_hz),
        "recommended_exact": rec.is_some_and(|c| input.exact_scheme() == Some(c.scheme) && c.decimation == 1),
        "fraction": a.options.fraction, "window_s": a.options.window, "samples": a.samples,
        "denoise_cutoff_hz": {"gyro": a.cutoffs[0], "acc": a.cutoffs[1]},
        "candidates": rows,
        "tangent_order": ["dphi", "dv", "dp"],
        "method": method(input),
        "calibration": a.options.calibration.as_ref().map(|p| p.display().to_string()),
        "rates_not_evaluated": a.rates_not_evaluated,
        "fit": a.fit().as_ref().map(fit_json),
        "input": a.source.as_ref().map(|s| crate::recording::input_json(s, &a.unit_check)),
    });
    if let (Value::Object(o), Value::Object(i)) = (&mut out, input_class_json(input)) {
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
