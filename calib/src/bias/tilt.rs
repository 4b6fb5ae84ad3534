//! Tilt geometry: roll and pitch of the gravity direction seen in the body frame, the zero-yaw
//! attitude they define, and the propagation of an attitude covariance to them.
//!
//! With Z-Y-X Euler angles, `R_wb = Rz(yaw)·Ry(pitch)·Rx(roll)`, the body "up" unit vector
//! `u = R_wbᵀ·ẑ` is `u = (−sin p, sin r cos p, cos r cos p)`, independent of yaw; hence
//! `roll = atan2(u_y, u_z)`, `pitch = atan2(−u_x, √(u_y² + u_z²))`. For a right perturbation
//! `R ← R·Exp(δφ)`, `∂u/∂δφ = [u]×`, so the covariance `C_φ` of the attitude's tangent maps to
//! `C_rp = J C_φ Jᵀ` with `J = ∂(roll, pitch)/∂u · [u]×`.

use nalgebra::{Matrix2, Matrix2x3, Matrix3, Vector3};
use preint_lie::{SO3, hat};

/// Roll and pitch \[rad\] (Z-Y-X Euler angles, `R_wb = Rz(yaw)·Ry(pitch)·Rx(roll)`) of the body
/// "up" unit vector `u = R_wbᵀ·ẑ`: `u = (−sin p, sin r cos p, cos r cos p)`, so
/// `roll = atan2(u_y, u_z)`, `pitch = atan2(−u_x, √(u_y² + u_z²))`. Also returns
/// `∂(roll, pitch)/∂u` (2×3). `u` need not be normalised.
///
/// ```
/// use nalgebra::Vector3;
/// use preint_calib::bias::{attitude_from_roll_pitch, roll_pitch_of_up};
///
/// let r = attitude_from_roll_pitch(0.2, -0.3);
/// let up_body = r.inverse().act(&Vector3::z());
/// let (roll, pitch, _) = roll_pitch_of_up(&up_body);
/// assert!((roll - 0.2).abs() < 1e-12 && (pitch + 0.3).abs() < 1e-12);
/// ```
pub fn roll_pitch_of_up(u: &Vector3<f64>) -> (f64, f64, Matrix2x3<f64>) {
    let u = u / u.norm();
    let ryz2 = u.y * u.y + u.z * u.z;
    let ryz = ryz2.sqrt();
    let roll = u.y.atan2(u.z);
    let pitch = (-u.x).atan2(ryz);
    let mut j = Matrix2x3::zeros();
    if ryz2 > 0.0 {
        j[(0, 1)] = u.z / ryz2;
        j[(0, 2)] = -u.y / ryz2;
        j[(1, 0)] = -ryz;
        j[(1, 1)] = u.x * u.y / ryz;
        j[(1, 2)] = u.x * u.z / ryz;
    }
    (roll, pitch, j)
}

/// The zero-yaw attitude `R_wb = Ry(pitch)·Rx(roll)` \[rad\].
pub fn attitude_from_roll_pitch(roll: f64, pitch: f64) -> SO3 {
    SO3::exp(&Vector3::new(0.0, pitch, 0.0)).compose(&SO3::exp(&Vector3::new(roll, 0.0, 0.0)))
}

/// The minimal rotation `R = Exp(θ·k)` with `R·from = to` (unit vectors, not checked), `k` the
/// unit axis of `from × to` and `θ` the angle between them; the identity when they are
/// parallel. `None` when they are antiparallel: then every half turn about an axis
/// perpendicular to `from` qualifies and the caller chooses one.
pub(crate) fn minimal_rotation(from: &Vector3<f64>, to: &Vector3<f64>) -> Option<SO3> {
    let axis = from.cross(to);
    let s = axis.norm();
    let c = from.dot(to);
    if s < 1e-12 {
        return (c > 0.0).then(SO3::identity);
    }
    Some(SO3::exp(&(axis / s * s.atan2(c))))
}

/// A rotation `R` with `Rᵀ·up_w = u_b` (both unit vectors): the minimal rotation taking
/// `u_b` to `up_w`; for the default z-up world, the zero-yaw attitude of
/// [`roll_pitch_of_up`]`(u_b)`.
pub(crate) fn attitude_from_up(u_b: &Vector3<f64>, up_w: &Vector3<f64>) -> SO3 {
    let u = u_b.normalize();
    let w = up_w.normalize();
    if (w - Vector3::z()).norm() < 1e-12 {
        let (r, p, _) = roll_pitch_of_up(&u);
        return attitude_from_roll_pitch(r, p);
    }
    minimal_rotation(&u, &w).unwrap_or_else(|| {
        // Antiparallel: half turn about an axis perpendicular to u.
        let perp = if u.x.abs() < 0.9 {
            u.cross(&Vector3::x())
        } else {
            u.cross(&Vector3::y())
        };
        SO3::exp(&(perp.normalize() * std::f64::consts::PI))
    })
}

/// Roll, pitch \[rad\] of the attitude `r` (R_wb) for the world up direction `up_w` (unit), and
/// their 2×2 covariance \[rad²\] from the covariance `c_phi` of `r`'s right-perturbation tangent
/// (module docs). Also returns the body up vector `u = rᵀ·up_w`.
pub(crate) fn roll_pitch_with_cov(
    r: &SO3,
    up_w: &Vector3<f64>,
    c_phi: &Matrix3<f64>,
) -> (f64, f64, Matrix2<f64>, Vector3<f64>) {
    let u = r.inverse().act(up_w);
    let (roll, pitch, d_rp_du) = roll_pitch_of_up(&u);
    let j_rp = d_rp_du * hat(&u);
    (roll, pitch, j_rp * c_phi * j_rp.transpose(), u)
}
