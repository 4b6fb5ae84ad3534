//! What the slice path carries from one interval to the next, and the preparation of several
//! intervals at once, one per lane ([`Carry::prepare_wide`]) with every lane's weights.

#[cfg(target_arch = "x86_64")]
use super::super::lanes::quad::F4;
use super::super::lanes::{F2, Lane};
use super::interval::{L3, Record, add, by3, cross, l3, prepare, slope, sub, v3};
use crate::propagation::blocks::V3;
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::Node;
use crate::scheme::hermite4::{Rule, slopes};

/// The steady state's weights ([`Weights`](crate::scheme::hermite4::Weights) for the centred stencil `{k, k+1, k+2}` of node
/// k+1), keyed by the two intervals \[ns\]: what the slice path needs per sample.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SteadyWeights {
    key: (i64, i64),
    rule: Rule,
    alpha: f64,
    beta: f64,
}

impl SteadyWeights {
    /// The weights for the nodes at `t` \[ns\] (the default key (0, 0) matches no stream).
    #[inline(always)]
    fn of(&mut self, t: [i64; 3]) -> &Self {
        let key = (t[1].wrapping_sub(t[0]), t[2].wrapping_sub(t[1]));
        if key != self.key {
            let (alpha, beta) = slopes(t, 1);
            *self = Self {
                key,
                rule: Rule::new(t[0], t[1]),
                alpha,
                beta,
            };
        }
        self
    }
}

/// What the slice path carries from one interval to the next (steady state): nodes k and
/// k+1 (time \[ns\], bias-corrected `ω`, `a`), and node k's `ω̇_k` and `s_k`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Carry {
    t0: i64,
    t1: i64,
    w0: V3,
    w1: V3,
    a0: V3,
    a1: V3,
    dw0: V3,
    s0: V3,
}

impl Carry {
    /// From nodes k and k+1 and node k's `ω̇_k` and `s_k`.
    pub(crate) fn new(n0: &Node, n1: &Node, dw0: V3, s0: V3) -> Self {
        Self {
            t0: n0.t_ns,
            t1: n1.t_ns,
            w0: n0.w,
            w1: n1.w,
            a0: n0.a,
            a1: n1.a,
            dw0,
            s0,
        }
    }

    /// `ω̇` and `s` of the newest complete node.
    pub(crate) fn finish(&self) -> (V3, V3) {
        (self.dw0, self.s0)
    }

    /// Interval k, completed by the new sample k+2 (`s`, corrected with `bias`): the weights
    /// and arithmetic of the one-by-one path ([`FastDeltas::step`](crate::fast::FastDeltas::step) with the stencil
    /// `{k−1, k, k+1, k+2}`).
    #[inline(always)]
    pub(crate) fn prepare_one(
        &mut self,
        s: &ImuSample,
        bias: &ImuBias,
        cache: &mut SteadyWeights,
    ) -> Record {
        let (w2, a2) = (s.gyro - bias.gyro, s.acc - bias.acc);
        let c = *cache.of([self.t0, self.t1, s.t_ns]);
        let (w0, w1, a0, a1) = (l3(&self.w0), l3(&self.w1), l3(&self.a0), l3(&self.a1));
        let dw1 = slope(&sub(&l3(&w2), &w1), &sub(&w1, &w0), c.alpha, c.beta);
        let da1 = slope(&sub(&l3(&a2), &a1), &sub(&a1, &a0), c.alpha, c.beta);
        let s1 = add(&cross(&w1, &a1), &da1);
        let (e, x, y) = prepare(
            c.rule.h_2,
            c.rule.h2_12,
            &w0,
            &w1,
            &a0,
            &a1,
            &l3(&self.dw0),
            &l3(&self.s0),
            &dw1,
            &s1,
        );
        *self = Self {
            t0: self.t1,
            t1: s.t_ns,
            w0: self.w1,
            w1: w2,
            a0: self.a1,
            a1: a2,
            dw0: v3(&dw1),
            s0: v3(&s1),
        };
        Record::one(&e, &x, &y, c.rule.h)
    }

    /// The intervals completed by `samples` (a multiple of `T::N` of them, all of which pass
    /// the common-case test), `T::N` at a time: lane j holds interval k+j, completed by sample
    /// k+2+j, with the same weights and operations as [`Carry::prepare_one`]. Writes
    /// `out[..samples.len()]`.
    #[inline(always)]
    pub(crate) fn prepare_wide<T: Wide>(
        &mut self,
        samples: &[ImuSample],
        bias: &ImuBias,
        cache: &mut LaneWeights<T>,
        out: &mut [Record],
    ) {
        let n = T::N;
        let splat3 = |v: &V3| by3(|i| T::splat(v[i]));
        let (bw, ba) = (splat3(&bias.gyro), splat3(&bias.acc));
        // The previous block's new nodes: (…, k, k+1); (…, ω̇_k) and (…, s_k).
        let last2 = |a: &V3, b: &V3| by3(|i| T::gather(|j| if j + 1 == n { b[i] } else { a[i] }));
        let (mut wc, mut ac) = (last2(&self.w0, &self.w1), last2(&self.a0, &self.a1));
        let (mut dprev, mut sprev) = (splat3(&self.dw0), splat3(&self.s0));
        let mut t = [self.t0, self.t1, 0, 0, 0, 0];
        for (q, rec) in samples.chunks_exact(n).zip(out.chunks_exact_mut(n)) {
            // Nodes k+2…k+n+1 (new), k…k+n−1 and k+1…k+n.
            let w2 = by3(|i| T::gather(|j| q[j].gyro[i]) - bw[i]);
            let a2 = by3(|i| T::gather(|j| q[j].acc[i]) - ba[i]);
            let (wn, an) = (
                by3(|i| T::nodes(wc[i], w2[i])),
                by3(|i| T::nodes(ac[i], a2[i])),
            );
            let (w0, w1, a0, a1) = (
                by3(|i| wn[i].0),
                by3(|i| wn[i].1),
                by3(|i| an[i].0),
                by3(|i| an[i].1),
            );
            for (tj, s) in t[2..].iter_mut().zip(q) {
                *tj = s.t_ns;
            }
            let c = cache.of(&t);
            let dw1 = slope(&sub(&w2, &w1), &sub(&w1, &w0), c.alpha, c.beta);
            let da1 = slope(&sub(&a2, &a1), &sub(&a1, &a0), c.alpha, c.beta);
            let s1 = add(&cross(&w1, &a1), &da1);
            let dw0 = by3(|i| T::after(dprev[i], dw1[i]));
            let s0 = by3(|i| T::after(sprev[i], s1[i]));
            let (e, x, y) = prepare(c.h_2, c.h2_12, &w0, &w1, &a0, &a1, &dw0, &s0, &dw1, &s1);
            T::records(&e, &x, &y, c.h, rec);
            (wc, ac, dprev, sprev) = (w2, a2, dw1, s1);
            (t[0], t[1]) = (t[n], t[n + 1]);
        }
        let lane = |l: &L3<T>, j: usize| V3::new(l[0].lane(j), l[1].lane(j), l[2].lane(j));
        *self = Self {
            t0: t[0],
            t1: t[1],
            w0: lane(&wc, n - 2),
            w1: lane(&wc, n - 1),
            a0: lane(&ac, n - 2),
            a1: lane(&ac, n - 1),
            dw0: lane(&dprev, n - 1),
            s0: lane(&sprev, n - 1),
        };
    }

    /// [`Carry::prepare_wide`] in [`F4`] lanes, compiled for AVX2.
    ///
    /// Only for processors with AVX2 ([`crate::fast::lanes::avx2`]): the caller checks.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(crate) fn prepare_quads(
        &mut self,
        samples: &[ImuSample],
        bias: &ImuBias,
        cache: &mut LaneWeights<F4>,
        out: &mut [Record],
    ) {
        self.prepare_wide(samples, bias, cache, out);
    }
}

/// A lane type that prepares `N` consecutive intervals at once ([`Carry::prepare_wide`]).
pub(crate) trait Wide: Lane {
    /// Lanes (intervals per step), at least 2.
    const N: usize;
    /// Lane j is `f(j)`.
    fn gather(f: impl Fn(usize) -> f64) -> Self;
    /// Lane `j`.
    fn lane(self, j: usize) -> f64;
    /// From the previous step's new nodes (k−N+2…k+1) and this step's (k+2…k+N+1): the
    /// interval starts k…k+N−1 and ends k+1…k+N.
    fn nodes(prev: Self, new: Self) -> (Self, Self);
    /// `(prev_N−1, cur_0, …, cur_N−2)`: a node quantity one lane back.
    fn after(prev: Self, cur: Self) -> Self;
    /// Writes the `N` lanes' records to `out[..N]`.
    fn records(e: &[Self; 4], x: &L3<Self>, y: &L3<Self>, h: Self, out: &mut [Record]);
}

impl Wide for F2 {
    const N: usize = 2;
    #[inline(always)]
    fn gather(f: impl Fn(usize) -> f64) -> Self {
        F2::new(f(0), f(1))
    }
    #[inline(always)]
    fn lane(self, j: usize) -> f64 {
        if j == 0 { self.lo() } else { self.hi() }
    }
    #[inline(always)]
    fn nodes(prev: Self, new: Self) -> (Self, Self) {
        (prev, F2::straddle(prev, new))
    }
    #[inline(always)]
    fn after(prev: Self, cur: Self) -> Self {
        F2::straddle(prev, cur)
    }
    #[inline(always)]
    fn records(e: &[Self; 4], x: &L3<Self>, y: &L3<Self>, h: Self, out: &mut [Record]) {
        out[..2].copy_from_slice(&Record::two(e, x, y, h));
    }
}

#[cfg(target_arch = "x86_64")]
impl Wide for F4 {
    const N: usize = 4;
    #[inline(always)]
    fn gather(f: impl Fn(usize) -> f64) -> Self {
        F4::new([f(0), f(1), f(2), f(3)])
    }
    #[inline(always)]
    fn lane(self, j: usize) -> f64 {
        self.lanes()[j]
    }
    #[inline(always)]
    fn nodes(prev: Self, new: Self) -> (Self, Self) {
        let n0 = F4::straddle2(prev, new);
        (n0, F4::odd_even(n0, new))
    }
    #[inline(always)]
    fn after(prev: Self, cur: Self) -> Self {
        F4::after(prev, cur)
    }
    #[inline(always)]
    fn records(e: &[Self; 4], x: &L3<Self>, y: &L3<Self>, h: Self, out: &mut [Record]) {
        out[..4].copy_from_slice(&Record::four(e, x, y, h));
    }
}

/// [`SteadyWeights`] of `T::N` consecutive intervals, one per lane, keyed by the `T::N + 1`
/// intervals \[ns\] their stencils span: every lane holds exactly what [`SteadyWeights::of`]
/// gives for its interval.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LaneWeights<T> {
    key: [i64; 5],
    h: T,
    h_2: T,
    h2_12: T,
    alpha: T,
    beta: T,
}

impl<T: Wide> LaneWeights<T> {
    /// The weights of intervals `[t_j, t_j+1]` (nodes `t_j+1`), j < `T::N`, for the nodes at
    /// `t[..T::N + 2]` \[ns\].
    #[inline(always)]
    fn of(&mut self, t: &[i64; 6]) -> &Self {
        let mut key = [0; 5];
        for j in 0..=T::N {
            key[j] = t[j + 1].wrapping_sub(t[j]);
        }
        if key[..=T::N] != self.key[..=T::N] {
            self.refresh(t, key);
        }
        self
    }

    #[cold]
    #[inline(never)]
    fn refresh(&mut self, t: &[i64; 6], key: [i64; 5]) {
        let rule = |j: usize| Rule::new(t[j], t[j + 1]);
        let ab = |j: usize| slopes([t[j], t[j + 1], t[j + 2]], 1);
        *self = Self {
            key,
            h: T::gather(|j| rule(j).h),
            h_2: T::gather(|j| rule(j).h_2),
            h2_12: T::gather(|j| rule(j).h2_12),
            alpha: T::gather(|j| ab(j).0),
            beta: T::gather(|j| ab(j).1),
        };
    }
}
