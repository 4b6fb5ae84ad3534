//! `preint speed`: throughput of each scheme on this machine, with and without covariance
//! (method: [`preint_analysis::speed`]; the median of 11 runs, comparable with the criterion
//! benchmark `cargo bench -p preint`, which reports a mean over its samples).

use crate::{CliError, Output, scheme};
use preint_analysis::speed::{Throughput, throughput};
use serde_json::{Value, json};
use std::fmt::Write as _;

/// Largest `--samples`: 10⁷ samples hold 560 MB, far more than a cache-resident throughput
/// measurement needs.
const MAX_SAMPLES: usize = 10_000_000;

/// Runs per measurement; the median is reported.
const RUNS: usize = 11;

/// Flags of `preint speed`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Number of samples to integrate per measurement, 10 to 10⁷ (10⁵ is the criterion
    /// bench's stream).
    #[arg(
        help_heading = "Benchmark",
        long,
        default_value_t = 100_000,
        allow_hyphen_values = true
    )]
    pub samples: usize,
}

/// The measured throughput.
#[derive(Clone, Debug)]
pub struct Speed {
    /// Samples per run.
    pub samples: usize,
    /// One row per scheme.
    pub rows: Vec<Throughput>,
}

/// Measures every scheme at every level.
pub fn compute(args: &Args) -> Result<Speed, CliError> {
    if !(10..=MAX_SAMPLES).contains(&args.samples) {
        return Err(CliError::Usage(format!(
            "--samples must be from 10 to {MAX_SAMPLES} (each sample is 56 bytes in memory), got {}",
            args.samples
        )));
    }
    Ok(Speed {
        samples: args.samples,
        rows: throughput(args.samples, RUNS)?,
    })
}

/// The JSON form: ns/sample per scheme and level.
pub fn to_json(s: &Speed) -> Value {
    let rows: Vec<_> = s
        .rows
        .iter()
        .map(|r| {
            json!({"scheme": scheme::label(r.scheme), "ns_per_sample":
            {"deltas": r.deltas, "covariance": r.covariance, "combined": r.combined}})
        })
        .collect();
    json!({"samples": s.samples, "rate_hz": 200.0, "schemes": rows,
        "method": "median of 11 runs of Preintegrator::integrate_slice over a synthetic 200 Hz stream"})
}

/// The human summary: a table of ns/sample.
pub fn to_text(s: &Speed) -> String {
    let mut h = format!(
        "{} samples, median of {RUNS} runs, ns per sample (this machine):\n",
        s.samples
    );
    let _ = writeln!(
        h,
        "{:<10} {:>12} {:>16} {:>14}",
        "scheme", "deltas only", "+cov+bias jac", "+15x15 cov"
    );
    for r in &s.rows {
        let _ = writeln!(
            h,
            "{:<10} {:>12.1} {:>16.1} {:>14.1}",
            scheme::label(r.scheme),
            r.deltas,
            r.covariance,
            r.combined
        );
    }
    h
}

/// Runs `preint speed`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let s = compute(args)?;
    Ok(Output {
        human: to_text(&s),
        json: to_json(&s),
    })
}
