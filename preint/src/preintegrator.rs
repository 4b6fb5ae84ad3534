//! The preintegrator: feeds samples one at a time (or a slice) through the chosen scheme and
//! returns a [`PreintegratedImu`].
//!
//! The window is `[first sample, last sample]` pushed; keyframe times between samples are
//! handled by [`crate::window::preintegrate`], which inserts interpolated boundary samples.
//! Intervals are processed with a small lag (Euler and midpoint: 1 sample, rk4: 3 samples)
//! because a sample's noise is added once it is no longer used and needs its time cell (see
//! [`Preintegrator`] and the internal `propagation` module); the tail is integrated by
//! [`Preintegrator::finish`], which does not consume the preintegrator.

use crate::error::PreintError;
use crate::measurement::{BiasJacobians, Cov9, Cov15, EdgeNoise, EdgeSource, PreintegratedImu};
use crate::noise::{CellRule, walk_scale, white_scale};
use crate::params::{CovShape, Level, PreintParams, Scheme};
use crate::propagation::{
    BiasWalk, Blk96, ErrorState, GenQ, IsoQ, NO_ID, NoiseQ, Origin, SLOTS, Sym9, Transition,
    rot_cols,
};
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::hermite::deltas::{Carry, LaneWeights, Record, State};
use crate::scheme::{Deltas, Node, euler, hermite, midpoint, span_s};
use crate::simd::F2;
use preint_lie::SO3;

const RING: usize = 8;
/// ΔR is re-orthonormalised (`R ← ½R(3I − RᵀR)`) every this many intervals.
const RENORM_EVERY: usize = 1024;

/// Intervals per block of [`Core::run_deltas_rk4`]: 64 × 96 bytes of prepared intervals stay
/// in the L1 cache.
const RK4_BLOCK: usize = 64;
/// Most edge samples whose gains are collected (rk4: context, 3 first, 3 last, context).
const CAPS: usize = 8;
/// Most distinct noise sources of the edge samples (each is a combination of ≤ 4).
const ACC: usize = 16;

#[derive(Clone, Copy, Debug)]
enum NoiseKind {
    Iso(IsoQ),
    Gen(GenQ),
}

/// A stream sample referenced by a window edge, with its intervals \[s\] to its stream
/// neighbours (0 if none).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Src {
    pub t_ns: i64,
    pub left_s: f64,
    pub right_s: f64,
}

/// What the window path knows about one edge of a window (see [`crate::window`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Side {
    /// Stream samples referenced here: the boundary sample's stencil first, then the rk4
    /// context sample and the neighbours whose stream intervals the window does not see.
    pub src: [Src; 8],
    pub n_src: usize,
    /// The boundary sample is `Σ w[i]·src[i]` for `i < nw`; `nw = 0`: no window information
    /// (the boundary is a pushed sample like any other).
    pub w: [f64; 4],
    pub nw: usize,
    /// rk4 context sample just outside the window (raw reading).
    pub ctx: Option<ImuSample>,
}

impl Side {
    fn find(&self, t_ns: i64) -> Option<&Src> {
        self.src[..self.n_src].iter().find(|s| s.t_ns == t_ns)
    }
}

/// Window-path information for both edges.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct WindowSpec {
    pub start: Side,
    pub end: Side,
}

/// The gain of an edge sample collected when it was retired.
#[derive(Clone, Copy, Debug, Default)]
struct Cap {
    /// Extended index (context before = 0 when present).
    ext: usize,
    /// Its total gain, pulled back to the origin (internal `propagation` module).
    g: Blk96,
    /// Timestamp of the sample itself.
    node_t: i64,
    /// Intervals to its window neighbours \[s\] (0 if none).
    left: f64,
    right: f64,
}

#[derive(Clone, Debug)]
struct Core {
    ring: [Node; RING],
    /// Window samples pushed.
    n: usize,
    /// 1 if a context sample precedes the window (it is `ring[0]`, extended index 0).
    cb: usize,
    ctx_after: Option<Node>,
    /// Origin of the pulled-back error.
    origin: Origin,
    /// Midpoint: length of the last interval integrated \[s\].
    h_prev: f64,
    /// rk4: the last stencil's weights, and the slice path's.
    weights: hermite::Weights,
    steady: hermite::SteadyWeights,
    /// The same for two intervals at a time (the rk4 slice path).
    pairs: LaneWeights<F2>,
    /// Four at a time (the rk4 slice path with AVX2).
    #[cfg(target_arch = "x86_64")]
    quads: LaneWeights<crate::simd::quad::F4>,
    /// Window intervals integrated.
    done: usize,
    d: Deltas,
    e: ErrorState,
    caps: [Cap; CAPS],
    ncap: usize,
}

/// Static configuration of the loop, fixed at construction.
#[derive(Clone, Copy, Debug)]
struct Cfg {
    scheme: Scheme,
    rule: CellRule,
    walk: BiasWalk,
    int_cov: Option<CovShape>,
    /// Number of first / last window samples whose gains are collected.
    e0: usize,
    e1: usize,
}

impl Core {
    /// Sample at extended index `i` (window sample `j` is `j + cb`; `cb + n` is the context
    /// after, if any).
    #[inline(always)]
    fn ext(&self, i: usize) -> Node {
        match self.ctx_after {
            Some(c) if i == self.cb + self.n => c,
            _ => self.ring[i % RING],
        }
    }

    /// Window sample `j`.
    #[inline(always)]
    fn node(&self, j: usize) -> &Node {
        &self.ring[(j + self.cb) % RING]
    }

    /// Intervals \[s\] from window sample `j` to its window neighbours (0 if none; `total`
    /// samples if known).
    #[inline(always)]
    fn intervals(&self, j: usize, total: usize) -> (f64, f64) {
        let t = self.node(j).t_ns;
        let left = if j > 0 {
            span_s(self.node(j - 1).t_ns, t)
        } else {
            0.0
        };
        let right = if j + 1 < total {
            span_s(t, self.node(j + 1).t_ns)
        } else {
            0.0
        };
        (left, right)
    }

    /// Whether the sample at extended index `ext` is an edge sample (its gain is collected
    /// instead of its noise being added): a context sample, one of the first `e0`, or (at
    /// the end, `fin`) one of the last `e1` window samples.
    #[inline(always)]
    fn is_edge(&self, cfg: &Cfg, ext: usize, fin: bool) -> bool {
        if ext < self.cb || ext >= self.cb + self.n {
            return true;
        }
        self.is_window_edge(cfg, ext - self.cb, fin)
    }

    /// [`Core::is_edge`] for window sample `j`.
    #[inline(always)]
    fn is_window_edge(&self, cfg: &Cfg, j: usize, fin: bool) -> bool {
        j < cfg.e0 || (fin && j + cfg.e1 >= self.n)
    }

    /// Stores the total pulled-back gain `g` of edge sample `ext`.
    #[inline(never)]
    fn capture(&mut self, ext: usize, g: &Blk96, left: f64, right: f64) -> bool {
        if self.ncap == CAPS {
            return false;
        }
        self.caps[self.ncap] = Cap {
            ext,
            g: *g,
            node_t: self.ext(ext).t_ns,
            left,
            right,
        };
        self.ncap += 1;
        true
    }

    /// Edge sample `ext`: its gain is stored for an exact merge, or, if the store is full,
    /// its white noise is added to the covariance now (as for an interior sample).
    fn capture_or_add<N: NoiseQ>(
        &mut self,
        cfg: &Cfg,
        noise: &N,
        ext: usize,
        g: &Blk96,
        (left, right): (f64, f64),
    ) {
        if !self.capture(ext, g, left, right) {
            let s = white_scale(cfg.rule.cell_s(left, right));
            self.e.add_noise(g, s, noise);
        }
    }

    /// rk4: retires the pending samples with extended index below `below`.
    #[inline(always)]
    fn retire_below<N: NoiseQ>(&mut self, cfg: &Cfg, noise: &N, below: usize, fin: bool) {
        let total = if fin { self.n } else { usize::MAX };
        for slot in 0..SLOTS {
            let id = self.e.pend[slot].id;
            if id == NO_ID || id >= below {
                continue;
            }
            let pd = self.e.take_pending(slot);
            let (left, right) = if id >= self.cb && id < self.cb + self.n {
                self.intervals(id - self.cb, total)
            } else {
                (0.0, 0.0)
            };
            if !(self.is_edge(cfg, id, fin) && self.capture(id, &pd.g, left, right)) {
                let s = white_scale(cfg.rule.cell_s(left, right));
                self.e.add_noise(&pd.g, s, noise);
            }
        }
    }

    /// Euler interval `k` (out of line: it keeps the per-interval code small enough for the
    /// compiler to inline the fixed-size matrix operations).
    #[inline(never)]
    fn euler_interval<N: NoiseQ, const LIN: bool>(
        &mut self,
        cfg: &Cfg,
        noise: &N,
        k: usize,
        total: usize,
        fin: bool,
    ) {
        let cb = self.cb;
        let n0 = *self.node(k);
        let t1 = self.node(k + 1).t_ns;
        let h = span_s(n0.t_ns, t1);
        if let Some((tr, g)) = euler::step::<LIN>(&mut self.d, &n0, h, t1, &mut self.origin) {
            let edge = self.is_window_edge(cfg, k, fin);
            // The held interval `h` decides the cell (`CellRule::Held`); the left
            // interval is only recorded for edge samples.
            let s = if edge {
                0.0
            } else {
                white_scale(cfg.rule.cell_s(0.0, h))
            };
            let c = (g.cv, g.cp, g.cp0);
            self.e
                .step_euler(&tr, &g.pb, &g.g, &g.r0, c, s, noise, &cfg.walk);
            if edge {
                let (left, right) = self.intervals(k, total);
                let blk = Blk96 {
                    g: g.g,
                    a: rot_cols(&g.r0, g.cv, g.cp),
                };
                self.capture_or_add(cfg, noise, k + cb, &blk, (left, right));
            }
            self.int_cov(cfg, tr.h);
        }
    }

    /// Midpoint interval `k` (out of line, see [`Core::euler_interval`]).
    #[inline(never)]
    fn midpoint_interval<N: NoiseQ, const LIN: bool>(
        &mut self,
        cfg: &Cfg,
        noise: &N,
        k: usize,
        fin: bool,
    ) {
        let cb = self.cb;
        let (n0, n1) = (*self.node(k), *self.node(k + 1));
        let h = span_s(n0.t_ns, n1.t_ns);
        if let Some((tr, g)) = midpoint::step::<LIN>(&mut self.d, &n0, &n1, h, &mut self.origin) {
            // Sample k's intervals to its neighbours: the previous interval and this one.
            let (left, right) = (if k > 0 { self.h_prev } else { 0.0 }, h);
            self.h_prev = h;
            let edge = self.is_window_edge(cfg, k, fin);
            let s0 = if edge {
                0.0
            } else {
                white_scale(cfg.rule.cell_s(left, right))
            };
            let done = self.e.step_mid(&tr, &g, &self.d.r, s0, noise, &cfg.walk);
            if edge {
                let blk = Blk96 {
                    g: done.g,
                    a: rot_cols(&g.r0, done.cv, done.cp),
                };
                self.capture_or_add(cfg, noise, k + cb, &blk, (left, right));
            }
            self.int_cov(cfg, tr.h);
        }
    }

    /// rk4 interval `k` (out of line, see [`Core::euler_interval`]).
    #[inline(never)]
    fn rk4_interval<N: NoiseQ, const LIN: bool>(
        &mut self,
        cfg: &Cfg,
        noise: &N,
        k: usize,
        fin: bool,
    ) {
        let (n, cb) = (self.n, self.cb);
        let ke = k + cb;
        let len = cb + n + usize::from(fin && self.ctx_after.is_some());
        let m = len.min(4);
        let s0 = if fin {
            ke.saturating_sub(1).min(len - m)
        } else {
            ke.saturating_sub(1)
        };
        if LIN {
            self.retire_below(cfg, noise, s0, fin);
        }
        let mut st = [&self.ring[0]; 4];
        for (j, x) in st.iter_mut().enumerate().take(m) {
            *x = match &self.ctx_after {
                Some(c) if s0 + j == cb + n => c,
                _ => &self.ring[(s0 + j) % RING],
            };
        }
        let (o, w) = (&mut self.origin, &mut self.weights);
        let pend = &mut self.e.pend;
        let mut gsum = Blk96::default();
        let sum = cfg.walk.combined.then_some(&mut gsum);
        let first = k == 0;
        if let Some((tr, pb)) =
            hermite::step::<LIN>(&mut self.d, &st, m, ke - s0, first, s0, o, w, pend, sum)
        {
            self.e.step_multi(&tr, &pb, &gsum, &cfg.walk);
            self.int_cov(cfg, tr.h);
        }
    }

    /// Counts one more interval integrated; every [`RENORM_EVERY`] intervals ΔR is
    /// re-orthonormalised.
    #[inline(always)]
    fn interval_done(&mut self) {
        Self::count_interval(&mut self.done, &mut self.d);
    }

    /// [`Core::interval_done`] on loose state.
    #[inline(always)]
    fn count_interval(done: &mut usize, d: &mut Deltas) {
        *done += 1;
        if done.is_multiple_of(RENORM_EVERY) {
            d.renormalize();
        }
    }

    /// [`Level::Deltas`] with Euler (`MID = false`) or midpoint (`MID = true`), in the steady
    /// state (`n ≥ 2`, every interval but the last integrated): integrates the leading samples
    /// of `samples` that pass [`Preintegrator::integrate`]'s common-case test, straight from
    /// the slice, and returns how many. The same scheme steps and re-orthonormalisation as
    /// [`Core::advance`], in the same order, so the deltas are bit-identical to pushing the
    /// samples one by one (`preint/tests/deltas_fast_path.rs`); what it saves is the ring
    /// traffic and the per-sample dispatch: the deltas and the two newest samples stay in
    /// registers. The ring is written back at the end.
    #[inline(never)]
    fn run_deltas<const MID: bool>(
        &mut self,
        samples: &[ImuSample],
        bias: &ImuBias,
        last_t_ns: i64,
        gap_limit: u64,
    ) -> usize {
        let (mut d, mut done) = (self.d, self.done);
        let (mut n0, mut n1) = (*self.node(self.n - 2), *self.node(self.n - 1));
        let o = &mut self.origin;
        let used = Self::slice_loop(samples, last_t_ns, gap_limit, &mut d, &mut done, {
            |d, s, _| {
                let h = span_s(n0.t_ns, n1.t_ns);
                if MID {
                    midpoint::step::<false>(d, &n0, &n1, h, o);
                } else {
                    euler::step::<false>(d, &n0, h, n1.t_ns, o);
                }
                (n0, n1) = (n1, Node::corrected(s, bias));
            }
        });
        self.finish_slice(d, done, samples, used, bias)
    }

    /// [`Core::run_deltas`] for rk4: in the steady state (`n ≥ 3`, every interval but the last
    /// two integrated) each new sample k+2 completes the derivative stencil `{k, k+1, k+2}`
    /// of node k+1 and so interval k = n − 2, which [`Core::rk4_interval`] would integrate with
    /// the same weights and operations (`hermite::deltas`, whose lane code is written once for
    /// one, two and four intervals at a time). What the next interval needs of nodes k and
    /// k+1 is carried ([`Carry`]).
    ///
    /// The samples are taken in blocks of [`RK4_BLOCK`] ([`Core::rk4_blocks`]): first
    /// everything that does not depend on ΔR (the node derivatives, `Exp(Ω)` and the two
    /// vectors that ΔR_k rotates, [`Carry::prepare_quads`] etc.) for the whole block, several
    /// intervals per SIMD register, then the chain through ΔR, Δv and Δp ([`State::step`]).
    /// A slice shorter than a block is taken one interval at a time.
    #[inline(never)]
    fn run_deltas_rk4(
        &mut self,
        samples: &[ImuSample],
        bias: &ImuBias,
        last_t_ns: i64,
        gap_limit: u64,
    ) -> usize {
        let (mut d, mut done) = (self.d, self.done);
        let n = self.n;
        let mut carry = Carry::new(self.node(n - 2), self.node(n - 1), &d);
        let used = if samples.len() < RK4_BLOCK {
            let w = &mut self.steady;
            Self::slice_loop(samples, last_t_ns, gap_limit, &mut d, &mut done, {
                |d, s, _| {
                    let r = carry.prepare_one(s, bias, w);
                    let mut st = State::load(d);
                    st.step(&r);
                    st.store(d);
                }
            })
        } else {
            let args = (samples, bias, last_t_ns, gap_limit);
            #[cfg(target_arch = "x86_64")]
            if crate::simd::avx2() {
                // SAFETY: this processor has AVX2.
                unsafe { self.rk4_blocks_avx2(&mut carry, &mut d, &mut done, args) }
            } else {
                self.rk4_blocks::<false>(&mut carry, &mut d, &mut done, args)
            }
            #[cfg(not(target_arch = "x86_64"))]
            self.rk4_blocks::<false>(&mut carry, &mut d, &mut done, args)
        };
        carry.finish(&mut d);
        self.finish_slice(d, done, samples, used, bias)
    }

    /// The blocks of [`Core::run_deltas_rk4`]: per block of up to [`RK4_BLOCK`] samples that
    /// pass the common-case test, the intervals they complete are prepared four at a time
    /// (`QUADS`, AVX2 only), two at a time and one at a time, then accumulated.
    #[inline(always)]
    fn rk4_blocks<const QUADS: bool>(
        &mut self,
        carry: &mut Carry,
        d: &mut Deltas,
        done: &mut usize,
        (samples, bias, last_t_ns, gap_limit): (&[ImuSample], &ImuBias, i64, u64),
    ) -> usize {
        let mut buf = [Record::default(); RK4_BLOCK];
        let (mut used, mut last) = (0, last_t_ns);
        loop {
            let rest = &samples[used..];
            let mut m = 0;
            for s in rest.iter().take(RK4_BLOCK) {
                if !Preintegrator::common_case(s, last, gap_limit) {
                    break;
                }
                last = s.t_ns;
                m += 1;
            }
            #[cfg(target_arch = "x86_64")]
            let i = if QUADS {
                let i = m & !3;
                // SAFETY: `QUADS` only from `rk4_blocks_avx2`, entered on processors with AVX2.
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
                unsafe { Self::accumulate_avx2(d, done, &buf[..m]) };
            } else {
                Self::accumulate(d, done, &buf[..m]);
            }
            #[cfg(not(target_arch = "x86_64"))]
            Self::accumulate(d, done, &buf[..m]);
            used += m;
            if m < RK4_BLOCK {
                return used;
            }
        }
    }

    /// The chain through ΔR, Δv and Δp over prepared intervals, counting them (with the
    /// re-orthonormalisation of [`Core::count_interval`]). Out of line: its registers are then
    /// allocated for this loop alone (inlined into the SSE2 block loop, they moved with every
    /// change to the preparation around it: 397 instead of 370 instructions per sample). The
    /// AVX2 copy ends up inlined into [`Core::rk4_blocks_avx2`] anyway (its 3-operand encoding
    /// needs no register copies), at the same count as before (230).
    #[inline(never)]
    fn accumulate(d: &mut Deltas, done: &mut usize, recs: &[Record]) {
        Self::accumulate_inline(d, done, recs);
    }

    /// [`Core::accumulate`] compiled for AVX2 (VEX encoding; the same operations).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn accumulate_avx2(d: &mut Deltas, done: &mut usize, recs: &[Record]) {
        Self::accumulate_inline(d, done, recs);
    }

    #[inline(always)]
    fn accumulate_inline(d: &mut Deltas, done: &mut usize, recs: &[Record]) {
        let mut st = State::load(d);
        for r in recs {
            st.step(r);
            *done += 1;
            if done.is_multiple_of(RENORM_EVERY) {
                st.store(d);
                d.renormalize();
                st = State::load(d);
            }
        }
        st.store(d);
    }

    /// [`Core::rk4_blocks`] compiled for AVX2 (VEX encoding everywhere, four-lane
    /// preparation). The same operations, so the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn rk4_blocks_avx2(
        &mut self,
        carry: &mut Carry,
        d: &mut Deltas,
        done: &mut usize,
        args: (&[ImuSample], &ImuBias, i64, u64),
    ) -> usize {
        self.rk4_blocks::<true>(carry, d, done, args)
    }

    /// The loop of the slice paths: takes the leading samples of `samples` that pass
    /// [`Preintegrator::integrate`]'s common-case test, hands each one and the index of the
    /// interval it completes to `step`, counts the interval (with the re-orthonormalisation of
    /// [`Core::advance`]) and returns how many samples it took. (`step` builds the sample's
    /// node itself, where it needs it: built before the step, it stays live across it and
    /// costs registers.)
    #[inline(always)]
    fn slice_loop(
        samples: &[ImuSample],
        mut last_t_ns: i64,
        gap_limit: u64,
        d: &mut Deltas,
        done: &mut usize,
        mut step: impl FnMut(&mut Deltas, &ImuSample, usize),
    ) -> usize {
        let mut used = 0;
        for s in samples {
            if !Preintegrator::common_case(s, last_t_ns, gap_limit) {
                break;
            }
            last_t_ns = s.t_ns;
            step(d, s, *done);
            Self::count_interval(done, d);
            used += 1;
        }
        used
    }

    /// After a slice path took `used` samples: its deltas and interval count, and the ring as
    /// pushing them one by one would have left it (the nodes of the last min(used, RING)
    /// samples; older ones are already there). Returns `used`.
    fn finish_slice(
        &mut self,
        d: Deltas,
        done: usize,
        samples: &[ImuSample],
        used: usize,
        bias: &ImuBias,
    ) -> usize {
        (self.d, self.done) = (d, done);
        self.n += used;
        let keep = used.min(RING);
        for (i, s) in samples[used - keep..used].iter().enumerate() {
            let j = self.n - keep + i;
            self.ring[(j + self.cb) % RING] = Node::corrected(s, bias);
        }
        used
    }

    /// Integrates every interval that is ready; with `fin`, all remaining intervals and the
    /// remaining noise (the window then has exactly `self.n` samples).
    #[inline(always)]
    fn advance<N: NoiseQ, const LIN: bool>(&mut self, cfg: &Cfg, noise: &N, fin: bool) {
        let n = self.n;
        let cb = self.cb;
        // Intervals `done..end` are ready: with `fin` all `n − 1`; streaming, those whose
        // samples have all arrived (one sample beyond the interval for Euler and midpoint, the
        // stencil `max(k + cb, 1) + 3 ≤ cb + n` for rk4: node k+1's derivative reads k+2).
        let end = if fin {
            n.saturating_sub(1)
        } else {
            match cfg.scheme {
                Scheme::Euler | Scheme::Midpoint => n.saturating_sub(2),
                Scheme::Hermite4 if cb == 0 && n < 4 => 0,
                Scheme::Hermite4 => n.saturating_sub(2),
            }
        };
        // In streaming mode `n` is a lower bound of the window size that is large enough for
        // every cell and stencil used here; with `fin` it is exact.
        let total = if fin { n } else { usize::MAX };
        while self.done < end {
            let k = self.done;
            match cfg.scheme {
                Scheme::Euler => self.euler_interval::<N, LIN>(cfg, noise, k, total, fin),
                Scheme::Midpoint => self.midpoint_interval::<N, LIN>(cfg, noise, k, fin),
                Scheme::Hermite4 => self.rk4_interval::<N, LIN>(cfg, noise, k, fin),
            }
            self.interval_done();
        }
        if fin && LIN && n >= 2 {
            match cfg.scheme {
                Scheme::Euler => {}
                Scheme::Midpoint => {
                    // The last sample: its gain is pending.
                    let r = self.d.r;
                    let m = self.e.take_mid(&r);
                    let g = Blk96 {
                        g: m.g,
                        a: rot_cols(&r, m.cv, m.cp),
                    };
                    let lr = self.intervals(n - 1, n);
                    self.capture_or_add(cfg, noise, cb + n - 1, &g, lr);
                }
                Scheme::Hermite4 => self.retire_below(cfg, noise, usize::MAX, true),
            }
        }
    }

    /// Integration noise of an interval of length `h` \[s\]. GTSAM adds it to δp in the
    /// body-(k+1) chart, i.e. `ΔR_k+1 Σ_int ΔR_k+1ᵀ h` in frame i; its pulled-back gain is the
    /// same (it has no ψ row).
    #[inline(always)]
    fn int_cov(&mut self, cfg: &Cfg, h: f64) {
        if let Some(ic) = &cfg.int_cov {
            let ws = walk_scale(h);
            match ic {
                CovShape::Isotropic(s) => self.e.p.add_pp_diag(s * ws),
                CovShape::General(m) => {
                    let r = &self.d.r;
                    self.e.p.add_pp(&(r * m * r.transpose() * ws));
                }
            }
        }
    }
}

/// Incremental on-manifold preintegrator (Forster 2017 chart, see [`crate::measurement`]).
///
/// ```
/// use preint::{ImuBias, ImuSample, PreintParams, Preintegrator, Scheme};
/// use nalgebra::Vector3;
/// let params = PreintParams::default().with_scheme(Scheme::Midpoint);
/// let mut pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
/// for k in 0..201i64 {
///     let s = ImuSample::new(k * 5_000_000, Vector3::new(0.0, 0.0, 0.1), Vector3::new(0.0, 0.0, 9.81));
///     pi.integrate(&s).unwrap();
/// }
/// let m = pi.finish().unwrap();
/// assert!((m.delta_t - 1.0).abs() < 1e-15);
/// assert!((m.delta_r.log().z - 0.1).abs() < 1e-12);
/// ```
///
/// Noise model ([`crate::noise`]): sample j carries independent white noise of covariance
/// `diag(Σ_g, Σ_a)·white_scale(c_j)`, where the cell `c_j` follows from the intervals to its
/// neighbours by the scheme's [`CellRule`]: the interval held by the sample for Euler (GTSAM),
/// the mean length of its adjacent intervals for midpoint and rk4 (`Δt` for uniform
/// sampling, matching [`ImuNoise`](crate::ImuNoise)'s per-sample `σ/√Δt`). The pushed samples
/// are the stream: the first sample has no left neighbour and the last no right one. Each
/// sample's noise is added exactly once, with the sum of its gains over every interval that
/// uses it (the internal `propagation` module).
///
/// Memory: with `keep_samples` (the default) every pushed sample is also stored for
/// re-integration. [`Preintegrator::new`] starts with an empty `Vec`, which then grows
/// geometrically (amortised O(1), about log₂ N reallocations for N samples);
/// [`Preintegrator::with_capacity`] reserves the room up front, and with `keep_samples = false`
/// nothing is stored. In those two cases [`Preintegrator::integrate`] never allocates
/// (`preint/tests/no_alloc.rs`).
#[derive(Clone, Debug)]
pub struct Preintegrator {
    params: PreintParams,
    bias_hat: ImuBias,
    noise: NoiseKind,
    cfg: Cfg,
    lin: bool,
    spec: WindowSpec,
    check_gaps: bool,
    /// Largest accepted gap \[ns\] (`u64::MAX` without the gap check).
    gap_limit: u64,
    samples: Vec<ImuSample>,
    first_t_ns: i64,
    last_t_ns: i64,
    core: Core,
}

impl Preintegrator {
    /// A preintegrator with bias estimate `bias_hat` ([b_g rad/s, b_a m/s²]); validates
    /// `params` and decides the noise path (isotropic closed form or general) once. With
    /// `keep_samples`, the stored samples live in a `Vec` that grows as samples arrive (see
    /// the type docs; use [`Preintegrator::with_capacity`] to avoid reallocations).
    pub fn new(params: PreintParams, bias_hat: ImuBias) -> Result<Self, PreintError> {
        Self::with_capacity(params, bias_hat, 0)
    }

    /// As [`Preintegrator::new`], reserving room for `capacity` stored samples so that
    /// `integrate` never allocates for the first `capacity` samples (when `keep_samples` is
    /// set; without it nothing is stored and nothing allocated).
    pub fn with_capacity(
        params: PreintParams,
        bias_hat: ImuBias,
        capacity: usize,
    ) -> Result<Self, PreintError> {
        Self::build(params, bias_hat, capacity, WindowSpec::default(), true)
    }

    /// The window path's constructor: `spec` describes the window edges, `check_gaps = false`
    /// skips the gap check (the stream was checked instead).
    pub(crate) fn build(
        params: PreintParams,
        bias_hat: ImuBias,
        capacity: usize,
        spec: WindowSpec,
        check_gaps: bool,
    ) -> Result<Self, PreintError> {
        params.validate()?;
        let finite = |v: &nalgebra::Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !finite(&bias_hat.gyro) || !finite(&bias_hat.acc) {
            return Err(PreintError::InvalidParameter {
                name: "bias_hat",
                reason: "non-finite component",
            });
        }
        let noise = match (
            CovShape::of(&params.gyro_cov),
            CovShape::of(&params.acc_cov),
        ) {
            (CovShape::Isotropic(g), CovShape::Isotropic(a)) => NoiseKind::Iso(IsoQ { g, a }),
            _ => NoiseKind::Gen(GenQ {
                g: params.gyro_cov,
                a: params.acc_cov,
            }),
        };
        let (e0, e1) = match params.scheme {
            Scheme::Euler | Scheme::Midpoint => (2, 2),
            Scheme::Hermite4 => (3, 3),
        };
        let cfg = Cfg {
            scheme: params.scheme,
            rule: params.scheme.cell_rule(),
            walk: BiasWalk {
                combined: params.level == Level::Combined,
                g: params.gyro_bias_rw_cov,
                a: params.acc_bias_rw_cov,
                iso: match (
                    CovShape::of(&params.gyro_bias_rw_cov),
                    CovShape::of(&params.acc_bias_rw_cov),
                ) {
                    (CovShape::Isotropic(g), CovShape::Isotropic(a)) => Some((g, a)),
                    _ => None,
                },
            },
            int_cov: params
                .integration_cov
                .as_ref()
                .map(CovShape::of)
                .filter(|c| *c != CovShape::Isotropic(0.0)),
            e0,
            e1,
        };
        let samples = if params.keep_samples {
            Vec::with_capacity(capacity)
        } else {
            Vec::new()
        };
        let rk4 = params.scheme == Scheme::Hermite4;
        let ctx_before = spec
            .start
            .ctx
            .filter(|_| rk4)
            .map(|s| Node::corrected(&s, &bias_hat));
        let ctx_after = spec
            .end
            .ctx
            .filter(|_| rk4)
            .map(|s| Node::corrected(&s, &bias_hat));
        let mut ring = [Node::default(); RING];
        if let Some(c) = ctx_before {
            ring[0] = c;
        }
        let gap_limit = if check_gaps {
            params.max_gap_ns as u64
        } else {
            u64::MAX
        };
        Ok(Self {
            lin: params.level != Level::Deltas,
            params,
            bias_hat,
            noise,
            cfg,
            spec,
            check_gaps,
            gap_limit,
            samples,
            first_t_ns: 0,
            last_t_ns: 0,
            core: Core {
                ring,
                n: 0,
                cb: usize::from(ctx_before.is_some()),
                ctx_after,
                origin: Origin::default(),
                h_prev: 0.0,
                weights: hermite::Weights::default(),
                steady: hermite::SteadyWeights::default(),
                pairs: LaneWeights::default(),
                #[cfg(target_arch = "x86_64")]
                quads: LaneWeights::default(),
                done: 0,
                d: Deltas::default(),
                e: ErrorState::default(),
                caps: [Cap::default(); CAPS],
                ncap: 0,
            },
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PreintParams {
        &self.params
    }

    /// The bias estimate used for integration.
    pub fn bias_hat(&self) -> &ImuBias {
        &self.bias_hat
    }

    /// Number of samples integrated so far.
    pub fn len(&self) -> usize {
        self.core.n
    }

    /// True if no sample was integrated yet.
    pub fn is_empty(&self) -> bool {
        self.core.n == 0
    }

    /// The stored samples (empty unless `keep_samples`).
    pub fn samples(&self) -> &[ImuSample] {
        &self.samples
    }

    /// Adds one sample. Rejects non-finite readings, duplicate or decreasing timestamps and
    /// gaps above `max_gap_ns`, naming the sample index (count of samples accepted so far) and
    /// timestamp; a rejected sample leaves the preintegrator unchanged.
    #[inline]
    pub fn integrate(&mut self, s: &ImuSample) -> Result<(), PreintError> {
        if self.core.n > 0 && Self::common_case(s, self.last_t_ns, self.gap_limit) {
            self.push(s);
            Ok(())
        } else {
            self.integrate_checked(s)
        }
    }

    /// The common case of [`Preintegrator::integrate`], in one test: `x·0 = 0` for finite x
    /// and NaN otherwise (a sum that overflows only sends the sample to the exact checks); a
    /// later timestamp than `last_t_ns`, and the gap as the exact u64 difference of two i64
    /// that are in order.
    #[inline(always)]
    fn common_case(s: &ImuSample, last_t_ns: i64, gap_limit: u64) -> bool {
        let (g, a) = (&s.gyro, &s.acc);
        let finite = ((g.x + a.x) + (g.y + a.y) + (g.z + a.z)) * 0.0 == 0.0;
        let gap = (s.t_ns as u64).wrapping_sub(last_t_ns as u64);
        finite && s.t_ns > last_t_ns && gap <= gap_limit
    }

    /// [`Preintegrator::integrate`] for the first sample and for samples that may be invalid.
    #[cold]
    #[inline(never)]
    fn integrate_checked(&mut self, s: &ImuSample) -> Result<(), PreintError> {
        let index = self.core.n;
        for (v, field) in [(&s.gyro, "gyro"), (&s.acc, "acc")] {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(PreintError::NonFinite {
                    index,
                    t_ns: s.t_ns,
                    field,
                });
            }
        }
        if index > 0 {
            let prev = self.last_t_ns;
            if s.t_ns == prev {
                return Err(PreintError::DuplicateTimestamp {
                    index,
                    t_ns: s.t_ns,
                });
            }
            if s.t_ns < prev {
                return Err(PreintError::DecreasingTimestamp {
                    index,
                    t_ns: s.t_ns,
                    prev_t_ns: prev,
                });
            }
            // i128: a gap that overflows i64 is reported as i64::MAX.
            let gap = s.t_ns as i128 - prev as i128;
            if self.check_gaps && gap > self.params.max_gap_ns as i128 {
                let gap = i64::try_from(gap).unwrap_or(i64::MAX);
                return Err(PreintError::GapTooLarge {
                    index,
                    t_ns: s.t_ns,
                    gap_ns: gap,
                    max_gap_ns: self.params.max_gap_ns,
                });
            }
        } else {
            self.first_t_ns = s.t_ns;
            // `ΔR_0 a_0 = a_0`, cached by the schemes that use the acceleration at both ends.
            self.core.d.u_last = s.acc - self.bias_hat.acc;
        }
        self.push(s);
        Ok(())
    }

    /// Stores a valid sample and integrates the intervals that became ready.
    #[inline(always)]
    fn push(&mut self, s: &ImuSample) {
        self.last_t_ns = s.t_ns;
        if self.params.keep_samples {
            self.samples.push(*s);
        }
        let core = &mut self.core;
        core.ring[(core.n + core.cb) % RING] = Node::corrected(s, &self.bias_hat);
        core.n += 1;
        Self::run(core, &self.cfg, &self.noise, self.lin, false);
    }

    /// Adds the samples in order; stops at the first invalid one (see [`Self::integrate`]),
    /// leaving the samples before it integrated. With [`Level::Deltas`], runs of valid
    /// samples go straight from the slice through the scheme's step (same result, bit for
    /// bit, as pushing them one by one).
    pub fn integrate_slice(&mut self, samples: &[ImuSample]) -> Result<(), PreintError> {
        let fast = !self.lin;
        // Euler and midpoint need two nodes, rk4 three (see `run_deltas_rk4`).
        let min_n = if self.cfg.scheme == Scheme::Hermite4 { 3 } else { 2 };
        let mut i = 0;
        while i < samples.len() {
            if fast && self.core.n >= min_n && self.core.done + 2 == self.core.n {
                let rest = &samples[i..];
                let (bias, last, gap) = (&self.bias_hat, self.last_t_ns, self.gap_limit);
                let used = match self.cfg.scheme {
                    Scheme::Midpoint => self.core.run_deltas::<true>(rest, bias, last, gap),
                    Scheme::Euler => self.core.run_deltas::<false>(rest, bias, last, gap),
                    Scheme::Hermite4 => self.core.run_deltas_rk4(rest, bias, last, gap),
                };
                if used > 0 {
                    self.last_t_ns = rest[used - 1].t_ns;
                    if self.params.keep_samples {
                        self.samples.extend_from_slice(&rest[..used]);
                    }
                    i += used;
                    continue;
                }
            }
            self.integrate(&samples[i])?;
            i += 1;
        }
        Ok(())
    }

    #[inline(always)]
    fn run(core: &mut Core, cfg: &Cfg, noise: &NoiseKind, lin: bool, fin: bool) {
        match (lin, noise) {
            (false, _) => core.advance::<IsoQ, false>(cfg, &IsoQ { g: 0.0, a: 0.0 }, fin),
            (true, NoiseKind::Iso(q)) => core.advance::<IsoQ, true>(cfg, q, fin),
            (true, NoiseKind::Gen(q)) => core.advance::<GenQ, true>(cfg, q, fin),
        }
    }

    /// The measurement over `[first sample, last sample]`: deltas, 9×9 covariance
    /// [δφ, δv, δp] and bias Jacobians in the Forster chart, and the 15×15 combined covariance
    /// [δφ, δv, δp, δb_g, δb_a] (with [`Level::Covariance`] its delta–bias cross blocks are
    /// zero and its 9×9 block is `cov`; with [`Level::Deltas`] covariances and Jacobians are
    /// zero). Integrates the remaining intervals on a copy, so more samples may be added
    /// afterwards.
    pub fn finish(&self) -> Result<PreintegratedImu, PreintError> {
        if self.core.n < 2 {
            return Err(PreintError::TooFewSamples { count: self.core.n });
        }
        let mut core = self.core.clone();
        Self::run(&mut core, &self.cfg, &self.noise, self.lin, true);
        Ok(self.output(&core))
    }

    /// Noise of the edge samples ([`crate::propagation`]): splits interpolated boundary
    /// samples into the stream samples they are made of and adds each stream sample's noise
    /// once, with its own cell, to the pulled-back covariance `p`. Returns the sources with
    /// their gains pushed forward to the end of the window (`tr`) and in the chart.
    fn resolve_edges(&self, core: &Core, p: &mut Sym9, tr: &Transition) -> EdgeNoise {
        let n = core.n;
        let cb = core.cb;
        // (key, gain, left, right, start, end)
        let mut acc = [(0i64, Blk96::default(), 0.0, 0.0, false, false); ACC];
        let mut na = 0;
        let mut extra = Sym9::default();
        let mut add = |key: i64, g: Blk96, left: f64, right: f64, start: bool, end: bool| {
            if let Some(a) = acc[..na].iter_mut().find(|a| a.0 == key) {
                a.1.add_assign(&g);
                a.4 |= start;
                a.5 |= end;
            } else if na < ACC {
                acc[na] = (key, g, left, right, start, end);
                na += 1;
            } else {
                // Unreachable by construction (≤ 10 distinct sources); never panic.
                let s = white_scale(self.cfg.rule.cell_s(left, right));
                self.add_full(&mut extra, &g, s);
            }
        };
        let spec = &self.spec;
        let lookup =
            |t: i64, left: f64, right: f64| match spec.start.find(t).or_else(|| spec.end.find(t)) {
                Some(s) => (s.left_s, s.right_s),
                None => (left, right),
            };
        for cap in &core.caps[..core.ncap] {
            let g = cap.g;
            let start = cap.ext < cb + self.cfg.e0;
            let end = cap.ext + self.cfg.e1 >= cb + n;
            let side = if cap.ext == cb && spec.start.nw > 0 {
                Some(&spec.start)
            } else if cap.ext == cb + n - 1 && spec.end.nw > 0 {
                Some(&spec.end)
            } else {
                None
            };
            match side {
                Some(sd) => {
                    for i in 0..sd.nw {
                        let s = &sd.src[i];
                        add(s.t_ns, g.scale(sd.w[i]), s.left_s, s.right_s, start, end);
                    }
                }
                None => {
                    let (l, r) = lookup(cap.node_t, cap.left, cap.right);
                    add(cap.node_t, g, l, r, start, end);
                }
            }
        }
        let mut out = EdgeNoise::new(self.params.gyro_cov, self.params.acc_cov, self.cfg.rule);
        let rt = core.d.r.transpose();
        for &(t_ns, g, left_s, right_s, start, end) in &acc[..na] {
            let s = white_scale(self.cfg.rule.cell_s(left_s, right_s));
            self.add_full(p, &g, s);
            out.push(EdgeSource {
                t_ns,
                gain: tr.apply(&g).chart(&rt),
                left_s,
                right_s,
                start,
                end,
            });
        }
        p.add_assign(&extra);
        out
    }

    fn add_full(&self, p: &mut Sym9, g: &Blk96, s: f64) {
        match &self.noise {
            NoiseKind::Iso(q) => q.add_full(p, g, s),
            NoiseKind::Gen(q) => q.add_full(p, g, s),
        }
    }

    fn output(&self, core: &Core) -> PreintegratedImu {
        let r = core.d.delta_r();
        let rt = r.transpose();
        let e = &core.e;
        let mut cov = Cov9::zeros();
        let mut cov15 = Cov15::zeros();
        let mut jac = BiasJacobians::default();
        let mut edge_noise = EdgeNoise::default();
        if self.lin {
            // Pulled back to the origin → pushed forward to the end (rotated coordinates) →
            // the documented chart.
            let tr = core
                .origin
                .push_to(core.node(core.n - 1).t_ns, &core.d.v, &core.d.p);
            let mut p = e.p;
            edge_noise = self.resolve_edges(core, &mut p, &tr);
            let to_chart = |p: &Sym9| {
                let p = tr.push_forward(p);
                let mut m = Cov9::zeros();
                let blocks = [
                    (0, 0, rt * p.rr * r),
                    (0, 3, rt * p.rv),
                    (0, 6, rt * p.rp),
                    (3, 3, p.vv),
                    (3, 6, p.vp),
                    (6, 6, p.pp),
                ];
                for (i, j, b) in blocks {
                    m.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
                    if i != j {
                        m.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
                    }
                }
                (m + m.transpose()) * 0.5
            };
            cov = to_chart(&p);
            let cov_walk = to_chart(&e.p_walk);
            let j = tr.apply(&e.j);
            jac = BiasJacobians {
                d_r_d_bg: rt * j.gyro_block(0),
                d_v_d_bg: j.gyro_block(1),
                d_v_d_ba: j.acc_block(1),
                d_p_d_bg: j.gyro_block(2),
                d_p_d_ba: j.acc_block(2),
            };
            cov15
                .fixed_view_mut::<9, 9>(0, 0)
                .copy_from(&(cov + cov_walk));
            let c = &e.c;
            let cross = [
                (0, 9, rt * c.gyro_block(0)),
                (3, 9, c.gyro_block(1)),
                (3, 12, c.acc_block(1)),
                (6, 9, c.gyro_block(2)),
                (6, 12, c.acc_block(2)),
            ];
            for (i, j, b) in cross {
                cov15.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
                cov15.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
            }
            let walk = &self.cfg.walk;
            cov15
                .fixed_view_mut::<3, 3>(9, 9)
                .copy_from(&(walk.g * e.walk_t));
            cov15
                .fixed_view_mut::<3, 3>(12, 12)
                .copy_from(&(walk.a * e.walk_t));
        }
        PreintegratedImu {
            t_i_ns: self.first_t_ns,
            t_j_ns: self.last_t_ns,
            delta_t: span_s(self.first_t_ns, self.last_t_ns),
            delta_r: SO3::from_matrix_unchecked(r),
            delta_v: core.d.v,
            delta_p: core.d.p,
            cov,
            cov15,
            jac,
            bias_hat: self.bias_hat,
            gravity: self.params.gravity,
            level: self.params.level,
            edge_noise,
        }
    }

    /// The measurement for a new bias estimate `bias`: if `‖δb_g‖ ≤ reintegrate_gyro_threshold`
    /// and `‖δb_a‖ ≤ reintegrate_acc_threshold` (δb = bias − bias_hat), the first-order
    /// correction [`PreintegratedImu::corrected`] (Forster eq. 44; covariance and Jacobians
    /// kept, `bias_hat` set to `bias`); otherwise the stored samples are re-integrated with
    /// `bias`.
    ///
    /// Without `keep_samples` there is nothing to re-integrate: the first-order correction is
    /// returned whatever the size of δb, with `reintegrated: false` (callers that need the
    /// accuracy of re-integration above the thresholds must keep the samples; the size of the
    /// first-order error is documented at [`crate::params::DEFAULT_REINTEGRATE_GYRO`]).
    pub fn measurement_for_bias(&self, bias: &ImuBias) -> Result<BiasUpdate, PreintError> {
        let dbg = (bias.gyro - self.bias_hat.gyro).norm();
        let dba = (bias.acc - self.bias_hat.acc).norm();
        let small = dbg <= self.params.reintegrate_gyro_threshold
            && dba <= self.params.reintegrate_acc_threshold;
        if small || !self.params.keep_samples {
            let mut m = self.finish()?;
            let (r, v, p) = m.corrected(bias);
            m.delta_r = r;
            m.delta_v = v;
            m.delta_p = p;
            m.bias_hat = *bias;
            return Ok(BiasUpdate {
                measurement: m,
                reintegrated: false,
            });
        }
        let mut other = self.clone();
        other.reintegrate(bias)?;
        Ok(BiasUpdate {
            measurement: other.finish()?,
            reintegrated: true,
        })
    }

    /// Replaces the bias estimate by `bias` and re-integrates the stored samples.
    ///
    /// Errors: [`PreintError::SamplesNotKept`] if `keep_samples` is off and samples were
    /// integrated (nothing to re-integrate; the preintegrator is left unchanged), and the
    /// errors of [`Preintegrator::new`] for a non-finite `bias`.
    pub fn reintegrate(&mut self, bias: &ImuBias) -> Result<(), PreintError> {
        if !self.params.keep_samples && self.core.n > 0 {
            return Err(PreintError::SamplesNotKept { count: self.core.n });
        }
        let mut fresh = Preintegrator::build(
            self.params.clone(),
            *bias,
            self.samples.len(),
            self.spec,
            self.check_gaps,
        )?;
        fresh.integrate_slice(&self.samples)?;
        *self = fresh;
        Ok(())
    }
}

/// Result of [`Preintegrator::measurement_for_bias`].
#[derive(Clone, Debug, PartialEq)]
pub struct BiasUpdate {
    /// The measurement at the new bias.
    pub measurement: PreintegratedImu,
    /// True if the samples were re-integrated, false for the first-order correction.
    pub reintegrated: bool,
}
