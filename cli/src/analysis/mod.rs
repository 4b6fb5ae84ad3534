//! Computations of the commands that run on the built-in scenes (the analyses of recordings
//! are in `preint_analysis`), and the report's gathering of them.
//!
//! - [`accuracy`]: error against a scene's exact deltas and cost per scheme and rate, fitted
//!   convergence order (`preint bench-steps`, the report).
//! - [`report`]: the numbers of `preint report`.
//! - [`recording`]: the numbers of `preint report --imu`, gathered from the analyses of
//!   `preint_analysis` on the user's recording.

pub mod accuracy;
pub mod recording;
pub mod report;
