//! Computations of the commands that run on the built-in scenes (the analyses of recordings
//! are in `preint_analysis`).
//!
//! - [`accuracy`]: error against a scene's exact deltas and cost per scheme and rate, fitted
//!   convergence order (`preint bench-steps`, the report).
//! - [`report`]: the numbers of `preint report`.

pub mod accuracy;
pub mod report;
