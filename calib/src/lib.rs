//! # solver — numeric differentiation, Jacobian checking, on-manifold Gauss-Newton, Allan variance
//!
//! - [`numdiff`]: forward, central and Ridders differentiation of any `Fn(&X) -> Y` between
//!   [`preint_lie::Manifold`]s (Ceres `NumericDiffCostFunction` semantics).
//! - [`checker`]: a Ceres `GradientChecker`-like comparison of analytic Jacobian blocks with
//!   Ridders' numeric Jacobian.
//! - [`gauss_newton`]: dense Gauss-Newton / Levenberg-Marquardt over manifolds with rank
//!   analysis, run by argmin's `Executor`.
//! - [`allan`]: overlapping Allan deviation and noise-parameter fits (Kalibr `imu.yaml`).
//! - [`bias`]: bias estimation (static, multi-pose with BIC model selection, known poses) and
//!   still-interval detection.
//!
//! Conventions (see `docs/ARCHITECTURE.md`): perturbations on the right, `X ⊕ δ = X·Exp(δ)`;
//! Jacobians are w.r.t. those tangents; noise densities in Kalibr units.

pub mod allan;
pub mod checker;
pub mod gauss_newton;
pub mod numdiff;

pub use checker::{CheckError, CheckOptions, CheckReport, check_jacobian, to_dmatrix};
pub use gauss_newton::{
    Damping, GaussNewton, GnError, GnState, LeastSquares, NumericLeastSquares, Solution,
    StopReason, finish, solve,
};
pub use numdiff::{Method, NumDiffError, NumDiffOptions, RiddersJacobian, jacobian, ridders};

pub mod bias;
pub use bias::{
    AccBiasPrior, BiasError, KnownPose, KnownPoseCalibration, KnownPoseOptions, ModelFit,
    MultiPoseCalibration, MultiPoseModel, MultiPoseOptions, StaticCalibration, StaticOptions,
    StillInterval, StillOptions, calibrate_known_poses, calibrate_multi_pose, calibrate_static,
    detect_still_intervals,
};
