//! Integration schemes: what one interval `[t_k, t_k+1]` does to the deltas, and its
//! linearisation in the one shape every scheme shares.
//!
//! Every scheme works on bias-corrected samples `ω = ω_m − b̂_g`, `a = a_m − b̂_a` (`Node`) and
//! updates `ΔR_k+1 = ΔR_k Exp(Ω_k)`, `Δv`, `Δp` in frame i (gravity excluded, Forster et al.
//! 2017, eq. 33). A scheme is one file implementing `IntervalScheme` (crate-internal):
//!
//! - its stencil (which samples interval k reads) and its noise cell rule;
//! - `IntervalScheme::step`: the deltas over one interval;
//! - `IntervalScheme::linearise`: the transition of the rotated error and the gain of each
//!   stencil sample (`Linearisation`), from which the scheme-agnostic `propagation` module
//!   builds the covariance, the bias Jacobians and the combined covariance;
//! - optionally a faster implementation of its deltas alone (`Fast`, in the `fast` module).
//!
//! and one line in the registry below, which makes it a [`Scheme`] of the public API.
//!
//! | scheme | stencil of interval k | order | file |
//! |---|---|---|---|
//! | [`Scheme::Euler`] | k (held over the interval) | 1 | [`euler`] |
//! | [`Scheme::Midpoint`] | k, k+1 | 2 | [`midpoint`] |
//! | [`Scheme::Hermite4`] | k−1 … k+2 | 4 | [`hermite4`] |
//! | [`Scheme::Galilean`] | k (held, exact Gal(3) exponential) | 1 (exact for held input) | [`galilean`] |

pub mod euler;
pub mod galilean;
pub mod hermite4;
pub mod midpoint;

use crate::noise::CellRule;
use crate::propagation::Shape;
use crate::propagation::blocks::{M3, V3};
use crate::propagation::linearisation::{Linearisation, MAX_STENCIL};
use crate::sample::{ImuBias, ImuSample, span_s};
use nalgebra::Matrix3;

/// One scheme: its stencil and the shape of its linearisation ([`Shape`], what the propagator
/// consumes), its noise cells, deltas step and linearisation (module docs).
pub(crate) trait IntervalScheme: Shape + Variant + Copy + Default + std::fmt::Debug + 'static {
    /// How a sample's noise cell follows from its neighbours ([`crate::noise`]).
    const CELL_RULE: CellRule;
    /// What the scheme carries from one interval to the next (e.g. `ΔR_k a_k`).
    type Carry: Copy + Default + std::fmt::Debug;
    /// What [`IntervalScheme::step`] hands to [`IntervalScheme::linearise`].
    type Step: Copy;

    /// Prepares the carry for a window whose first node is `first`.
    fn start(carry: &mut Self::Carry, first: &Node);
    /// Integrates the interval from node `st.k` to node `st.k + 1`.
    fn step(d: &mut Deltas, carry: &mut Self::Carry, st: &Stencil) -> Self::Step;
    /// The interval's transition and its stencil samples' gains, in rotated coordinates at
    /// node k+1.
    fn linearise(step: &Self::Step, st: &Stencil) -> Linearisation<Self::NodeTerms>;
}

/// The [`Scheme`] of an [`IntervalScheme`] type (given by the registry).
pub(crate) trait Variant {
    /// The scheme.
    const SCHEME: Scheme;
}

/// The registry: one line per scheme (its `Scheme` variant, type, name and accepted aliases).
macro_rules! registry {
    ($d:tt $( $(#[$doc:meta])* $variant:ident => $ty:ty, $name:literal $(| $alias:literal)* ;)*) => {
        /// Integration scheme. N samples in a window make N−1 intervals `[t_k, t_k+1]`,
        /// `h = t_k+1 − t_k`.
        ///
        /// Which input each scheme integrates exactly, and its order otherwise. *Held* input:
        /// `(ω_k, a_k)` constant over `[t_k, t_k+1]` (a sample-and-hold stream, an integrating
        /// IMU's delta-angle and delta-velocity outputs divided by the interval). *Smooth*
        /// input: point samples of a smooth signal (a MEMS IMU); the order is that of the
        /// deltas' global error over a window, `O(hᵒʳᵈᵉʳ)`.
        ///
        /// | scheme | smooth input | exact when |
        /// |---|---|---|
        /// | `Euler` | order 1 | ΔR: ω held; Δv, Δp: held input with `a_k ∥ ω_k` (`Exp(θ)a = a` along the axis), e.g. no rotation while accelerating |
        /// | `Midpoint` | order 2 | ΔR: ω linear between samples about a fixed axis (`Exp` of the trapezoid is then `Exp(∫ω)`); Δv: no rotation and `a` linear between samples; Δp: no rotation and `a` constant. Not on held input: it averages the samples on both sides of a step |
        /// | `Hermite4` | order 4 | ΔR: a cubic rate about a fixed axis, a constant ω included; Δv: a cubic `a` without rotation. Not on held input |
        /// | `Galilean` | order 1 | ΔR, Δv, Δp: held input (the Gal(3) exponential of each interval's constant `(ω_k, a_k)`) |
        ///
        /// Held-input exactness is not smooth-input accuracy: on smooth motion `Galilean` is as
        /// far from the truth as `Euler` and `Hermite4` is orders of magnitude closer. The claims
        /// are checked against closed forms (the product of the 5×5 exponentials of the held
        /// inputs) and measured slopes in `cli/tests/advise_exact.rs`; `preint advise --input
        /// smooth|held` chooses its reference by them.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Scheme {
            $( $(#[$doc])* $variant, )*
        }

        impl Scheme {
            /// Every scheme, in the order of the registry.
            pub const ALL: &'static [Scheme] = &[$(Scheme::$variant),*];

            /// The scheme's name (`euler`, `midpoint`, `hermite4`, `galilean`).
            pub fn name(self) -> &'static str {
                match self { $(Scheme::$variant => $name,)* }
            }

            /// The scheme called `name` or one of its aliases (`rk4` and `high-order` for
            /// `hermite4`).
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($name $(| $alias)* => Some(Scheme::$variant),)*
                    _ => None,
                }
            }
        }

        $( impl Variant for $ty {
            const SCHEME: Scheme = Scheme::$variant;
        } )*

        /// `with_scheme!(value, S => body)`: `body` with `S` the [`IntervalScheme`] type of
        /// the scheme `value`.
        macro_rules! with_scheme {
            ($d value:expr, $d s:ident => $d body:expr) => {
                match $d value {
                    $( crate::scheme::Scheme::$variant => {
                        #[allow(dead_code)]
                        type $d s = $ty;
                        $d body
                    } )*
                }
            };
        }
        pub(crate) use with_scheme;
    };
}

registry! { $
    /// Forster et al. 2017 (= GTSAM `PreintegratedImuMeasurementsManifold`): sample k held
    /// over interval k; `ΔR_k+1 = ΔR_k Exp(ω_k h)`, `Δv_k+1 = Δv_k + ΔR_k a_k h`,
    /// `Δp_k+1 = Δp_k + Δv_k h + ½ ΔR_k a_k h²`. Global error O(h). ΔR exact when ω is
    /// held over each interval, Δv and Δp only when also `a_k ∥ ω_k` (`Exp(θ)a = a` along the
    /// axis; a held body accelerating across its rotation axis is missed at O(h): 0.0723 m/s
    /// at 20 Hz on GTSAM's stress input). See [`euler`].
    Euler => crate::scheme::euler::Euler, "euler";
    /// `ω̄ = ½(ω_k + ω_k+1)`, `ΔR_k+1 = ΔR_k Exp(ω̄ h)`, `ā = ½(ΔR_k a_k + ΔR_k+1 a_k+1)`,
    /// `Δv_k+1 = Δv_k + ā h`, `Δp_k+1 = Δp_k + Δv_k h + ½ ā h²`. Global error O(h²). ΔR
    /// exact for a rate linear between samples about a fixed axis; Δv without rotation for
    /// `a` linear between samples, Δp only for `a` constant; not exact on held input (its
    /// mean rate straddles each step). See [`midpoint`].
    Midpoint => crate::scheme::midpoint::Midpoint, "midpoint";
    /// 4th-order Hermite–Magnus scheme (the command line also accepts `rk4`, the name users
    /// look for, although it is not a Runge–Kutta method): each node's `ω̇`, `ȧ` from the
    /// quadratic through it and its two neighbours;
    /// `Ω = h/2(ω_k+ω_k+1) + h²/12(ω̇_k − ω̇_k+1 + ω_k×ω_k+1)` (4th-order Magnus); Δv by the
    /// corrected trapezoid on `u = ΔR a` with `u̇ = ΔR(ω×a + ȧ)`, Δp by the corrected trapezoid
    /// on `v`. One Exp per interval. Global error O(h⁴) on smooth input. ΔR exact for a cubic
    /// rate about a fixed axis, Δv for a cubic `a` without rotation; not exact on held input,
    /// whose steps its quadratics smooth over. See [`hermite4`].
    Hermite4 => crate::scheme::hermite4::Hermite4, "hermite4" | "rk4" | "high-order";
    /// Delama et al., RA-L 2025 (= GTSAM 4.3 `PreintegratedImuMeasurementsG`): sample k held
    /// over interval k, composed with the exact Gal(3) exponential of `(ω_k, a_k)`;
    /// `ΔR_k+1 = ΔR_k Exp(θ)`, `Δv_k+1 = Δv_k + ΔR_k Jl(θ) a_k h`,
    /// `Δp_k+1 = Δp_k + Δv_k h + ΔR_k N(θ) a_k h²`, `θ = ω_k h`. Exact (ΔR, Δv, Δp) when
    /// the input is held constant over each interval (sample-and-hold streams, integrating
    /// IMUs); global error O(h) on smooth input, as Euler's. See [`galilean`].
    Galilean => crate::scheme::galilean::Galilean, "galilean";
}

impl Scheme {
    /// How a sample's noise cell follows from its neighbours in this scheme (see
    /// [`crate::noise`]): [`CellRule::Held`] for Euler and Galilean, [`CellRule::Centered`]
    /// otherwise.
    pub fn cell_rule(self) -> CellRule {
        with_scheme!(self, S => S::CELL_RULE)
    }

    /// Samples interval k reads before node k and after node k+1 (`(0, 0)` for Euler,
    /// midpoint and Galilean, `(1, 1)` for the Hermite scheme).
    pub fn stencil_reach(self) -> (usize, usize) {
        with_scheme!(self, S => (S::NODES_BEFORE, S::NODES_AFTER))
    }
}

/// A bias-corrected sample: time \[ns\], `ω` [rad/s], `a` [m/s²].
///
/// Aligned so that `w` and `a` each start a 16-byte pair: the vector stores that write a node
/// and the loads that read it soon after then cover the same bytes (a load spanning two
/// pending stores cannot be forwarded and stalls).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct Node {
    pub w: V3,
    _pad_w: f64,
    pub a: V3,
    pub t_ns: i64,
}

impl Node {
    #[inline(always)]
    pub(crate) fn new(t_ns: i64, w: V3, a: V3) -> Self {
        Self {
            w,
            _pad_w: 0.0,
            a,
            t_ns,
        }
    }

    /// The node of sample `s` for the bias estimate `bias`: `ω_m − b_g`, `a_m − b_a`.
    #[inline(always)]
    pub(crate) fn corrected(s: &ImuSample, bias: &ImuBias) -> Self {
        Self::new(s.t_ns, s.gyro - bias.gyro, s.acc - bias.acc)
    }
}

/// The nodes interval k reads: `nodes[..len]` are consecutive samples (positions ≥ `len` may
/// be any node: their weights are zero), node k is at position `k`, node k+1 at `k + 1`.
/// `first`: the window's first interval.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stencil<'a> {
    pub nodes: [&'a Node; MAX_STENCIL],
    pub len: usize,
    pub k: usize,
    pub first: bool,
}

impl Stencil<'_> {
    /// Node k.
    #[inline(always)]
    pub(crate) fn n0(&self) -> &Node {
        self.nodes[self.k]
    }

    /// Node k+1.
    #[inline(always)]
    pub(crate) fn n1(&self) -> &Node {
        self.nodes[self.k + 1]
    }

    /// The interval's length `h` \[s\].
    #[inline(always)]
    pub(crate) fn h(&self) -> f64 {
        span_s(self.n0().t_ns, self.n1().t_ns)
    }
}

/// ΔR is re-orthonormalised (`R ← ½R(3I − RᵀR)`) every this many intervals.
pub(crate) const RENORM_EVERY: usize = 1024;

/// Running deltas: `ΔR_k` (a rotation matrix), `Δv_k` [m/s], `Δp_k` \[m\], frame i.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Deltas {
    pub r: M3,
    pub v: V3,
    pub p: V3,
}

impl Default for Deltas {
    fn default() -> Self {
        Self {
            r: M3::identity(),
            v: V3::zeros(),
            p: V3::zeros(),
        }
    }
}

impl Deltas {
    /// Re-orthonormalises ΔR to first order, `R(3I − RᵀR)/2`.
    #[inline]
    pub(crate) fn renormalize(&mut self) {
        let r = self.r;
        self.r = r * (M3::identity() * 3.0 - r.transpose() * r) * 0.5;
    }
}

/// `s I + α[φ]× + β[φ]×²`, built entry-wise from `[φ]×² = φφᵀ − θ²I` (no 3×3 products): with
/// Rodrigues' coefficients `(b, c)` ([`preint_lie::so3::RodriguesCoeffs`]), `s·Jl(φ)` is
/// `(s, s b, s c)` and `s·Jr(φ)` is `(s, −s b, s c)` (Solà et al. 2018, eqs. 143–146).
#[inline(always)]
pub(crate) fn s_plus_hat_hat2(phi: &V3, s: f64, alpha: f64, beta: f64) -> M3 {
    let (x, y, z) = (phi.x, phi.y, phi.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (bxy, bxz, byz) = (beta * x * y, beta * x * z, beta * y * z);
    let (ax, ay, az) = (alpha * x, alpha * y, alpha * z);
    Matrix3::new(
        s - beta * (yy + zz),
        bxy - az,
        bxz + ay,
        bxy + az,
        s - beta * (xx + zz),
        byz - ax,
        bxz - ay,
        byz + ax,
        s - beta * (xx + yy),
    )
}
