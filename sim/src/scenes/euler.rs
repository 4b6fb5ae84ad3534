//! Scenes whose position and ZYX Euler angles are sums of sinusoids: `aggressive`, and any
//! user-defined one.

use crate::scene::{Scene, SceneState, state_from_euler};
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// A scalar signal `x(t) = c + r·t + Σ_k A_k sin(w_k t + φ_k)` with its analytic derivatives
/// `ẋ = r + Σ A_k w_k cos(w_k t + φ_k)`, `ẍ = −Σ A_k w_k² sin(w_k t + φ_k)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sines {
    /// Constant term `c`.
    pub offset: f64,
    /// Linear rate `r` [unit/s].
    pub rate: f64,
    /// Terms `(A_k [unit], w_k [rad/s], φ_k \[rad\])`.
    pub terms: Vec<(f64, f64, f64)>,
}

impl Sines {
    /// `offset + rate·t + Σ A sin(2π f t + φ)` from `(A, f \[Hz\], φ \[rad\])` triples.
    pub fn hz(offset: f64, rate: f64, terms: &[(f64, f64, f64)]) -> Self {
        Self {
            offset,
            rate,
            terms: terms.iter().map(|&(a, f, ph)| (a, TAU * f, ph)).collect(),
        }
    }

    /// `[x(t), ẋ(t), ẍ(t)]` at `t` \[s\].
    pub fn eval(&self, t: f64) -> [f64; 3] {
        let mut out = [self.offset + self.rate * t, self.rate, 0.0];
        for &(a, w, ph) in &self.terms {
            let (s, c) = (w * t + ph).sin_cos();
            out[0] += a * s;
            out[1] += a * w * c;
            out[2] -= a * w * w * s;
        }
        out
    }
}

/// Evaluates three signals into `[value, first, second derivative]` vectors.
fn eval3(s: &[Sines; 3], t: f64) -> [Vector3<f64>; 3] {
    let (x, y, z) = (s[0].eval(t), s[1].eval(t), s[2].eval(t));
    [0, 1, 2].map(|i| Vector3::new(x[i], y[i], z[i]))
}

/// A scene with position `p(t)` [m, world] and ZYX Euler angles `(roll, pitch, yaw)(t)` \[rad\]
/// given per axis as [`Sines`]. Attitude `R_wb = Rz(yaw)·Ry(pitch)·Rx(roll)`; body rate
/// `ω_b = W Θ̇` and `ω̇_b = W Θ̈ + Ẇ Θ̇` ([`crate::scene::euler_zyx_body_rates`]).
#[derive(Clone, Debug, PartialEq)]
pub struct EulerScene {
    /// Registry name.
    pub name: String,
    /// Position x, y, z \[m\].
    pub position: [Sines; 3],
    /// Roll φ, pitch θ, yaw ψ \[rad\].
    pub euler: [Sines; 3],
}

impl EulerScene {
    /// `aggressive`: MAV-like high-bandwidth motion, sums of sinusoids up to 3.1 Hz.
    /// Terms are `(A, f \[Hz\], φ \[rad\])` of `A sin(2π f t + φ)`:
    ///
    /// | signal | offset, rate | terms |
    /// |---|---|---|
    /// | x \[m\] | 0, 0 | (1.0, 0.3, 0), (0.15, 1.1, 0.5), (0.02, 2.7, 1.0) |
    /// | y \[m\] | 0, 0 | (0.8, 0.4, 1.2), (0.1, 1.3, 2.0), (0.015, 3.1, 0.3) |
    /// | z \[m\] | 1.5, 0 | (0.3, 0.5, 0.7), (0.05, 1.7, 0.1), (0.01, 2.9, 2.2) |
    /// | roll \[rad\] | 0, 0 | (0.35, 0.8, 0), (0.08, 2.5, 1.0) |
    /// | pitch \[rad\] | 0, 0 | (0.3, 0.6, 0.4), (0.07, 2.2, 0.2) |
    /// | yaw \[rad\] | 0, 0.3 rad/s | (0.6, 0.35, 0), (0.05, 3.0, 0.5) |
    ///
    /// Position and Euler angles (yaw minus its ramp) are band-limited to 3.1 Hz (all
    /// frequencies are multiples of 0.05 Hz, so everything except the yaw ramp repeats every
    /// 20 s). Measured over one period (tests/scenes.rs): peak `|a|` per axis 16.4, 15.5,
    /// 9.33 m/s² (kinematic, gravity excluded), peak `|ω_b|` 4.31 rad/s; `|pitch|` ≤ 0.3 + 0.07
    /// = 0.37 rad by construction (max 0.364), far from gimbal lock. (`ω_b` and `a` in the body
    /// frame are products of these signals and so contain higher harmonics.)
    pub fn aggressive() -> Self {
        Self {
            name: "aggressive".into(),
            position: [
                Sines::hz(
                    0.0,
                    0.0,
                    &[(1.0, 0.3, 0.0), (0.15, 1.1, 0.5), (0.02, 2.7, 1.0)],
                ),
                Sines::hz(
                    0.0,
                    0.0,
                    &[(0.8, 0.4, 1.2), (0.1, 1.3, 2.0), (0.015, 3.1, 0.3)],
                ),
                Sines::hz(
                    1.5,
                    0.0,
                    &[(0.3, 0.5, 0.7), (0.05, 1.7, 0.1), (0.01, 2.9, 2.2)],
                ),
            ],
            euler: [
                Sines::hz(0.0, 0.0, &[(0.35, 0.8, 0.0), (0.08, 2.5, 1.0)]),
                Sines::hz(0.0, 0.0, &[(0.3, 0.6, 0.4), (0.07, 2.2, 0.2)]),
                Sines::hz(0.0, 0.3, &[(0.6, 0.35, 0.0), (0.05, 3.0, 0.5)]),
            ],
        }
    }
}

impl Scene for EulerScene {
    fn name(&self) -> &str {
        &self.name
    }

    fn state(&self, t: f64) -> SceneState {
        state_from_euler(eval3(&self.position, t), eval3(&self.euler, t))
    }
}
