//! Window edges: what the window path knows about the stream beyond each edge, the gains of
//! the samples near the edges (collected instead of added, so that a merge can correlate two
//! windows), and their resolution into stream samples when the measurement is read
//! ([`preintegrate`](crate::preintegrate()) and [`crate::merge()`] describe the model).

use crate::edges::{EdgeNoise, EdgeSource};
use crate::noise::{CellRule, white_scale};
use crate::propagation::blocks::{Gain96, M3, PackedSym9};
use crate::propagation::transition::Transition;
use crate::sample::ImuSample;

/// A stream sample referenced by a window edge, with its intervals \[s\] to its stream
/// neighbours (0 if none).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Src {
    pub t_ns: i64,
    pub left_s: f64,
    pub right_s: f64,
}

/// What the window path knows about one edge of a window (see [`preintegrate`](crate::preintegrate())).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Side {
    /// Stream samples referenced here: the boundary sample's stencil first, then the context
    /// sample and the neighbours whose stream intervals the window does not see.
    pub src: [Src; 8],
    pub n_src: usize,
    /// The boundary sample is `Σ w[i]·src[i]` for `i < nw`; `nw = 0`: no window information
    /// (the boundary is a pushed sample like any other).
    pub w: [f64; 4],
    pub nw: usize,
    /// Context sample just outside the window (raw reading), for stencils that reach it.
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

/// Most edge samples whose gains are collected (wide stencils: context, 3 first, 3 last,
/// context).
const MAX_EDGE_GAINS: usize = 8;
/// Most distinct noise sources of the edge samples (each is a combination of ≤ 4).
const MAX_SOURCES: usize = 16;

/// The gain of an edge sample, collected when it was retired.
#[derive(Clone, Copy, Debug, Default)]
struct EdgeGain {
    /// Extended index (the context sample before the window, if any, is 0).
    ext: usize,
    /// Its total gain, pulled back to the origin.
    g: Gain96,
    /// Timestamp of the sample itself.
    t_ns: i64,
    /// Intervals to its window neighbours \[s\] (0 if none).
    left: f64,
    right: f64,
}

/// The gains of the edge samples of a window.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct EdgeGains {
    gains: [EdgeGain; MAX_EDGE_GAINS],
    len: usize,
}

impl EdgeGains {
    /// Stores the total pulled-back gain `g` of edge sample `ext` (at `t_ns`, intervals
    /// `left`, `right` \[s\] to its window neighbours); `false` if the store is full.
    #[inline(never)]
    pub(crate) fn push(
        &mut self,
        ext: usize,
        t_ns: i64,
        g: &Gain96,
        left: f64,
        right: f64,
    ) -> bool {
        if self.len == MAX_EDGE_GAINS {
            return false;
        }
        self.gains[self.len] = EdgeGain {
            ext,
            g: *g,
            t_ns,
            left,
            right,
        };
        self.len += 1;
        true
    }
}

/// Where a window's edge samples sit: `ctx_before` (1 if a context sample precedes the window,
/// extended index 0), the window's sample count `n`, and how many first and last window
/// samples are edge samples.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeLayout {
    pub ctx_before: usize,
    pub n: usize,
    pub first: usize,
    pub last: usize,
}

/// Noise of the edge samples: splits interpolated boundary samples into the stream samples
/// they are made of and adds each stream sample's noise once, with its own cell, to the
/// pulled-back covariance `p` (`add_noise(p, gain, white_scale)`). Returns the sources with
/// their gains pushed forward to the end of the window (`tr`) and in the chart (`rt = ΔRᵀ`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve(
    edges: &EdgeGains,
    layout: EdgeLayout,
    spec: &WindowSpec,
    rule: CellRule,
    (gyro_cov, acc_cov): (M3, M3),
    p: &mut PackedSym9,
    tr: &Transition,
    rt: &M3,
    mut add_noise: impl FnMut(&mut PackedSym9, &Gain96, f64),
) -> EdgeNoise {
    let EdgeLayout {
        ctx_before: before,
        n,
        first,
        last,
    } = layout;
    // (key, gain, left, right, start, end)
    let mut acc = [(0i64, Gain96::default(), 0.0, 0.0, false, false); MAX_SOURCES];
    let mut na = 0;
    let mut extra = PackedSym9::default();
    let mut add = |key: i64, g: Gain96, left: f64, right: f64, start: bool, end: bool| {
        if let Some(a) = acc[..na].iter_mut().find(|a| a.0 == key) {
            a.1.add_assign(&g);
            a.4 |= start;
            a.5 |= end;
        } else if na < MAX_SOURCES {
            acc[na] = (key, g, left, right, start, end);
            na += 1;
        } else {
            // Unreachable by construction (≤ 10 distinct sources); never panic.
            add_noise(&mut extra, &g, white_scale(rule.cell_s(left, right)));
        }
    };
    let lookup =
        |t: i64, left: f64, right: f64| match spec.start.find(t).or_else(|| spec.end.find(t)) {
            Some(s) => (s.left_s, s.right_s),
            None => (left, right),
        };
    for cap in &edges.gains[..edges.len] {
        let g = cap.g;
        let start = cap.ext < before + first;
        let end = cap.ext + last >= before + n;
        let side = if cap.ext == before && spec.start.nw > 0 {
            Some(&spec.start)
        } else if cap.ext == before + n - 1 && spec.end.nw > 0 {
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
                let (l, r) = lookup(cap.t_ns, cap.left, cap.right);
                add(cap.t_ns, g, l, r, start, end);
            }
        }
    }
    let mut out = EdgeNoise::new(gyro_cov, acc_cov, rule);
    for &(t_ns, g, left_s, right_s, start, end) in &acc[..na] {
        add_noise(p, &g, white_scale(rule.cell_s(left_s, right_s)));
        out.push(EdgeSource {
            t_ns,
            gain: tr.apply(&g).chart(rt),
            left_s,
            right_s,
            start,
            end,
        });
    }
    p.add_assign(&extra);
    out
}
