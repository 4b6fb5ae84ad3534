//! The library behind the `preint` command line: each subcommand's flags, computation and
//! printed forms, and the analyses they run, callable without the binary.
//!
//! # Layout
//! - [`cli`]: the parsed command line ([`Cli`], [`Command`]).
//! - [`commands`]: one module per subcommand. Each holds its flags (`Args`, a
//!   [`clap::Args`]), a `compute` that returns the numbers as a struct, `to_json` and `to_text`
//!   that print them, and `run` = compute, then both prints, as an [`Output`].
//! - [`analysis`]: the computations that are more than a call into the `preint` or
//!   `preint-calib` crates: the scheme/rate advice, accuracy against cost, zero-phase
//!   denoising, throughput measurement, the factor's χ² at ground truth, and the report's
//!   figures.
//! - [`charts`] and [`html`]: SVG charts and the self-contained HTML page.
//! - Shared helpers: [`scheme`] (the `--scheme` values), [`noise`] (noise densities),
//!   [`checks`] (flag values and units), [`format`](mod@format) (matrices as JSON and text), [`parse`]
//!   (flag value parsers), [`progress`].
//!
//! # Conventions
//! World frame z up, gravity `(0, 0, −G)` with `G = 9.81 m/s²` unless a `gravity` argument says
//! otherwise; the accelerometer measures specific force (`+G` on the up axis at rest);
//! rotations are perturbed on the right (`R ← R Exp(δφ)`); preintegration tangent order
//! `[δφ, δv, δp]`; bias order `[b_g, b_a]`; timestamps integer nanoseconds. SI units
//! throughout: rad, rad/s, m/s², m/s, m, s; noise densities are continuous-time
//! (rad/s/√Hz, m/s²/√Hz; random walks rad/s²/√Hz, m/s³/√Hz).

#![deny(missing_docs)]
// Channel loops index several parallel arrays (axes, curves, fits) by the same index.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod calibration_file;
pub mod charts;
pub mod checks;
pub mod cli;
pub mod commands;
pub mod earth_args;
pub mod error;
pub mod format;
pub mod html;
pub mod imu_args;
pub mod input;
pub mod noise;
pub mod parse;
pub mod preint_args;
pub mod progress;
pub mod scheme;
pub mod stream;

pub use cli::{Cli, Command};
pub use commands::run;
pub use error::{CliError, Output};
