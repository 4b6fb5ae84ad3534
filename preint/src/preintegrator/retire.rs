//! Retiring a sample: once no later interval reads it, its noise enters the covariance with
//! its total gain, or (near a window's edge) its gain is collected for exact merges; with a
//! rate coupling (samples whose specific force was corrected with their rate before the loop),
//! the gain first carries the gyro noise and bias that the correction moves into the specific
//! force; with the intrinsics' Jacobians requested, each gain is also accumulated for them
//! (`intrinsic.rs`).

use super::edges::EdgeGains;
use super::engine::RING;
use super::intrinsic::Sink;
use crate::noise::white_scale;
use crate::propagation::blocks::{Cols9, PackedSym9, add_cols, sub_cols};
use crate::propagation::{AccGain, NoiseCov, SampleGain, add_acc_through};
use crate::sample::span_s;
use crate::scheme::{IntervalScheme, Node};

/// Hands retired samples' noise to the covariance, or their gains to the edge store.
pub(super) struct Retirer<'a, N, K> {
    ring: &'a [Node; RING],
    ctx_after: Option<&'a Node>,
    edges: &'a mut EdgeGains,
    noise: &'a N,
    ctx_before: usize,
    n: usize,
    at_end: bool,
    /// The bias Jacobian's share through the nodes' rate coupling (`N::COUPLED`).
    coupled_j: &'a mut Cols9,
    /// Where each total gain goes for the intrinsics' Jacobians (`()`: nowhere).
    intr: K,
}

impl<'a, N, K> Retirer<'a, N, K> {
    /// For a window with `(ctx_before, n, at_end)`: context samples before it, samples, and
    /// whether it is complete.
    #[inline(always)]
    pub(super) fn new(
        ring: &'a [Node; RING],
        ctx_after: Option<&'a Node>,
        edges: &'a mut EdgeGains,
        noise: &'a N,
        (ctx_before, n, at_end): (usize, usize, bool),
        coupled_j: &'a mut Cols9,
        intr: K,
    ) -> Self {
        Self {
            ring,
            ctx_after,
            edges,
            noise,
            ctx_before,
            n,
            at_end,
            coupled_j,
            intr,
        }
    }
}

impl<N: NoiseCov, K: Sink> Retirer<'_, N, K> {
    /// Node at extended index `i`.
    #[inline(always)]
    fn ext(&self, i: usize) -> &Node {
        match self.ctx_after {
            Some(c) if i == self.ctx_before + self.n => c,
            _ => &self.ring[i % RING],
        }
    }

    /// Retires sample `id` (extended index) with its total gain.
    #[inline(always)]
    pub(super) fn retire<S: IntervalScheme>(
        &mut self,
        p: &mut PackedSym9,
        id: usize,
        gain: &SampleGain,
    ) {
        if K::ON {
            // Every sample's total gain passes here once (edge samples too); the intrinsics'
            // Jacobians take it before the rate coupling (the two are not combined).
            let node = *self.ext(id);
            self.intr.add(gain, &node);
        }
        if N::COUPLED {
            self.retire_coupled::<S>(p, id, gain);
        } else {
            self.retire_gain::<S>(p, id, gain);
        }
    }

    /// [`Retirer::retire`] for samples with a rate coupling ([`NoiseCov::COUPLED`]): the raw
    /// gyro noise also moves the node's specific force, so its gain is `G_g + G_a D` (and the
    /// bias Jacobian takes `−G_a D`).
    #[inline(always)]
    fn retire_coupled<S: IntervalScheme>(
        &mut self,
        p: &mut PackedSym9,
        id: usize,
        gain: &SampleGain,
    ) {
        let d = self.noise.coupling(&self.ext(id).w);
        let mut through = [[0.0; 9]; 3];
        match gain.acc {
            AccGain::Rot { r: rot, cv, cp } => {
                let m = rot * d;
                for (c, col) in through.iter_mut().enumerate() {
                    for i in 0..3 {
                        col[3 + i] = cv * m[(i, c)];
                        col[6 + i] = cp * m[(i, c)];
                    }
                }
            }
            AccGain::Full(a) => add_acc_through(&mut through, a, &d),
        }
        sub_cols(self.coupled_j, &through);
        let mut g = *gain.g;
        add_cols(&mut g, &through);
        self.retire_gain::<S>(
            p,
            id,
            &SampleGain {
                g: &g,
                acc: gain.acc,
            },
        );
    }

    /// Adds the noise of sample `id` with its total gain, or collects the gain of an edge sample.
    #[inline(always)]
    fn retire_gain<S: IntervalScheme>(&mut self, p: &mut PackedSym9, id: usize, gain: &SampleGain) {
        let (before, n) = (self.ctx_before, self.n);
        let in_window = id >= before && id < before + n;
        let (left, right) = if in_window {
            let j = id - before;
            let total = if self.at_end { n } else { usize::MAX };
            let t = self.ring[id % RING].t_ns;
            let left = if j > 0 {
                span_s(self.ring[(id - 1) % RING].t_ns, t)
            } else {
                0.0
            };
            let right = if j + 1 < total {
                span_s(t, self.ring[(id + 1) % RING].t_ns)
            } else {
                0.0
            };
            (left, right)
        } else {
            (0.0, 0.0)
        };
        let edge = !in_window
            || id - before < edge_count::<S>()
            || (self.at_end && id - before + edge_count::<S>() >= n);
        if edge
            && self
                .edges
                .push(id, self.ext(id).t_ns, &gain.full(), left, right)
        {
            return;
        }
        gain.add_noise(p, self.noise, white_scale(S::CELL_RULE.cell_s(left, right)));
    }
}

/// First and last window samples whose gains are collected: those whose stencils or cells
/// may reach across the window's edge.
pub(super) const fn edge_count<S: IntervalScheme>() -> usize {
    S::NODES_BEFORE + 2
}
