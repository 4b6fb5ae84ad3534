//! Private `sin_cos` and first/second-quadrant `atan2` for the closed-form branches of
//! [`crate::so3`] and [`crate::se3`]: glibc's `sincos` and `atan2` cost ~18–25 ns each on the
//! portable x86-64 target, more than the rest of a large-angle `Exp` or `Log`.
//!
//! - [`sin_cos`]: Cody–Waite reduction by π/2 with fdlibm's three-stage split constant (each
//!   stage 33 bits of π/2, the later stages taken only when the first one cancels more than 16
//!   resp. 49 bits), the reduced argument kept as a double-double `y₀ + y₁`, then the fdlibm
//!   minimax kernels on [−π/4, π/4] (FreeBSD msun `k_sin.c`/`k_cos.c` coefficients, public
//!   domain; the evaluation order is theirs, the code is ours). For `|x| ≥ 2²⁰·π/2` or
//!   non-finite `x` it returns `f64::sin_cos`.
//! - [`atan2_upper`]: `atan2(y, x)` for `y ≥ 0`: the quadrant folded into a table of
//!   `(base_hi, base_lo)` ∈ {0, atan ½, atan 1, atan 3⁄2, π/2} or π minus those, and fdlibm's
//!   `s_atan.c` interval reduction written on `(y, |x|)` so that the reduced argument costs one
//!   division (`(2y − |x|)/(2|x| + y)` instead of `t = y/|x|` then `(2t − 1)/(2 + t)`), then
//!   fdlibm's 11-term atan polynomial.
//!
//! Measured against f64::sin_cos / f64::atan2 (glibc) by the unit tests below (1.8 M and
//! 1.6 M points incl. the reduction's worst cases near k·π/2 and the interval edges): within
//! 1 ulp everywhere, bit-identical at ~94 % of points. The closed-form coefficients built on
//! them are checked against 60-digit mpmath values in `tests/so3.rs`.

// 2/π and π/2 split into 33 + 33 + 33 bits plus tails (fdlibm e_rem_pio2.c), as bit patterns.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
const PIO2_2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
const PIO2_2T: f64 = f64::from_bits(0x3BA3_198A_2E03_7073);
const PIO2_3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
const PIO2_3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);
/// 1.5·2⁵²: adding and subtracting it rounds a double of magnitude < 2⁵¹ to an integer.
const TOINT: f64 = 1.5 / f64::EPSILON;
/// Above this the three-stage reduction (n < 2²⁰) is no longer exact; std takes over.
const MEDIUM: f64 = 1_048_576.0 * std::f64::consts::FRAC_PI_2;

// fdlibm __kernel_sin: sin x ≈ x + S1 x³ + … + S6 x¹³ on [−π/4, π/4].
const S1: f64 = f64::from_bits(0xBFC5_5555_5555_5549);
const S2: f64 = f64::from_bits(0x3F81_1111_1110_F8A6);
const S3: f64 = f64::from_bits(0xBF2A_01A0_19C1_61D5);
const S4: f64 = f64::from_bits(0x3EC7_1DE3_57B1_FE7D);
const S5: f64 = f64::from_bits(0xBE5A_E5E6_8A2B_9CEB);
const S6: f64 = f64::from_bits(0x3DE5_D93A_5ACF_D57C);
// fdlibm __kernel_cos: cos x ≈ 1 − x²/2 + C1 x⁴ + … + C6 x¹⁴ on [−π/4, π/4].
const C1: f64 = f64::from_bits(0x3FA5_5555_5555_554C);
const C2: f64 = f64::from_bits(0xBF56_C16C_16C1_5177);
const C3: f64 = f64::from_bits(0x3EFA_01A0_19CB_1590);
const C4: f64 = f64::from_bits(0xBE92_7E4F_809C_52AD);
const C5: f64 = f64::from_bits(0x3E21_EE9E_BDB4_B1C4);
const C6: f64 = f64::from_bits(0xBDA8_FAE9_BE88_38D4);

/// `√x` for the large-angle branches. On x86-64 this is `sqrtsd x, x` in one register: the
/// compiler's own `sqrtsd dst, src` leaves `dst`'s upper lane in place, a false dependency on
/// whatever last wrote `dst`, which LLVM does not break at function entry; in a loop over
/// these (out-of-line) functions that chains each call to the previous call's last division
/// (measured: `jr_inv` at 1.9 rad 45 ns instead of 22 ns).
#[inline(always)]
pub(crate) fn sqrt(x: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        let mut y = x;
        // SAFETY: a register-only SSE2 instruction (baseline on x86-64); no memory, no flags.
        unsafe {
            core::arch::asm!(
                "sqrtsd {0}, {0}",
                inout(xmm_reg) y,
                options(pure, nomem, nostack, preserves_flags)
            );
        }
        y
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        x.sqrt()
    }
}

/// Biased exponent field of `x`.
#[inline(always)]
fn exponent(x: f64) -> i64 {
    ((x.to_bits() >> 52) & 0x7ff) as i64
}

/// `(sin x, cos x)`, each within 1 ulp (fdlibm kernels after a Cody–Waite reduction by π/2);
/// `f64::sin_cos` for `|x| ≥ 2²⁰·π/2` and non-finite `x`.
#[inline(always)]
pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    let ax = x.abs();
    // Also catches NaN (every comparison with NaN is false).
    if ax >= MEDIUM || ax.is_nan() {
        return std_sin_cos(x);
    }
    // n = rint(x·2/π), |n| < 2²⁰, read from the low mantissa bits of x·2/π + 1.5·2⁵².
    // n·PIO2_1 is exact (33 + 20 bits) and so, by Sterbenz, is r = x − n·PIO2_1; the tail
    // n·PIO2_1T is rounded, which leaves y₀ + y₁ good to ~85 bits of x (fdlibm e_rem_pio2.c,
    // "medium" case). If r cancelled more than 16 bits (x within ~2⁻¹⁶|x| of a multiple of
    // π/2) the reduction is redone with more of π/2, out of line. For |x| ≤ π/4, n = 0 and
    // the reduction returns y₀ = x, y₁ = 0 exactly.
    let t = x * INV_PIO2 + TOINT;
    let f = t - TOINT;
    let n = t.to_bits();
    let r = x - f * PIO2_1;
    let w = f * PIO2_1T;
    let mut y0 = r - w;
    let mut y1 = (r - y0) - w;
    if y0.abs() < ax * (1.0 / 65536.0) {
        (y0, y1) = reduce_more(x, f);
    }
    let (s, c) = kernels(y0, y1);
    // Quadrant n mod 4: (s, c), (c, −s), (−s, −c), (−c, s), without branches.
    let (a, b) = if n & 1 == 0 { (s, c) } else { (c, s) };
    let flip = |v: f64, bit: u64| f64::from_bits(v.to_bits() ^ ((bit & 2) << 62));
    (flip(a, n), flip(b, n.wrapping_add(1)))
}

/// `f64::sin_cos` out of line (large or non-finite arguments).
#[cold]
#[inline(never)]
fn std_sin_cos(x: f64) -> (f64, f64) {
    x.sin_cos()
}

/// The reduction of [`sin_cos`] when `x − n·PIO2_1` cancels more than 16 bits: fdlibm's second
/// (118 bits) and, past 49 bits of cancellation, third (151 bits) stage.
#[cold]
#[inline(never)]
fn reduce_more(x: f64, f: f64) -> (f64, f64) {
    let ex = exponent(x);
    let mut r = x - f * PIO2_1;
    let t = r;
    let mut w = f * PIO2_2;
    r = t - w;
    w = f * PIO2_2T - ((t - r) - w);
    let mut y0 = r - w;
    if ex - exponent(y0) > 49 {
        let t = r;
        w = f * PIO2_3;
        r = t - w;
        w = f * PIO2_3T - ((t - r) - w);
        y0 = r - w;
    }
    (y0, (r - y0) - w)
}

/// `(sin(y₀ + y₁), cos(y₀ + y₁))` for |y₀| ≤ ~π/4, |y₁| ≤ ½ ulp(y₀): fdlibm's
/// `__kernel_sin` (with tail) and FreeBSD's `__kernel_cos`, sharing y₀² and y₀⁴.
#[inline(always)]
fn kernels(x: f64, y: f64) -> (f64, f64) {
    let z = x * x;
    let w = z * z;
    let v = z * x;
    let rs = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let s = x - ((z * (0.5 * y - v * rs) - y) - v * S1);
    let rc = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let one_m_hz = 1.0 - hz;
    let c = one_m_hz + (((1.0 - one_m_hz) - hz) + (z * rc - x * y));
    (s, c)
}

/// Exact `a + b = s + e` (Knuth's two-sum), for the constant tables.
const fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `(hi, lo)` of `π − (ahi + alo)` to ~2⁻¹⁰⁶ relative.
const fn pi_minus(ahi: f64, alo: f64) -> (f64, f64) {
    let (s, e) = two_sum(PI_HI, -ahi);
    let lo = e + (PI_LO - alo);
    let hi = s + lo;
    (hi, lo - (hi - s))
}

const PI_HI: f64 = f64::from_bits(0x4009_21FB_5444_2D18);
const PI_LO: f64 = f64::from_bits(0x3CA1_A626_3314_5C07);
// atan(½), atan(1), atan(3⁄2), atan(∞) as hi + lo (fdlibm s_atan.c atanhi/atanlo).
const ATAN_HI: [f64; 4] = [
    f64::from_bits(0x3FDD_AC67_0561_BB4F),
    f64::from_bits(0x3FE9_21FB_5444_2D18),
    f64::from_bits(0x3FEF_730B_D281_F69B),
    f64::from_bits(0x3FF9_21FB_5444_2D18),
];
const ATAN_LO: [f64; 4] = [
    f64::from_bits(0x3C7A_2B7F_222F_65E2),
    f64::from_bits(0x3C81_A626_3314_5C07),
    f64::from_bits(0x3C70_0788_7AF0_CBBD),
    f64::from_bits(0x3C91_A626_3314_5C07),
];
/// Base angles per reduction interval: x ≥ 0 uses `atan(cₖ)`, x < 0 uses `π − atan(cₖ)`.
const BASE_POS: [(f64, f64); 5] = [
    (0.0, 0.0),
    (ATAN_HI[0], ATAN_LO[0]),
    (ATAN_HI[1], ATAN_LO[1]),
    (ATAN_HI[2], ATAN_LO[2]),
    (ATAN_HI[3], ATAN_LO[3]),
];
const BASE_NEG: [(f64, f64); 5] = [
    (PI_HI, PI_LO),
    pi_minus(ATAN_HI[0], ATAN_LO[0]),
    pi_minus(ATAN_HI[1], ATAN_LO[1]),
    pi_minus(ATAN_HI[2], ATAN_LO[2]),
    (ATAN_HI[3], ATAN_LO[3]),
];
// fdlibm s_atan.c: atan u ≈ u − u(aT0 u² − aT1 u⁴ + …) for |u| ≤ 7/16.
const AT: [f64; 11] = [
    f64::from_bits(0x3FD5_5555_5555_550D),
    f64::from_bits(0xBFC9_9999_9998_EBC4),
    f64::from_bits(0x3FC2_4924_9200_83FF),
    f64::from_bits(0xBFBC_71C6_FE23_1671),
    f64::from_bits(0x3FB7_45CD_C54C_206E),
    f64::from_bits(0xBFB3_B0F2_AF74_9A6D),
    f64::from_bits(0x3FB1_0D66_A0D0_3D51),
    f64::from_bits(0xBFAD_DE2D_52DE_FD9A),
    f64::from_bits(0x3FA9_7B4B_2476_0DEB),
    f64::from_bits(0xBFA2_B444_2C6A_6C2F),
    f64::from_bits(0x3F90_AD3A_E322_DA11),
];

/// `atan2(y, x) ∈ [0, π]` for finite `y ≥ 0` and finite `x`, not both zero; within 1 ulp
/// where tested (see the module docs).
///
/// With `t = y/|x|`, fdlibm's intervals t < 7/16, < 11/16, < 19/16, < 39/16, ≥ 39/16 reduce
/// to `atan t = atan cₖ + atan u`, `u = (t − cₖ)/(1 + cₖ t) = (y − cₖ|x|)/(|x| + cₖ y)`
/// (cₖ = 0, ½, 1, 3⁄2, ∞), |u| ≤ 0.41; for x < 0 the result is `π − atan t`, folded into the
/// base so that the hi/lo sum is formed once.
#[inline]
pub(crate) fn atan2_upper(y: f64, x: f64) -> f64 {
    let ax = x.abs();
    let y16 = 16.0 * y;
    let (id, u) = if y16 < 7.0 * ax {
        (0, y / ax)
    } else if y16 < 11.0 * ax {
        (1, (2.0 * y - ax) / (2.0 * ax + y))
    } else if y16 < 19.0 * ax {
        (2, (y - ax) / (y + ax))
    } else if y16 < 39.0 * ax {
        (3, (2.0 * y - 3.0 * ax) / (2.0 * ax + 3.0 * y))
    } else {
        (4, -ax / y)
    };
    let ((hi, lo), u) = if x < 0.0 {
        (BASE_NEG[id], -u)
    } else {
        (BASE_POS[id], u)
    };
    let z = u * u;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    hi - ((u * (s1 + s2) - lo) - u)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Distance in units in the last place between two finite doubles (across zero too).
    fn ulps(a: f64, b: f64) -> u64 {
        let key = |x: f64| {
            let b = x.to_bits() as i64;
            if b < 0 { i64::MIN - b } else { b }
        };
        key(a).abs_diff(key(b))
    }

    /// SplitMix64, uniform in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        }
    }

    #[test]
    #[allow(clippy::excessive_precision)] // fdlibm's 21-digit literals, kept as printed.
    fn constants_are_the_fdlibm_values() {
        // The decimal literals printed in fdlibm next to the bit patterns used above.
        let pairs = [
            (S1, -1.66666666666666324348e-01),
            (S6, 1.58969099521155010221e-10),
            (C1, 4.16666666666666019037e-02),
            (C6, -1.13596475577881948265e-11),
            (PIO2_1, 1.57079632673412561417e+00),
            (PIO2_1T, 6.07710050650619224932e-11),
            (PIO2_3T, 8.47842766036889956997e-32),
            (AT[0], 3.33333333333329318027e-01),
            (AT[10], 1.62858201153657823623e-02),
            (ATAN_HI[2], 9.82793723247329054082e-01),
            (ATAN_LO[2], 1.39033110312309984516e-17),
        ];
        for (got, want) in pairs {
            assert_eq!(got, want);
        }
        // π − atan(1) = 3π/4, π − atan(∞) would be π/2: the const double-double arithmetic.
        let (h, l) = BASE_NEG[2];
        assert_eq!(h, 3.0 * std::f64::consts::FRAC_PI_4);
        assert!(l.abs() < 1e-16 && l != 0.0);
    }

    /// Worst ulp distance of our (sin, cos) from std's at `x`, and whether they differ.
    fn sc_err(x: f64) -> (u64, bool) {
        let (s, c) = sin_cos(x);
        let (s0, c0) = x.sin_cos();
        let e = ulps(s, s0).max(ulps(c, c0));
        (e, s != s0 || c != c0)
    }

    #[test]
    fn sin_cos_within_one_ulp_of_std() {
        // Dense grid over [0, 4π] (the closed forms use [¼, π]; Exp accepts any angle), random
        // points out to the fast-path bound, and the doubles nearest k·π/2 (the reduction's
        // worst cancellation) with their neighbours.
        let (mut worst, mut differ, mut n) = (0u64, 0usize, 0usize);
        let mut check = |x: f64| {
            for x in [x, -x] {
                let (e, d) = sc_err(x);
                assert!(e <= 1, "sin_cos({x:e}) differs from std by {e} ulp");
                worst = worst.max(e);
                differ += d as usize;
                n += 1;
            }
        };
        let m = 400_000;
        for i in 0..=m {
            check(4.0 * PI * i as f64 / m as f64);
        }
        let mut rng = Rng(1);
        for _ in 0..200_000 {
            check(1.0 + (PI - 1.0) * rng.uniform());
            check(MEDIUM * rng.uniform().powi(4));
        }
        for k in 1..20_000u64 {
            let x = k as f64 * std::f64::consts::FRAC_PI_2;
            let b = x.to_bits();
            for d in [-2i64, -1, 0, 1, 2] {
                check(f64::from_bits(b.wrapping_add_signed(d)));
            }
        }
        check(PI);
        check(1.0);
        // Fallbacks.
        assert_eq!(sin_cos(1e300), 1e300f64.sin_cos());
        assert!(sin_cos(f64::NAN).0.is_nan() && sin_cos(f64::INFINITY).1.is_nan());
        println!(
            "sin_cos vs std: {n} points, max {worst} ulp, {differ} ({:.3}%) not bit-identical",
            100.0 * differ as f64 / n as f64
        );
    }

    #[test]
    fn atan2_within_one_ulp_of_std() {
        // Angles over (0, π) from (sin θ, cos θ)-like pairs (as Log feeds it: ‖s‖ and c,
        // not exactly on the unit circle), and raw random (y, x) over a wide dynamic range.
        let (mut worst, mut differ, mut n) = (0u64, 0usize, 0usize);
        let mut check = |y: f64, x: f64| {
            let (a, a0) = (atan2_upper(y, x), y.atan2(x));
            let e = ulps(a, a0);
            assert!(e <= 1, "atan2({y:e}, {x:e}) = {a:e} vs std {a0:e}: {e} ulp");
            worst = worst.max(e);
            differ += (a != a0) as usize;
            n += 1;
        };
        let m = 400_000;
        let mut rng = Rng(2);
        for i in 1..m {
            let t = PI * i as f64 / m as f64;
            let (s, c) = t.sin_cos();
            check(s, c);
            let k = 1.0 + 1e-3 * (rng.uniform() - 0.5);
            check(s * k, c);
        }
        for _ in 0..400_000 {
            let y = 10f64.powf(8.0 * rng.uniform() - 4.0);
            let x = 10f64.powf(8.0 * rng.uniform() - 4.0);
            check(y, x);
            check(y, -x);
        }
        // Interval edges t = 7/16, 11/16, 19/16, 39/16 and their neighbours.
        for num in [7.0, 11.0, 19.0, 39.0] {
            let t: f64 = num / 16.0;
            for d in -3i64..=3 {
                let tt = f64::from_bits(t.to_bits().wrapping_add_signed(d));
                check(tt, 1.0);
                check(tt, -1.0);
                check(1.0, 1.0 / tt);
            }
        }
        check(1.0, 0.0);
        check(1.0, -0.0);
        check(0.0, 1.0);
        check(0.0, -1.0);
        check(1.0, 1e-300);
        println!(
            "atan2 vs std: {n} points, max {worst} ulp, {differ} ({:.3}%) not bit-identical",
            100.0 * differ as f64 / n as f64
        );
    }
}
