//! One module per subcommand. Each has its flags (`Args`), `compute` (the numbers, as a
//! struct), `to_json` and `to_text` (the two printed forms) and `run` (all three, as an
//! [`Output`]). Commands do not call each other: what two of them share lives in
//! [`crate::analysis`] or the helper modules.

use crate::{CliError, Command, Output};

pub mod advise;
pub mod allan;
pub mod audit;
pub mod bench_steps;
pub mod calibrate;
pub mod convert;
pub mod factor;
pub mod initialise;
pub mod integrate;
pub mod report;
pub mod simulate;
pub mod speed;

/// Runs the selected subcommand. Nothing non-finite leaves it: an output whose summary holds
/// `inf` or `NaN` is refused (`finite`), the inputs' own checks naming the cause first.
pub fn run(command: &Command) -> Result<Output, CliError> {
    match dispatch(command) {
        Ok(out) => finite(out),
        Err(CliError::Refused { output, msg }) => match finite(*output) {
            Ok(output) => Err(CliError::Refused {
                output: Box::new(output),
                msg,
            }),
            Err(e) => Err(e),
        },
        Err(e) => Err(e),
    }
}

/// `out`, or an error naming the line of its summary that holds a non-finite number (the
/// JSON form of the same number would be `null`).
fn finite(out: Output) -> Result<Output, CliError> {
    match preint_io::error::non_finite_line(&out.human) {
        None => Ok(out),
        Some((line, text)) => Err(CliError::Failed(format!(
            "the result holds a non-finite number (line {line} of the summary: `{text}`), so it \
             is not printed: the inputs are outside what the method can handle (check the \
             values of the flags and files given), or this is a bug to report with the command \
             line"
        ))),
    }
}

/// The selected subcommand's own run.
fn dispatch(command: &Command) -> Result<Output, CliError> {
    match command {
        Command::Simulate(a) => simulate::run(a),
        Command::Integrate(a) => integrate::run(a),
        Command::Factor(a) => factor::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Initialise(a) => initialise::run(a),
        Command::Allan(a) => allan::run(a),
        Command::BenchSteps(a) => bench_steps::run(a),
        Command::Advise(a) => advise::run(a),
        Command::Speed(a) => speed::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Audit(a) => audit::run(a),
        Command::Report(a) => report::run(a),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// An output whose summary holds a non-finite number is refused, naming the line; words
    /// that contain `inf` (`info`) are not numbers.
    #[test]
    fn a_non_finite_summary_is_refused() {
        let out = |human: &str| Output {
            human: human.to_string(),
            json: json!({}),
        };
        let e = finite(out("ok\np = [1, -inf] m\n"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 2 of the summary") && e.contains("-inf"),
            "{e}"
        );
        assert!(finite(out("σ NaN\n")).is_err());
        assert!(finite(out("info: inferred, 1e308\n")).is_ok());
    }
}
