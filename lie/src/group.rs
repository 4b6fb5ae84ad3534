//! The operations every Lie group of this crate has, as one trait, so that code (and the test
//! suite) can be written once for SO(3) and SE(3), as manif's `LieGroupBase` allows in C++.
//!
//! The trait only forwards to the inherent methods and free functions of each group
//! ([`SO3::exp`], [`crate::so3::jr`], [`SE3::log_jac`], …), which stay the primary API and
//! carry the documentation of their formulas; calling through the trait costs nothing extra.
//!
//! Conventions (Solà, Deray, Atchuthan 2018, "A micro Lie theory for state estimation in
//! robotics", §§ II–III): perturbations are on the right, `X ⊕ τ = X·Exp(τ)` and
//! `Y ⊖ X = Log(X⁻¹Y)`; every Jacobian is the derivative of the result's right perturbation
//! with respect to each input's right perturbation, `lim (f(X ⊕ τ) ⊖ f(X))/τ`.

use crate::{Manifold, SE3, SO3, se3, so3};
use core::fmt::Debug;
use nalgebra::{Matrix3, Matrix3x6, Matrix6, Vector3, Vector6};

/// A Lie group acting on points of R³, with the exponential map, its Jacobians and the
/// Jacobians of the group operations.
///
/// `X.retract(τ)` of the [`Manifold`] supertrait is `X ⊕ τ = X·Exp(τ)` for every
/// implementation.
///
/// ```
/// use nalgebra::{Vector3, Vector6};
/// use preint_lie::{LieGroup, SE3, SO3};
///
/// // `Y ⊖ X = Log(X⁻¹Y)`, written once for every group.
/// fn between<G: LieGroup>(x: &G, y: &G) -> G::Tangent {
///     x.inverse().compose(y).log()
/// }
///
/// let r = SO3::exp(&Vector3::new(0.1, -0.4, 0.3));
/// let phi = Vector3::new(0.2, 0.1, -0.3);
/// assert!((between(&r, &r.plus(&phi)) - phi).norm() < 1e-15);
///
/// let t = SE3::exp(&Vector6::new(1.0, 2.0, 3.0, 0.1, -0.4, 0.3));
/// let xi = Vector6::new(0.5, -0.2, 0.1, 0.2, 0.1, -0.3);
/// assert!((between(&t, &t.plus(&xi)) - xi).norm() < 1e-14);
/// assert_eq!((SO3::DOF, SE3::DOF), (3, 6));
/// ```
pub trait LieGroup: Manifold + Copy + PartialEq + Debug {
    /// Degrees of freedom: the dimension of the tangent space (3 for SO(3), 6 for SE(3)).
    const DOF: usize;
    /// Tangent vector τ: the rotation vector φ \[rad\] for SO(3), `[ρ, θ]` (translation
    /// first) for SE(3).
    type Tangent: Copy + Debug + PartialEq + Manifold;
    /// `DOF × DOF` matrix on the tangent space: adjoints and Jacobians.
    type Jacobian: Copy + Debug + PartialEq;
    /// `3 × DOF` Jacobian of [`LieGroup::act`] with respect to the group element.
    type ActJacobian: Copy + Debug + PartialEq;

    /// The identity element.
    fn identity() -> Self;
    /// Exponential map `Exp(τ)`.
    fn exp(tau: &Self::Tangent) -> Self;
    /// `Exp(τ)` and its Jacobian `Jr(τ)`.
    fn exp_jac(tau: &Self::Tangent) -> (Self, Self::Jacobian);
    /// Logarithmic map `Log(X)`.
    fn log(&self) -> Self::Tangent;
    /// `Log(X)` and its Jacobian `Jr⁻¹(Log X)`.
    fn log_jac(&self) -> (Self::Tangent, Self::Jacobian);
    /// Inverse `X⁻¹`.
    fn inverse(&self) -> Self;
    /// `X⁻¹` and its Jacobian `−Ad(X)`.
    fn inverse_jac(&self) -> (Self, Self::Jacobian);
    /// Composition `X·Y`.
    fn compose(&self, other: &Self) -> Self;
    /// `X·Y` and its Jacobians w.r.t. X (`Ad(Y)⁻¹`) and Y (`I`).
    fn compose_jac(&self, other: &Self) -> (Self, Self::Jacobian, Self::Jacobian);
    /// Action on a point: `X·p`.
    fn act(&self, p: &Vector3<f64>) -> Vector3<f64>;
    /// `X·p` and its Jacobians w.r.t. X (`3 × DOF`) and p (`3 × 3`).
    fn act_jac(&self, p: &Vector3<f64>) -> (Vector3<f64>, Self::ActJacobian, Matrix3<f64>);
    /// Adjoint `Ad(X)`: `X·Exp(τ) = Exp(Ad(X) τ)·X`.
    fn adjoint(&self) -> Self::Jacobian;
    /// Right-plus `X ⊕ τ = X·Exp(τ)`.
    fn plus(&self, tau: &Self::Tangent) -> Self;
    /// Right-minus `self ⊖ X = Log(X⁻¹·self)`.
    fn minus(&self, x: &Self) -> Self::Tangent;
    /// Right Jacobian `Jr(τ)`: `Exp(τ + δ) ≈ Exp(τ)·Exp(Jr(τ) δ)`.
    fn jr(tau: &Self::Tangent) -> Self::Jacobian;
    /// Left Jacobian `Jl(τ) = Jr(−τ)`: `Exp(τ + δ) ≈ Exp(Jl(τ) δ)·Exp(τ)`.
    fn jl(tau: &Self::Tangent) -> Self::Jacobian;
    /// Inverse right Jacobian `Jr⁻¹(τ)`.
    fn jr_inv(tau: &Self::Tangent) -> Self::Jacobian;
    /// Inverse left Jacobian `Jl⁻¹(τ)`.
    fn jl_inv(tau: &Self::Tangent) -> Self::Jacobian;
}

/// Forwards every method of [`LieGroup`] to the group's inherent methods (`$ty::…`) and the
/// free Jacobian functions of its module (`$module::…`); `$exp_jac` names the inherent
/// `Exp`-with-Jacobian method.
macro_rules! forward_lie_group {
    ($ty:ident, $module:ident, $dof:literal, $tangent:ty, $jac:ty, $act_jac:ty, $exp_jac:ident) => {
        impl LieGroup for $ty {
            const DOF: usize = $dof;
            type Tangent = $tangent;
            type Jacobian = $jac;
            type ActJacobian = $act_jac;

            #[inline]
            fn identity() -> Self {
                $ty::identity()
            }
            #[inline]
            fn exp(tau: &$tangent) -> Self {
                $ty::exp(tau)
            }
            #[inline]
            fn exp_jac(tau: &$tangent) -> (Self, $jac) {
                $ty::$exp_jac(tau)
            }
            #[inline]
            fn log(&self) -> $tangent {
                $ty::log(self)
            }
            #[inline]
            fn log_jac(&self) -> ($tangent, $jac) {
                $ty::log_jac(self)
            }
            #[inline]
            fn inverse(&self) -> Self {
                $ty::inverse(self)
            }
            #[inline]
            fn inverse_jac(&self) -> (Self, $jac) {
                $ty::inverse_jac(self)
            }
            #[inline]
            fn compose(&self, other: &Self) -> Self {
                $ty::compose(self, other)
            }
            #[inline]
            fn compose_jac(&self, other: &Self) -> (Self, $jac, $jac) {
                $ty::compose_jac(self, other)
            }
            #[inline]
            fn act(&self, p: &Vector3<f64>) -> Vector3<f64> {
                $ty::act(self, p)
            }
            #[inline]
            fn act_jac(&self, p: &Vector3<f64>) -> (Vector3<f64>, $act_jac, Matrix3<f64>) {
                $ty::act_jac(self, p)
            }
            #[inline]
            fn adjoint(&self) -> $jac {
                $ty::adjoint(self)
            }
            #[inline]
            fn plus(&self, tau: &$tangent) -> Self {
                $ty::plus(self, tau)
            }
            #[inline]
            fn minus(&self, x: &Self) -> $tangent {
                $ty::minus(self, x)
            }
            #[inline]
            fn jr(tau: &$tangent) -> $jac {
                $module::jr(tau)
            }
            #[inline]
            fn jl(tau: &$tangent) -> $jac {
                $module::jl(tau)
            }
            #[inline]
            fn jr_inv(tau: &$tangent) -> $jac {
                $module::jr_inv(tau)
            }
            #[inline]
            fn jl_inv(tau: &$tangent) -> $jac {
                $module::jl_inv(tau)
            }
        }
    };
}

forward_lie_group!(
    SO3,
    so3,
    3,
    Vector3<f64>,
    Matrix3<f64>,
    Matrix3<f64>,
    exp_jr
);
forward_lie_group!(
    SE3,
    se3,
    6,
    Vector6<f64>,
    Matrix6<f64>,
    Matrix3x6<f64>,
    exp_jac
);
