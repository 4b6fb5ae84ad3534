//! Typed errors of the preintegrator: every variant names the offending sample (its index in
//! the order samples were given, and its timestamp) or parameter, and the problem.

use crate::sample::ImuBias;
use thiserror::Error;

/// Why a preintegration input was rejected. Sample indices count from 0 in the order the
/// samples were passed to the preintegrator (or in the slice given to
/// [`preintegrate`](crate::window::preintegrate)); timestamps are in ns.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PreintError {
    /// A gyro or accelerometer component is NaN or infinite.
    #[error("sample {index} (t = {t_ns} ns): non-finite {field} value")]
    NonFinite {
        /// Sample index.
        index: usize,
        /// Sample timestamp \[ns\].
        t_ns: i64,
        /// `"gyro"` or `"acc"`.
        field: &'static str,
    },
    /// A timestamp equals the previous one (Δt = 0).
    #[error("sample {index} (t = {t_ns} ns): duplicate timestamp (Δt = 0)")]
    DuplicateTimestamp {
        /// Sample index.
        index: usize,
        /// Sample timestamp \[ns\].
        t_ns: i64,
    },
    /// A timestamp is earlier than the previous one (Δt < 0).
    #[error("sample {index} (t = {t_ns} ns): timestamp decreases (previous {prev_t_ns} ns, Δt = {} ns)", t_ns - prev_t_ns)]
    DecreasingTimestamp {
        /// Sample index.
        index: usize,
        /// Sample timestamp \[ns\].
        t_ns: i64,
        /// Previous sample timestamp \[ns\].
        prev_t_ns: i64,
    },
    /// The gap to the previous sample exceeds `PreintParams::max_gap_ns`.
    #[error(
        "sample {index} (t = {t_ns} ns): gap of {gap_ns} ns to the previous sample exceeds the maximum {max_gap_ns} ns"
    )]
    GapTooLarge {
        /// Sample index.
        index: usize,
        /// Sample timestamp \[ns\].
        t_ns: i64,
        /// Gap to the previous sample \[ns\].
        gap_ns: i64,
        /// Configured maximum \[ns\].
        max_gap_ns: i64,
    },
    /// The window holds fewer than two samples (no interval to integrate).
    #[error("window has {count} sample(s); at least 2 are needed (N samples make N−1 intervals)")]
    TooFewSamples {
        /// Number of samples in the window.
        count: usize,
    },
    /// The keyframe interval `[t_i, t_j]` is empty or reversed (Δt ≤ 0).
    #[error("keyframe window [{t_i_ns}, {t_j_ns}] ns has non-positive duration")]
    NonPositiveWindow {
        /// Keyframe i time \[ns\].
        t_i_ns: i64,
        /// Keyframe j time \[ns\].
        t_j_ns: i64,
    },
    /// A keyframe time lies outside the time span of the given samples.
    #[error("keyframe time {t_ns} ns is outside the samples [{first_ns}, {last_ns}] ns")]
    KeyframeOutsideSamples {
        /// Keyframe time \[ns\].
        t_ns: i64,
        /// First sample time \[ns\] (`i64::MAX` if there are none).
        first_ns: i64,
        /// Last sample time \[ns\] (`i64::MIN` if there are none).
        last_ns: i64,
    },
    /// Re-integration was asked for, but `PreintParams::keep_samples` is off so the samples
    /// were not stored.
    #[error(
        "cannot re-integrate: keep_samples is off, so the {count} integrated sample(s) were not stored"
    )]
    SamplesNotKept {
        /// Number of samples integrated (and not stored).
        count: usize,
    },
    /// The measurement came out non-finite from finite inputs: some input is of an extreme
    /// magnitude (a bias estimate or reading of 1e300, a sample interval of centuries).
    #[error(
        "the preintegration gave non-finite {what}: an input is of extreme magnitude (bias \
         estimate, readings or sample interval)"
    )]
    NonFiniteResult {
        /// `"deltas"`, `"covariance"` or `"bias Jacobians"`.
        what: &'static str,
    },
    /// A query time of [`crate::deskew`] lies outside the keyframe window `[t_i, t_j]`.
    #[error("query {index} (t = {t_ns} ns) is outside the window [{t_i_ns}, {t_j_ns}] ns")]
    QueryOutsideWindow {
        /// Query index (in the order given).
        index: usize,
        /// Query time \[ns\].
        t_ns: i64,
        /// Keyframe i time \[ns\].
        t_i_ns: i64,
        /// Keyframe j time \[ns\].
        t_j_ns: i64,
    },
    /// The query times of [`crate::deskew`] decrease (they must be non-decreasing).
    #[error("query {index} (t = {t_ns} ns) is earlier than the previous query ({prev_t_ns} ns)")]
    QueryNotSorted {
        /// Query index (in the order given).
        index: usize,
        /// Query time \[ns\].
        t_ns: i64,
        /// Previous query time \[ns\].
        prev_t_ns: i64,
    },
    /// A point given to [`crate::deskew::deskew_points`] has a NaN or infinite coordinate.
    #[error("point {index} (t = {t_ns} ns): non-finite coordinate")]
    NonFinitePoint {
        /// Point index (in the order given).
        index: usize,
        /// Point time \[ns\].
        t_ns: i64,
    },
    /// A bias other than the measurement's `bias_hat` was given to a measurement preintegrated
    /// at [`Level::Deltas`](crate::Level::Deltas), which has no bias Jacobians to correct its
    /// deltas with ([`PreintegratedImu::check_bias`](crate::PreintegratedImu::check_bias)).
    #[error(
        "this measurement was preintegrated at level deltas, without bias Jacobians: it cannot \
         be corrected to bias {} (it was integrated at {}); preintegrate at level covariance \
         or combined, or re-preintegrate at the new bias",
        show_bias(.bias),
        show_bias(.bias_hat)
    )]
    NoBiasJacobians {
        /// The bias asked for (gyro [rad/s], accelerometer [m/s²]).
        bias: ImuBias,
        /// The bias the measurement was integrated with.
        bias_hat: ImuBias,
    },
    /// A parameter is invalid (non-finite, negative variance, non-positive threshold…).
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// Field name in [`PreintParams`](crate::params::PreintParams).
        name: &'static str,
        /// What is wrong with it.
        reason: &'static str,
    },
}

/// `b` as `gyro [x, y, z] rad/s, acc [x, y, z] m/s²` (shortest round-trip numbers).
fn show_bias(b: &ImuBias) -> String {
    let (g, a) = (&b.gyro, &b.acc);
    format!(
        "gyro [{:?}, {:?}, {:?}] rad/s, acc [{:?}, {:?}, {:?}] m/s²",
        g.x, g.y, g.z, a.x, a.y, a.z
    )
}
