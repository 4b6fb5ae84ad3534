//! # preint — on-manifold IMU preintegration
//!
//! Conventions (see `docs/ARCHITECTURE.md`): world frame z up, gravity `g = (0, 0, −9.81)` by
//! default; the accelerometer measures specific force; rotation perturbations on the right;
//! preintegrated tangent order **[δφ, δv, δp]**, bias order **[b_g, b_a]**; integer-ns times.

#![deny(missing_docs)]

pub mod factor;
pub mod io;
pub mod measurement;
pub mod merge;
pub mod navstate;
pub mod noise;
pub mod sample;

pub use measurement::{
    BiasJacobians, Cov9, Cov15, EdgeNoise, EdgeSource, PreintegratedImu, negate_delta_bias_blocks,
};
pub use noise::{CellRule, ImuNoise};
pub use sample::{ImuBias, ImuSample, dt_seconds};

pub mod error;
pub(crate) mod fast;
pub mod params;
pub mod preintegrator;
pub(crate) mod propagation;
pub mod scheme;
pub mod window;

pub use error::PreintError;
pub use factor::{CombinedImuFactor, FactorError, ImuFactor};
pub use merge::{MergeError, merge};
pub use navstate::{NavState, predict};
pub use params::{Level, PreintParams, Scheme};
pub use preintegrator::{BiasUpdate, Preintegrator};
pub use window::preintegrate;

pub use factor::{CombinedImuFactorJacobians, FactorJacobians, ImuFactorJacobians};
/// The linear algebra of every public type (vectors, matrices).
pub use nalgebra;
pub use navstate::NavTangent;
/// SO(3) and SE(3): the `ΔR` of a measurement is a [`SO3`].
pub use preint_lie as lie;
pub use preint_lie::SO3;

/// The README's code blocks, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
