//! The IMU intrinsics' correction of a sample ([`crate::intrinsics::Correction`]), with AVX2
//! and FMA where the processor has them.
//!
//! The corrected sample is the 6-vector `[ω'; a'] = M [ω; a]`, `M = [[K_w, K_wa], [0, K_a]]`
//! ([`Columns`]). Each output entry is the fused multiply-add chain over the inputs in the
//! order `ω_x, ω_y, ω_z, a_x, a_y, a_z`, one rounding per step ([`Columns::apply_plain`]). The
//! vector path ([`avx2`]) builds the first four rows `(ω'_x, ω'_y, ω'_z, a'_x)` as one
//! four-lane register and the last two as one two-lane register, column by column with the
//! same fused multiply-adds in the same order (the zero columns of `M` add exact zeros), so
//! every entry is the plain path's bit for bit (`preint/tests/intrinsics.rs`); the only
//! difference is the sign of an `a'_x` that is exactly zero (`+0` where the plain path may give
//! `−0`). About 22 instructions per sample against about 32 for the compiler's own
//! vectorisation of the plain loop.

use crate::sample::ImuSample;
use nalgebra::{Matrix3, Vector3};

/// The columns of `M = [[K_w, K_wa], [0, K_a]]` (6×6): rows 0–3 of each column (`lo`) and rows
/// 4–5 of the last three (`hi`; the first three are zero there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Columns {
    lo: [[f64; 4]; 6],
    hi: [[f64; 2]; 3],
}

impl Columns {
    /// The map `ω' = K_w ω + K_wa a`, `a' = K_a a`.
    pub(crate) fn of(k_w: &Matrix3<f64>, k_wa: &Matrix3<f64>, k_a: &Matrix3<f64>) -> Self {
        let mut lo = [[0.0; 4]; 6];
        let mut hi = [[0.0; 2]; 3];
        for c in 0..3 {
            lo[c] = [k_w[(0, c)], k_w[(1, c)], k_w[(2, c)], 0.0];
            lo[3 + c] = [k_wa[(0, c)], k_wa[(1, c)], k_wa[(2, c)], k_a[(0, c)]];
            hi[c] = [k_a[(1, c)], k_a[(2, c)]];
        }
        Self { lo, hi }
    }

    /// `K_w[r, c]`, `K_wa[r, c]`, `K_a[r, c]`.
    #[inline(always)]
    fn k_w(&self, r: usize, c: usize) -> f64 {
        self.lo[c][r]
    }
    #[inline(always)]
    fn k_wa(&self, r: usize, c: usize) -> f64 {
        self.lo[3 + c][r]
    }
    #[inline(always)]
    fn k_a(&self, r: usize, c: usize) -> f64 {
        if r == 0 {
            self.lo[3 + c][3]
        } else {
            self.hi[c][r - 1]
        }
    }

    /// Sample `s` corrected, its timestamp kept, with the vector path where the processor has
    /// it (module docs).
    #[inline(always)]
    pub(crate) fn apply(&self, s: &ImuSample) -> ImuSample {
        #[cfg(target_arch = "x86_64")]
        if avx2::available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked above).
            return unsafe { avx2::apply_one(self, s) };
        }
        self.apply_plain(s)
    }

    /// The correction without vector instructions: the fused multiply-add chains of the
    /// module docs.
    pub(crate) fn apply_plain(&self, s: &ImuSample) -> ImuSample {
        let (w, a) = (&s.gyro, &s.acc);
        let gyro = Vector3::from_fn(|r, _| {
            let g = self
                .k_w(r, 2)
                .mul_add(w.z, self.k_w(r, 1).mul_add(w.y, self.k_w(r, 0) * w.x));
            self.k_wa(r, 2).mul_add(
                a.z,
                self.k_wa(r, 1)
                    .mul_add(a.y, self.k_wa(r, 0).mul_add(a.x, g)),
            )
        });
        let acc = Vector3::from_fn(|r, _| {
            self.k_a(r, 2)
                .mul_add(a.z, self.k_a(r, 1).mul_add(a.y, self.k_a(r, 0) * a.x))
        });
        ImuSample::new(s.t_ns, gyro, acc)
    }

    /// Every sample of `src` corrected into `dst` (the shorter length).
    pub(crate) fn apply_all(&self, src: &[ImuSample], dst: &mut [ImuSample]) {
        #[cfg(target_arch = "x86_64")]
        if avx2::available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked above).
            unsafe { avx2::apply_all(self, src, dst) };
            return;
        }
        for (d, s) in dst.iter_mut().zip(src) {
            *d = self.apply_plain(s);
        }
    }
}

/// [`Columns::apply`] as a function chosen once for this processor (the vector path or the
/// plain one), for a loop that corrects one sample at a time: no feature test per sample.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Kernel(unsafe fn(&Columns, &ImuSample) -> ImuSample);

impl Kernel {
    /// The kernel for the processor this runs on.
    pub(crate) fn for_this_cpu() -> Self {
        #[cfg(target_arch = "x86_64")]
        if avx2::available() {
            return Kernel(avx2::apply_one);
        }
        Kernel(Columns::apply_plain)
    }

    /// `m` applied to `s`.
    #[inline(always)]
    pub(crate) fn apply(&self, m: &Columns, s: &ImuSample) -> ImuSample {
        // SAFETY: the function was chosen for the processor by `for_this_cpu`, and a process
        // does not change processors' features.
        unsafe { (self.0)(m, s) }
    }
}

/// [`Columns::apply`] in AVX2 and FMA instructions (module docs).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::Columns;
    use crate::sample::ImuSample;
    use std::arch::x86_64::*;

    /// Whether the CPU has AVX2 and FMA (cached by the standard library).
    #[inline(always)]
    pub(super) fn available() -> bool {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }

    // `gyro` and `acc` are six consecutive f64 (`ImuSample` is `repr(C)`).
    const GYRO: usize = std::mem::offset_of!(ImuSample, gyro);
    const _: () = assert!(std::mem::offset_of!(ImuSample, acc) == GYRO + 24);

    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn apply_all(m: &Columns, src: &[ImuSample], dst: &mut [ImuSample]) {
        for (d, s) in dst.iter_mut().zip(src) {
            // SAFETY: this function's own requirement.
            *d = unsafe { apply_one(m, s) };
        }
    }

    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(super) unsafe fn apply_one(m: &Columns, s: &ImuSample) -> ImuSample {
        // SAFETY (both): four and two in-bounds f64 of `m`; unaligned loads.
        let lo = |k: usize| unsafe { _mm256_loadu_pd(m.lo[k].as_ptr()) };
        let hi = |k: usize| unsafe { _mm_loadu_pd(m.hi[k].as_ptr()) };
        let b = _mm256_broadcast_sd;
        let (w, a) = (&s.gyro, &s.acc);
        let (w0, w1, w2) = (b(&w.x), b(&w.y), b(&w.z));
        let (a0, a1, a2) = (b(&a.x), b(&a.y), b(&a.z));
        let mut l = _mm256_mul_pd(lo(0), w0);
        l = _mm256_fmadd_pd(lo(1), w1, l);
        l = _mm256_fmadd_pd(lo(2), w2, l);
        l = _mm256_fmadd_pd(lo(3), a0, l);
        l = _mm256_fmadd_pd(lo(4), a1, l);
        l = _mm256_fmadd_pd(lo(5), a2, l);
        let mut h = _mm_mul_pd(hi(0), _mm256_castpd256_pd128(a0));
        h = _mm_fmadd_pd(hi(1), _mm256_castpd256_pd128(a1), h);
        h = _mm_fmadd_pd(hi(2), _mm256_castpd256_pd128(a2), h);
        let mut d = *s;
        // SAFETY: `d.gyro` and `d.acc` are six consecutive f64 (the layout asserted above)
        // inside `d`; unaligned stores.
        unsafe {
            let y = (&mut d as *mut ImuSample)
                .cast::<u8>()
                .add(GYRO)
                .cast::<f64>();
            _mm256_storeu_pd(y, l);
            _mm_storeu_pd(y.add(4), h);
        }
        d
    }
}
