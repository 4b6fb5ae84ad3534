//! The types and functions most programs use, for a glob import:
//!
//! ```
//! use preint::prelude::*;
//! let params = PreintParams::default().with_scheme(Scheme::Hermite4).with_level(Level::Combined);
//! let pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
//! assert!(pi.is_empty());
//! ```

pub use crate::lie::SO3;
pub use crate::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, ImuSample, Level, NavState, PreintError,
    PreintParams, PreintegratedImu, Preintegrator, Scheme, merge, predict, preintegrate,
};
