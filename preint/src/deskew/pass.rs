//! The running pass behind [`super::WindowDeltas`]: the stream's node sequence, a query
//! window's node sequence, the engine's stencil, and the deltas and carry kept at the pass's
//! last nodes (the method is in the module docs of [`super`]).

use crate::preintegrator::Maps;
use crate::propagation::linearisation::MAX_STENCIL;
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::{Deltas, IntervalScheme, Node, RENORM_EVERY, Stencil};

/// A stream sample as the loop sees it: through the preintegrator's transforms in front of
/// the loop (the IMU intrinsics, GTSAM's per-sample lever arm), then bias-corrected.
#[derive(Clone, Copy, Debug)]
pub(super) struct Corr {
    pub bias: ImuBias,
    pub maps: Maps,
}

impl Corr {
    pub(super) fn node(&self, s: &ImuSample) -> Node {
        Node::corrected(&self.maps.map(s), &self.bias)
    }
}

/// The stream's node sequence from the window's start: context sample (hermite4), boundary
/// sample at `t_i`, then every later stream sample kept by the window rules.
#[derive(Debug)]
pub(super) struct Stream<'a> {
    pub samples: &'a [ImuSample],
    pub corr: Corr,
    pub ctx: Option<Node>,
    pub first: Node,
    /// 1 with a context sample, else 0.
    pub c: usize,
    /// The first stream sample after the boundary sample.
    pub lo: usize,
    /// Nodes in the sequence.
    pub len: usize,
}

impl Stream<'_> {
    fn at(&self, p: usize) -> Node {
        match p.cmp(&self.c) {
            std::cmp::Ordering::Less => self.ctx.unwrap_or(self.first),
            std::cmp::Ordering::Equal => self.first,
            std::cmp::Ordering::Greater => self.corr.node(&self.samples[self.lo + p - self.c - 1]),
        }
    }
}

/// The node sequence of the window `[t_i, t]`: the stream's up to `end_pos`, then the boundary
/// sample at `t` and the context sample after it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Query {
    pub end_pos: usize,
    pub end: Node,
    pub after: Option<Node>,
    pub len: usize,
}

impl Query {
    fn at(&self, s: &Stream, p: usize) -> Node {
        match p.cmp(&self.end_pos) {
            std::cmp::Ordering::Less => s.at(p),
            std::cmp::Ordering::Equal => self.end,
            std::cmp::Ordering::Greater => self.after.unwrap_or(self.end),
        }
    }
}

/// Interval `k` of a window whose node sequence (`c` context nodes first) has `len` nodes, with
/// the engine's stencil: the `S::STENCIL` nodes from `k + c − NODES_BEFORE`, shifted back at
/// the sequence's end.
fn interval<S: IntervalScheme>(
    d: &mut Deltas,
    carry: &mut S::Carry,
    at: impl Fn(usize) -> Node,
    (len, c, k): (usize, usize, usize),
) {
    let k_ext = k + c;
    let m = len.min(S::STENCIL);
    let first_id = k_ext.saturating_sub(S::NODES_BEFORE).min(len - m);
    let buf: [Node; MAX_STENCIL] = std::array::from_fn(|j| at(first_id + j.min(m - 1)));
    let st = Stencil {
        nodes: [&buf[0], &buf[1], &buf[2], &buf[3]],
        len: m,
        k: k_ext - first_id,
        first: k == 0,
    };
    S::step(d, carry, &st);
    if (k + 1).is_multiple_of(RENORM_EVERY) {
        d.renormalize();
    }
}

/// Snapshots kept by the running pass (queries step back at most a few intervals).
const SNAPS: usize = 16;

/// The running pass of scheme `S` with the deltas and carry at its last [`SNAPS`] nodes.
#[derive(Clone, Debug)]
pub(super) struct Runner<S: IntervalScheme> {
    done: usize,
    d: Deltas,
    carry: S::Carry,
    snaps: [(Deltas, S::Carry); SNAPS],
}

/// What a query needs of a scheme's running pass, behind one pointer.
pub(super) trait Pass: std::fmt::Debug {
    fn deltas(&mut self, s: &Stream, q: &Query) -> Deltas;
}

impl<S: IntervalScheme> Runner<S> {
    pub(super) fn new(first: &Node) -> Self {
        let mut carry = S::Carry::default();
        S::start(&mut carry, first);
        let d = Deltas::default();
        Self {
            done: 0,
            d,
            carry,
            snaps: [(d, carry); SNAPS],
        }
    }

    fn advance(&mut self, s: &Stream, to: usize) {
        while self.done < to {
            interval::<S>(
                &mut self.d,
                &mut self.carry,
                |p| s.at(p),
                (s.len, s.c, self.done),
            );
            self.done += 1;
            self.snaps[self.done % SNAPS] = (self.d, self.carry);
        }
    }

    /// Intervals of the query window identical to the stream's: interval k matches if its
    /// stencil is the same in both sequences and lies below the first position `p` where they
    /// differ (a property closed downwards in k).
    fn shared(s: &Stream, q: &Query, p: usize, n_q: usize) -> usize {
        let fits = |k: usize| {
            let k_ext = k + s.c;
            let (mr, mq) = (s.len.min(S::STENCIL), q.len.min(S::STENCIL));
            let start = k_ext.saturating_sub(S::NODES_BEFORE);
            let (fr, fq) = (start.min(s.len - mr), start.min(q.len - mq));
            mr == mq && fr == fq && fr + mr <= p
        };
        let mut k0 = n_q - 1;
        while k0 > 0 && !fits(k0 - 1) {
            k0 -= 1;
        }
        k0
    }
}

impl<S: IntervalScheme> Pass for Runner<S> {
    fn deltas(&mut self, s: &Stream, q: &Query) -> Deltas {
        // First position where the query's sequence leaves the stream's.
        let mut p = q.end_pos;
        while p < q.len && p < s.len && s.at(p).t_ns == q.at(s, p).t_ns {
            p += 1;
        }
        let n_q = q.end_pos - s.c + 1;
        let k0 = Self::shared(s, q, p, n_q);
        if self.done >= k0 + SNAPS {
            // Only for queries stepping back further than any sorted sequence does.
            *self = Self::new(&s.first);
        }
        self.advance(s, k0);
        let (mut d, mut carry) = self.snaps[k0 % SNAPS];
        for k in k0..n_q - 1 {
            interval::<S>(&mut d, &mut carry, |x| q.at(s, x), (q.len, s.c, k));
        }
        d
    }
}
