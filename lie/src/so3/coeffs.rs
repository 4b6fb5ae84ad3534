//! The scalar coefficients of SO(3)'s `Exp`, `Log` and Jacobians, and the polynomial
//! evaluation they share (see the numerics notes of [`super`]).
//!
//! The `pub` items here ([`RodriguesCoeffs`], [`exp_coeffs`], [`jac_coeffs`], [`d_coeff`],
//! [`exp_quat_coeffs`], [`EXP_QUAT_SERIES`], [`EXP_QUAT_SERIES_BELOW`], [`i_plus_hat_hat2`])
//! are re-exported from `so3` with `#[doc(hidden)]`: they are kernels, not API. They are
//! public because `preint` builds its per-sample rotation steps from them (several angles in
//! SIMD lanes, one coefficient set shared by `Exp` and `Jr`), and must round exactly as
//! [`super::SO3::exp`] and [`super::jr`] do; the mpmath coefficient tests in `tests/so3.rs`
//! call them too. Their signatures may change with `preint`'s needs.

use nalgebra::{Matrix3, Vector3};

/// Horner evaluation of Σ c_k x^k. Plain multiply-add, not `f64::mul_add`: on the portable
/// x86-64 target (no FMA) `mul_add` is a call into libm's software `fma`.
/// Starts from the last coefficient: the compiler cannot drop a leading `0·x + c` (it is not
/// `c` for infinite x), which would add a multiply and an add to every series' latency.
#[inline(always)]
pub(crate) fn horner(x: f64, c: &[f64]) -> f64 {
    let (&last, rest) = c.split_last().expect("at least one coefficient");
    let mut acc = last;
    for &ck in rest.iter().rev() {
        acc = acc * x + ck;
    }
    acc
}

// Taylor coefficients in θ², for θ < 0.1 (the first omitted term, θ¹⁰/11!, is < 3e-18 relative).
// A = sin θ/θ = Σ (−1)^k θ^{2k}/(2k+1)!
const A_SERIES: [f64; 5] = [1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0];
// B = (1 − cos θ)/θ² = Σ (−1)^k θ^{2k}/(2k+2)!
const B_SERIES: [f64; 5] = [
    1.0 / 2.0,
    -1.0 / 24.0,
    1.0 / 720.0,
    -1.0 / 40320.0,
    1.0 / 3628800.0,
];
// C = (θ − sin θ)/θ³ = Σ (−1)^k θ^{2k}/(2k+3)!
const C_SERIES: [f64; 5] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5040.0,
    -1.0 / 362880.0,
    1.0 / 39916800.0,
];
// D = 1/θ² − (1 + cos θ)/(2 θ sin θ) = (1 − (θ/2) cot(θ/2))/θ², from x cot x = Σ (−1)^k B_2k (2x)^{2k}/(2k)!
// (Bernoulli numbers): D = 1/12 + θ²/720 + θ⁴/30240 + θ⁶/1209600 + θ⁸/47900160 + …
const D_SERIES: [f64; 5] = [
    1.0 / 12.0,
    1.0 / 720.0,
    1.0 / 30240.0,
    1.0 / 1209600.0,
    1.0 / 47900160.0,
];

// Polynomials in x = θ² − POLY_MID for 0.1 ≤ θ ≤ π (θ² from 0.01 to fl(π²)), printed by
// `lie/tools/fit_poly.py`: degree-9 Chebyshev interpolants of b(θ²), c(θ²) and
// qa = a/(π² − θ²) (the zero of a = sin θ/θ at π factored out, so that a keeps its relative
// precision up to π). No sqrt, sin_cos or division: the coefficients are even functions of θ.
const PI2_HI: f64 = 9.869604401089358;
const PI2_LO: f64 = 6.265295508739711e-16;
const POLY_MID: f64 = 4.939802200544679;
// max relative error (f64, evaluated as `poly` does, 20 000 points): 1.77 eps
const QA_POLY: [f64; 10] = [
    0.07255861482888722,
    -0.005080515305618535,
    0.00013938014007554343,
    -2.093986086069455e-06,
    2.001125994500491e-08,
    -1.327903457655872e-10,
    6.485727767456568e-13,
    -2.4311397689370836e-15,
    7.220343740581226e-18,
    -1.74040675166308e-20,
];
// max relative error (f64, evaluated as `poly` does, 20 000 points): 1.20 eps
const B_POLY: [f64; 10] = [
    0.325234627025735,
    -0.02963374069585886,
    0.001059273811545564,
    -1.9839223600678132e-05,
    2.280129636119179e-07,
    -1.7711639676555208e-09,
    9.9207323606325e-12,
    -4.197082468679499e-14,
    1.3891290049771992e-16,
    -3.6927146049886227e-19,
];
// max relative error (f64, evaluated as `poly` does, 20 000 points): 0.84 eps
const C_POLY: [f64; 10] = [
    0.1300255263008822,
    -0.006563213388358138,
    0.00016105534780223158,
    -2.2981224856374353e-06,
    2.135406276949112e-08,
    -1.3931178978058103e-10,
    6.729233137764263e-13,
    -2.5032376492055595e-15,
    7.393823231039694e-18,
    -1.7749876727227043e-20,
];

// D(√t), max relative error (f64, Horner, 20 000 points): 0.77 eps
const D_POLY: [f64; 15] = [
    0.09111496204096993,
    0.0017880308159743674,
    4.915841641790693e-05,
    1.4092343199307815e-06,
    4.071593448353104e-08,
    1.1783068314499603e-09,
    3.4112108292146564e-11,
    9.876280216252141e-13,
    2.859474354775627e-14,
    8.279379908303351e-16,
    2.397136539570888e-17,
    6.922953512529858e-19,
    2.0044096549007404e-20,
    6.283426883727e-22,
    1.81924689401072e-23,
];

// π/2 as hi + lo (hi = fl(π/2)).
pub(super) const PIO2_HI: f64 = std::f64::consts::FRAC_PI_2;
pub(super) const PIO2_LO: f64 = 6.123233995736766e-17;
// Log's half-angle kernel A(u) = atan(√u)/√u for u = tan²(θ/2) ≤ 0.34 (θ ≤ π/3 is u ≤ 1/3),
// printed by `lie/tools/fit_poly.py` (degree-14 Chebyshev interpolant in x = u − ATAN_MID,
// evaluated by `poly15`).
pub(super) const ATAN_MID: f64 = 0.17;
// max relative error 0.50 eps
pub(super) const ATAN_POLY: [f64; 15] = [
    0.9484929883111662,
    -0.27585921650091644,
    0.14274132128879077,
    -0.08758436275597166,
    0.0584121257786962,
    -0.040939988067047586,
    0.029657488612760626,
    -0.021996623804789492,
    0.01660552729737929,
    -0.012709578281196083,
    0.009835038637988763,
    -0.00766411548525781,
    0.006029183326723882,
    -0.005127493184297567,
    0.0040842603736525795,
];

/// Two tables interleaved, `[[p_k, q_k]]`, for [`poly2`].
const fn zip(p: &[f64; 10], q: &[f64; 10]) -> [[f64; 2]; 10] {
    let mut out = [[0.0; 2]; 10];
    let mut k = 0;
    while k < 10 {
        out[k] = [p[k], q[k]];
        k += 1;
    }
    out
}
/// `(qa, b)`, Exp's pair.
const QA_B_POLY: [[f64; 2]; 10] = zip(&QA_POLY, &B_POLY);
/// `(b, c)`, the Jacobians' pair.
const B_C_POLY: [[f64; 2]; 10] = zip(&B_POLY, &C_POLY);

/// Two degree-9 polynomials at the same `x`: the tail `c₂ + c₃x + … + c₉x⁷` by Estrin's scheme
/// (three levels of independent multiply-adds), then two Horner steps for `c₁` and `c₀`, which
/// carry the rounding that matters (as accurate as full Horner; `fit_poly.py` prints the errors
/// of this order of evaluation) on a dependency chain of 5 multiply-adds instead of 9. Both polynomials share one
/// SSE2 register on x86-64 (`mulpd`/`addpd`), and each lane is rounded exactly as the scalar
/// fallback rounds it.
#[inline(always)]
fn poly2(x: f64, c: &[[f64; 2]; 10]) -> [f64; 2] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_add_pd, _mm_loadu_pd, _mm_mul_pd, _mm_set1_pd, _mm_storeu_pd};
        // SAFETY: SSE2 is part of the x86-64 baseline; every load and the store touch the two
        // f64 of a `[f64; 2]`.
        unsafe {
            let k = |i: usize| _mm_loadu_pd(c[i].as_ptr());
            let madd = |a, b, x| _mm_add_pd(_mm_mul_pd(b, x), a);
            let x1 = _mm_set1_pd(x);
            let x2 = _mm_mul_pd(x1, x1);
            let x4 = _mm_mul_pd(x2, x2);
            let (p0, p1) = (madd(k(2), k(3), x1), madd(k(4), k(5), x1));
            let (p2, p3) = (madd(k(6), k(7), x1), madd(k(8), k(9), x1));
            let tail = madd(madd(p0, p1, x2), madd(p2, p3, x2), x4);
            let acc = madd(k(0), madd(k(1), tail, x1), x1);
            let mut out = [0.0; 2];
            _mm_storeu_pd(out.as_mut_ptr(), acc);
            out
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let lane = |j: usize| poly(x, &std::array::from_fn(|i| c[i][j]));
        [lane(0), lane(1)]
    }
}

/// The degree-14 `D_POLY`: Estrin for `c₁…c₁₄` (four levels), then one Horner step for `c₀`
/// (0.82 ε at `fit_poly.py`'s points, against 0.77 ε for full Horner, on a chain of 5
/// multiply-adds instead of 14: SE(3)'s `Log` waits for it).
#[inline(always)]
pub(super) fn poly15(x: f64, c: &[f64; 15]) -> f64 {
    let (x2, p) = (x * x, |i: usize| c[i] + c[i + 1] * x);
    let (x4, x8) = (x2 * x2, (x2 * x2) * (x2 * x2));
    let (q0, q1) = (p(1) + p(3) * x2, p(5) + p(7) * x2);
    let (q2, q3) = (p(9) + p(11) * x2, p(13));
    let tail = (q0 + q1 * x4) + (q2 + q3 * x4) * x8;
    tail * x + c[0]
}

/// One polynomial by the scheme of [`poly2`].
#[inline(always)]
fn poly(x: f64, c: &[f64; 10]) -> f64 {
    let (x2, p) = (x * x, |i: usize| c[i] + c[i + 1] * x);
    let tail = (p(2) + p(4) * x2) + (p(6) + p(8) * x2) * (x2 * x2);
    (tail * x + c[1]) * x + c[0]
}

/// `a = sin θ/θ` on the polynomial branch from `qa(θ²)`: `(π² − θ²)·qa` with π² in two parts.
#[inline(always)]
fn a_from_qa(theta2: f64, qa: f64) -> f64 {
    ((PI2_HI - theta2) + PI2_LO) * qa
}

/// The scalar coefficients of Rodrigues' formula and of the SO(3) Jacobians at angle θ:
/// `a = sin θ/θ`, `b = (1 − cos θ)/θ²`, `c = (θ − sin θ)/θ³`.
#[derive(Clone, Copy, Debug)]
pub struct RodriguesCoeffs {
    /// sin θ / θ
    pub a: f64,
    /// (1 − cos θ) / θ²
    pub b: f64,
    /// (θ − sin θ) / θ³
    pub c: f64,
}

/// Below θ = 0.1 five Taylor terms already leave < 3e-18 relative truncation error
/// (θ¹⁰/11!); per-sample IMU angles live here.
const SHORT_SERIES_BELOW: f64 = 0.1;

/// `(sin θ/θ, (1 − cos θ)/θ²)` at θ² \[rad²\]: the two coefficients Exp needs.
#[inline]
pub fn exp_coeffs(theta2: f64) -> (f64, f64) {
    // Series and polynomial inline (no sqrt, sin_cos or division); θ > π out of line.
    if theta2 < SHORT_SERIES_BELOW * SHORT_SERIES_BELOW {
        (estrin5(theta2, &A_SERIES), estrin5(theta2, &B_SERIES))
    } else if theta2 <= PI2_HI {
        let [qa, b] = poly2(theta2 - POLY_MID, &QA_B_POLY);
        (a_from_qa(theta2, qa), b)
    } else {
        let k = RodriguesCoeffs::beyond_pi(theta2);
        (k.a, k.b)
    }
}

// Exp as a unit quaternion (cos(θ/2), (sin(θ/2)/θ)·φ), for θ < 0.1; the first omitted terms,
// θ¹⁰/(4⁵·10!) and θ¹⁰/(2¹¹·11!), are < 3e-20 relative.
// cos(θ/2) = Σ (−1)^k θ^{2k}/(4^k (2k)!)
const QC_SERIES: [f64; 5] = [
    1.0,
    -1.0 / 8.0,
    1.0 / 384.0,
    -1.0 / 46080.0,
    1.0 / 10321920.0,
];
// sin(θ/2)/θ = Σ (−1)^k θ^{2k}/(2^{2k+1} (2k+1)!)
const QS_SERIES: [f64; 5] = [
    1.0 / 2.0,
    -1.0 / 48.0,
    1.0 / 3840.0,
    -1.0 / 645120.0,
    1.0 / 185794560.0,
];

/// The two series [`exp_quat_coeffs`] evaluates below θ² = [`EXP_QUAT_SERIES_BELOW`]
/// (`cos(θ/2)` and `sin(θ/2)/θ` in powers of θ²), for callers that evaluate them on several
/// angles at once. Evaluated as `c₀ + (c₁x + x²((c₂ + c₃x) + c₄x²))`, `x = θ²`, they round
/// exactly as [`exp_quat_coeffs`].
pub const EXP_QUAT_SERIES: [[f64; 5]; 2] = [QC_SERIES, QS_SERIES];
/// Where [`exp_quat_coeffs`] switches from [`EXP_QUAT_SERIES`] to the closed form \[rad²\].
pub const EXP_QUAT_SERIES_BELOW: f64 = SHORT_SERIES_BELOW * SHORT_SERIES_BELOW;

/// `(cos(θ/2), sin(θ/2)/θ)` at θ² \[rad²\]: `Exp(φ)` as the unit quaternion
/// `(w, x, y, z) = (cos(θ/2), (sin(θ/2)/θ)·φ)` (Hamilton; Solà 2017, "Quaternion kinematics
/// for the error-state Kalman filter", the quaternion exponential map). Five-term series below
/// θ = 0.1 (no sqrt or `sin_cos`; every per-sample IMU angle), `sqrt` and `sin_cos(θ/2)` above.
/// Neither coefficient cancels anywhere: measured ≤ 0.6 ε against 60-digit references
/// (`tests/so3.rs`).
#[inline]
pub fn exp_quat_coeffs(theta2: f64) -> (f64, f64) {
    if theta2 < EXP_QUAT_SERIES_BELOW {
        (estrin5(theta2, &QC_SERIES), estrin5(theta2, &QS_SERIES))
    } else {
        exp_quat_coeffs_closed(theta2)
    }
}

/// `c₀ + (c₁x + x²((c₂ + c₃x) + c₄x²))` (Estrin): three multiply-add levels instead of
/// Horner's four, for a per-sample step whose chain of dependent operations bounds how far
/// consecutive steps overlap. For x < 0.01 the bracket is < 2e-3 of c₀ and c₀ is added last,
/// so the result is rounded about once, as with Horner.
#[inline(always)]
fn estrin5(x: f64, c: &[f64; 5]) -> f64 {
    let x2 = x * x;
    c[0] + (c[1] * x + x2 * ((c[2] + c[3] * x) + c[4] * x2))
}

#[inline(never)]
#[cold]
fn exp_quat_coeffs_closed(theta2: f64) -> (f64, f64) {
    let theta = theta2.sqrt();
    let (s, c) = (0.5 * theta).sin_cos();
    (c, s / theta)
}

/// `((1 − cos θ)/θ², (θ − sin θ)/θ³)` at θ² \[rad²\]: the two coefficients of Jr and Jl.
#[inline]
pub fn jac_coeffs(theta2: f64) -> (f64, f64) {
    if theta2 < SHORT_SERIES_BELOW * SHORT_SERIES_BELOW {
        (estrin5(theta2, &B_SERIES), estrin5(theta2, &C_SERIES))
    } else if theta2 <= PI2_HI {
        let [b, c] = poly2(theta2 - POLY_MID, &B_C_POLY);
        (b, c)
    } else {
        let k = RodriguesCoeffs::beyond_pi(theta2);
        (k.b, k.c)
    }
}

/// `I + α[φ]× + β[φ]×²`, built entry-wise from `[φ]×² = φφᵀ − θ²I` (no 3×3 products).
#[inline(always)]
pub fn i_plus_hat_hat2(phi: &Vector3<f64>, alpha: f64, beta: f64) -> Matrix3<f64> {
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (bxy, bxz, byz) = (beta * x * y, beta * x * z, beta * y * z);
    let (ax, ay, az) = (alpha * x, alpha * y, alpha * z);
    Matrix3::new(
        1.0 - beta * (yy + zz),
        bxy - az,
        bxz + ay,
        bxy + az,
        1.0 - beta * (xx + zz),
        byz - ax,
        bxz - ay,
        byz + ax,
        1.0 - beta * (xx + yy),
    )
}

impl RodriguesCoeffs {
    /// Coefficients for the rotation vector `phi` (rad).
    #[inline]
    pub fn new(phi: &Vector3<f64>) -> Self {
        let theta2 = phi.norm_squared();
        if theta2 < SHORT_SERIES_BELOW * SHORT_SERIES_BELOW {
            Self {
                a: estrin5(theta2, &A_SERIES),
                b: estrin5(theta2, &B_SERIES),
                c: estrin5(theta2, &C_SERIES),
            }
        } else if theta2 <= PI2_HI {
            let x = theta2 - POLY_MID;
            let [qa, b] = poly2(x, &QA_B_POLY);
            Self {
                a: a_from_qa(theta2, qa),
                b,
                c: poly(x, &C_POLY),
            }
        } else {
            Self::beyond_pi(theta2)
        }
    }

    /// The three coefficients for θ > π, in closed form (for [`RodriguesCoeffs::new`],
    /// [`exp_coeffs`] and [`jac_coeffs`]): there `cos θ < 0`, so `1 − cos θ` and `θ − sin θ`
    /// do not cancel. One `sqrt` and one `sin_cos`. Divisions, not multiplications by
    /// reciprocals formed while `sin_cos` runs: a reciprocal's extra rounding triples how
    /// often Exp's orthonormality error exceeds 1e-15 (measured on this closed form for θ ≥ 1:
    /// 174 against 56 of 2·10⁶ random φ).
    #[inline(never)]
    fn beyond_pi(theta2: f64) -> Self {
        let theta = theta2.sqrt();
        let (s, c) = theta.sin_cos();
        Self {
            a: s / theta,
            b: (1.0 - c) / theta2,
            c: (theta - s) / (theta2 * theta),
        }
    }
}

/// `D(θ) = 1/θ² − (1 + cos θ)/(2 θ sin θ)`, the coefficient of `[φ]×²` in `Jr⁻¹` and `Jl⁻¹`.
/// Finite for θ < 2π; at θ = π it equals 1/π². Takes θ² \[rad²\].
#[inline]
pub fn d_coeff(theta2: f64) -> f64 {
    // Below θ = 0.1 five terms of the Bernoulli series (ratio ~(θ/2π)² per term); up to π a
    // degree-14 polynomial in θ² (`D_POLY`: D's poles at θ = ±2π are close, so it needs
    // more terms than Exp's). The closed form, which cancels 1 − (θ/2)cot(θ/2) by up to
    // ~6 bits near θ = ½ (measured 29 ε there), only serves θ > π, where it adds.
    if theta2 < SHORT_SERIES_BELOW * SHORT_SERIES_BELOW {
        estrin5(theta2, &D_SERIES)
    } else if theta2 <= PI2_HI {
        poly15(theta2 - POLY_MID, &D_POLY)
    } else {
        d_coeff_beyond_pi(theta2)
    }
}

/// [`d_coeff`] for θ > π: `cot(θ/2) < 0`, so `1 − (θ/2)cot(θ/2) > 1` does not cancel.
#[inline(never)]
fn d_coeff_beyond_pi(theta2: f64) -> f64 {
    let theta = theta2.sqrt();
    let half = 0.5 * theta;
    // (1 + cos θ)/sin θ = cot(θ/2), from one `sin_cos` of θ/2.
    let (s, c) = half.sin_cos();
    (1.0 - half * c / s) / theta2
}
