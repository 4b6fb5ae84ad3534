//! # lie — SO(3) and SE(3) for on-manifold estimation
//!
//! Small fixed-size types with exact exp/log near θ = 0 and θ = π, and the Jacobians that
//! on-manifold preintegration and optimisation need, following Solà, Deray, Atchuthan,
//! *A micro Lie theory for state estimation in robotics* (2018); equation numbers in the docs
//! refer to that paper.
//!
//! Conventions:
//! - Perturbations are on the **right**: `X ⊕ δ = X·Exp(δ)`, `Y ⊖ X = Log(X⁻¹Y)`.
//! - SO(3) tangent: rotation vector φ (rad). SE(3) tangent: `[ρ, θ]`, translation first (Solà,
//!   Barfoot, C++ Sophus; GTSAM and sophus-rs put the rotation first).
//! - Right Jacobian `Jr(φ)`: `Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ)δ)`; left `Jl(φ) = Jr(−φ)`.
//! - Jacobians of an operation are returned next to its value by the `*_jac` variants
//!   (`log_jac`, `compose_jac`, `act_jac`, …), each w.r.t. right perturbations of its inputs.

pub mod group;
pub mod manifold;
pub mod se3;
pub mod so3;

pub use group::LieGroup;
pub use manifold::Manifold;
pub use se3::SE3;
pub use so3::{SO3, hat, jl, jl_inv, jr, jr_inv, vee};
