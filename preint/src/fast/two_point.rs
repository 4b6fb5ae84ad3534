//! Deltas-only paths of the schemes with the stencil `{k, k+1}` ([`crate::scheme::euler`],
//! [`crate::scheme::midpoint`]): the same rules with ΔR as a quaternion, one by one and
//! straight from a slice (bit for bit the same).

use super::{FastDeltas, QuatDeltas, SliceInput, slice_loop};
use crate::propagation::blocks::V3;
use crate::sample::span_s;
use crate::scheme::{Node, Stencil};

/// Euler: `Δp += Δv h + ½ ΔR_k a_k h²`, `Δv += ΔR_k a_k h`, `ΔR ← ΔR_k Exp(ω_k h)`.
#[inline(always)]
fn euler(d: &mut QuatDeltas, n0: &Node, h: f64) {
    let u = d.q.rotate(&n0.a);
    let h2 = 0.5 * h * h;
    d.p += d.v * h + u * h2;
    d.v += u * h;
    d.q = d.q.mul_exp_scaled(&n0.w, h);
}

/// Midpoint: `ΔR_k+1 = ΔR_k Exp(½(ω_k + ω_k+1) h)`, `ā = ½(u_last + ΔR_k+1 a_k+1)`,
/// `Δp += Δv h + ½ ā h²`, `Δv += ā h`; `u_last ← ΔR_k+1 a_k+1`.
#[inline(always)]
fn midpoint(d: &mut QuatDeltas, u_last: &mut V3, n0: &Node, n1: &Node, h: f64) {
    let q1 = d.q.mul_exp_scaled(&(n0.w + n1.w), 0.5 * h);
    let u1 = q1.rotate(&n1.a);
    let abar = (*u_last + u1) * 0.5;
    let hh = 0.5 * h * h;
    d.p += d.v * h + abar * hh;
    d.v += abar * h;
    d.q = q1;
    *u_last = u1;
}

/// The deltas alone of a scheme with the stencil `{k, k+1}`: Euler (`MID = false`) or midpoint
/// (`MID = true`, which carries `ΔR_k a_k`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TwoPointDeltas<const MID: bool> {
    d: QuatDeltas,
    u_last: V3,
}

/// Euler's deltas alone.
pub(crate) type EulerDeltas = TwoPointDeltas<false>;
/// The midpoint scheme's deltas alone.
pub(crate) type MidpointDeltas = TwoPointDeltas<true>;

impl<const MID: bool> TwoPointDeltas<MID> {
    /// The interval between nodes `n0` and `n1`.
    #[inline(always)]
    fn interval(d: &mut QuatDeltas, u_last: &mut V3, n0: &Node, n1: &Node) {
        let h = span_s(n0.t_ns, n1.t_ns);
        if MID {
            midpoint(d, u_last, n0, n1, h);
        } else {
            euler(d, n0, h);
        }
    }
}

impl<const MID: bool> FastDeltas for TwoPointDeltas<MID> {
    const SLICE_FROM: usize = 2;

    fn start(&mut self, first: &Node) {
        // ΔR_0 a_0 = a_0.
        self.u_last = first.a;
    }

    #[inline(always)]
    fn step(&mut self, st: &Stencil) {
        Self::interval(&mut self.d, &mut self.u_last, st.n0(), st.n1());
    }

    #[inline(never)]
    fn run_slice(&mut self, last: &[Node; 2], input: &SliceInput, done: &mut usize) -> usize {
        let [mut n0, mut n1] = *last;
        let (mut d, mut u_last) = (self.d, self.u_last);
        let used = slice_loop(input, &mut d, done, |d, s| {
            Self::interval(d, &mut u_last, &n0, &n1);
            (n0, n1) = (n1, Node::corrected(s, input.bias));
        });
        (self.d, self.u_last) = (d, u_last);
        used
    }

    fn quat(&mut self) -> &mut QuatDeltas {
        &mut self.d
    }
}
