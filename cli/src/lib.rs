//! The `preint` command line. The library exposes what the binary (`src/main.rs`) and the
//! command-line tests need: the parsed command line ([`Cli`], [`Command`]), [`run`] and what it
//! returns ([`Output`], [`CliError`]). The computations on recordings, their result structs
//! and their JSON are `preint_analysis`, which the Python package uses too; this crate adds the
//! flags, the human summaries, the charts and the report.
//!
//! # Layout (private modules)
//! - `cli`: the parsed command line ([`Cli`], [`Command`]).
//! - `commands`: one module per subcommand. Each holds its flags (`Args`, a [`clap::Args`],
//!   which converts into the library's `Options` where the library computes), a `compute` that
//!   returns the numbers as a struct, `to_json` and `to_text` that print them, and `run` =
//!   compute, then both prints, as an [`Output`].
//! - `analysis`: the computations on the built-in scenes: accuracy against cost and the
//!   report's figures.
//! - `charts` and `html`: SVG charts and the self-contained HTML page.
//! - Shared helpers: `scheme` (the `--scheme` values), `imu_args` (the reader flags, into
//!   `preint_analysis::ImuInput`), `preint_args` and `earth_args` (preintegration and
//!   Earth-rotation flags), `fit` (the goodness of fit in text and `--strict`), `input`
//!   (ground-truth rows, scenes).
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

mod analysis;
mod charts;
mod cli;
mod commands;
mod earth_args;
mod error;
mod fit;
mod html;
mod imu_args;
mod input;
mod preint_args;
mod scheme;

pub use cli::{Cli, Command};
pub use commands::run;
pub use error::{CliError, Output};
