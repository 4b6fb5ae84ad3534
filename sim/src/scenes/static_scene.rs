//! `static`: a body at rest.

use crate::scene::{Scene, SceneState, rot_zyx};
use nalgebra::Vector3;
use preint_lie::SO3;

/// `static`: the body at rest at position `p` \[m\] with fixed attitude `r_wb` (body→world):
/// `v = a = 0`, `ω_b = ω̇_b = 0`. A noise-free accelerometer reads `R_wbᵀ·(0, 0, +9.81)`.
///
/// The default (the `static` scene) is tilted so that the gravity reading has three non-zero
/// components: `R_wb = Rz(0.8)·Ry(−0.3)·Rx(0.2)` (ZYX Euler angles roll 0.2, pitch −0.3,
/// yaw 0.8 rad) at `p = (1, 2, 3)` m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticScene {
    /// Attitude, body→world.
    pub r_wb: SO3,
    /// Position in the world frame \[m\].
    pub p: Vector3<f64>,
}

impl StaticScene {
    /// A body at rest with attitude `r_wb` (body→world) at position `p` \[m\].
    pub fn new(r_wb: SO3, p: Vector3<f64>) -> Self {
        Self { r_wb, p }
    }
}

impl Default for StaticScene {
    fn default() -> Self {
        Self::new(
            rot_zyx(&Vector3::new(0.2, -0.3, 0.8)),
            Vector3::new(1.0, 2.0, 3.0),
        )
    }
}

impl Scene for StaticScene {
    fn name(&self) -> &str {
        "static"
    }

    fn state(&self, _t_s: f64) -> SceneState {
        SceneState {
            p: self.p,
            v: Vector3::zeros(),
            a: Vector3::zeros(),
            r_wb: self.r_wb,
            omega_b: Vector3::zeros(),
            omega_dot_b: Vector3::zeros(),
        }
    }
}
