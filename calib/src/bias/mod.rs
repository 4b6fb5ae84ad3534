//! Bias estimation problems, each modelling no more than its data can support.
//!
//! - [`still`]: still-interval detection by moving variance (multi-position protocol).
//! - [`static_bias`]: one static attitude → gyro bias and gravity direction (roll, pitch); the
//!   accelerometer bias is reported unobservable unless a prior is given.
//! - [`multipose`]: several static attitudes linked by gyro preintegration (Tedaldi, Pretto,
//!   Menegatti, ICRA 2014; imu_tk) → gyro and accelerometer bias, attitude of each still
//!   interval, optional scale factors and misalignments (accelerometer lower-triangular, gyro
//!   full), the model chosen by BIC among the identifiable, converged candidates; the bias
//!   random walk is marginalised (its covariance, which correlates intervals and links, whitens
//!   the stacked residual), so the biases are those at a reference time and no parameter is
//!   added.
//! - [`known_poses`]: segments with known, optionally noisy poses → biases, velocities and
//!   gravity direction from preintegration factors (ORB-SLAM3 inertial-only initialisation,
//!   VINS-Mono gyro bias), the pose noise propagated into every residual block with the
//!   correlation between factors that share a pose.
//!
//! - [`earth_rate`]: the Earth rate in a static recording (its vertical part removed, its
//!   horizontal part removed with a heading or else carried in the bias σ).
//!
//! Shared pieces: [`SegmentStats`] (means and variances of a run of samples) and the tilt
//! geometry [`roll_pitch_of_up`], [`attitude_from_roll_pitch`].
//!
//! # Conventions
//! World z up, gravity `g = (0, 0, −9.81)` m/s² by default; the accelerometer measures specific
//! force `a_m = R_wbᵀ(a_w − g) + b_a + n_a` (so at rest `a_m = R_wbᵀ(−g) + b_a`, +9.81 on the up
//! axis; [`multipose`] adds the scale/misalignment matrices `S_a`, `S_g`); gyro
//! `ω_m = ω_b + b_g + n_g`; rotation perturbations on the right `R ← R·Exp(δφ)`; bias order
//! **[b_g, b_a]**; integer-nanosecond time.
//! Noise figures are Kalibr densities ([`preint::ImuNoise`]): a mean of white noise of density σ
//! over `T` seconds has standard deviation `σ/√T`.
//!
//! Every estimate comes with a standard deviation from the solver covariance `(JᵀJ)⁻¹` of the
//! whitened problem, i.e. predicted from the noise densities (not rescaled by the residuals),
//! so it is wrong if the densities are; each result also reports `chi2` so that this can be
//! checked (`chi2/dof ≈ 1` when the densities are right).

pub mod earth_rate;
pub mod known_poses;
pub mod multipose;
pub mod static_bias;
pub mod still;

mod stats;
mod tilt;
pub(crate) mod validate;

use crate::gauss_newton::GnError;
use preint::PreintError;

pub use earth_rate::{EarthRateInBody, earth_rate_in_body, remove_earth_rate};
pub use known_poses::{
    BiasPrior, KnownPose, KnownPoseCalibration, KnownPoseOptions, calibrate_known_poses,
};
pub use multipose::{
    ModelFit, MultiPoseCalibration, MultiPoseModel, MultiPoseOptions, calibrate_multi_pose,
};
pub use static_bias::{AccBiasPrior, StaticCalibration, StaticOptions, calibrate_static};
pub use stats::SegmentStats;
pub use still::{StillInterval, StillOptions, detect_still_intervals};
pub use tilt::{attitude_from_roll_pitch, roll_pitch_of_up};

/// Errors of the bias-estimation problems. Each names the input at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BiasError {
    /// Not enough samples (or still intervals, poses) for the problem.
    #[error("too few {what}: {found}, need at least {needed}")]
    TooFew {
        /// What is counted (`"samples"`, `"still intervals"`, `"poses"`).
        what: &'static str,
        /// How many were given / found.
        found: usize,
        /// How many are needed.
        needed: usize,
    },
    /// A sample holds NaN or ∞.
    #[error("sample {index} (t = {t_ns} ns): non-finite value")]
    NonFinite {
        /// Sample index.
        index: usize,
        /// Its timestamp \[ns\].
        t_ns: i64,
    },
    /// Timestamps are not strictly increasing.
    #[error("sample {index} (t = {t_ns} ns): timestamp not after the previous one")]
    NotIncreasing {
        /// Sample index.
        index: usize,
        /// Its timestamp \[ns\].
        t_ns: i64,
    },
    /// A noise density or option is out of its domain.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The preintegration of a window failed.
    #[error("preintegration: {0}")]
    Preint(#[from] PreintError),
    /// The Gauss-Newton solver failed.
    #[error("solver: {0}")]
    Solver(#[from] GnError),
}
