//! Conversions between [`SO3`] and unit quaternions (Hamilton convention), and the quaternion
//! extraction `Log` uses near θ = π.

use super::{SO3, horner};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

impl SO3 {
    /// From a unit quaternion (Hamilton, `w + xi + yj + zk`, body→world when used as attitude).
    #[inline]
    pub fn from_quaternion(q: &UnitQuaternion<f64>) -> Self {
        Self {
            m: q.to_rotation_matrix().into_inner(),
        }
    }

    /// From quaternion components `(w, x, y, z)`; the quaternion is normalised first.
    /// Returns `None` if its norm is zero or not finite.
    pub fn from_wxyz(w: f64, x: f64, y: f64, z: f64) -> Option<Self> {
        let n = (w * w + x * x + y * y + z * z).sqrt();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        Some(Self::from_quaternion(&UnitQuaternion::new_unchecked(
            Quaternion::new(w / n, x / n, y / n, z / n),
        )))
    }

    /// The unit quaternion of this rotation, with `w ≥ 0` (Shepperd's method: the largest of
    /// `w², x², y², z²` is extracted from the diagonal, so no branch divides by a small number).
    pub fn to_quaternion(&self) -> UnitQuaternion<f64> {
        let q = shepperd(&self.m);
        UnitQuaternion::new_normalize(q)
    }
}

/// Shepperd's rotation-matrix → quaternion, returning `w ≥ 0`. Not normalised (it is unit to
/// round-off for an orthonormal input).
pub(super) fn shepperd(m: &Matrix3<f64>) -> Quaternion<f64> {
    let (m00, m11, m22) = (m[(0, 0)], m[(1, 1)], m[(2, 2)]);
    let tr = m00 + m11 + m22;
    let q = if tr >= m00 && tr >= m11 && tr >= m22 {
        let s = 2.0 * (1.0 + tr).sqrt(); // 4w
        Quaternion::new(
            0.25 * s,
            (m[(2, 1)] - m[(1, 2)]) / s,
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(1, 0)] - m[(0, 1)]) / s,
        )
    } else if m00 >= m11 && m00 >= m22 {
        let s = 2.0 * (1.0 + m00 - m11 - m22).sqrt(); // 4x
        Quaternion::new(
            (m[(2, 1)] - m[(1, 2)]) / s,
            0.25 * s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
        )
    } else if m11 >= m22 {
        let s = 2.0 * (1.0 + m11 - m00 - m22).sqrt(); // 4y
        Quaternion::new(
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            0.25 * s,
            (m[(1, 2)] + m[(2, 1)]) / s,
        )
    } else {
        let s = 2.0 * (1.0 + m22 - m00 - m11).sqrt(); // 4z
        Quaternion::new(
            (m[(1, 0)] - m[(0, 1)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
            (m[(1, 2)] + m[(2, 1)]) / s,
            0.25 * s,
        )
    };
    if q.w < 0.0 { -q } else { q }
}

/// Log of a unit quaternion `(w, v)` with `w ≥ 0` as a rotation vector:
/// `φ = 2 atan2(‖v‖, w) v/‖v‖`, written as `(2/w)·(atan x / x)·v`, x = ‖v‖/w, for small x so
/// that nothing divides by ‖v‖ (which underflows for θ ~ 1e-300).
#[inline]
pub(super) fn log_quaternion(w: f64, v: &Vector3<f64>) -> Vector3<f64> {
    let n2 = v.norm_squared();
    if n2 < 1e-6 * w * w {
        // x² < 1e-6: atan(x)/x = 1 − x²/3 + x⁴/5 − x⁶/7, truncation < 1e-24.
        let x2 = n2 / (w * w);
        let f = horner(x2, &[1.0, -1.0 / 3.0, 1.0 / 5.0, -1.0 / 7.0]);
        v * (2.0 * f / w)
    } else {
        let n = n2.sqrt();
        v * (2.0 * n.atan2(w) / n)
    }
}
