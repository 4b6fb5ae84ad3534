//! The library behind the `preint` command line: each subcommand's flags, computation and
//! printed forms, and the analyses they run, callable without the binary.
//!
//! # Layout
//! - [`cli`]: the parsed command line ([`Cli`], [`Command`]).
//! - [`commands`]: one module per subcommand. Each holds its flags (`Args`, a
//!   [`clap::Args`]), a `compute` that returns the numbers as a struct, `to_json` and `to_text`
//!   that print them, and `run` = compute, then both prints, as an [`Output`].
//! - [`analysis`]: the computations on the built-in scenes: accuracy against cost and the
//!   report's figures. What is computed from a recording (reading with the unit checks, the
//!   scheme/rate advice, denoising, throughput, the factor's χ² at ground truth, the
//!   calibration file) is `preint_analysis`, shared with the Python package.
//! - [`charts`] and [`html`]: SVG charts and the self-contained HTML page.
//! - Shared helpers: [`scheme`] (the `--scheme` values), [`imu_args`] (the reader flags),
//!   [`preint_args`] and [`earth_args`] (preintegration and Earth-rotation flags), [`fit`] (the
//!   goodness of fit in text and `--strict`), [`input`] (ground-truth rows, scenes).
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
pub mod charts;
pub mod cli;
pub mod commands;
pub mod earth_args;
pub mod error;
pub mod fit;
pub mod html;
pub mod imu_args;
pub mod input;
pub mod preint_args;
pub mod scheme;

pub use cli::{Cli, Command};
pub use commands::run;
pub use error::{CliError, Output};
