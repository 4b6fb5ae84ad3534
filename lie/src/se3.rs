//! SE(3), rigid-body transforms `T = (R, t)` acting as `x ↦ R x + t`.
//!
//! Tangent vectors are `ξ = [ρ, θ] ∈ R⁶`, **translation first**, as in Solà 2018 § 10.6,
//! Barfoot 2017 and C++ Sophus. (GTSAM's `Pose3` and sophus-rs put the rotation first.) `Exp(ξ) = (Exp(θ), Jl(θ) ρ)` (Solà eq. 172); perturbations are on the right:
//! `T ⊕ ξ = T·Exp(ξ)`.

use crate::so3::{self, SO3, hat};
use nalgebra::{Matrix3, Matrix4, Matrix6, Vector3, Vector6};

/// Taylor coefficients in θ² of the three scalars of `Q(ρ, θ)` (Solà eq. 180), each
/// `Σ_k (−1)^k n_k θ^{2k}/m_k!`; twelve terms, used for θ < 2 (truncation < 1e-20 relative).
const fn q_series(kind: u32) -> [f64; 12] {
    let mut out = [0.0; 12];
    let mut k = 0;
    while k < 12 {
        // m = 2k+3 (a), 2k+4 (b), 2k+5 (c); numerator 1, 1, k+1.
        let m = 2 * k + 3 + kind as usize;
        let mut f = 1.0;
        let mut i = 2;
        while i <= m {
            f *= i as f64;
            i += 1;
        }
        let num = if kind == 2 { (k + 1) as f64 } else { 1.0 };
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        out[k] = sign * num / f;
        k += 1;
    }
    out
}
const QA: [f64; 12] = q_series(0);
const QB: [f64; 12] = q_series(1);
const QC: [f64; 12] = q_series(2);

/// `Q(ρ, θ)`, the off-diagonal block of the SE(3) left Jacobian (Barfoot 2017 eq. 7.86,
/// Solà eq. 180):
/// `Q = ½ρ̂ + a(θ̂ρ̂ + ρ̂θ̂ + θ̂ρ̂θ̂) + b(θ̂²ρ̂ + ρ̂θ̂² − 3θ̂ρ̂θ̂) + c(θ̂ρ̂θ̂² + θ̂²ρ̂θ̂)` with
/// `a = (θ − sin θ)/θ³`, `b = (θ² + 2cos θ − 2)/(2θ⁴)`, `c = (2θ − 3 sin θ + θ cos θ)/(2θ⁵)`.
pub fn q_block(rho: &Vector3<f64>, theta: &Vector3<f64>) -> Matrix3<f64> {
    let (a, b, c) = q_coeffs(theta.norm_squared());
    let th = hat(theta);
    let rh = hat(rho);
    let thrh = th * rh;
    let rhth = rh * th;
    let thrhth = thrh * th;
    let th2 = th * th;
    rh * 0.5
        + (thrh + rhth + thrhth) * a
        + (th2 * rh + rhth * th - thrhth * 3.0) * b
        + (thrhth * th + th * thrhth) * c
}

/// The scalars `(a, b, c)` of [`q_block`] at θ² \[rad²\]: `a = (θ − sin θ)/θ³`,
/// `b = (θ² + 2cos θ − 2)/(2θ⁴)`, `c = (2θ − 3 sin θ + θ cos θ)/(2θ⁵)`; Taylor series below θ = 2.
#[doc(hidden)] // a kernel of `q_block`, public for the reference tests in `tests/se3.rs`
pub fn q_coeffs(t2: f64) -> (f64, f64, f64) {
    if t2 < 4.0 {
        (
            so3::horner(t2, &QA),
            so3::horner(t2, &QB),
            so3::horner(t2, &QC),
        )
    } else {
        let t = t2.sqrt();
        let (s, co) = t.sin_cos();
        (
            (t - s) / (t2 * t),
            (t2 + 2.0 * co - 2.0) / (2.0 * t2 * t2),
            (2.0 * t - 3.0 * s + t * co) / (2.0 * t2 * t2 * t),
        )
    }
}

/// A rigid-body transform: rotation `R` and translation `t` (`x_world = R x_body + t` for a
/// body→world pose).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SE3 {
    /// Rotation part.
    pub r: SO3,
    /// Translation part.
    pub t: Vector3<f64>,
}

#[inline]
fn split(xi: &Vector6<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (xi.fixed_rows::<3>(0).into(), xi.fixed_rows::<3>(3).into())
}

#[inline]
fn join(rho: &Vector3<f64>, theta: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(rho.x, rho.y, rho.z, theta.x, theta.y, theta.z)
}

/// 6×6 block matrix `[[a, b], [0, d]]`.
fn upper_block(a: &Matrix3<f64>, b: &Matrix3<f64>, d: &Matrix3<f64>) -> Matrix6<f64> {
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(a);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(b);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(d);
    m
}

impl SE3 {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            r: SO3::identity(),
            t: Vector3::zeros(),
        }
    }

    /// From rotation and translation.
    pub fn new(r: SO3, t: Vector3<f64>) -> Self {
        Self { r, t }
    }

    /// Homogeneous 4×4 matrix `[[R, t], [0, 1]]`.
    pub fn matrix(&self) -> Matrix4<f64> {
        let mut m = Matrix4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(self.r.matrix());
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.t);
        m
    }

    /// `Exp(ξ)`, ξ = [ρ, θ] (translation first; θ in rad): `(Exp(θ), Jl(θ) ρ)` (Solà eq. 172),
    /// the screw motion that turns by θ while it moves along ρ in the rotating frame.
    ///
    /// ```
    /// use nalgebra::{Vector3, Vector6};
    /// use preint_lie::SE3;
    /// use std::f64::consts::{FRAC_PI_2, PI};
    ///
    /// // θ = 0: a pure translation by ρ.
    /// let t = SE3::exp(&Vector6::new(1.0, 2.0, 3.0, 0.0, 0.0, 0.0));
    /// assert_eq!(t.t, Vector3::new(1.0, 2.0, 3.0));
    /// // A quarter turn about z with ρ = x: t = Jl(θ)ρ = (2/π)(1, 1, 0).
    /// let t = SE3::exp(&Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, FRAC_PI_2));
    /// assert!((t.t - Vector3::new(1.0, 1.0, 0.0) * (2.0 / PI)).norm() < 1e-15);
    /// assert!((t.act(&Vector3::x()) - (t.t + Vector3::y())).norm() < 1e-15);
    /// ```
    #[inline]
    pub fn exp(xi: &Vector6<f64>) -> Self {
        let (rho, theta) = split(xi);
        // One set of coefficients (polynomials in θ² up to π, see `so3`) for both parts:
        // R = I + a θ̂ + b θ̂² (Rodrigues), Jl(θ)ρ = ρ + b θ×ρ + c θ×(θ×ρ).
        let k = so3::RodriguesCoeffs::new(&theta);
        let tr = theta.cross(&rho);
        Self {
            r: SO3::from_matrix_unchecked(so3::i_plus_hat_hat2(&theta, k.a, k.b)),
            t: rho + tr * k.b + theta.cross(&tr) * k.c,
        }
    }

    /// `Log(T) = [Jl⁻¹(θ) t, θ]` with θ = Log(R) (Solà eq. 173), translation first; ‖θ‖ ≤ π.
    ///
    /// ```
    /// use nalgebra::{Vector3, Vector6};
    /// use preint_lie::SE3;
    ///
    /// let xi = Vector6::new(0.5, -1.0, 2.0, 0.3, -0.2, 2.5);
    /// let t = SE3::exp(&xi);
    /// assert!((t.log() - xi).norm() < 1e-14 * xi.norm());
    /// // The rotation part is SO(3)'s Log, bit for bit.
    /// assert_eq!(Vector3::from(t.log().fixed_rows::<3>(3)), t.r.log());
    /// ```
    #[inline]
    pub fn log(&self) -> Vector6<f64> {
        let (theta, theta2) = self.r.log_theta2();
        let d = so3::d_coeff(theta2);
        // Jl⁻¹(θ)t = t − ½ θ×t + D θ×(θ×t).
        let tt = theta.cross(&self.t);
        join(&(self.t - tt * 0.5 + theta.cross(&tt) * d), &theta)
    }

    /// `Log(T)` and its Jacobian `d Log(T ⊕ δ)/dδ = Jr⁻¹(Log T)`.
    pub fn log_jac(&self) -> (Vector6<f64>, Matrix6<f64>) {
        let xi = self.log();
        (xi, jr_inv(&xi))
    }

    /// `Exp(ξ)` and its right Jacobian `Jr(ξ)`.
    pub fn exp_jac(xi: &Vector6<f64>) -> (Self, Matrix6<f64>) {
        (Self::exp(xi), jr(xi))
    }

    /// Inverse `(Rᵀ, −Rᵀ t)`.
    pub fn inverse(&self) -> Self {
        let ri = self.r.inverse();
        Self {
            r: ri,
            t: -(ri.act(&self.t)),
        }
    }

    /// Inverse with Jacobian `−Ad(T)`.
    pub fn inverse_jac(&self) -> (Self, Matrix6<f64>) {
        (self.inverse(), -self.adjoint())
    }

    /// Composition `T₁·T₂ = (R₁R₂, R₁t₂ + t₁)`.
    pub fn compose(&self, o: &Self) -> Self {
        Self {
            r: self.r.compose(&o.r),
            t: self.r.act(&o.t) + self.t,
        }
    }

    /// `T₁·T₂` with Jacobians `Ad(T₂)⁻¹` and `I` (Solà eqs. 159–160).
    pub fn compose_jac(&self, o: &Self) -> (Self, Matrix6<f64>, Matrix6<f64>) {
        (self.compose(o), o.inverse().adjoint(), Matrix6::identity())
    }

    /// Transforms a point: `R x + t`.
    pub fn act(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.r.act(x) + self.t
    }

    /// `R x + t` with Jacobians `d/dT = [R, −R[x]×]` (3×6, order [ρ, θ]) and `d/dx = R`
    /// (Solà eq. 181).
    pub fn act_jac(
        &self,
        x: &Vector3<f64>,
    ) -> (Vector3<f64>, nalgebra::Matrix3x6<f64>, Matrix3<f64>) {
        let r = self.r.matrix();
        let mut j = nalgebra::Matrix3x6::zeros();
        j.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
        j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r * hat(x)));
        (self.act(x), j, *r)
    }

    /// Adjoint `Ad(T) = [[R, [t]×R], [0, R]]` for ξ = [ρ, θ] (Solà eq. 178):
    /// `T·Exp(ξ) = Exp(Ad(T) ξ)·T`.
    pub fn adjoint(&self) -> Matrix6<f64> {
        let r = self.r.matrix();
        upper_block(r, &(hat(&self.t) * r), r)
    }

    /// Right-plus `T ⊕ ξ = T·Exp(ξ)`.
    pub fn plus(&self, xi: &Vector6<f64>) -> Self {
        self.compose(&Self::exp(xi))
    }

    /// Right-minus `S ⊖ T = Log(T⁻¹ S)` (`self` is S).
    pub fn minus(&self, t: &Self) -> Vector6<f64> {
        t.inverse().compose(self).log()
    }
}

/// se(3) hat: `[[θ̂, ρ], [0, 0]]` for ξ = [ρ, θ].
pub fn hat6(xi: &Vector6<f64>) -> Matrix4<f64> {
    let (rho, theta) = split(xi);
    let mut m = Matrix4::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&hat(&theta));
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&rho);
    m
}

/// se(3) vee, inverse of [`hat6`] (reads the antisymmetric part of the rotation block).
pub fn vee6(m: &Matrix4<f64>) -> Vector6<f64> {
    let rho = Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
    let theta = so3::vee(&m.fixed_view::<3, 3>(0, 0).into_owned());
    join(&rho, &theta)
}

/// Left Jacobian of SE(3): `Jl(ξ) = [[Jl(θ), Q(ρ, θ)], [0, Jl(θ)]]` (Solà eq. 179).
pub fn jl(xi: &Vector6<f64>) -> Matrix6<f64> {
    let (rho, theta) = split(xi);
    let j = so3::jl(&theta);
    upper_block(&j, &q_block(&rho, &theta), &j)
}

/// Right Jacobian of SE(3): `Jr(ξ) = Jl(−ξ)`: `Exp(ξ + δ) ≈ Exp(ξ)·Exp(Jr(ξ) δ)`.
///
/// ```
/// use nalgebra::{Matrix6, Vector6};
/// use preint_lie::{SE3, se3};
///
/// let xi = Vector6::new(0.5, -1.0, 2.0, 0.3, -0.2, 1.5);
/// assert!((se3::jr(&xi) * se3::jr_inv(&xi) - Matrix6::identity()).amax() < 1e-14);
/// let d = Vector6::new(1e-6, 2e-6, -1e-6, -2e-6, 1e-6, 1.5e-6);
/// let linear = SE3::exp(&xi).compose(&SE3::exp(&(se3::jr(&xi) * d)));
/// assert!(SE3::exp(&(xi + d)).minus(&linear).norm() < 1e-11);
/// ```
pub fn jr(xi: &Vector6<f64>) -> Matrix6<f64> {
    jl(&-xi)
}

/// Inverse left Jacobian: `[[Jl⁻¹, −Jl⁻¹ Q Jl⁻¹], [0, Jl⁻¹]]`.
pub fn jl_inv(xi: &Vector6<f64>) -> Matrix6<f64> {
    let (rho, theta) = split(xi);
    let ji = so3::jl_inv(&theta);
    upper_block(&ji, &(-ji * q_block(&rho, &theta) * ji), &ji)
}

/// Inverse right Jacobian: `Jr⁻¹(ξ) = Jl⁻¹(−ξ)`.
pub fn jr_inv(xi: &Vector6<f64>) -> Matrix6<f64> {
    jl_inv(&-xi)
}
