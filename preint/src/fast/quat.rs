//! Unit quaternions for ΔR at [`crate::Level::Deltas`] (Hamilton convention; Solà 2017,
//! "Quaternion kinematics for the error-state Kalman filter").

use crate::propagation::blocks::{M3, V3};
use nalgebra::Matrix3;
use preint_lie::so3::exp_quat_coeffs;

/// A unit quaternion `(w, v)`, Hamilton convention: `R(q) x = q ⊗ x ⊗ q*` (Solà 2017,
/// "Quaternion kinematics for the error-state Kalman filter": the product, §1.2.2, and the
/// vector rotation formula).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Quat {
    pub w: f64,
    pub v: V3,
}

impl Quat {
    pub(crate) const IDENTITY: Self = Self {
        w: 1.0,
        v: V3::new(0.0, 0.0, 0.0),
    };

    /// `q ⊗ Exp(φ)`, `Exp(φ) = (cos(θ/2), (sin(θ/2)/θ) φ)` ([`exp_quat_coeffs`]), given
    /// `theta2 = θ²` (which the caller can form without waiting for φ, see
    /// [`Quat::mul_exp_scaled`]).
    #[inline(always)]
    pub(crate) fn mul_exp(&self, phi: &V3, theta2: f64) -> Self {
        let (c, s) = exp_quat_coeffs(theta2);
        let (w, x, y, z) = (self.w, self.v.x, self.v.y, self.v.z);
        let (ex, ey, ez) = (s * phi.x, s * phi.y, s * phi.z);
        Self {
            w: w * c - x * ex - y * ey - z * ez,
            v: V3::new(
                w * ex + x * c + y * ez - z * ey,
                w * ey - x * ez + y * c + z * ex,
                w * ez + x * ey - y * ex + z * c,
            ),
        }
    }

    /// `q ⊗ Exp(k w)` for a rate `w` [rad/s] and a time `k` \[s\], with θ² formed as `|w|²·k²`:
    /// `|w|²` does not wait for `k`, which shortens each step's chain of dependent operations
    /// (the steps of a loop overlap only as far as the out-of-order window reaches).
    #[inline(always)]
    pub(crate) fn mul_exp_scaled(&self, w: &V3, k: f64) -> Self {
        self.mul_exp(&(w * k), w.norm_squared() * (k * k))
    }

    /// `R(q) x = x + w t + v × t`, `t = 2 v × x` (unit q).
    #[inline(always)]
    pub(crate) fn rotate(&self, x: &V3) -> V3 {
        let (w, u) = (self.w, &self.v);
        let t = [
            2.0 * (u.y * x.z - u.z * x.y),
            2.0 * (u.z * x.x - u.x * x.z),
            2.0 * (u.x * x.y - u.y * x.x),
        ];
        V3::new(
            x.x + w * t[0] + (u.y * t[2] - u.z * t[1]),
            x.y + w * t[1] + (u.z * t[0] - u.x * t[2]),
            x.z + w * t[2] + (u.x * t[1] - u.y * t[0]),
        )
    }

    /// `R(q/|q|)`: normalised first, so the drift since the last [`Quat::renormalize`] does
    /// not reach the matrix.
    pub(crate) fn matrix(&self) -> M3 {
        let (w, v) = (self.w, &self.v);
        self.scaled_matrix(2.0 / (w * w + v.x * v.x + v.y * v.y + v.z * v.z))
    }

    /// `I + s (w[v]× + [v]×²)` written entry-wise (`R(q)` for `s = 2/|q|²`).
    #[inline(always)]
    fn scaled_matrix(&self, s: f64) -> M3 {
        let (w, x, y, z) = (self.w, self.v.x, self.v.y, self.v.z);
        let (sx, sy, sz) = (s * x, s * y, s * z);
        let (xx, yy, zz) = (x * sx, y * sy, z * sz);
        let (xy, xz, yz) = (x * sy, x * sz, y * sz);
        let (wx, wy, wz) = (w * sx, w * sy, w * sz);
        Matrix3::new(
            1.0 - (yy + zz),
            xy - wz,
            xz + wy,
            xy + wz,
            1.0 - (xx + zz),
            yz - wx,
            xz - wy,
            yz + wx,
            1.0 - (xx + yy),
        )
    }

    /// `q (3 − |q|²)/2`: one Newton step towards |q| = 1.
    #[inline]
    pub(crate) fn renormalize(&mut self) {
        let k = 0.5 * (3.0 - (self.w * self.w + self.v.norm_squared()));
        self.w *= k;
        self.v *= k;
    }
}
