//! Lanes of `f64`: [`F2`], two in one SSE2 register (part of the x86-64 baseline, so no
//! run-time detection and no special build; a plain `[f64; 2]` on other targets), and on
//! x86-64 [`quad::F4`], four in one AVX register, for processors that have AVX2 ([`avx2`]).
//!
//! Every operation is the lane-wise IEEE operation (no fused multiply-add), so a computation
//! written once over [`Lane`] rounds identically on `f64`, `F2` and `F4`: the Hermite slice path
//! prepares four or two intervals at a time and the one-by-one path prepares one in `f64`, and
//! their deltas are bit-identical (the tests of [`super::hermite4`] and `preint/tests/deltas_fast_path.rs`). LLVM does not find this
//! layout itself: it pairs the x and y components of one 3-vector and leaves z alone, and
//! spends the difference on shuffles (a cross product) and register copies.

use std::ops::{Add, Mul, Neg, Sub};

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{
    __m128d, _mm_add_pd, _mm_castsi128_pd, _mm_cvtsd_f64, _mm_mul_pd, _mm_set_epi64x, _mm_set_pd,
    _mm_set1_pd, _mm_shuffle_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm_unpacklo_pd, _mm_xor_pd,
};

/// Scalar arithmetic that runs lane-wise: `f64` (one lane) or [`F2`] (two).
pub(crate) trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// `x` in every lane.
    fn splat(x: f64) -> Self;
    /// [`preint_lie::so3::exp_quat_coeffs`] in every lane.
    fn exp_quat_coeffs(theta2: Self) -> (Self, Self);
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }

    #[inline(always)]
    fn exp_quat_coeffs(theta2: Self) -> (Self, Self) {
        preint_lie::so3::exp_quat_coeffs(theta2)
    }
}

/// `c₀ + (c₁x + x²((c₂ + c₃x) + c₄x²))` in every lane: [`preint_lie::so3::EXP_QUAT_SERIES`]'s order.
#[inline(always)]
fn estrin5<T: Lane>(x: T, c: &[f64; 5]) -> T {
    let k = |i: usize| T::splat(c[i]);
    let x2 = x * x;
    k(0) + (k(1) * x + x2 * ((k(2) + k(3) * x) + k(4) * x2))
}

/// Two `f64` lanes, `(lo, hi)`; 16-byte aligned.
#[derive(Clone, Copy)]
#[repr(transparent)]
pub(crate) struct F2(
    #[cfg(target_arch = "x86_64")] __m128d,
    #[cfg(not(target_arch = "x86_64"))] [f64; 2],
);

// SAFETY (every `unsafe` block below): the intrinsics are SSE2 register operations, part of the
// x86-64 baseline; none touches memory.
#[cfg(target_arch = "x86_64")]
impl F2 {
    #[inline(always)]
    pub(crate) fn new(lo: f64, hi: f64) -> Self {
        Self(unsafe { _mm_set_pd(hi, lo) })
    }

    #[inline(always)]
    pub(crate) fn lo(self) -> f64 {
        unsafe { _mm_cvtsd_f64(self.0) }
    }

    #[inline(always)]
    pub(crate) fn hi(self) -> f64 {
        unsafe { _mm_cvtsd_f64(_mm_unpackhi_pd(self.0, self.0)) }
    }

    /// `(a.lo, b.lo)`.
    #[inline(always)]
    pub(crate) fn lows(a: Self, b: Self) -> Self {
        Self(unsafe { _mm_unpacklo_pd(a.0, b.0) })
    }

    /// `(a.hi, b.hi)`.
    #[inline(always)]
    pub(crate) fn highs(a: Self, b: Self) -> Self {
        Self(unsafe { _mm_unpackhi_pd(a.0, b.0) })
    }

    /// `(a.hi, b.lo)`: the pair one lane further along a sequence split as `a, b`.
    #[inline(always)]
    pub(crate) fn straddle(a: Self, b: Self) -> Self {
        Self(unsafe { _mm_shuffle_pd::<0b01>(a.0, b.0) })
    }

    /// `(hi, lo)`.
    #[inline(always)]
    pub(crate) fn swap(self) -> Self {
        Self(unsafe { _mm_shuffle_pd::<0b01>(self.0, self.0) })
    }

    /// The sign bit of lane lo (`lo`) and of lane hi (`hi`) flipped: an exact negation.
    #[inline(always)]
    pub(crate) fn flip(self, lo: bool, hi: bool) -> Self {
        let m = |b: bool| if b { i64::MIN } else { 0 };
        Self(unsafe { _mm_xor_pd(self.0, _mm_castsi128_pd(_mm_set_epi64x(m(hi), m(lo)))) })
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl F2 {
    #[inline(always)]
    pub(crate) fn new(lo: f64, hi: f64) -> Self {
        Self([lo, hi])
    }
    #[inline(always)]
    pub(crate) fn lo(self) -> f64 {
        self.0[0]
    }
    #[inline(always)]
    pub(crate) fn hi(self) -> f64 {
        self.0[1]
    }
    #[inline(always)]
    pub(crate) fn lows(a: Self, b: Self) -> Self {
        Self([a.0[0], b.0[0]])
    }
    #[inline(always)]
    pub(crate) fn highs(a: Self, b: Self) -> Self {
        Self([a.0[1], b.0[1]])
    }
    #[inline(always)]
    pub(crate) fn straddle(a: Self, b: Self) -> Self {
        Self([a.0[1], b.0[0]])
    }
    #[inline(always)]
    pub(crate) fn swap(self) -> Self {
        Self([self.0[1], self.0[0]])
    }
    #[inline(always)]
    pub(crate) fn flip(self, lo: bool, hi: bool) -> Self {
        let f = |x: f64, b: bool| if b { -x } else { x };
        Self([f(self.0[0], lo), f(self.0[1], hi)])
    }
}

impl F2 {
    /// `lo` in lane lo and lane hi.
    #[inline(always)]
    pub(crate) fn splat_lo(self) -> Self {
        Self::lows(self, self)
    }

    /// `hi` in lane lo and lane hi.
    #[inline(always)]
    pub(crate) fn splat_hi(self) -> Self {
        Self::highs(self, self)
    }
}

impl Default for F2 {
    fn default() -> Self {
        Self::splat(0.0)
    }
}

impl std::fmt::Debug for F2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "F2({:e}, {:e})", self.lo(), self.hi())
    }
}

macro_rules! lane_op {
    ($tr:ident, $m:ident, $sse:ident, $op:tt) => {
        impl $tr for F2 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                #[cfg(target_arch = "x86_64")]
                {
                    Self(unsafe { $sse(self.0, o.0) })
                }
                #[cfg(not(target_arch = "x86_64"))]
                {
                    Self([self.0[0] $op o.0[0], self.0[1] $op o.0[1]])
                }
            }
        }
    };
}
lane_op!(Add, add, _mm_add_pd, +);
lane_op!(Sub, sub, _mm_sub_pd, -);
lane_op!(Mul, mul, _mm_mul_pd, *);

impl Neg for F2 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.flip(true, true)
    }
}

impl Lane for F2 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            Self(unsafe { _mm_set1_pd(x) })
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            Self([x, x])
        }
    }

    /// Both lanes' series at once when both angles are below the series' range end (every
    /// per-sample angle), in the order [`preint_lie::so3::EXP_QUAT_SERIES`] prescribes; otherwise
    /// lane by lane.
    #[inline(always)]
    fn exp_quat_coeffs(theta2: Self) -> (Self, Self) {
        use preint_lie::so3::{EXP_QUAT_SERIES, EXP_QUAT_SERIES_BELOW};
        let (lo, hi) = (theta2.lo(), theta2.hi());
        if lo < EXP_QUAT_SERIES_BELOW && hi < EXP_QUAT_SERIES_BELOW {
            (
                estrin5(theta2, &EXP_QUAT_SERIES[0]),
                estrin5(theta2, &EXP_QUAT_SERIES[1]),
            )
        } else {
            let (c0, s0) = preint_lie::so3::exp_quat_coeffs(lo);
            let (c1, s1) = preint_lie::so3::exp_quat_coeffs(hi);
            (Self::new(c0, c1), Self::new(s0, s1))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_round_like_scalars() {
        let (a, b) = (F2::new(0.1, -3.0), F2::new(0.7, 1e-300));
        let (x, y) = ((a + b) * a - b, -(a * b));
        assert_eq!(x.lo(), (0.1 + 0.7) * 0.1 - 0.7);
        assert_eq!(x.hi(), (-3.0 + 1e-300) * -3.0 - 1e-300);
        assert_eq!(y.lo(), -(0.1 * 0.7));
        assert_eq!(y.hi(), -(-3.0 * 1e-300));
        let z = F2::new(0.0, 2.0).flip(true, false);
        assert!(z.lo() == 0.0 && z.lo().is_sign_negative() && z.hi() == 2.0);
        assert_eq!((a.swap().lo(), a.swap().hi()), (-3.0, 0.1));
        let s = F2::straddle(a, b);
        assert_eq!((s.lo(), s.hi()), (-3.0, 0.7));
        let (l, h) = (F2::lows(a, b), F2::highs(a, b));
        assert_eq!((l.lo(), l.hi(), h.lo(), h.hi()), (0.1, 0.7, -3.0, 1e-300));
        assert_eq!((a.splat_lo().hi(), a.splat_hi().lo()), (0.1, -3.0));
    }

    #[test]
    fn two_lane_exp_coefficients_are_the_scalar_ones() {
        // Both lanes in the series, one or both beyond it (θ = 0.1 is the switch), and θ > π.
        let thetas = [0.0, 1e-9, 0.003, 0.0999, 0.1, 0.10001, 1.3, 3.5];
        for &t0 in &thetas {
            for &t1 in &thetas {
                let (c, s) = F2::exp_quat_coeffs(F2::new(t0 * t0, t1 * t1));
                let (c0, s0) = preint_lie::so3::exp_quat_coeffs(t0 * t0);
                let (c1, s1) = preint_lie::so3::exp_quat_coeffs(t1 * t1);
                let bits = |x: f64| x.to_bits();
                assert_eq!(
                    [c.lo(), c.hi(), s.lo(), s.hi()].map(bits),
                    [c0, c1, s0, s1].map(bits),
                    "θ = {t0}, {t1}"
                );
            }
        }
    }
}

/// Four `f64` lanes in one AVX register, for x86-64 processors that have AVX2 (checked at
/// run time by the caller: see [`avx2`]). Every method may only run on such a processor:
/// the Hermite slice path calls them only inside a `#[target_feature(enable = "avx2")]` function
/// that it enters after [`avx2`] returned true.
#[cfg(target_arch = "x86_64")]
pub(crate) mod quad {
    use super::{F2, Lane, estrin5};
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_castpd256_pd128, _mm256_extractf128_pd, _mm256_mul_pd,
        _mm256_permute2f128_pd, _mm256_set_pd, _mm256_set1_pd, _mm256_shuffle_pd, _mm256_storeu_pd,
        _mm256_sub_pd, _mm256_unpackhi_pd, _mm256_unpacklo_pd, _mm256_xor_pd,
    };
    use std::ops::{Add, Mul, Neg, Sub};

    /// Four lanes `(l0, l1, l2, l3)`.
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    pub(crate) struct F4(__m256d);

    // SAFETY (every `unsafe` block in this module): AVX register operations (no memory but
    // the local array of `lanes`); the module's contract is that they run only after the
    // processor was found to have AVX2.
    impl F4 {
        #[inline(always)]
        pub(crate) fn new(l: [f64; 4]) -> Self {
            Self(unsafe { _mm256_set_pd(l[3], l[2], l[1], l[0]) })
        }

        #[inline(always)]
        pub(crate) fn lanes(self) -> [f64; 4] {
            let mut out = [0.0; 4];
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
            out
        }

        /// `(a3, b0, b1, b2)`: the lanes one back along a sequence split as `a, b`.
        #[inline(always)]
        pub(crate) fn after(a: Self, b: Self) -> Self {
            unsafe {
                let mid = _mm256_permute2f128_pd::<0x21>(a.0, b.0); // (a2, a3, b0, b1)
                Self(_mm256_shuffle_pd::<0b0101>(mid, b.0))
            }
        }

        /// `(a1, b0, a3, b2)`: for `a` = nodes j…j+3 and `b` = nodes j+2…j+5, nodes j+1…j+4.
        #[inline(always)]
        pub(crate) fn odd_even(a: Self, b: Self) -> Self {
            Self(unsafe { _mm256_shuffle_pd::<0b0101>(a.0, b.0) })
        }

        /// `(a2, a3, b0, b1)`: two lanes further.
        #[inline(always)]
        pub(crate) fn straddle2(a: Self, b: Self) -> Self {
            Self(unsafe { _mm256_permute2f128_pd::<0x21>(a.0, b.0) })
        }

        /// `(a0, b0, a2, b2)` and `(a1, b1, a3, b3)`.
        #[inline(always)]
        pub(crate) fn interleave(a: Self, b: Self) -> (Self, Self) {
            unsafe {
                (
                    Self(_mm256_unpacklo_pd(a.0, b.0)),
                    Self(_mm256_unpackhi_pd(a.0, b.0)),
                )
            }
        }

        /// The lower and upper halves, `(l0, l1)` and `(l2, l3)`.
        #[inline(always)]
        pub(crate) fn halves(self) -> (F2, F2) {
            unsafe {
                (
                    F2(_mm256_castpd256_pd128(self.0)),
                    F2(_mm256_extractf128_pd::<1>(self.0)),
                )
            }
        }
    }

    impl Default for F4 {
        fn default() -> Self {
            Self::splat(0.0)
        }
    }

    impl std::fmt::Debug for F4 {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "F4({:?})", self.lanes())
        }
    }

    macro_rules! quad_op {
        ($tr:ident, $m:ident, $avx:ident) => {
            impl $tr for F4 {
                type Output = Self;
                #[inline(always)]
                fn $m(self, o: Self) -> Self {
                    Self(unsafe { $avx(self.0, o.0) })
                }
            }
        };
    }
    quad_op!(Add, add, _mm256_add_pd);
    quad_op!(Sub, sub, _mm256_sub_pd);
    quad_op!(Mul, mul, _mm256_mul_pd);

    impl Neg for F4 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            Self(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }

    impl Lane for F4 {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            Self(unsafe { _mm256_set1_pd(x) })
        }

        /// All four lanes' series at once when every angle is below the series' range end;
        /// otherwise lane by lane (as [`super::F2`]).
        #[inline(always)]
        fn exp_quat_coeffs(theta2: Self) -> (Self, Self) {
            use preint_lie::so3::{EXP_QUAT_SERIES, EXP_QUAT_SERIES_BELOW};
            let l = theta2.lanes();
            if l.iter().all(|&t| t < EXP_QUAT_SERIES_BELOW) {
                (
                    estrin5(theta2, &EXP_QUAT_SERIES[0]),
                    estrin5(theta2, &EXP_QUAT_SERIES[1]),
                )
            } else {
                let [c0, c1, c2, c3] = l.map(preint_lie::so3::exp_quat_coeffs);
                (
                    Self::new([c0.0, c1.0, c2.0, c3.0]),
                    Self::new([c0.1, c1.1, c2.1, c3.1]),
                )
            }
        }
    }
}

#[cfg(test)]
thread_local! {
    /// Unit tests set this to run the portable paths on a processor with AVX2.
    pub(crate) static NO_AVX2: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this processor has AVX2 (detected once, then a cached load).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2() -> bool {
    #[cfg(test)]
    if NO_AVX2.with(|c| c.get()) {
        return false;
    }
    std::is_x86_feature_detected!("avx2")
}
