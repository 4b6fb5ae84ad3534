//! # preint-lie — SO(3) and SE(3) for on-manifold estimation
//!
//! Small fixed-size types with exact exp/log near θ = 0 and θ = π, and the Jacobians that
//! on-manifold preintegration and optimisation need, following Solà, Deray, Atchuthan,
//! *A micro Lie theory for state estimation in robotics* (2018, arXiv:1812.01537); equation
//! numbers in the docs refer to that paper. SE(3)'s `Q` block follows Barfoot, *State
//! Estimation for Robotics* (2017), § 7.1.5.
//!
//! - [`SO3`] (module [`so3`]): rotations as matrices, with [`hat`]/[`vee`] and the Jacobians
//!   [`jr`], [`jl`], [`jr_inv`], [`jl_inv`]; quaternion conversions (Hamilton, `w ≥ 0`).
//! - [`SE3`] (module [`se3`]): rigid transforms `x ↦ R x + t`, with `se3::jr`, `se3::jl` and
//!   their inverses.
//! - [`LieGroup`]: the operations both share, for group-generic code.
//! - [`Manifold`]: retract/local coordinates for groups, vectors and their products, as
//!   numeric differentiation and solvers need them.
//!
//! Conventions:
//! - Perturbations are on the **right**: `X ⊕ δ = X·Exp(δ)`, `Y ⊖ X = Log(X⁻¹Y)`.
//! - SO(3) tangent: rotation vector φ (rad). SE(3) tangent: `[ρ, θ]`, translation first (Solà,
//!   Barfoot, C++ Sophus; GTSAM and sophus-rs put the rotation first). Translations are in the
//!   caller's unit of length.
//! - Right Jacobian `Jr(φ)`: `Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ)δ)`; left `Jl(φ) = Jr(−φ)`.
//! - Jacobians of an operation are returned next to its value by the `*_jac` variants
//!   (`log_jac`, `compose_jac`, `act_jac`, …), each w.r.t. right perturbations of its inputs.
//!
//! ```
//! use nalgebra::Vector3;
//! use preint_lie::{SO3, jr_inv};
//!
//! // The rotation error between an estimate and a measurement, and its Jacobian with respect
//! // to a right perturbation of the estimate: r = Log(R_meas⁻¹·R), ∂r/∂δ = Jr⁻¹(r).
//! let r_est = SO3::exp(&Vector3::new(0.1, 0.2, -0.3));
//! let r_meas = SO3::exp(&Vector3::new(0.1, 0.25, -0.3));
//! let (r, j) = r_meas.inverse().compose(&r_est).log_jac();
//! assert!(r.norm() < 0.06);
//! assert_eq!(j, jr_inv(&r));
//! ```

#![deny(missing_docs)]

pub mod group;
pub mod manifold;
pub mod se3;
pub mod so3;

pub use group::LieGroup;
pub use manifold::Manifold;
pub use se3::SE3;
pub use so3::{SO3, hat, jl, jl_inv, jr, jr_inv, vee};
