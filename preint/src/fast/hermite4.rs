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
//! one-by-one path ([`step`]) runs the same code in `f64`, so they all agree bit for bit.

#[cfg(target_arch = "x86_64")]
use super::lanes::quad::F4;
use super::lanes::{F2, Lane};
use super::quat::Quat;
use super::{FastDeltas, QuatDeltas};
use crate::preintegrator::validation::common_case;
use crate::propagation::blocks::{M3, V3};
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::hermite4::{Hermite4, Rule, Weights, slopes};
use crate::scheme::{Node, RENORM_EVERY, Stencil};

/// The steady state's weights ([`Weights`] for the centred stencil `{k, k+1, k+2}` of node
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

/// A 3-vector in lanes: `[x, y, z]`.
type L3<T> = [T; 3];

/// `[f(0), f(1), f(2)]` (`array::map` is not always inlined, and a call in the lane code costs
/// more than the work).
#[inline(always)]
fn by3<T>(f: impl Fn(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

#[inline(always)]
fn add<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
fn sub<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
fn scale<T: Lane>(a: &L3<T>, s: T) -> L3<T> {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline(always)]
fn cross<T: Lane>(a: &L3<T>, b: &L3<T>) -> L3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `R(q)` for a unit quaternion `q = (w, x, y, z)`, by rows: `I + 2(w[q_v]× + [q_v]×²)`
/// (in lanes its 21 operations and the 15 of a product [`mv`] are all packed).
#[inline(always)]
fn rot_matrix<T: Lane>(q: &[T; 4]) -> [L3<T>; 3] {
    let [w, x, y, z] = *q;
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, yy, zz) = (x * x2, y * y2, z * z2);
    let (xy, xz, yz) = (x * y2, x * z2, y * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let one = T::splat(1.0);
    [
        [one - (yy + zz), xy - wz, xz + wy],
        [xy + wz, one - (xx + zz), yz - wx],
        [xz - wy, yz + wx, one - (xx + yy)],
    ]
}

/// `M v`.
#[inline(always)]
fn mv<T: Lane>(m: &[L3<T>; 3], v: &L3<T>) -> L3<T> {
    by3(|i| (m[i][0] * v[0] + m[i][1] * v[1]) + m[i][2] * v[2])
}

/// `α d₁₂ + β d₀₁`: a node's derivative from its two differences (as the parent's `slope`).
#[inline(always)]
fn slope<T: Lane>(d12: &L3<T>, d01: &L3<T>, alpha: T, beta: T) -> L3<T> {
    add(&scale(d12, alpha), &scale(d01, beta))
}

#[inline(always)]
fn l3(v: &V3) -> L3<f64> {
    [v.x, v.y, v.z]
}

#[inline(always)]
fn v3(l: &L3<f64>) -> V3 {
    V3::new(l[0], l[1], l[2])
}

/// `s = ω × a + ȧ` of a node (frame of the node), rounded as [`Carry`] rounds it.
#[inline(always)]
pub(crate) fn s_of(w: &V3, a: &V3, da: &V3) -> V3 {
    v3(&add(&cross(&l3(w), &l3(a)), &l3(da)))
}

/// `(E, x, y)` of the interval (module docs) from its rule (`h/2`, `h²/12`), the rates and
/// accelerations of both nodes, node k's `ω̇_k` and `s_k`, and node k+1's `ω̇_k+1` and `s_k+1`.
/// `E` is the unit quaternion `(cos(θ/2), sin(θ/2)/θ Ω)` of
/// `Ω = h/2 (ω_k + ω_k+1) + h²/12 (ω̇_k − ω̇_k+1 + ω_k × ω_k+1)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn prepare<T: Lane>(
    h_2: T,
    h12: T,
    w0: &L3<T>,
    w1: &L3<T>,
    a0: &L3<T>,
    a1: &L3<T>,
    dw0: &L3<T>,
    s0: &L3<T>,
    dw1: &L3<T>,
    s1: &L3<T>,
) -> ([T; 4], L3<T>, L3<T>) {
    let om = add(
        &scale(&add(w0, w1), h_2),
        &scale(&add(&sub(dw0, dw1), &cross(w0, w1)), h12),
    );
    let (c, s) = T::exp_quat_coeffs((om[0] * om[0] + om[1] * om[1]) + om[2] * om[2]);
    let e = [c, s * om[0], s * om[1], s * om[2]];
    let m = rot_matrix(&e);
    let (eb, ea) = (mv(&m, &sub(&scale(a1, h_2), &scale(s1, h12))), mv(&m, a1));
    let x = add(&add(&scale(a0, h_2), &scale(s0, h12)), &eb);
    let y = add(&scale(&x, h_2), &scale(&sub(a0, &ea), h12));
    (e, x, y)
}

/// One prepared interval, laid out for [`State::step`]: `E = (c, e_x, e_y, e_z)` as the pairs
/// `(c, e_x)`, `(e_y, e_z)`; `(x_i, y_i)` by component; `(h, h)` \[s\].
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub(crate) struct Record {
    e1: F2,
    e2: F2,
    xy: [F2; 3],
    h: F2,
}

impl Record {
    #[inline(always)]
    fn one(e: &[f64; 4], x: &L3<f64>, y: &L3<f64>, h: f64) -> Self {
        Self {
            e1: F2::new(e[0], e[1]),
            e2: F2::new(e[2], e[3]),
            xy: by3(|i| F2::new(x[i], y[i])),
            h: F2::splat(h),
        }
    }

    /// The records of the four intervals in lanes 0…3.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn four(e: &[F4; 4], x: &L3<F4>, y: &L3<F4>, h: F4) -> [Self; 4] {
        // (a0, b0, a2, b2), (a1, b1, a3, b3) split into the pairs of lanes 0, 2 and 1, 3.
        let split = |a: F4, b: F4| {
            let (l, h) = F4::interleave(a, b);
            let ((p0, p2), (p1, p3)) = (l.halves(), h.halves());
            [p0, p1, p2, p3]
        };
        let (e1, e2, hh) = (split(e[0], e[1]), split(e[2], e[3]), split(h, h));
        let xy: [[F2; 4]; 3] = by3(|i| split(x[i], y[i]));
        std::array::from_fn(|j| Self {
            e1: e1[j],
            e2: e2[j],
            xy: [xy[0][j], xy[1][j], xy[2][j]],
            h: hh[j],
        })
    }

    /// The records of the two intervals in lanes lo and hi.
    #[inline(always)]
    fn two(e: &[F2; 4], x: &L3<F2>, y: &L3<F2>, h: F2) -> [Self; 2] {
        [
            Self {
                e1: F2::lows(e[0], e[1]),
                e2: F2::lows(e[2], e[3]),
                xy: by3(|i| F2::lows(x[i], y[i])),
                h: h.splat_lo(),
            },
            Self {
                e1: F2::highs(e[0], e[1]),
                e2: F2::highs(e[2], e[3]),
                xy: by3(|i| F2::highs(x[i], y[i])),
                h: h.splat_hi(),
            },
        ]
    }
}

/// The running deltas in lanes: ΔR's quaternion as `(w, x)`, `(y, z)` and `(Δv_i, Δp_i)` by
/// component.
#[derive(Clone, Copy, Debug)]
pub(crate) struct State {
    qa: F2,
    qb: F2,
    vp: [F2; 3],
}

impl State {
    #[inline(always)]
    pub(crate) fn load(d: &QuatDeltas) -> Self {
        let (q, v, p) = (&d.q, &d.v, &d.p);
        Self {
            qa: F2::new(q.w, q.v.x),
            qb: F2::new(q.v.y, q.v.z),
            vp: by3(|i| F2::new(v[i], p[i])),
        }
    }

    #[inline(always)]
    pub(crate) fn store(&self, d: &mut QuatDeltas) {
        d.q = Quat {
            w: self.qa.lo(),
            v: V3::new(self.qa.hi(), self.qb.lo(), self.qb.hi()),
        };
        d.v = V3::new(self.vp[0].lo(), self.vp[1].lo(), self.vp[2].lo());
        d.p = V3::new(self.vp[0].hi(), self.vp[1].hi(), self.vp[2].hi());
    }

    /// One interval: `Δv += ΔR_k x`, `Δp = (Δp + h Δv) + ΔR_k y`, `q = q ⊗ E`.
    #[inline(always)]
    pub(crate) fn step(&mut self, r: &Record) {
        let (w, x) = (self.qa.splat_lo(), self.qa.splat_hi());
        let (y, z) = (self.qb.splat_lo(), self.qb.splat_hi());
        // R(q) P = P + w t + q_v × t, t = 2 q_v × P (Quat::rotate, both vectors at once).
        let (qv, p) = ([x, y, z], &r.xy);
        let t = cross(&qv, p);
        let t = add(&t, &t);
        let rxy = add(&add(p, &scale(&t, w)), &cross(&qv, &t));
        let zero = F2::splat(0.0);
        for (vp, o) in self.vp.iter_mut().zip(&rxy) {
            // (v + 0, p + v h) + (R x, R y)_i
            *vp = (*vp + F2::lows(zero, *vp) * r.h) + *o;
        }
        // q ⊗ E, the lanes of (w', x') and (y', z') (Hamilton product, as Quat::mul).
        let (e1, e2) = (r.e1, r.e2);
        let (e1s, e2s) = (e1.swap(), e2.swap());
        self.qa = (w * e1 + x * e1s.flip(true, false))
            + (y * e2.flip(true, false) + z * e2s.flip(true, true));
        self.qb = (w * e2 + x * e2s.flip(true, false)) + (y * e1.flip(false, true) + z * e1s);
    }
}

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
    /// and arithmetic of the one-by-one path ([`super::step`] with the stencil
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
    /// Only for processors with AVX2 ([`super::lanes::avx2`]): the caller checks.
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

/// The slice path's arguments: the samples, the bias estimate, the last timestamp before
/// them \[ns\] and the largest gap \[ns\].
type SliceArgs<'a> = (&'a [ImuSample], &'a ImuBias, i64, u64);

impl FastDeltas for HermiteDeltas {
    const ENABLED: bool = true;
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
    fn run_slice(
        &mut self,
        last: &[Node; 2],
        samples: &[ImuSample],
        bias: &ImuBias,
        last_t_ns: i64,
        gap_limit: u64,
        done: &mut usize,
    ) -> usize {
        let mut d = self.d;
        let mut carry = Carry::new(&last[0], &last[1], self.dw_last, self.s_last);
        let used = if samples.len() < BLOCK {
            let w = &mut self.steady;
            super::slice_loop(samples, last_t_ns, gap_limit, &mut d, done, |d, s| {
                let r = carry.prepare_one(s, bias, w);
                let mut st = State::load(d);
                st.step(&r);
                st.store(d);
            })
        } else {
            let args = (samples, bias, last_t_ns, gap_limit);
            #[cfg(target_arch = "x86_64")]
            if super::lanes::avx2() {
                // SAFETY: this processor has AVX2.
                unsafe { self.blocks_avx2(&mut carry, &mut d, done, args) }
            } else {
                self.blocks::<false>(&mut carry, &mut d, done, args)
            }
            #[cfg(not(target_arch = "x86_64"))]
            self.blocks::<false>(&mut carry, &mut d, done, args)
        };
        (self.dw_last, self.s_last) = carry.finish();
        self.d = d;
        used
    }

    fn renormalize(&mut self) {
        self.d.q.renormalize();
    }

    fn deltas(&self) -> (M3, V3, V3) {
        self.d.deltas()
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
        (samples, bias, last_t_ns, gap_limit): SliceArgs,
    ) -> usize {
        let mut buf = [Record::default(); BLOCK];
        let (mut used, mut last) = (0, last_t_ns);
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
        args: SliceArgs,
    ) -> usize {
        self.blocks::<true>(carry, d, done, args)
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
