//! `preint`: the command line of the on-manifold IMU preintegration project.
//!
//! Parses the command line and dispatches to [`preint_cli::run`]. Every subcommand prints a
//! human summary, or one JSON object on stdout with `--json`. Errors go to stderr with exit
//! code 2 and name the file, line and problem.

use clap::Parser;
use preint_cli::Cli;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let print = |out: &preint_cli::Output| {
        if cli.json {
            println!("{}", out.json);
        } else {
            print!("{}", out.human);
        }
    };
    match preint_cli::run(&cli.command) {
        Ok(out) => {
            print(&out);
            ExitCode::SUCCESS
        }
        Err(e) => {
            if let preint_cli::CliError::Refused { output, .. } = &e {
                print(output);
            }
            eprintln!("preint: error: {e}");
            ExitCode::from(2)
        }
    }
}
