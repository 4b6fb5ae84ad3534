//! `preint`: the command line of the on-manifold IMU preintegration project.
//!
//! Parses the command line and dispatches to [`preint_cli::run`]. Every subcommand prints a
//! human summary, or one JSON object on stdout with `--json`. Errors go to stderr with exit
//! code 2 and name the file, line and problem.
//!
//! A reader that closes the pipe early (`preint integrate … | head -1`) has taken what it
//! wanted: the printing stops there, with no message, and the exit status is the command's
//! own (0 on success), as `git` and `ripgrep` do. Rust ignores SIGPIPE, so the write returns
//! `BrokenPipe` instead of killing the process; clap's help and usage output swallows it the
//! same way. Any other failure to write stdout is an error (exit 2).

use clap::Parser;
use preint_cli::{Cli, CliError, Output};
use std::io::{ErrorKind, Write};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let (output, error) = match preint_cli::run(&cli.command) {
        Ok(out) => (Some(out), None),
        Err(CliError::Refused { output, msg }) => (Some(*output), Some(msg)),
        Err(e) => (None, Some(e.to_string())),
    };
    let mut status = if error.is_some() { 2 } else { 0 };
    if let Some(out) = &output {
        match print(out, cli.json) {
            Err(e) if e.kind() != ErrorKind::BrokenPipe => {
                report(&format!("writing the output: {e}"));
                status = 2;
            }
            _ => {}
        }
    }
    if let Some(msg) = error {
        report(&msg);
    }
    ExitCode::from(status)
}

/// Prints the output on stdout: the JSON object with `--json`, else the human summary.
fn print(out: &Output, json: bool) -> std::io::Result<()> {
    let mut stdout = std::io::stdout().lock();
    if json {
        writeln!(stdout, "{}", out.json)?;
    } else {
        stdout.write_all(out.human.as_bytes())?;
    }
    stdout.flush()
}

/// Writes `preint: error: MSG` on stderr (nothing if stderr itself is closed).
fn report(msg: &str) {
    let _ = writeln!(std::io::stderr(), "preint: error: {msg}");
}
