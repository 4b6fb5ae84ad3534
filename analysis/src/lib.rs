//! What the `preint` command line and the Python package compute from a recording, with the
//! result structs and their JSON: the two faces print the same numbers because they are built
//! here, once. The command line adds its flags (clap) and the human summaries; the Python
//! package its arguments and dicts.
//!
//! # Layout
//! - Reading: [`recording`] (the recording and how to read it, [`ImuInput`]; read whole with
//!   the unit checks), [`stream`] (read once in bounded memory: the unit checks on a prefix,
//!   the keyframe window, the span a solver holds), [`checks`] (option values and units),
//!   [`noise`] (noise densities), [`calibration_file`] (what `calibrate --out` writes and
//!   `--calibration` reads), [`parse`] (option values and their physical ranges).
//! - The commands both faces run, each as `Options` → `compute` → a result struct →
//!   `to_json`: [`advise`] (the cheapest scheme and lowest rate, after [`denoise`], for the
//!   [`input_class`] declared), [`allan`] (Allan deviation and noise fits), [`calibrate`]
//!   (biases, time offset, intrinsics, with the problem the data makes observable; the noise
//!   model from ground truth, [`calibrate::noise_model`]), [`audit`] (what is wrong with a
//!   recording).
//! - Other analyses: [`consistency`] (a factor's χ² at ground truth; the `fit` object),
//!   [`factor_windows`] (the IMU factor at ground truth over one window or many),
//!   [`truth_windows`] (back-to-back windows over a recording and its ground truth),
//!   [`speed`] (throughput of each scheme on this machine).
//! - Printing helpers: [`format`](mod@format) (matrices as JSON and text), [`progress`] (bars
//!   on stderr, at a terminal only).
//!
//! Errors are [`Error`]: a reader's (naming file and line), an invalid option (naming its
//! flag), or a computation that cannot answer (saying why).
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

pub mod advise;
pub mod allan;
pub mod audit;
pub mod calibrate;
pub mod calibration_file;
pub mod checks;
pub mod chi2_windows;
pub mod consistency;
pub mod denoise;
pub mod error;
pub mod factor_windows;
pub mod format;
pub mod initialise;
pub mod input_class;
pub mod noise;
pub mod noise_windows;
pub mod parse;
pub mod progress;
pub mod recording;
pub mod speed;
pub mod stream;
pub mod truth_windows;

pub use error::Error;
pub use recording::ImuInput;
