//! # preint — on-manifold IMU preintegration
//!
//! The gyroscope and accelerometer samples between two keyframes become one relative-motion
//! measurement (ΔR, Δv, Δp) with its covariance and bias Jacobians ([`PreintegratedImu`]), and
//! the IMU factors a back end optimises ([`ImuFactor`], [`CombinedImuFactor`]); Forster,
//! Carlone, Dellaert, Scaramuzza, T-RO 2017.
//!
//! - Parameters and inputs: [`PreintParams`] (noise densities, [`Scheme`], [`Level`]),
//!   [`ImuSample`], [`ImuBias`], [`ImuNoise`].
//! - Preintegration: [`preintegrate`] (a keyframe window of a stream, boundary samples
//!   interpolated) or a [`Preintegrator`] fed sample by sample; [`merge()`] of consecutive
//!   windows; [`Preintegrator::measurement_for_bias`] for a new bias estimate.
//! - Inside a window: [`deskew`] (the deltas and predicted state at any time between the
//!   keyframes, one pass over the samples; lidar points deskewed).
//! - The measurement: [`PreintegratedImu`] (its `cov`, `cov15`, `residual_cov15()` and bias
//!   Jacobians), [`predict`] and [`NavState`]; [`try_predict`] and
//!   [`PreintegratedImu::try_corrected`] refuse a bias a [`Level::Deltas`] measurement (no
//!   bias Jacobians) cannot be corrected to.
//! - Factors: [`ImuFactor`], [`CombinedImuFactor`] (residual, analytic Jacobians, whitening).
//! - Time offset: [`time_offset`] (`t_imu = t_cam + t_d`): the deltas' derivative
//!   [`PreintegratedImu::jac_td`], the first-order correction, re-integration above a
//!   threshold, and `evaluate_with_time_offset` on both factors.
//! - Earth rotation: [`earth`] (`PreintParams::omega_coriolis`, [`CoriolisMode`]): a world frame
//!   rotating at a constant rate in prediction and both factors.
//! - An IMU away from the body origin: [`SensorPose`], [`LeverArm`]; IMU intrinsics:
//!   [`intrinsics`]; a window's own discretisation error: [`truncation`].
//! - Schemes: [`Scheme`] (the mathematics of each) and its registry row [`SchemeInfo`].
//! - [`prelude`]: the types and functions most programs use. Every public type has one path:
//!   the types are here, the functions of a subject in its module.
//!
//! Reading and writing files is the `preint-io` crate's job; this crate does no I/O.
//!
//! Conventions: world frame z up, gravity `g = (0, 0, −9.81)` m/s² by default; the
//! accelerometer measures specific force; rotations are perturbed on the right
//! (`R ← R Exp(δφ)`); preintegrated tangent order **[δφ, δv, δp]**, bias order
//! **[b_g, b_a]**; timestamps integer nanoseconds; noise as continuous-time densities.

#![deny(missing_docs)]

mod bias_correction;
mod choices;
pub mod deskew;
pub mod earth;
pub mod edges;
mod error;
mod extrinsics;
mod factor;
mod fast;
pub mod intrinsics;
mod measurement;
mod merge;
mod navstate;
mod noise;
mod params;
mod preintegrator;
pub mod prelude;
mod propagation;
mod sample;
mod scheme;
pub mod second_order;
pub mod time_offset;
pub mod truncation;
mod validation;
mod window;

pub use choices::{BiasCorrection, CoriolisMode, Level, LeverArm};
pub use error::PreintError;
pub use factor::{
    CombinedImuFactor, CombinedImuFactorJacobians, FactorError, FactorJacobians, ImuFactor,
    ImuFactorJacobians, ResidualMode, sqrt_information,
};
pub use measurement::{BiasJacobians, Cov9, Cov15, PreintegratedImu};
pub use merge::{MergeError, merge};
pub use navstate::{NavState, NavTangent, predict, try_predict};
pub use noise::{CellRule, ImuNoise};
pub use params::{
    DEFAULT_MAX_GAP_NS, DEFAULT_REINTEGRATE_ACC, DEFAULT_REINTEGRATE_GYRO,
    DEFAULT_REINTEGRATE_TIME_OFFSET, PreintParams, SensorPose,
};
pub use preintegrator::{BiasUpdate, Preintegrator};
pub use sample::{ImuBias, ImuSample, dt_seconds};
pub use scheme::{Scheme, SchemeInfo, TruncationCompanion};
pub use window::{
    check_samples, preintegrate, preintegrate_with_intrinsic_jacobian, window_samples,
};

/// The linear algebra of every public type (vectors, matrices).
pub use nalgebra;
/// SO(3) and SE(3): the `ΔR` of a measurement is a [`lie::SO3`].
pub use preint_lie as lie;

/// The README's code blocks, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;

/// The crate's own README (its crates.io page), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct CrateReadmeDoctests;
