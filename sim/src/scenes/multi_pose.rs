//! `multi-pose-static`: still poses joined by smooth rotations (multi-position calibration).

use crate::scene::{Scene, SceneState};
use nalgebra::Vector3;
use preint_lie::SO3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Quintic blend `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` on `τ ∈ [0, 1]` (clamped outside) with its
/// derivatives `[s, ds/dτ, d²s/dτ²]`; `s' = s'' = 0` at both ends, so a motion built on it is C².
pub fn quintic_blend(tau: f64) -> [f64; 3] {
    if tau <= 0.0 {
        return [0.0, 0.0, 0.0];
    }
    if tau >= 1.0 {
        return [1.0, 0.0, 0.0];
    }
    let t2 = tau * tau;
    let t3 = t2 * tau;
    [
        t3 * (10.0 + tau * (-15.0 + 6.0 * tau)),
        30.0 * t2 * (1.0 - tau) * (1.0 - tau),
        60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau),
    ]
}

/// `multi-pose-static`: a sequence of still attitudes `P_0 … P_{n−1}` (body→world) at a fixed
/// position, each held for `hold_s`, joined by rotations of duration `move_s`.
///
/// With period `T = hold_s + move_s`, for `t ∈ [iT, iT + hold_s)` the body rests at `P_i`; for
/// `t ∈ [iT + hold_s, (i+1)T)` with `τ = (t − iT − hold_s)/move_s`:
/// `R_wb = P_i·Exp(s(τ) φ_i)`, `φ_i = Log(P_iᵀ P_{i+1})`, `ω_b = φ_i ṡ`, `ω̇_b = φ_i s̈`
/// (`s` = [`quintic_blend`], `ṡ = s'(τ)/move_s`, `s̈ = s''(τ)/move_s²`). Before `t = 0` the body is
/// at `P_0`; after the last transition it stays at `P_{n−1}`. Position fixed, `v = a = 0`.
///
/// Default (the `multi-pose-static` scene): `hold_s = 3`, `move_s = 2`, `p = 0`, seven poses
/// whose gravity reading (`R_wbᵀ(0,0,9.81)`) points along +z, +y, −z, −y, −x (body axes), an
/// oblique pose `Rz(0.2)Ry(0.3)Rx(0.4)`, then +x:
/// `I, Rx(π/2), Rx(π), Rx(−π/2), Ry(π/2), Rz(0.2)Ry(0.3)Rx(0.4), Ry(−π/2)`.
/// Total 33 s ([`MultiPoseStaticScene::duration_s`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MultiPoseStaticScene {
    poses: Vec<SO3>,
    steps: Vec<Vector3<f64>>,
    hold_s: f64,
    move_s: f64,
    p: Vector3<f64>,
}

impl MultiPoseStaticScene {
    /// Poses `poses` (body→world), each held `hold_s` \[s\] and joined by `move_s` \[s\] rotations,
    /// at position `p` \[m\]. Returns `None` if `poses` is empty, or `hold_s < 0`, `move_s ≤ 0`
    /// or either is not finite.
    pub fn new(poses: Vec<SO3>, hold_s: f64, move_s: f64, p: Vector3<f64>) -> Option<Self> {
        let ok = !poses.is_empty()
            && hold_s.is_finite()
            && move_s.is_finite()
            && hold_s >= 0.0
            && move_s > 0.0;
        if !ok {
            return None;
        }
        let steps = poses
            .windows(2)
            .map(|w| (w[0].inverse() * w[1]).log())
            .collect();
        Some(Self {
            poses,
            steps,
            hold_s,
            move_s,
            p,
        })
    }

    /// The still attitudes, body→world.
    pub fn poses(&self) -> &[SO3] {
        &self.poses
    }

    /// The still intervals `[start, end)` \[s\], one per pose (the last one ends after its hold).
    pub fn static_intervals(&self) -> Vec<(f64, f64)> {
        let period = self.hold_s + self.move_s;
        (0..self.poses.len())
            .map(|i| (i as f64 * period, i as f64 * period + self.hold_s))
            .collect()
    }

    /// Time \[s\] at which the last hold ends: `n·hold_s + (n−1)·move_s`.
    pub fn duration_s(&self) -> f64 {
        let n = self.poses.len() as f64;
        n * self.hold_s + (n - 1.0) * self.move_s
    }
}

impl Default for MultiPoseStaticScene {
    fn default() -> Self {
        let rx = |a: f64| SO3::exp(&Vector3::new(a, 0.0, 0.0));
        let ry = |a: f64| SO3::exp(&Vector3::new(0.0, a, 0.0));
        let oblique = crate::scene::rot_zyx(&Vector3::new(0.4, 0.3, 0.2));
        let poses = vec![
            SO3::identity(),
            rx(FRAC_PI_2),
            rx(PI),
            rx(-FRAC_PI_2),
            ry(FRAC_PI_2),
            oblique,
            ry(-FRAC_PI_2),
        ];
        Self::new(poses, 3.0, 2.0, Vector3::zeros()).expect("valid default poses")
    }
}

impl Scene for MultiPoseStaticScene {
    fn name(&self) -> &str {
        "multi-pose-static"
    }

    fn state(&self, t: f64) -> SceneState {
        let period = self.hold_s + self.move_s;
        let mut st = SceneState {
            p: self.p,
            v: Vector3::zeros(),
            a: Vector3::zeros(),
            r_wb: self.poses[0],
            omega_b: Vector3::zeros(),
            omega_dot_b: Vector3::zeros(),
        };
        if t <= 0.0 || t.is_nan() {
            return st;
        }
        let i = (t / period).floor();
        if i >= self.steps.len() as f64 {
            st.r_wb = self.poses[self.poses.len() - 1];
            return st;
        }
        let i = i as usize;
        let tau = (t - i as f64 * period - self.hold_s) / self.move_s;
        let [s, ds, dds] = quintic_blend(tau);
        let phi = self.steps[i];
        st.r_wb = self.poses[i] * SO3::exp(&(phi * s));
        st.omega_b = phi * (ds / self.move_s);
        st.omega_dot_b = phi * (dds / (self.move_s * self.move_s));
        st
    }
}
