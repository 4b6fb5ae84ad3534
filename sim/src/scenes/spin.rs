//! `spin`: fast rotation about a tilted axis.

use crate::scene::{Scene, SceneState, rot_zyx};
use nalgebra::Vector3;
use preint_lie::SO3;

/// `spin`: constant-rate rotation about an axis fixed in the body, at a fixed position:
/// `R_wb(t) = R_0·Exp(ω_b t)`, `ω_b = rate·n_b` (constant, so `ω̇_b = 0`), `p = p_0`,
/// `v = a = 0`. The axis is fixed in the world too (`R_wb n_b = R_0 n_b`).
///
/// Default (the `spin` scene): `rate = 10` rad/s about `n_b = (1, −0.5, 2)/‖·‖`, with
/// `R_0 = Rz(0.5)·Ry(−0.2)·Rx(0.3)`, so the spin axis is tilted w.r.t. gravity; `p_0 = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpinScene {
    /// Attitude at t = 0, body→world.
    pub r0: SO3,
    /// Body angular velocity ω_b = rate·n_b [rad/s].
    pub omega_b: Vector3<f64>,
    /// Position \[m\], world frame.
    pub p: Vector3<f64>,
}

impl SpinScene {
    /// Spin at `rate_rad_s` [rad/s] about the body axis `axis_b` (normalised here; a zero axis
    /// gives no rotation), starting at attitude `r0`, at position `p` \[m\].
    pub fn new(r0: SO3, axis_b: Vector3<f64>, rate_rad_s: f64, p: Vector3<f64>) -> Self {
        let n = axis_b.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
        Self {
            r0,
            omega_b: n * rate_rad_s,
            p,
        }
    }
}

impl Default for SpinScene {
    fn default() -> Self {
        Self::new(
            rot_zyx(&Vector3::new(0.3, -0.2, 0.5)),
            Vector3::new(1.0, -0.5, 2.0),
            10.0,
            Vector3::zeros(),
        )
    }
}

impl Scene for SpinScene {
    fn name(&self) -> &str {
        "spin"
    }

    fn state(&self, t: f64) -> SceneState {
        SceneState {
            p: self.p,
            v: Vector3::zeros(),
            a: Vector3::zeros(),
            r_wb: self.r0 * SO3::exp(&(self.omega_b * t)),
            omega_b: self.omega_b,
            omega_dot_b: Vector3::zeros(),
        }
    }
}
