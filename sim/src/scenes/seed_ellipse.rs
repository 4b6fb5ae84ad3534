//! `seed-ellipse`: a slow horizontal ellipse with a fast vertical oscillation.

use crate::scene::{Scene, SceneState, state_from_euler};
use nalgebra::Vector3;
use std::f64::consts::PI;

/// `seed-ellipse`: a horizontal ellipse (semi-axes 15 m and 20 m, 20 s per lap) with a 1 m
/// vertical oscillation ten times faster, yawing once per lap and rocking in roll and pitch
/// (exact derivatives).
///
/// With `K = π/10` rad/s and `K1 = 10`:
/// - position \[m\]: `p = (15 cos Kt + 5, 20 sin Kt + 5, sin(K1 K t) + 5)`,
///   `v = (−15K sin Kt, 20K cos Kt, K1 K cos(K1 K t))`,
///   `a = (−15K² cos Kt, −20K² sin Kt, −(K1 K)² sin(K1 K t))`;
/// - ZYX Euler angles \[rad\]: `(roll, pitch, yaw) = (0.1 cos t, 0.2 sin t, K t)`,
///   `R_wb = Rz(yaw)·Ry(pitch)·Rx(roll)`;
/// - `ω_b = W(roll, pitch)·(roll̇, pitcḣ, yaẇ)` with the Euler-rate→body-rate matrix `W`
///   ([`crate::scene::euler_rate_to_body_rate`]), `ω̇_b = W Θ̈ + Ẇ Θ̇`
///   ([`crate::scene::euler_zyx_body_rates`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeedEllipseScene;

impl SeedEllipseScene {
    /// `K = π/10` [rad/s].
    pub const K: f64 = PI / 10.0;
    /// `K1 = 10` (vertical frequency multiplier).
    pub const K1: f64 = 10.0;
}

impl Scene for SeedEllipseScene {
    fn name(&self) -> &str {
        "seed-ellipse"
    }

    fn state(&self, t: f64) -> SceneState {
        let k = Self::K;
        let kz = Self::K1 * k;
        let (s, c) = (k * t).sin_cos();
        let (sz, cz) = (kz * t).sin_cos();
        let p = Vector3::new(15.0 * c + 5.0, 20.0 * s + 5.0, sz + 5.0);
        let v = Vector3::new(-15.0 * k * s, 20.0 * k * c, kz * cz);
        let a = Vector3::new(-15.0 * k * k * c, -20.0 * k * k * s, -kz * kz * sz);
        let (st, ct) = t.sin_cos();
        let e = Vector3::new(0.1 * ct, 0.2 * st, k * t);
        let ed = Vector3::new(-0.1 * st, 0.2 * ct, k);
        let edd = Vector3::new(-0.1 * ct, -0.2 * st, 0.0);
        state_from_euler([p, v, a], [e, ed, edd])
    }
}
