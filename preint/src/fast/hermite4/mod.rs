//! The Hermite scheme ([`crate::scheme::hermite4`]) at [`crate::Level::Deltas`]: ΔR as a
//! quaternion, no linearisation.
//!
//! With `E = Exp(Ω)` (so `ΔR_k+1 = ΔR_k E`) and `s_m = ω_m × a_m + ȧ_m` (so
//! `u̇_m = ΔR_m s_m`), the velocity and position rules of the parent module become
//!
//! ```text
//! Δv_k+1 = Δv_k + ΔR_k x,          x = (h/2 a_k + h²/12 s_k) + E (h/2 a_k+1 − h²/12 s_k+1)
//! Δp_k+1 = Δp_k + h Δv_k + ΔR_k y,  y = h/2 x + h²/12 (a_k − E a_k+1)
//! ```
//!
//! `E`, `x` and `y` do not depend on ΔR ([`prepare`]); what does is one quaternion product and
//! two rotations by ΔR_k ([`State::step`]), and the rotations do not wait for ΔR_k+1. The
//! slice path takes the samples in blocks of [`BLOCK`]: it prepares a block's intervals four
//! at a time (one per [`F4`] lane, with AVX2) or two (one per [`F2`] lane)
//! ([`Carry::prepare_wide`]: every operation is then a packed one, where LLVM's own pairing of
//! 3-vectors leaves a third of them scalar and adds shuffles), then accumulates the block. The
//! one-by-one path ([`HermiteDeltas::step`](FastDeltas::step)) runs the same code in `f64`, so they all agree bit for bit.

mod carry;
mod interval;

use super::lanes::F2;
#[cfg(target_arch = "x86_64")]
use super::lanes::quad::F4;
use super::{FastDeltas, QuatDeltas, SliceInput, slice_loop};
use crate::propagation::blocks::V3;
use crate::scheme::hermite4::{Hermite4, Rule, Weights};
use crate::scheme::{Node, RENORM_EVERY, Stencil};
use crate::validation::common_case;
use carry::{Carry, LaneWeights, SteadyWeights};
use interval::{Record, State, add, cross, l3, prepare, s_of, v3};

impl HermiteDeltas {
    /// One interval of the one-by-one path (nodes `n0`, `n1`, node k+1's derivatives `dw1`,
    /// `da1`; node k's are `self.dw_last`, `self.s_last`), as [`Carry`] computes it.
    #[inline(always)]
    fn interval(&mut self, c: &Rule, n0: &Node, n1: &Node, dw1: &V3, da1: &V3) {
        let s1 = add(&cross(&l3(&n1.w), &l3(&n1.a)), &l3(da1));
        let (e, x, y) = prepare(
            c.h_2,
            c.h2_12,
            &l3(&n0.w),
            &l3(&n1.w),
            &l3(&n0.a),
            &l3(&n1.a),
            &l3(&self.dw_last),
            &l3(&self.s_last),
            &l3(dw1),
            &s1,
        );
        let mut st = State::load(&self.d);
        st.step(&Record::one(&e, &x, &y, c.h));
        st.store(&mut self.d);
        self.dw_last = *dw1;
        self.s_last = v3(&s1);
    }
}

/// Intervals per block of the slice path: 64 × 96 bytes of prepared intervals stay in the L1
/// cache.
const BLOCK: usize = 64;

/// The Hermite scheme's deltas alone: ΔR as a quaternion, node k's `ω̇_k` and `s_k`, and the
/// weights of the one-by-one path, the steady state and the lanes.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HermiteDeltas {
    d: QuatDeltas,
    dw_last: V3,
    s_last: V3,
    weights: Weights,
    steady: SteadyWeights,
    /// Two intervals at a time.
    pairs: LaneWeights<F2>,
    /// Four at a time (with AVX2).
    #[cfg(target_arch = "x86_64")]
    quads: LaneWeights<F4>,
}

impl FastDeltas for HermiteDeltas {
    const SLICE_FROM: usize = 3;

    fn start(&mut self, _: &Node) {}

    /// The interval's node derivatives from the plain scheme's weights (the same stencils,
    /// so the same derivatives), then [`HermiteDeltas::interval`].
    #[inline(always)]
    fn step(&mut self, st: &Stencil) {
        let (c, d0, d1) = Hermite4::node_rates(&mut self.weights, st);
        let (n0, n1) = (st.n0(), st.n1());
        if st.first {
            let (dw0, da0) = d0.of(st);
            self.dw_last = dw0;
            self.s_last = s_of(&n0.w, &n0.a, &da0);
        }
        let (dw1, da1) = d1.of(st);
        self.interval(&c, n0, n1, &dw1, &da1);
    }

    /// In the steady state (every interval but the last two integrated) each new sample k+2
    /// completes the derivative stencil `{k, k+1, k+2}` of node k+1 and so interval k, which
    /// [`HermiteDeltas::step`] would integrate with the same weights and operations. What the
    /// next interval needs of nodes k and k+1 is carried ([`Carry`]). A slice shorter than a
    /// block is taken one interval at a time.
    #[inline(never)]
    fn run_slice(&mut self, last: &[Node; 2], input: &SliceInput, done: &mut usize) -> usize {
        let mut d = self.d;
        let mut carry = Carry::new(&last[0], &last[1], self.dw_last, self.s_last);
        let used = if input.samples.len() < BLOCK {
            let w = &mut self.steady;
            slice_loop(input, &mut d, done, |d, s| {
                let r = carry.prepare_one(s, input.bias, w);
                let mut st = State::load(d);
                st.step(&r);
                st.store(d);
            })
        } else {
            #[cfg(target_arch = "x86_64")]
            if super::lanes::avx2() {
                // SAFETY: this processor has AVX2.
                unsafe { self.blocks_avx2(&mut carry, &mut d, done, input) }
            } else {
                self.blocks::<false>(&mut carry, &mut d, done, input)
            }
            #[cfg(not(target_arch = "x86_64"))]
            self.blocks::<false>(&mut carry, &mut d, done, input)
        };
        (self.dw_last, self.s_last) = carry.finish();
        self.d = d;
        used
    }

    fn quat(&mut self) -> &mut QuatDeltas {
        &mut self.d
    }
}

impl HermiteDeltas {
    /// The blocks of the slice path: per block of up to [`BLOCK`] samples that pass the
    /// common-case test, the intervals they complete are prepared four at a time (`QUADS`,
    /// AVX2 only), two at a time and one at a time, then accumulated.
    #[inline(always)]
    fn blocks<const QUADS: bool>(
        &mut self,
        carry: &mut Carry,
        d: &mut QuatDeltas,
        done: &mut usize,
        input: &SliceInput,
    ) -> usize {
        let (samples, bias, gap_limit) = (input.samples, input.bias, input.gap_limit);
        let mut buf = [Record::default(); BLOCK];
        let (mut used, mut last) = (0, input.last_t_ns);
        loop {
            let rest = &samples[used..];
            let mut m = 0;
            for s in rest.iter().take(BLOCK) {
                if !common_case(s, last, gap_limit) {
                    break;
                }
                last = s.t_ns;
                m += 1;
            }
            #[cfg(target_arch = "x86_64")]
            let i = if QUADS {
                let i = m & !3;
                // SAFETY: `QUADS` only from `blocks_avx2`, entered on processors with AVX2.
                unsafe { carry.prepare_quads(&rest[..i], bias, &mut self.quads, &mut buf[..i]) };
                i
            } else {
                0
            };
            #[cfg(not(target_arch = "x86_64"))]
            let i = 0;
            let even = i + ((m - i) & !1);
            carry.prepare_wide(&rest[i..even], bias, &mut self.pairs, &mut buf[i..even]);
            if m > even {
                buf[even] = carry.prepare_one(&rest[even], bias, &mut self.steady);
            }
            #[cfg(target_arch = "x86_64")]
            if QUADS {
                // SAFETY: as for `prepare_quads` above.
                unsafe { accumulate_avx2(d, done, &buf[..m]) };
            } else {
                accumulate(d, done, &buf[..m]);
            }
            #[cfg(not(target_arch = "x86_64"))]
            accumulate(d, done, &buf[..m]);
            used += m;
            if m < BLOCK {
                return used;
            }
        }
    }

    /// [`HermiteDeltas::blocks`] compiled for AVX2 (VEX encoding everywhere, four-lane
    /// preparation). The same operations, so the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn blocks_avx2(
        &mut self,
        carry: &mut Carry,
        d: &mut QuatDeltas,
        done: &mut usize,
        input: &SliceInput,
    ) -> usize {
        self.blocks::<true>(carry, d, done, input)
    }
}

/// The chain through ΔR, Δv and Δp over prepared intervals, counting them (with the
/// re-orthonormalisation every [`RENORM_EVERY`] intervals). Out of line: its registers are
/// then allocated for this loop alone (inlined into the SSE2 block loop, they moved with every
/// change to the preparation around it). The AVX2 copy is inlined into
/// [`HermiteDeltas::blocks_avx2`] (its 3-operand encoding needs no register copies).
#[inline(never)]
fn accumulate(d: &mut QuatDeltas, done: &mut usize, recs: &[Record]) {
    accumulate_inline(d, done, recs);
}

/// [`accumulate`] compiled for AVX2 (VEX encoding; the same operations).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
fn accumulate_avx2(d: &mut QuatDeltas, done: &mut usize, recs: &[Record]) {
    accumulate_inline(d, done, recs);
}

#[inline(always)]
fn accumulate_inline(d: &mut QuatDeltas, done: &mut usize, recs: &[Record]) {
    let mut st = State::load(d);
    for r in recs {
        st.step(r);
        *done += 1;
        if done.is_multiple_of(RENORM_EVERY) {
            st.store(d);
            d.q.renormalize();
            st = State::load(d);
        }
    }
    st.store(d);
}

#[cfg(test)]
mod tests {
    use crate::fast::lanes::NO_AVX2;
    use crate::{ImuBias, ImuSample, Level, PreintParams, Preintegrator, Scheme};
    use nalgebra::Vector3;

    /// Jittered stamps; a stretch spinning at up to 36 rad/s (0.18 rad per interval, beyond
    /// the Exp series, so the lane code takes its lane-by-lane branch there).
    fn stream(n: usize) -> Vec<ImuSample> {
        (0..n as i64)
            .map(|k| {
                let t = k as f64 * 5e-3;
                let spin = if (700..900).contains(&k) { 36.0 } else { 0.5 };
                ImuSample::new(
                    k * 5_000_000 + (k * 7919 % 13) * 10_000,
                    Vector3::new(0.4 * (1.3 * t).sin(), 0.3 * t.cos(), spin * (0.7 * t).cos()),
                    Vector3::new(0.6 * (0.9 * t).sin(), 0.2 * t.cos(), 9.81 + 0.3 * t.sin()),
                )
            })
            .collect()
    }

    fn run(s: &[ImuSample], chunks: &[usize], portable: bool) -> crate::PreintegratedImu {
        let mut prm = PreintParams::default()
            .with_scheme(Scheme::Hermite4)
            .with_level(Level::Deltas);
        prm.keep_samples = false;
        let bias = ImuBias::new(
            Vector3::new(0.01, -0.02, 0.005),
            Vector3::new(0.1, 0.05, -0.2),
        );
        let mut pi = Preintegrator::new(prm, bias).unwrap();
        NO_AVX2.with(|c| c.set(portable));
        let mut i = 0;
        for &len in chunks.iter().cycle() {
            if i == s.len() {
                break;
            }
            let len = len.min(s.len() - i);
            if len == 1 {
                pi.integrate(&s[i]).unwrap();
            } else {
                pi.integrate_slice(&s[i..i + len]).unwrap();
            }
            i += len;
        }
        NO_AVX2.with(|c| c.set(false));
        pi.finish().unwrap()
    }

    /// The four-lane (AVX2), two-lane and one-lane preparations, in blocks of every length
    /// modulo 4 and across the re-orthonormalisation, give the one-by-one deltas bit for bit.
    #[test]
    fn every_lane_width_gives_the_one_by_one_bits() {
        let s = stream(2500);
        let one = run(&s, &[1], false);
        let chunks = [64, 65, 66, 67, 131, 200, 2, 3, 1];
        for portable in [false, true] {
            assert_eq!(
                run(&s, &[s.len()], portable),
                one,
                "one slice, portable {portable}"
            );
            assert_eq!(
                run(&s, &chunks, portable),
                one,
                "chunks, portable {portable}"
            );
        }
    }
}
