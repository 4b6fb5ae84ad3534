//! The Galilean scheme (= GTSAM 4.3 `GalileanPreintegration`, `PreintegratedImuMeasurementsG`;
//! Delama et al., *Equivariant IMU Preintegration With Biases: A Galilean Group Approach*,
//! RA-L 2025): sample k held over interval k, the interval composed with the exact
//! Gal(3) exponential of the held `(ω_k, a_k)`:
//!
//! ```text
//! θ = ω_k h,   ΔR_k+1 = ΔR_k Exp(θ),   Δv_k+1 = Δv_k + ΔR_k Jl(θ) a_k h,
//! Δp_k+1 = Δp_k + Δv_k h + ΔR_k N(θ) a_k h²,
//! Jl(θ) = Σ_{n≥0} [θ]×ⁿ/(n+1)! = I + f₂[θ]× + f₃[θ]×²,   N(θ) = Σ_{n≥0} [θ]×ⁿ/(n+2)! = ½I + f₃[θ]× + f₄[θ]×²
//! ```
//!
//! with `f_m(t) = Σ_k (−1)^k t^{2k}/(2k+m)!` at `t = |θ|` (`f₂ = (1 − cos t)/t²`,
//! `f₃ = (t − sin t)/t³`, `f₄ = (t²/2 + cos t − 1)/t⁴`). `Jl(θ) a h` and `N(θ) a h²` are the
//! velocity and position of `∫ ΔR(s) a ds`, `∫ (h − s) ΔR(s) a ds` under a constant rate, so the
//! deltas are exact whenever the input is constant over each interval; on smooth input the
//! global error is O(h), as Euler's.
//!
//! Linearisation in the rotated chart `ψ = ΔR δφ`: the transition has `U1 = ΔR_k Jl(θ) a h`,
//! `U2 = ΔR_k N(θ) a h²` (exactly the increments), and sample k's gain over interval k is the
//! general 9×6
//!
//! ```text
//! gyro:  ψ ← ΔR_k Jl(θ) h,   v ← ΔR_k ∂(Jl(θ)a)/∂θ h²,   p ← ΔR_k ∂(N(θ)a)/∂θ h³
//! accel: v ← ΔR_k Jl(θ) h,   p ← ΔR_k N(θ) h²
//! ```
//!
//! (`Exp(θ) Jr(θ) = Jl(θ)`), handed to the propagator whole (`HeldGain`). With
//! `M(θ) = sI + α[θ]× + β[θ]×²`, `[θ]× a = θ × a`, `[θ]×² a = θ(θ·a) − a|θ|²` and
//! `∂α/∂θ = α'(t)/t θᵀ`:
//!
//! ```text
//! ∂(M(θ)a)/∂θ = −α[a]× + β((θ·a)I + θaᵀ − 2aθᵀ) + (α'/t (θ × a) + β'/t θ × (θ × a)) θᵀ
//! ```
//!
//! with `f_m'(t)/t = (f_{m−1} − m f_m)/t² = Σ_{k≥1} (−1)^k 2k t^{2k−2}/(2k+m)!` (series below
//! t = 2, accurate to round-off; `∂(Jl(θ)a)/∂θ` equals Barfoot's `Q(a, θ) − [Jl(θ)a]× Jl(θ)`).
//! Sample k's noise cell is the interval it is held over ([`CellRule::Held`]), as GTSAM's.

use crate::propagation::linearisation::{GainBasis, GainCoef, GainForm, HeldGain, Linearisation, MAX_STENCIL};
use super::{Deltas, IntervalScheme, Node, SchemeInfo, Stencil, TruncationCompanion, s_plus_hat_hat2};
use crate::choices::BiasCorrection;
use crate::noise::CellRule;
use crate::propagation::Shape;
use crate::propagation::blocks::{Gain96, M3, V3};
use crate::propagation::transition::Transition;
use preint_lie::so3::{RodriguesCoeffs, i_plus_hat_hat2};

/// Galilean's registry row ([`SchemeInfo`]).
pub(crate) const INFO: SchemeInfo = SchemeInfo {
    name: "galilean",
    aliases: &[],
    help: "First order on smooth input, exact when the input is constant over each interval (the sample at the start held, composed with the exact Gal(3) exponential; GTSAM 4.3's PreintegratedImuMeasurementsG).",
    order: 1,
    exact_on: "exact (ΔR, Δv, Δp) when ω and a are held over each interval: sample-and-hold streams, integrating IMUs (delta-angle/delta-velocity outputs)",
    exact_when_held: true,
    rank: 2,
    bias_correction: BiasCorrection::Group,
    truncation: TruncationCompanion::Hermite4Upsampled,
    colour: "#cc79a7",
};

/// The documentation of [`Scheme::Galilean`](super::Scheme::Galilean).
macro_rules! variant_docs {
    () => {
        "Delama et al., RA-L 2025 (= GTSAM 4.3 `PreintegratedImuMeasurementsG`): sample k held \
         over interval k, composed with the exact Gal(3) exponential of `(ω_k, a_k)`; \
         `ΔR_k+1 = ΔR_k Exp(θ)`, `Δv_k+1 = Δv_k + ΔR_k Jl(θ) a_k h`, \
         `Δp_k+1 = Δp_k + Δv_k h + ΔR_k N(θ) a_k h²`, `θ = ω_k h`. Exact (ΔR, Δv, Δp) when \
         the input is held constant over each interval (sample-and-hold streams, integrating \
         IMUs); global error O(h) on smooth input, as Euler's."
    };
}
pub(crate) use variant_docs;

/// The Galilean scheme ([`crate::Scheme::Galilean`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Galilean;

/// Terms of the series below [`SERIES_BELOW`]: the first omitted term of `f₂` at t = 2 is
/// `4¹⁴/30!` ≈ 1e-24.
const TERMS: usize = 14;
/// Where the coefficients switch from their series to the closed forms \[rad²\] (t = 2).
const SERIES_BELOW: f64 = 4.0;
/// Terms of the short series below [`SHORT_BELOW`] (every per-sample angle of an IMU): the
/// first omitted relative term is below `10⁻¹⁰·12/14!` ≈ 1.4e-20.
const SHORT: usize = 5;
/// Where the short series ends \[rad²\] (t = 0.1).
const SHORT_BELOW: f64 = 0.01;

/// `1/n!` for `n ≤ 35`.
const fn inv_factorial(n: usize) -> f64 {
    let mut f = 1.0;
    let mut i = 2;
    while i <= n {
        f *= i as f64;
        i += 1;
    }
    1.0 / f
}

/// The first `N` terms of the series of `f_m` (`deriv = false`) or of `f_m'(t)/t`
/// (`deriv = true`) in powers of t².
const fn series<const N: usize>(m: usize, deriv: bool) -> [f64; N] {
    let mut out = [0.0; N];
    let mut j = 0;
    while j < N {
        out[j] = if deriv {
            // (−1)^(j+1) 2(j+1) / (2j+2+m)!
            let s = if j % 2 == 0 { -1.0 } else { 1.0 };
            s * (2 * (j + 1)) as f64 * inv_factorial(2 * j + 2 + m)
        } else {
            let s = if j % 2 == 0 { 1.0 } else { -1.0 };
            s * inv_factorial(2 * j + m)
        };
        j += 1;
    }
    out
}

/// `f₄`, `f₂'/t`, `f₃'/t`, `f₄'/t`: long and short series.
const LONG: [[f64; TERMS]; 4] = [
    series(4, false),
    series(2, true),
    series(3, true),
    series(4, true),
];
const SHORT_SERIES: [[f64; SHORT]; 4] = [
    series(4, false),
    series(2, true),
    series(3, true),
    series(4, true),
];

#[inline(always)]
fn horner<const N: usize>(x: f64, c: &[f64; N]) -> f64 {
    let mut acc = c[N - 1];
    for &ck in c[..N - 1].iter().rev() {
        acc = acc * x + ck;
    }
    acc
}

/// `f₄(t) = (t²/2 + cos t − 1)/t⁴` at `t² = t2`, given `f₂` (the relation `f₂ = ½ − t² f₄`
/// above the series).
#[inline(always)]
pub(crate) fn f4(t2: f64, f2: f64) -> f64 {
    if t2 < SHORT_BELOW {
        horner(t2, &SHORT_SERIES[0])
    } else if t2 < SERIES_BELOW {
        horner(t2, &LONG[0])
    } else {
        (0.5 - f2) / t2
    }
}

/// `(f₂'/t, f₃'/t, f₄'/t)` at `t² = t2` [1/rad²], given `f₁ … f₄` (closed forms above the
/// series).
#[inline(always)]
pub(crate) fn derivs(t2: f64, f: [f64; 4]) -> (f64, f64, f64) {
    if t2 < SHORT_BELOW {
        let c = &SHORT_SERIES;
        (horner(t2, &c[1]), horner(t2, &c[2]), horner(t2, &c[3]))
    } else if t2 < SERIES_BELOW {
        (
            horner(t2, &LONG[1]),
            horner(t2, &LONG[2]),
            horner(t2, &LONG[3]),
        )
    } else {
        let [f1, f2, f3, f4] = f;
        (
            (f1 - 2.0 * f2) / t2,
            (f2 - 3.0 * f3) / t2,
            (f3 - 4.0 * f4) / t2,
        )
    }
}

/// `∂(M(θ)a)/∂θ` for `M(θ) = sI + α[θ]× + β[θ]×²` with `(α'/t, β'/t) = (da, db)` (module
/// docs), given `(θ × a, θ × (θ × a)) = (ta, tta)`.
#[inline(always)]
pub(crate) fn d_m_a(
    th: &V3,
    a: &V3,
    (ta, tta): (&V3, &V3),
    (alpha, beta): (f64, f64),
    (da, db): (f64, f64),
) -> M3 {
    let dot = th.dot(a) * beta;
    let w = ta * da + tta * db;
    let (ab, ta_b) = (a * beta, th * beta);
    let (ax, ay, az) = (a.x * alpha, a.y * alpha, a.z * alpha);
    // −α[a]× + β(θ·a)I + βθaᵀ − 2βaθᵀ + w θᵀ
    M3::new(
        dot + ta_b.x * a.x - 2.0 * ab.x * th.x + w.x * th.x,
        az + ta_b.x * a.y - 2.0 * ab.x * th.y + w.x * th.y,
        -ay + ta_b.x * a.z - 2.0 * ab.x * th.z + w.x * th.z,
        -az + ta_b.y * a.x - 2.0 * ab.y * th.x + w.y * th.x,
        dot + ta_b.y * a.y - 2.0 * ab.y * th.y + w.y * th.y,
        ax + ta_b.y * a.z - 2.0 * ab.y * th.z + w.y * th.z,
        ay + ta_b.z * a.x - 2.0 * ab.z * th.x + w.z * th.x,
        -ax + ta_b.z * a.y - 2.0 * ab.z * th.y + w.z * th.y,
        dot + ta_b.z * a.z - 2.0 * ab.z * th.z + w.z * th.z,
    )
}

/// What a Galilean step hands to its linearisation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GalileanStep {
    th: V3,
    t2: f64,
    k: RodriguesCoeffs,
    f4: f64,
    a: V3,
    ta: V3,
    tta: V3,
    r0: M3,
    u1: V3,
    u2: V3,
    h: f64,
}

impl Shape for Galilean {
    const NODES_BEFORE: usize = 0;
    const NODES_AFTER: usize = 0;
    const END_NODE_NOISE: bool = false;
    const GAIN_FORM: GainForm = GainForm {
        psi_vp: false,
        acc_on_own_node: false,
    };
    type NodeTerms = HeldGain;
}

impl IntervalScheme for Galilean {
    const CELL_RULE: CellRule = CellRule::Held;
    type Carry = ();
    type Step = GalileanStep;

    fn start(_: &mut (), _: &Node) {}

    #[inline(always)]
    fn step(d: &mut Deltas, _: &mut (), st: &Stencil) -> GalileanStep {
        let (n0, h) = (st.n0(), st.h());
        let th = n0.w * h;
        let t2 = th.norm_squared();
        let k = RodriguesCoeffs::new(&th);
        let f4 = f4(t2, k.b);
        let e = i_plus_hat_hat2(&th, k.a, k.b);
        let a = n0.a;
        let ta = th.cross(&a);
        let tta = th.cross(&ta);
        let jla = a + ta * k.b + tta * k.c;
        let na = a * 0.5 + ta * k.c + tta * f4;
        let r0 = d.r;
        let u1 = r0 * (jla * h);
        let u2 = r0 * (na * (h * h));
        d.p += d.v * h + u2;
        d.v += u1;
        d.r = r0 * e;
        GalileanStep {
            th,
            t2,
            k,
            f4,
            a,
            ta,
            tta,
            r0,
            u1,
            u2,
            h,
        }
    }

    #[inline(always)]
    fn linearise(s: &GalileanStep, _: &Stencil) -> Linearisation<HeldGain> {
        let (h, k) = (s.h, &s.k);
        let (d2, d3, d4) = derivs(s.t2, [k.a, k.b, k.c, s.f4]);
        let jl = s_plus_hat_hat2(&s.th, h, h * k.b, h * k.c);
        let n = s_plus_hat_hat2(&s.th, 0.5 * h * h, h * h * k.c, h * h * s.f4);
        let dj = d_m_a(&s.th, &s.a, (&s.ta, &s.tta), (k.b, k.c), (d2, d3));
        let dn = d_m_a(&s.th, &s.a, (&s.ta, &s.tta), (k.c, s.f4), (d3, d4));
        let f = s.r0 * jl;
        let (fv, fp) = (s.r0 * (dj * (h * h)), s.r0 * (dn * (h * h * h)));
        let np = s.r0 * n;
        let mut g = Gain96::default();
        for c in 0..3 {
            for i in 0..3 {
                g.g[c][i] = f[(i, c)];
                g.g[c][3 + i] = fv[(i, c)];
                g.g[c][6 + i] = fp[(i, c)];
                g.a[c][i] = f[(i, c)];
                g.a[c][3 + i] = np[(i, c)];
            }
        }
        Linearisation {
            tr: Transition {
                h,
                u1: s.u1,
                u2: s.u2,
            },
            basis: GainBasis::default(),
            coef: [GainCoef::default(); MAX_STENCIL],
            node: HeldGain(g),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use preint_lie::so3::{SO3, hat, jl};

    /// `Σ_{n<60} [θ]×ⁿ/(n+m)!` by its definition.
    fn series_matrix(th: &V3, m: usize) -> M3 {
        let x = hat(th);
        let (mut out, mut p) = (M3::zeros(), M3::identity());
        for n in 0..60 {
            out += p * inv_factorial(n + m);
            p *= x;
        }
        out
    }

    fn n_of(th: &V3) -> M3 {
        let t2 = th.norm_squared();
        let k = RodriguesCoeffs::new(th);
        s_plus_hat_hat2(th, 0.5, k.c, f4(t2, k.b))
    }

    fn jl_of(th: &V3) -> M3 {
        let k = RodriguesCoeffs::new(th);
        s_plus_hat_hat2(th, 1.0, k.b, k.c)
    }

    /// The analytic `(∂(Jl a)/∂θ, ∂(N a)/∂θ)`.
    fn analytic(th: &V3, a: &V3) -> (M3, M3) {
        let t2 = th.norm_squared();
        let k = RodriguesCoeffs::new(th);
        let f4 = f4(t2, k.b);
        let (d2, d3, d4) = derivs(t2, [k.a, k.b, k.c, f4]);
        let ta = th.cross(a);
        let tta = th.cross(&ta);
        (
            d_m_a(th, a, (&ta, &tta), (k.b, k.c), (d2, d3)),
            d_m_a(th, a, (&ta, &tta), (k.c, f4), (d3, d4)),
        )
    }

    /// Central differences of `f(θ)` (step `e`).
    fn numeric(th: &V3, e: f64, f: impl Fn(&V3) -> V3) -> M3 {
        let mut out = M3::zeros();
        for c in 0..3 {
            let mut d = V3::zeros();
            d[c] = e;
            out.set_column(c, &((f(&(th + d)) - f(&(th - d))) / (2.0 * e)));
        }
        out
    }

    fn angles() -> Vec<V3> {
        vec![
            V3::zeros(),
            V3::new(1e-9, -2e-9, 3e-9),
            V3::new(0.01, -0.02, 0.005),
            V3::new(0.3, -0.2, 0.5),
            V3::new(1.0, 0.4, -0.6),
            V3::new(1.2, -0.4, 0.6) * (std::f64::consts::FRAC_PI_2 / 1.4),
            V3::new(0.0, 1.99, 0.1),
            V3::new(2.0, -1.0, 1.5),
        ]
    }

    /// `Jl` and `N` as computed equal their defining series to round-off, and `Jl` equals
    /// the SO(3) left Jacobian.
    #[test]
    fn jl_and_n_match_their_series() {
        for th in angles() {
            let (n, s) = (n_of(&th), series_matrix(&th, 2));
            assert!((n - s).amax() < 4e-16, "{th:?}: {:e}", (n - s).amax());
            let (j, s) = (jl_of(&th), series_matrix(&th, 1));
            assert!((j - s).amax() < 4e-16, "{th:?}: {:e}", (j - s).amax());
            assert!((j - jl(&th)).amax() < 4e-16);
        }
    }

    /// `N(θ)` is `∫₀¹ (1 − s) Exp(sθ) ds` (Simpson on 2000 panels).
    #[test]
    fn n_is_the_weighted_integral_of_exp() {
        let th = V3::new(0.7, -1.1, 0.4);
        let m = 2000;
        let mut acc = M3::zeros();
        for i in 0..=m {
            let s = i as f64 / m as f64;
            let w = if i == 0 || i == m {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            acc += SO3::exp(&(th * s)).matrix() * ((1.0 - s) * w);
        }
        acc /= 3.0 * m as f64;
        assert!((acc - n_of(&th)).amax() < 1e-13);
    }

    /// Both derivatives against central differences, and `∂(Jl a)/∂θ` against Barfoot's
    /// `Q(a, θ) − [Jl(θ)a]× Jl(θ)` (`preint_lie::se3::q_block`).
    #[test]
    fn derivatives_match_central_differences_and_the_se3_q_block() {
        let a = V3::new(2.0, -1.0, 0.5);
        for th in angles() {
            let (dj, dn) = analytic(&th, &a);
            let nj = numeric(&th, 1e-5, |t| jl_of(t) * a);
            let nn = numeric(&th, 1e-5, |t| n_of(t) * a);
            assert!((dj - nj).amax() < 1e-9, "{th:?}: {:e}", (dj - nj).amax());
            assert!((dn - nn).amax() < 1e-9, "{th:?}: {:e}", (dn - nn).amax());
            let q = preint_lie::se3::q_block(&a, &th) - hat(&(jl_of(&th) * a)) * jl_of(&th);
            assert!((dj - q).amax() < 1e-14, "{th:?}: {:e}", (dj - q).amax());
        }
    }

    /// At t = 0.1 the short and the long series agree to round-off.
    #[test]
    fn short_and_long_series_agree_at_the_switch() {
        let t2 = SHORT_BELOW * (1.0 - 1e-12);
        for i in 0..4 {
            let (s, l) = (horner(t2, &SHORT_SERIES[i]), horner(t2, &LONG[i]));
            assert!((s - l).abs() <= 1e-16 * l.abs(), "{i}: {s} {l}");
        }
    }

    /// Below and above t = 2 the series and the closed forms agree.
    #[test]
    fn series_and_closed_forms_agree_at_the_switch() {
        for t in [1.7f64, 1.99, 2.01, 2.3] {
            let th = V3::new(t, 0.0, 0.0);
            let k = RodriguesCoeffs::new(&th);
            let t2 = t * t;
            let closed_f4 = (t2 / 2.0 + t.cos() - 1.0) / (t2 * t2);
            assert!((f4(t2, k.b) - closed_f4).abs() < 1e-15);
            let f = [k.a, k.b, k.c, closed_f4];
            let closed = (
                (f[0] - 2.0 * f[1]) / t2,
                (f[1] - 3.0 * f[2]) / t2,
                (f[2] - 4.0 * f[3]) / t2,
            );
            let (d2, d3, d4) = derivs(t2, f);
            assert!((d2 - closed.0).abs() < 1e-14);
            assert!((d3 - closed.1).abs() < 1e-14);
            assert!((d4 - closed.2).abs() < 1e-14);
        }
    }
}
