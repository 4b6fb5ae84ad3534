//! Computations the commands share, callable on their own.
//!
//! - [`advise`]: discretisation error against noise σ per scheme and rate, and the cheapest
//!   acceptable choice (`preint advise`).
//! - [`accuracy`]: error against a scene's exact deltas and cost per scheme and rate, fitted
//!   convergence order (`preint bench-steps`, the report).
//! - [`input_class`]: smooth or held input, the reference and lower rates for each, and when
//!   each scheme is exact.
//! - [`denoise`]: zero-phase low-pass separating white noise from motion.
//! - [`speed`]: throughput of each scheme on this machine.
//! - [`consistency`]: an IMU factor's residual at ground truth, whitened, with χ².
//! - [`report`]: the numbers of `preint report`.

pub mod accuracy;
pub mod advise;
pub mod consistency;
pub mod denoise;
pub mod input_class;
pub mod report;
pub mod speed;
