//! Integration schemes: one interval `[t_k, t_k+1]` of the deltas and, when asked, its
//! linearisation (transition and per-sample gains, see the internal `propagation` module).
//!
//! Every scheme works on bias-corrected samples `ω = ω_m − b̂_g`, `a = a_m − b̂_a` and updates
//! `ΔR_k+1 = ΔR_k Exp(Ω_k)`, `Δv`, `Δp` in frame i (gravity excluded, Forster eq. 33).

pub mod euler;
pub mod hermite;
pub mod midpoint;

use crate::propagation::{M3, V3};
use crate::sample::{ImuBias, ImuSample};
use nalgebra::Matrix3;
use preint_lie::so3::exp_quat_coeffs;

/// A bias-corrected sample: time \[ns\], `ω` [rad/s], `a` [m/s²].
///
/// Aligned so that `w` and `a` each start a 16-byte pair: the vector stores that write a node
/// and the loads that read it soon after then cover the same bytes (a load spanning two
/// pending stores cannot be forwarded and stalls).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct Node {
    pub w: V3,
    _pad_w: f64,
    pub a: V3,
    pub t_ns: i64,
}

impl Node {
    #[inline(always)]
    pub(crate) fn new(t_ns: i64, w: V3, a: V3) -> Self {
        Self {
            w,
            _pad_w: 0.0,
            a,
            t_ns,
        }
    }

    /// The node of sample `s` for the bias estimate `bias`: `ω_m − b_g`, `a_m − b_a`.
    #[inline(always)]
    pub(crate) fn corrected(s: &ImuSample, bias: &ImuBias) -> Self {
        Self::new(s.t_ns, s.gyro - bias.gyro, s.acc - bias.acc)
    }
}

/// Running deltas: `ΔR_k = r·R(q)`, `Δv_k` [m/s], `Δp_k` \[m\]; `u_last = ΔR_k a_k` cached by
/// the schemes that evaluate the acceleration at both ends of an interval.
///
/// ΔR is accumulated in one of two forms, and the other stays exactly the identity: as the
/// unit quaternion `q` by every scheme at [`crate::Level::Deltas`] (a product is 28 flops
/// instead of 45, a rotation of a vector 30 instead of 15 + the Exp matrix's 20, and 4 numbers
/// in registers instead of 9), as the matrix `r` everywhere else (the gains need ΔR_k and
/// ΔR_k+1 as matrices). The two agree to round-off (`preint/tests/deltas_fast_path.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Deltas {
    pub r: M3,
    pub q: Quat,
    pub v: V3,
    pub p: V3,
    pub u_last: V3,
    /// `u̇_k = ΔR_k s_k`, `s_k = ω_k × a_k + ȧ_k`, and `ω̇_k` at the last node (the Hermite
    /// scheme; `du_last` with ΔR as the matrix `r`, `s_last` (frame k) with the quaternion).
    pub du_last: V3,
    pub s_last: V3,
    pub dw_last: V3,
}

impl Default for Deltas {
    fn default() -> Self {
        Self {
            r: M3::identity(),
            q: Quat::IDENTITY,
            v: V3::zeros(),
            p: V3::zeros(),
            u_last: V3::zeros(),
            du_last: V3::zeros(),
            s_last: V3::zeros(),
            dw_last: V3::zeros(),
        }
    }
}

impl Deltas {
    /// ΔR as a matrix: `r·R(q)`, exact because one factor is the identity (`I·M` and `M·I`
    /// add only exact zeros).
    #[inline]
    pub(crate) fn delta_r(&self) -> M3 {
        debug_assert!(self.r == M3::identity() || self.q == Quat::IDENTITY);
        self.r * self.q.matrix()
    }

    /// Re-orthonormalises ΔR to first order, `R(3I − RᵀR)/2` and `q(3 − |q|²)/2`; the
    /// identity (the form not in use) is a fixed point of both, exactly.
    #[inline]
    pub(crate) fn renormalize(&mut self) {
        let r = self.r;
        self.r = r * (M3::identity() * 3.0 - r.transpose() * r) * 0.5;
        self.q.renormalize();
    }
}

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

/// `(t1 − t0)·1e-9` \[s\] computed in i128, so any pair of i64 timestamps is safe.
#[inline(always)]
pub(crate) fn span_s(t0_ns: i64, t1_ns: i64) -> f64 {
    // Same integer, same rounding: the i64 → f64 conversion is a single instruction, the
    // i128 one a library call.
    match t1_ns.checked_sub(t0_ns) {
        Some(d) => d as f64 * 1e-9,
        None => (t1_ns as i128 - t0_ns as i128) as f64 * 1e-9,
    }
}

/// `s I + α[φ]× + β[φ]×²`, built entry-wise from `[φ]×² = φφᵀ − θ²I` (no 3×3 products): with
/// Rodrigues' coefficients `(b, c)` ([`preint_lie::so3::RodriguesCoeffs`]), `s·Jl(φ)` is
/// `(s, s b, s c)` and `s·Jr(φ)` is `(s, −s b, s c)`.
#[inline(always)]
pub(crate) fn s_plus_hat_hat2(phi: &V3, s: f64, alpha: f64, beta: f64) -> M3 {
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (bxy, bxz, byz) = (beta * x * y, beta * x * z, beta * y * z);
    let (ax, ay, az) = (alpha * x, alpha * y, alpha * z);
    Matrix3::new(
        s - beta * (yy + zz),
        bxy - az,
        bxz + ay,
        bxy + az,
        s - beta * (xx + zz),
        byz - ax,
        bxz - ay,
        byz + ax,
        s - beta * (xx + yy),
    )
}
