//! Subcommand implementations. Each returns an [`Output`]: a human summary and a JSON object.

use crate::{Cli, Command};
use serde_json::{Value, json};
use std::fmt::Write as _;

/// What a subcommand prints: a human summary, or (with `--json`) one JSON object.
pub struct Output {
    /// Human-readable summary (ends with a newline).
    pub human: String,
    /// Machine-readable result.
    pub json: Value,
}

/// Errors reported on stderr with a non-zero exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Reading or parsing an input file failed (the message names file and line).
    #[error(transparent)]
    Io(#[from] preint::io::IoError),
    /// A flag value is invalid.
    #[error("{0}")]
    Usage(String),
    /// The computation failed (message says why).
    #[error("{0}")]
    Failed(String),
}

/// Runs the selected subcommand.
pub fn run(cli: &Cli) -> Result<Output, CliError> {
    match &cli.command {
        Command::Integrate { .. } => integrate::run(&cli.command),
        Command::Speed { .. } => speed::run(&cli.command),
        Command::Allan { .. } => allan::run(&cli.command),
        Command::Advise { .. } => advise::run(&cli.command),
        Command::BenchSteps { .. } => bench_steps::run(&cli.command),
        Command::Simulate { .. } => simulate::run(&cli.command),
        Command::Calibrate { .. } => calibrate::run(&cli.command),
        Command::Factor { .. } => factor::run(&cli.command),
        Command::Report { .. } => report::run(&cli.command),
    }
}

pub mod advise;
pub mod allan;
pub mod bench_steps;
pub mod calibrate;
pub mod factor;
pub mod integrate;
pub mod report;
pub mod simulate;
pub mod speed;

/// A progress bar on stderr with `len` steps, or `None` when stderr is not a terminal (CI,
/// pipes, `--json` consumers see nothing extra).
pub fn progress(len: u64, what: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(len);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_prefix(what.to_string());
    Some(pb)
}

/// A 3×3 (or any) matrix as a JSON list of rows.
pub fn rows<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// A vector as a JSON list.
pub fn list(v: &nalgebra::Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// Formats a matrix for the human summary, one row per line with a left margin.
pub fn fmt_matrix<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    m: &nalgebra::Matrix<f64, R, C, S>,
    margin: &str,
) -> String {
    let mut s = String::new();
    for i in 0..m.nrows() {
        s.push_str(margin);
        for j in 0..m.ncols() {
            let _ = write!(s, "{:>13.5e}", m[(i, j)]);
        }
        s.push('\n');
    }
    s
}
