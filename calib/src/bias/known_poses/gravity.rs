//! The gravity direction as a state with two degrees of freedom.
//!
//! `g = R_wg·g₀`, `g₀ = (0, 0, −|g|)`, `R_wg ∈ SO3` perturbed on the right by `(δ₀, δ₁, 0)`
//! only: a rotation about `g₀` changes nothing, so the tangent has 2 DoF (as ORB-SLAM3 zeroes
//! that update component, Campos et al., T-RO 2021) and the problem has no gauge freedom.
//! `∂g/∂δ = −R_wg [g₀]×`, restricted to its first two columns.

use super::super::tilt::minimal_rotation;
use nalgebra::{Matrix3, Matrix3x2, Vector3};
use preint_lie::{Manifold, SO3, hat};

/// Gravity direction `R_wg` with the 2-DoF right perturbation `R_wg·Exp((δ₀, δ₁, 0))` (module
/// docs). `local` returns the first two components of `Log(R_aᵀR_b)`, the inverse of
/// `retract` for perturbations of that form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GravityDir(pub(crate) SO3);

impl Manifold for GravityDir {
    fn dim(&self) -> usize {
        2
    }
    fn retract(&self, d: &[f64]) -> Self {
        GravityDir(self.0.plus(&Vector3::new(d[0], d[1], 0.0)))
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        let v = o.0.minus(&self.0);
        out[0] = v.x;
        out[1] = v.y;
    }
}

impl GravityDir {
    /// The direction with `R_wg·g₀ = g_init` (the minimal rotation; a half turn about x when
    /// `g_init` is antiparallel to `g₀`).
    pub(crate) fn aligned_with(g0: &Vector3<f64>, g_init: &Vector3<f64>) -> Self {
        let rwg0 = minimal_rotation(&g0.normalize(), &g_init.normalize())
            .unwrap_or_else(|| SO3::exp(&Vector3::new(std::f64::consts::PI, 0.0, 0.0)));
        GravityDir(rwg0)
    }

    /// `g = R_wg·g₀` and `G = ∂g/∂δ = −R_wg [g₀]×` (first two columns).
    pub(crate) fn gravity(&self, g0: &Vector3<f64>) -> (Vector3<f64>, Matrix3x2<f64>) {
        let full: Matrix3<f64> = -self.0.matrix() * hat(g0);
        (self.0.act(g0), full.fixed_columns::<2>(0).into_owned())
    }
}
