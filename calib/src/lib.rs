//! # preint-calib — IMU calibration, and the optimiser it uses
//!
//! Calibration and noise identification for an IMU, built on the `preint` preintegration
//! crate: static, multi-position and known-pose bias estimation with model selection, the
//! overlapping Allan deviation with Kalibr-style noise figures, and the tools these estimators
//! are made of — a dense on-manifold Gauss-Newton / Levenberg-Marquardt solver with rank
//! analysis, Ceres-style numeric differentiation and a Jacobian checker.
//!
//! # Module map
//! - [`bias`]: bias estimation problems.
//!   - [`bias::static_bias`]: one static attitude → gyro bias, roll and pitch
//!     ([`calibrate_static`]).
//!   - [`bias::multipose`]: several static attitudes linked by gyro preintegration (Tedaldi et
//!     al., ICRA 2014) → biases, optional scale factors and misalignments chosen by BIC, the bias
//!     random walk marginalised ([`calibrate_multi_pose`]).
//!   - [`bias::known_poses`]: known, optionally noisy poses → biases, velocities and gravity
//!     direction from preintegration factors (Forster et al., T-RO 2017)
//!     ([`calibrate_known_poses`]).
//!   - [`bias::still`]: still-interval detection ([`detect_still_intervals`]).
//! - [`allan`]: overlapping Allan deviation (IEEE Std 952-1997) and the white-noise, random-walk
//!   and bias-instability fits ([`allan::ImuAllan`], Kalibr `imu.yaml`).
//! - [`fit`]: the goodness of fit of an estimate, its χ² against `χ²_dof` ([`Fit`]: credible
//!   or not, and why), and the standard deviations scaled by `√(χ²/dof)`.
//! - [`gauss_newton`]: the solver every estimator uses ([`solve`], [`LeastSquares`],
//!   [`GaussNewton`]), run by argmin's executor; covariance and unobservable directions of the
//!   estimate ([`Solution`]).
//! - [`noise_fit`]: maximum-likelihood noise densities, bias random walks and ground-truth
//!   errors from IMU factor residuals at known states (Fisher scoring, [`noise_fit::fit`]).
//! - [`numdiff`]: forward, central and Ridders differentiation of any `Fn(&X) -> Y` between
//!   [`preint_lie::Manifold`]s (Ceres `NumericDiffCostFunction` semantics).
//! - [`checker`]: analytic Jacobian blocks against Ridders' numeric Jacobian (in the spirit of
//!   Ceres' `GradientChecker`).
//!
//! # Conventions
//! Perturbations on the right, `X ⊕ δ = X·Exp(δ)`, and Jacobians w.r.t. those tangents (the
//! [`preint_lie`] conventions); world z up, gravity `(0, 0, −9.81)` m/s² by default; bias order
//! **[b_g, b_a]**; integer-nanosecond timestamps; noise densities in Kalibr units (gyro
//! rad/s/√Hz and rad/s²/√Hz, accelerometer m/s²/√Hz and m/s³/√Hz, [`preint::ImuNoise`]). Every
//! estimate comes with a standard deviation predicted from the noise densities and a χ² to
//! check them.

#![deny(missing_docs)]

pub mod allan;
pub mod bias;
pub mod checker;
pub mod fit;
pub mod gauss_newton;
pub mod init;
pub mod noise_fit;
pub mod numdiff;

pub use bias::{
    AccBiasPrior, BiasError, KnownPose, KnownPoseCalibration, KnownPoseOptions, ModelFit,
    MultiPoseCalibration, MultiPoseModel, MultiPoseOptions, StaticCalibration, StaticOptions,
    StillInterval, StillOptions, calibrate_known_poses, calibrate_multi_pose, calibrate_static,
    detect_still_intervals,
};
pub use checker::{CheckError, CheckOptions, CheckReport, check_jacobian, to_dmatrix};
pub use fit::Fit;
pub use gauss_newton::{
    Damping, GaussNewton, GnError, GnState, LeastSquares, NumericLeastSquares, Solution,
    StopReason, finish, solve,
};
pub use numdiff::{Method, NumDiffError, NumDiffOptions, RiddersJacobian, jacobian, ridders};
