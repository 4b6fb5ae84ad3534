//! Integration schemes: what one interval `[t_k, t_k+1]` does to the deltas, and its
//! linearisation in the one shape every scheme shares.
//!
//! Every scheme works on bias-corrected samples `ω = ω_m − b̂_g`, `a = a_m − b̂_a` (`Node`) and
//! updates `ΔR_k+1 = ΔR_k Exp(Ω_k)`, `Δv`, `Δp` in frame i (gravity excluded, Forster et al.
//! 2017, eq. 33). A scheme is one file, which holds
//!
//! - the shape of its linearisation (`propagation::Shape`: its stencil, whether the end node's
//!   noise enters an interval, which parts of the gain basis it uses) and its noise cell rule;
//! - `IntervalScheme::step`: the deltas over one interval;
//! - `IntervalScheme::linearise`: the transition of the rotated error and the gain of each
//!   stencil sample (`Linearisation`), from which the scheme-agnostic `propagation` module
//!   builds the covariance, the bias Jacobians and the combined covariance;
//! - its registry row (`INFO`, a [`SchemeInfo`]: everything the command line, `advise`, the
//!   report, the charts and the Python package say about it) and the documentation of its
//!   [`Scheme`] variant (`variant_docs!`, a macro because a `#[doc]` attribute takes a literal);
//!
//! and one line in the registry below, which declares the file and makes it a [`Scheme`] of
//! the public API. A faster implementation of its deltas alone attaches itself in the `fast`
//! module; without one the scheme runs its plain step at every level.

use crate::choices::BiasCorrection;
use crate::noise::CellRule;
use crate::propagation::Shape;
use crate::propagation::blocks::{M3, V3};
use crate::propagation::linearisation::{Linearisation, MAX_STENCIL};
use crate::sample::{ImuBias, ImuSample, span_s};
use nalgebra::Matrix3;

/// One scheme: its stencil and the shape of its linearisation ([`Shape`], what the propagator
/// consumes), its noise cells, deltas step and linearisation (module docs).
pub(crate) trait IntervalScheme:
    Shape + Variant + Copy + Default + std::fmt::Debug + 'static
{
    /// How a sample's noise cell follows from its neighbours ([`ImuNoise`](crate::ImuNoise)).
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

/// What every face of the crate (the command line, `advise`, the report, the charts, the
/// Python package) says about a scheme: one row per scheme, in its own file
/// ([`Scheme::info`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SchemeInfo {
    /// Its name on the command line, in printed output and in Python (`euler`).
    pub name: &'static str,
    /// Other names accepted for it (`rk4`, `high-order` for `hermite4`).
    pub aliases: &'static [&'static str],
    /// One line for `--help`.
    pub help: &'static str,
    /// Global order of its deltas' error on smooth input (error ∝ hᵒʳᵈᵉʳ, h the sample
    /// period); every scheme's measured slope is checked against it
    /// (`preint/tests/scheme_contract.rs`).
    pub order: u32,
    /// The input on which each of its deltas is exact.
    pub exact_on: &'static str,
    /// Whether its deltas are exact (to round-off) on held input: `(ω_k, a_k)` constant over
    /// each interval (a sample-and-hold stream, an integrating IMU); `preint advise --input
    /// held` takes the scheme that is as its reference (checked in `cli/tests/advise_exact.rs`).
    pub exact_when_held: bool,
    /// Simplicity rank: among candidates of near-equal cost `preint advise` recommends the
    /// lowest (model no more than the scene needs).
    pub rank: u32,
    /// The bias correction its measurements carry when
    /// [`PreintParams::bias_correction`](crate::PreintParams::bias_correction) is `None`.
    pub bias_correction: BiasCorrection,
    /// How [`truncation::estimate`](crate::truncation::estimate) estimates its truncation
    /// error.
    pub truncation: TruncationCompanion,
    /// Its colour in every chart and table, `#rrggbb`.
    pub colour: &'static str,
}

/// The companion integration [`truncation::estimate`](crate::truncation::estimate) estimates a
/// scheme's truncation error with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TruncationCompanion {
    /// The 4th-order `hermite4` scheme on the window's samples upsampled four times:
    /// `e ≈ D_h ⊖ D_fine`.
    Hermite4Upsampled,
    /// Richardson's estimate from the scheme itself on every other sample, with its order
    /// `q`: `e ≈ −(D_h ⊖ D_2h) / (2^q − 1)`.
    Richardson,
}

/// The registry: one line per scheme, `Variant => file::Type`, which declares the scheme's
/// file, its [`Scheme`] variant (documented by the file's `variant_docs!`), its row
/// (`file::INFO`) and its [`IntervalScheme`] type.
macro_rules! registry {
    ($d:tt $( $variant:ident => $m:ident :: $ty:ident, )*) => {
        $( pub(crate) mod $m; )*

        /// Integration scheme. N samples in a window make N−1 intervals `[t_k, t_k+1]`,
        /// `h = t_k+1 − t_k`.
        ///
        /// Each scheme is exact on some input and of some order otherwise ([`SchemeInfo`]).
        /// *Held* input: `(ω_k, a_k)` constant over `[t_k, t_k+1]` (a sample-and-hold stream,
        /// an integrating IMU's delta-angle and delta-velocity outputs divided by the
        /// interval). *Smooth* input: point samples of a smooth signal (a MEMS IMU); the order
        /// is that of the deltas' global error over a window, `O(hᵒʳᵈᵉʳ)`. Held-input
        /// exactness is not smooth-input accuracy: on smooth motion `Galilean` is as far from
        /// the truth as `Euler` and `Hermite4` is orders of magnitude closer. The claims are
        /// checked against closed forms (the product of the 5×5 exponentials of the held
        /// inputs) and measured slopes in `cli/tests/advise_exact.rs` and
        /// `preint/tests/scheme_contract.rs`; `preint advise --input smooth|held` chooses its
        /// reference by them.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Scheme {
            $( #[doc = $m::variant_docs!()] $variant, )*
        }

        impl Scheme {
            /// Every scheme, in the order of the registry (the order of every table and chart).
            pub const ALL: &'static [Scheme] = &[$(Scheme::$variant),*];

            /// The scheme's registry row.
            pub fn info(self) -> &'static SchemeInfo {
                match self { $(Scheme::$variant => &$m::INFO,)* }
            }
        }

        $( impl Variant for $m::$ty {
            const SCHEME: Scheme = Scheme::$variant;
        } )*

        /// `with_scheme!(value, S => body)`: `body` with `S` the [`IntervalScheme`] type of
        /// the scheme `value`.
        macro_rules! with_scheme {
            ($d value:expr, $d s:ident => $d body:expr) => {
                match $d value {
                    $( crate::scheme::Scheme::$variant => {
                        #[allow(dead_code)]
                        type $d s = crate::scheme::$m::$ty;
                        $d body
                    } )*
                }
            };
        }
        pub(crate) use with_scheme;
    };
}

registry! { $
    Euler => euler::Euler,
    Midpoint => midpoint::Midpoint,
    Hermite4 => hermite4::Hermite4,
    Galilean => galilean::Galilean,
}

impl Scheme {
    /// The scheme's name (`euler`, `midpoint`, `hermite4`, `galilean`): [`SchemeInfo::name`].
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The scheme called `name` or one of its [`SchemeInfo::aliases`] (`rk4` and
    /// `high-order` for `hermite4`).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|s| {
            let info = s.info();
            info.name == name || info.aliases.contains(&name)
        })
    }
}

impl Scheme {
    /// How a sample's noise cell follows from its neighbours in this scheme (see
    /// [`ImuNoise`](crate::ImuNoise)): [`CellRule::Held`] for Euler and Galilean, [`CellRule::Centered`]
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
