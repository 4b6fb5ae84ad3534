//! Deltas-only fast paths ([`crate::Level::Deltas`]): a reader of the mathematics can skip
//! this module. Everything here computes what the schemes' plain steps
//! ([`Scheme`](crate::Scheme)) compute, faster, and is checked against them:
//!
//! - ΔR as a unit quaternion ([`quat`]): a product is 28 flops instead of 45, a rotation of a
//!   vector 30 instead of 15 plus the 20 of Exp's matrix, and the rotation takes 4 registers
//!   instead of 9, so less of the loop's state spills. It agrees with the matrix to ~3e-14
//!   over 40 000 samples (`preint/tests/deltas_fast_path.rs`).
//! - Slices integrated straight from the caller's samples, the deltas and the newest samples
//!   in registers instead of the ring the noise bookkeeping needs ([`two_point`],
//!   [`hermite4`]); bit for bit the result of pushing the samples one by one.
//! - The Hermite scheme rearranged so that only one quaternion product and two rotations
//!   depend on ΔR, the rest prepared for blocks of intervals several at a time in SIMD lanes
//!   ([`lanes`]: SSE2 pairs, AVX2 quadruples detected at run time; no fused multiply-add, so
//!   every lane width gives the one-by-one bits).
//! - The IMU intrinsics' correction of each sample in AVX2 and FMA instructions
//!   ([`correction`]), the same fused multiply-adds as the plain path.
//!
//! Every `unsafe` block of the crate is in this module: the vector instructions, each behind a
//! run-time test of the processor's features.
//!
//! The fast paths attach themselves to the schemes ([`Attached::of`]): a scheme's file does not
//! name its fast path, and a scheme without one runs its plain step at every level.

pub(crate) mod correction;
pub(crate) mod hermite4;
pub(crate) mod lanes;
pub(crate) mod quat;
pub(crate) mod two_point;

use crate::propagation::blocks::{M3, V3};
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::{Node, RENORM_EVERY, Scheme, Stencil};
use crate::validation::common_case;
use hermite4::HermiteDeltas;
use quat::Quat;
use two_point::{EulerDeltas, MidpointDeltas};

/// What the slice path reads: the samples, the bias estimate, the timestamp of the last sample
/// before them \[ns\] and the largest gap \[ns\].
pub(crate) struct SliceInput<'a> {
    pub samples: &'a [ImuSample],
    pub bias: &'a ImuBias,
    pub last_t_ns: i64,
    pub gap_limit: u64,
}

/// A scheme's deltas alone, faster than its plain step.
pub(crate) trait FastDeltas: Copy + Default + std::fmt::Debug {
    /// Window samples after which [`FastDeltas::run_slice`] can take over (the steady state of
    /// the engine, with every interval but the last one or two integrated).
    const SLICE_FROM: usize;
    /// Starts a window at its first node.
    fn start(&mut self, first: &Node);
    /// One interval, from its stencil (the one-by-one path).
    fn step(&mut self, st: &Stencil);
    /// In the steady state (`last`: the two newest window nodes; every interval before them
    /// integrated): integrates the leading samples of `input` that pass the common-case test,
    /// counting intervals in `done`, and returns how many it took.
    fn run_slice(&mut self, last: &[Node; 2], input: &SliceInput, done: &mut usize) -> usize;
    /// The running deltas.
    fn quat(&mut self) -> &mut QuatDeltas;
}

/// The fast path attached to a scheme, if it has one: the registry of this module. Held
/// inline in the loop's state (one per preintegrator, the size of the largest path's), not
/// boxed: a box would add a pointer chase to every interval of the one-by-one path.
#[derive(Clone, Copy, Debug, Default)]
#[allow(clippy::large_enum_variant)]
pub(crate) enum Attached {
    /// No fast path: the scheme's plain step runs at every level.
    #[default]
    None,
    Euler(EulerDeltas),
    Midpoint(MidpointDeltas),
    Hermite4(HermiteDeltas),
}

/// `body` with `f` the attached path's [`FastDeltas`] (`$none` without one).
macro_rules! each {
    ($self:expr, $f:ident => $body:expr, $none:expr) => {
        match $self {
            Attached::None => $none,
            Attached::Euler($f) => $body,
            Attached::Midpoint($f) => $body,
            Attached::Hermite4($f) => $body,
        }
    };
}

/// Which fast path attaches to `scheme`: 0 for none, else its [`Attached`] variant's number
/// (a constant of each scheme's loop, so that the one-by-one path dispatches at compile time).
pub(crate) const fn kind(scheme: Scheme) -> u8 {
    match scheme {
        Scheme::Euler => 1,
        Scheme::Midpoint => 2,
        Scheme::Hermite4 => 3,
        _ => 0,
    }
}

impl Attached {
    /// The fast path of `scheme` (none for a scheme this module does not list).
    pub(crate) fn of(scheme: Scheme) -> Self {
        match kind(scheme) {
            1 => Attached::Euler(EulerDeltas::default()),
            2 => Attached::Midpoint(MidpointDeltas::default()),
            3 => Attached::Hermite4(HermiteDeltas::default()),
            _ => Attached::None,
        }
    }

    /// Whether there is a fast path.
    #[inline(always)]
    pub(crate) fn is_some(&self) -> bool {
        !matches!(self, Attached::None)
    }

    /// [`FastDeltas::SLICE_FROM`] (`usize::MAX` without a fast path).
    #[inline(always)]
    pub(crate) fn slice_from(&self) -> usize {
        fn of<F: FastDeltas>(_: &F) -> usize {
            F::SLICE_FROM
        }
        each!(self, f => of(f), usize::MAX)
    }

    /// [`FastDeltas::start`].
    pub(crate) fn start(&mut self, first: &Node) {
        each!(self, f => f.start(first), ())
    }

    /// [`FastDeltas::step`] of the path of kind `k` ([`kind`]; a constant where it is called,
    /// so that only that path's code is there); false without it.
    #[inline(always)]
    pub(crate) fn step(&mut self, k: u8, st: &Stencil) -> bool {
        match (k, self) {
            (1, Attached::Euler(f)) => f.step(st),
            (2, Attached::Midpoint(f)) => f.step(st),
            (3, Attached::Hermite4(f)) => f.step(st),
            _ => return false,
        }
        true
    }

    /// [`FastDeltas::run_slice`]; 0 without a fast path.
    pub(crate) fn run_slice(
        &mut self,
        last: &[Node; 2],
        input: &SliceInput,
        done: &mut usize,
    ) -> usize {
        each!(self, f => f.run_slice(last, input, done), 0)
    }

    /// Re-orthonormalises ΔR.
    pub(crate) fn renormalize(&mut self) {
        each!(self, f => f.quat().q.renormalize(), ())
    }

    /// `(ΔR, Δv [m/s], Δp [m])` (identity and zeros without a fast path).
    pub(crate) fn deltas(&self) -> (M3, V3, V3) {
        let mut copy = *self;
        each!(&mut copy, f => f.quat().deltas(), QuatDeltas::default().deltas())
    }
}

/// Running deltas with ΔR as a unit quaternion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct QuatDeltas {
    pub q: Quat,
    pub v: V3,
    pub p: V3,
}

impl Default for QuatDeltas {
    fn default() -> Self {
        Self {
            q: Quat::IDENTITY,
            v: V3::zeros(),
            p: V3::zeros(),
        }
    }
}

impl QuatDeltas {
    /// `(ΔR, Δv, Δp)`.
    pub(crate) fn deltas(&self) -> (M3, V3, V3) {
        (self.q.matrix(), self.v, self.p)
    }

    /// Counts one more interval; every [`RENORM_EVERY`] intervals ΔR is re-orthonormalised
    /// (as the engine does for the one-by-one path).
    #[inline(always)]
    pub(crate) fn count_interval(&mut self, done: &mut usize) {
        *done += 1;
        if done.is_multiple_of(RENORM_EVERY) {
            self.q.renormalize();
        }
    }
}

/// The loop of the slice paths: takes the leading samples of `input` that pass the
/// common-case test, hands each one to `step` (which integrates the interval it completes),
/// counts the interval and returns how many samples it took. (`step` builds the sample's node
/// itself, where it needs it: built before the step, it stays live across it and costs
/// registers.)
#[inline(always)]
pub(crate) fn slice_loop(
    input: &SliceInput,
    d: &mut QuatDeltas,
    done: &mut usize,
    mut step: impl FnMut(&mut QuatDeltas, &ImuSample),
) -> usize {
    let (mut last_t_ns, mut used) = (input.last_t_ns, 0);
    for s in input.samples {
        if !common_case(s, last_t_ns, input.gap_limit) {
            break;
        }
        last_t_ns = s.t_ns;
        step(d, s);
        d.count_interval(done);
        used += 1;
    }
    used
}
