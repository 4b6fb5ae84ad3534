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
pub mod integrate;
pub mod report;
pub mod simulate;
pub mod speed;

/// Runs the selected subcommand.
pub fn run(command: &Command) -> Result<Output, CliError> {
    match command {
        Command::Simulate(a) => simulate::run(a),
        Command::Integrate(a) => integrate::run(a),
        Command::Factor(a) => factor::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Allan(a) => allan::run(a),
        Command::BenchSteps(a) => bench_steps::run(a),
        Command::Advise(a) => advise::run(a),
        Command::Speed(a) => speed::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Audit(a) => audit::run(a),
        Command::Report(a) => report::run(a),
    }
}
