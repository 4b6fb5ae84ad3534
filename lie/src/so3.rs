//! SO(3), the group of 3-D rotations, stored as a rotation matrix.
//!
//! Conventions (Solà, Deray, Atchuthan 2018, "A micro Lie theory", §§ 4–5 and App. B):
//! - `Exp(φ) = I + (sin θ/θ)[φ]× + ((1 − cos θ)/θ²)[φ]×²`, θ = ‖φ‖ (Rodrigues, Solà eq. 77).
//! - Perturbations are on the **right** (body side): `R ⊕ δ = R·Exp(δ)`, `S ⊖ R = Log(Rᵀ S)`.
//! - Right Jacobian `Jr(φ)`: `Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ) δ)` (Solà eq. 143);
//!   left Jacobian `Jl(φ) = Jr(−φ) = Jr(φ)ᵀ`: `Exp(φ + δ) ≈ Exp(Jl(φ) δ)·Exp(φ)` (eq. 145).
//!
//! Numerics. `a = sin θ/θ`, `b = (1 − cos θ)/θ²`, `c = (θ − sin θ)/θ³` and Jr⁻¹'s
//! `D = 1/θ² − (1 + cos θ)/(2θ sin θ)` are even in θ, so they are computed from θ² = φᵀφ
//! without a square root, on three branches:
//! - θ < 0.1 (every per-sample IMU angle): five-term Taylor series in θ² (truncation < 3e-18),
//!   by Estrin's scheme with c₀ added last (three dependent multiply-add levels, not four).
//! - 0.1 ≤ θ ≤ π: polynomials in θ² (Chebyshev interpolants from `lie/tools/fit_poly.py`;
//!   degree 9, D degree 14), with the zero of `a` at θ = π factored out,
//!   `a = (π² − θ²)·qa(θ²)`, so that `a` keeps its relative precision up to π. No sqrt, no
//!   `sin_cos`, no division: no dependent sqrt → sin_cos → division chain as in the closed
//!   forms.
//! - θ > π: closed form with one `sqrt` and one `f64::sin_cos`; there `cos θ < 0`, so
//!   `1 − cos θ`, `θ − sin θ` and `1 − (θ/2)cot(θ/2)` do not cancel.
//!
//! Measured relative errors against 60-digit mpmath values at √(exact f64 θ²) for 473 angles in
//! [1e-8, 5.5] (`tests/so3.rs`, `coefficients_within_a_few_eps_on_dense_angles`; ε = 2⁻⁵²):
//! series ≤ 0.7 ε; polynomials a ≤ 1.8 ε, b ≤ 1.2 ε, c ≤ 0.9 ε, D ≤ 0.8 ε (20 000 points in
//! `fit_poly.py`); closed form ≤ 1.9 ε. (Below π, D's closed form would cancel up to ~6 bits
//! near θ = ½: 29 ε measured there.) Above π, `a` computed from θ² is only as precise
//! as θ = √θ²: its relative error grows as |θ cot θ − 1|·ε/2 near 2π (and within ~1e-5 rad
//! above π); `a·θ = sin θ` stays within a few ε absolute.
//! `Log` reads sin θ·n from the antisymmetric part and cos θ from the trace, on five branches:
//! an eight-term arcsine series for sin θ < 0.1; up to θ = π/3 the half angle,
//! `u = tan²(θ/2) = sin²θ/(1 + cos θ)²` and a degree-14 polynomial for `atan(√u)/√u` (one
//! division, no sqrt or `atan2`); up to 2π/3 `π/2 − atan(cot θ)` with the same polynomial; up
//! to cos θ = −0.9 `atan2` (sqrt, one division in `atan2`, one after); and near π Shepperd's
//! quaternion extraction. So it is exact near θ = 0 and at θ = π, where a formula that divides
//! by `sin θ` fails, and a slightly drifted R costs it nothing extra. Measured Log(Exp φ)
//! relative errors (`tests/so3.rs`, 200 000 angles): series 1.4 ε, half angle 2.6 ε, cotangent
//! 2.2 ε, atan2 2.1 ε, Shepperd 1.7 ε.
//!
//! The coefficient kernels (`exp_coeffs`, `jac_coeffs`, `d_coeff`, `exp_quat_coeffs`,
//! `RodriguesCoeffs`, …) are public for `preint`'s per-sample fast paths but hidden from these
//! docs: they are not part of the supported API.

mod coeffs;
mod quat;

pub(crate) use coeffs::horner;
use coeffs::{ATAN_MID, ATAN_POLY, PIO2_HI, PIO2_LO, poly15};
#[doc(hidden)]
pub use coeffs::{
    EXP_QUAT_SERIES, EXP_QUAT_SERIES_BELOW, RodriguesCoeffs, d_coeff, exp_coeffs, exp_quat_coeffs,
    i_plus_hat_hat2, jac_coeffs,
};
use nalgebra::{Matrix3, Vector3};
use quat::{log_quaternion, shepperd};

/// Skew-symmetric matrix `[v]×` with `[v]× w = v × w` (the hat operator of so(3)).
#[inline]
pub fn hat(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Inverse of [`hat`]: the vector of a skew-symmetric matrix. Only the antisymmetric part of
/// `m` is read: `vee(m) = ½ (m − mᵀ)∨`.
#[inline]
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// Right Jacobian of SO(3): `Jr(φ) = I − b[φ]× + c[φ]×²` (Solà eq. 143), with
/// `b = (1 − cos θ)/θ²`, `c = (θ − sin θ)/θ³`: `Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ) δ)`.
///
/// ```
/// use nalgebra::Vector3;
/// use preint_lie::{SO3, jr};
///
/// let phi = Vector3::new(0.4, -1.1, 0.8);
/// let d = Vector3::new(1e-6, -2e-6, 1.5e-6);
/// let exact = SO3::exp(&(phi + d));
/// // First order in δ: the error left is O(|δ|²) ≈ 1e-12 …
/// let linear = SO3::exp(&phi) * SO3::exp(&(jr(&phi) * d));
/// assert!(exact.minus(&linear).norm() < 1e-11);
/// // … where ignoring Jr leaves O(|φ||δ|).
/// let naive = SO3::exp(&phi) * SO3::exp(&d);
/// assert!(exact.minus(&naive).norm() > 1e-7);
/// ```
#[inline]
pub fn jr(phi: &Vector3<f64>) -> Matrix3<f64> {
    let (b, c) = jac_coeffs(phi.norm_squared());
    i_plus_hat_hat2(phi, -b, c)
}

/// Inverse right Jacobian: `Jr⁻¹(φ) = I + ½[φ]× + D[φ]×²` (Solà eq. 144), with
/// `D = 1/θ² − (1 + cos θ)/(2θ sin θ)`, valid for θ < 2π: `Log(Exp(φ)·Exp(δ)) ≈ φ + Jr⁻¹(φ) δ`.
///
/// ```
/// use nalgebra::{Matrix3, Vector3};
/// use preint_lie::{SO3, jr, jr_inv};
///
/// let phi = Vector3::new(0.4, -1.1, 0.8);
/// assert!((jr(&phi) * jr_inv(&phi) - Matrix3::identity()).amax() < 1e-15);
/// let d = Vector3::new(1e-6, -2e-6, 1.5e-6);
/// let log = (SO3::exp(&phi) * SO3::exp(&d)).log();
/// assert!((log - (phi + jr_inv(&phi) * d)).norm() < 1e-11);
/// ```
#[inline]
pub fn jr_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    i_plus_hat_hat2(phi, 0.5, d_coeff(phi.norm_squared()))
}

/// Left Jacobian: `Jl(φ) = Jr(−φ) = I + b[φ]× + c[φ]×²` (Solà eq. 145):
/// `Exp(φ + δ) ≈ Exp(Jl(φ) δ)·Exp(φ)`. For SO(3) also `Jl = Jrᵀ = R·Jr`, R = Exp(φ).
///
/// ```
/// use nalgebra::Vector3;
/// use preint_lie::{SO3, jl, jr};
///
/// let phi = Vector3::new(0.4, -1.1, 0.8);
/// assert!((jl(&phi) - jr(&phi).transpose()).amax() < 1e-15);
/// assert!((jl(&phi) - SO3::exp(&phi).matrix() * jr(&phi)).amax() < 1e-15);
/// let d = Vector3::new(1e-6, -2e-6, 1.5e-6);
/// let linear = SO3::exp(&(jl(&phi) * d)) * SO3::exp(&phi);
/// assert!(SO3::exp(&(phi + d)).minus(&linear).norm() < 1e-11);
/// ```
#[inline]
pub fn jl(phi: &Vector3<f64>) -> Matrix3<f64> {
    jr(&-phi)
}

/// Inverse left Jacobian: `Jl⁻¹(φ) = I − ½[φ]× + D[φ]×²` (Solà eq. 146), valid for θ < 2π:
/// `Log(Exp(δ)·Exp(φ)) ≈ φ + Jl⁻¹(φ) δ`.
///
/// ```
/// use nalgebra::{Matrix3, Vector3};
/// use preint_lie::{jl, jl_inv};
///
/// let phi = Vector3::new(0.4, -1.1, 0.8);
/// assert!((jl(&phi) * jl_inv(&phi) - Matrix3::identity()).amax() < 1e-15);
/// ```
#[inline]
pub fn jl_inv(phi: &Vector3<f64>) -> Matrix3<f64> {
    jr_inv(&-phi)
}

/// A rotation in SO(3), stored as the rotation matrix `R` (for a body→world attitude,
/// `v_world = R v_body`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SO3 {
    m: Matrix3<f64>,
}

impl Default for SO3 {
    fn default() -> Self {
        Self::identity()
    }
}

impl SO3 {
    /// The identity rotation.
    #[inline]
    pub fn identity() -> Self {
        Self {
            m: Matrix3::identity(),
        }
    }

    /// Wraps a matrix that the caller guarantees is a rotation (orthonormal, det +1).
    /// Use [`SO3::from_matrix`] when it may have drifted.
    #[inline]
    pub fn from_matrix_unchecked(m: Matrix3<f64>) -> Self {
        Self { m }
    }

    /// The nearest rotation (Frobenius norm) to `m`: the rotation `R` with `RᵀM` symmetric
    /// (and, for `det M > 0`, positive definite: the polar factor), determinant forced to +1
    /// (for `det M < 0` the sign of the smallest singular direction is flipped). Use it to
    /// re-orthonormalise a drifted matrix.
    ///
    /// Computed by SVD, then refined by Newton steps on the optimality condition, because
    /// nalgebra 0.33's 3×3 SVD leaves `U Σ Vᵀ − M` up to ~4e-12 when two singular values are
    /// close (measured), which puts `U Vᵀ` that far from the polar factor. With `P = R₀ᵀM`,
    /// `S = sym(P)`, the first-order condition `skew(Exp(−δ)P) = 0` gives
    /// `δ = 2 ((tr S) I − S)⁻¹ vee(P)` and `R = R₀ Exp(δ)`; the error then drops quadratically
    /// (to ~1e-15, tests/so3.rs). If that linear system is singular (two smallest singular
    /// values equal for `det M < 0`: the nearest rotation is not unique) the SVD result is kept.
    pub fn from_matrix(m: &Matrix3<f64>) -> Self {
        let svd = m.svd(true, true);
        let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
        let mut r = u * vt;
        if r.determinant() < 0.0 {
            let mut u2 = u;
            u2.column_mut(2).neg_mut();
            r = u2 * vt;
        }
        let mut out = Self { m: r };
        for _ in 0..2 {
            let p = out.m.transpose() * m;
            let s = (p + p.transpose()) * 0.5;
            let a = Matrix3::from_diagonal_element(s.trace()) - s;
            let Some(delta) = a.lu().solve(&(vee(&p) * 2.0)) else {
                break;
            };
            if !(delta.iter().all(|x| x.is_finite()) && delta.norm() < 0.1) {
                break;
            }
            out = out.compose(&Self::exp(&delta));
        }
        out
    }

    /// The rotation matrix.
    #[inline]
    pub fn matrix(&self) -> &Matrix3<f64> {
        &self.m
    }

    /// Exponential map `Exp(φ)` of a rotation vector φ (rad), Rodrigues' formula (Solà eq. 77):
    /// the rotation by θ = ‖φ‖ about φ/θ. Any φ is accepted (θ > π wraps around).
    /// Like any rounded rotation matrix, an entry may exceed 1 in magnitude by an ulp or two
    /// (`Exp((0, π/2, 0))[(2, 0)]` is −1 − 2⁻⁵²): clamp before `asin`/`acos`.
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use preint_lie::SO3;
    /// use std::f64::consts::FRAC_PI_2;
    ///
    /// // A quarter turn about z takes x to y.
    /// let r = SO3::exp(&Vector3::new(0.0, 0.0, FRAC_PI_2));
    /// assert!((r.act(&Vector3::x()) - Vector3::y()).norm() < 1e-15);
    /// assert!(r.orthonormality_error() < 1e-15);
    /// // Tiny angles keep their relative precision.
    /// assert_eq!(SO3::exp(&Vector3::new(1e-300, 0.0, 0.0)).matrix()[(2, 1)], 1e-300);
    /// ```
    #[inline]
    pub fn exp(phi: &Vector3<f64>) -> Self {
        let (a, b) = exp_coeffs(phi.norm_squared());
        Self {
            m: i_plus_hat_hat2(phi, a, b),
        }
    }

    /// `Exp(φ)` and its right Jacobian `Jr(φ)` sharing one set of coefficients.
    #[inline]
    pub fn exp_jr(phi: &Vector3<f64>) -> (Self, Matrix3<f64>) {
        let k = RodriguesCoeffs::new(phi);
        (
            Self {
                m: i_plus_hat_hat2(phi, k.a, k.b),
            },
            i_plus_hat_hat2(phi, -k.b, k.c),
        )
    }

    /// Logarithmic map `Log(R)`: the rotation vector φ (rad) with ‖φ‖ ∈ [0, π] and
    /// `Exp(φ) = R`, computed on the branches of the module docs. At exactly θ = π either of
    /// the two opposite vectors may be returned.
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use preint_lie::SO3;
    /// use std::f64::consts::PI;
    ///
    /// let phi = Vector3::new(0.3, -2.0, 1.5); // θ ≈ 2.52 rad
    /// assert!((SO3::exp(&phi).log() - phi).norm() < 1e-14 * phi.norm());
    /// // Angles above π come back as the equivalent rotation with θ ≤ π.
    /// let wrapped = SO3::exp(&Vector3::new(0.0, 0.0, 1.5 * PI)).log();
    /// assert!((wrapped - Vector3::new(0.0, 0.0, -0.5 * PI)).norm() < 1e-15);
    /// // At θ = π: one of ±π·n.
    /// assert!((SO3::exp(&Vector3::new(PI, 0.0, 0.0)).log().norm() - PI).abs() < 1e-15);
    /// ```
    #[inline]
    pub fn log(&self) -> Vector3<f64> {
        self.log_theta2().0
    }

    /// `Log(R)` and θ² = ‖Log R‖², on the `atan2` branch as `θ·θ`, so that a caller that needs
    /// a coefficient of θ² (SE(3)'s `Log`, for D) can start on it before φ is formed.
    #[inline(always)]
    pub(crate) fn log_theta2(&self) -> (Vector3<f64>, f64) {
        let m = &self.m;
        // two_s = 2 sin θ·n (antisymmetric part), two_c = 2 cos θ: the factors ½ are left out
        // (a power of two, so every result below is bit for bit what it would be with them).
        let two_s = Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        );
        let two_c = m[(0, 0)] + m[(1, 1)] + m[(2, 2)] - 1.0;
        let four_s2 = two_s.norm_squared(); // 4 sin²θ
        if two_c > 0.0 && four_s2 < 0.04 {
            // θ < 0.1: θ/sin θ = asin(σ)/σ = Σ (2k)!/(4^k (k!)² (2k+1)) σ^{2k}, σ = sin θ;
            // eight terms leave < 1.2e-18 (`ASIN_SERIES`).
            let phi = (two_s * 0.5) * horner(0.25 * four_s2, &ASIN_SERIES);
            (phi, phi.norm_squared())
        } else if two_c >= 1.0 {
            // θ ≤ π/3: the half angle, without sqrt or atan2. tan(θ/2) = sin θ/(1 + cos θ), so
            // u = tan²(θ/2) = 4 sin²θ/(2 + 2cos θ)² ≤ 1/3 and θ = 2 tan(θ/2) A(u) with
            // A(u) = atan(√u)/√u (a polynomial): θ/(2 sin θ) = 2A(u)/(2 + 2cos θ). One
            // division, where atan2 needs sqrt → division → polynomial → division. Both parts
            // of R enter, as in atan2, and with about the same conditioning here
            // (|∂θ/∂cos θ| = tan(θ/2), |∂θ/∂sin θ| = 1; atan2's sin θ and |cos θ|). Above π/3 the
            // polynomial would need many more terms.
            let iv = 1.0 / (2.0 + two_c);
            let u = four_s2 * (iv * iv);
            let at = poly15(u - ATAN_MID, &ATAN_POLY);
            (two_s * (2.0 * at * iv), 4.0 * u * (at * at))
        } else if two_c > -1.0 {
            // π/3 < θ < 2π/3: θ = π/2 − atan(cot θ) with |cot θ| < 1/√3, so the same
            // polynomial, A(r²) for r = cos θ/sin θ, gives the angle: atan2's own reduction
            // for this range (conditioning as atan2's), without its case selection and table.
            // Two divisions by 2 sin θ, not one reciprocal and two products: the reciprocal's
            // rounding would add 0.3 ε and a quarter to the round-trip error of drifted
            // matrices.
            let two_sn = four_s2.sqrt();
            let r = two_c / two_sn;
            let theta = PIO2_HI - (r * poly15(r * r - ATAN_MID, &ATAN_POLY) - PIO2_LO);
            (two_s * (theta / two_sn), theta * theta)
        } else if two_c > -1.8 {
            // θ < 2.69: sin θ ≥ 0.43, so two_s carries full relative precision. atan2 is
            // invariant under the common factor 2, and θ/(2 sin θ)·(2 sin θ·n) = θ n.
            let two_sn = four_s2.sqrt();
            let theta = two_sn.atan2(two_c);
            (two_s * (theta / two_sn), theta * theta)
        } else {
            // Near π the antisymmetric part vanishes: extract the axis from the diagonal.
            let q = shepperd(m);
            let phi = log_quaternion(q.w, &q.imag());
            (phi, phi.norm_squared())
        }
    }

    /// `Log(R)` and its Jacobian `d Log(R ⊕ δ)/dδ = Jr⁻¹(Log R)`.
    pub fn log_jac(&self) -> (Vector3<f64>, Matrix3<f64>) {
        let phi = self.log();
        (phi, jr_inv(&phi))
    }

    /// Inverse `R⁻¹ = Rᵀ`.
    #[inline]
    pub fn inverse(&self) -> Self {
        Self {
            m: self.m.transpose(),
        }
    }

    /// Inverse and its Jacobian `d(R⁻¹)/dR = −Ad(R) = −R` (Solà eq. 155).
    #[inline]
    pub fn inverse_jac(&self) -> (Self, Matrix3<f64>) {
        (self.inverse(), -self.m)
    }

    /// Composition `R·S`.
    #[inline]
    pub fn compose(&self, other: &Self) -> Self {
        Self {
            m: self.m * other.m,
        }
    }

    /// `R·S` with Jacobians `d(RS)/dR = Sᵀ` and `d(RS)/dS = I` (Solà eqs. 159–160).
    #[inline]
    pub fn compose_jac(&self, other: &Self) -> (Self, Matrix3<f64>, Matrix3<f64>) {
        (
            self.compose(other),
            other.m.transpose(),
            Matrix3::identity(),
        )
    }

    /// Rotates a vector: `R v`.
    #[inline]
    pub fn act(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.m * v
    }

    /// `R v` with Jacobians `d(Rv)/dR = −R[v]×` and `d(Rv)/dv = R` (Solà eqs. 167–168).
    #[inline]
    pub fn act_jac(&self, v: &Vector3<f64>) -> (Vector3<f64>, Matrix3<f64>, Matrix3<f64>) {
        (self.m * v, -self.m * hat(v), self.m)
    }

    /// Adjoint `Ad(R) = R`: `R·Exp(δ) = Exp(Ad(R) δ)·R`.
    #[inline]
    pub fn adjoint(&self) -> Matrix3<f64> {
        self.m
    }

    /// Right-plus `R ⊕ δ = R·Exp(δ)`.
    #[inline]
    pub fn plus(&self, delta: &Vector3<f64>) -> Self {
        self.compose(&Self::exp(delta))
    }

    /// Right-minus `S ⊖ R = Log(Rᵀ S)` (`self` is S).
    #[inline]
    pub fn minus(&self, r: &Self) -> Vector3<f64> {
        r.inverse().compose(self).log()
    }

    /// Re-orthonormalises a drifted rotation matrix by the polar decomposition.
    pub fn normalized(&self) -> Self {
        Self::from_matrix(&self.m)
    }

    /// Largest absolute entry of `RᵀR − I`: how far the stored matrix is from orthonormal.
    pub fn orthonormality_error(&self) -> f64 {
        (self.m.transpose() * self.m - Matrix3::identity()).amax()
    }
}

impl core::ops::Mul for SO3 {
    type Output = SO3;
    #[inline]
    fn mul(self, rhs: SO3) -> SO3 {
        self.compose(&rhs)
    }
}

impl core::ops::Mul<Vector3<f64>> for SO3 {
    type Output = Vector3<f64>;
    #[inline]
    fn mul(self, rhs: Vector3<f64>) -> Vector3<f64> {
        self.act(&rhs)
    }
}

/// asin(σ)/σ = Σ_k (2k)!/(4^k (k!)² (2k+1)) σ^{2k} (the arcsine series, DLMF 4.24.1), eight
/// terms: for σ < 0.1 the first omitted term, (6435/557056) σ¹⁶, is < 1.2e-18. (Six terms
/// would leave (231/13312) σ¹² ≈ 1.7e-14 relative at σ = 0.1, 78 ε.)
const ASIN_SERIES: [f64; 8] = [
    1.0,
    1.0 / 6.0,
    3.0 / 40.0,
    5.0 / 112.0,
    35.0 / 1152.0,
    63.0 / 2816.0,
    231.0 / 13312.0,
    143.0 / 10240.0,
];
