//! The covariance against the exact first-order linearisation, deterministic (no Monte Carlo).
//!
//! For a preintegration `f(samples)` the first-order covariance under the documented noise
//! model (`preint::ImuNoise`: every stream sample k carries independent white noise
//! `n_k = [n_g, n_a]` of covariance `Q_k = diag(Σ_g, Σ_a)/c_k`, `c_k` its cell from its stream
//! neighbours) is `Σ_k J_k Q_k J_kᵀ`, with `J_k = ∂e/∂n_k` (9×6) and
//! `e = [Log(ΔR₀ᵀ ΔR), Δv − Δv₀, Δp − Δp₀]` the chart of `preint::PreintegratedImu`. Here `J_k` is
//! computed by central differences of the *deltas only* (`Level::Deltas`, so nothing of the
//! covariance recursion is used), for every sample and channel, and `c_k` is written out from
//! the rustdoc rule. The code's covariance must agree with that sum. (Windows pushed directly
//! into a preintegrator: the generic scheme contract, `scheme_contract.rs`.)
//!
//! Accuracy of the reference. Central differences with step ε have truncation error
//! `ε²/6·|∂³e/∂n³|` and round-off `≈ u·|e₀|/ε` per column (u = 1.1e-16). A sample's noise moves
//! the deltas by `≈ h·n` (h = 5 ms), and the deltas are linear in `n_a` and nonlinear in `n_g`
//! only through `Exp(h n_g)`, so relative truncation ≈ (h ε)² ≈ 2.5e-11 for ε = 1e-3, and
//! relative round-off ≈ u·|Δ|/(ε h) ≤ 1.1e-16·3/(1e-3·2.5e-3) ≈ 1.3e-10 (|Δ| ≤ 3 over 0.4 s,
//! gains ≥ h/2). Errors of the covariance are of the same relative order (≈ 2× the column
//! error, ≤ 3e-10), so agreement is asserted at [`TOL`] = 1e-9, per 3×3 block relative to the
//! geometric mean of the two diagonal blocks (measured: ≤ 3e-11 in every case below). A wrong
//! model is far off: a boundary sample taken as a noise source of its own is off by ≥ 7e-3
//! (midpoint, hermite4, last test), a
//! merge without the shared samples by ≥ 1e-3.

mod common;

use common::linearisation::*;
use preint::window_samples;
use preint::{ImuSample, Level, PreintParams, PreintegratedImu, Scheme, merge, preintegrate};

/// Keyframes between samples, 1 µs from a sample on either side, and on a sample, through
/// `preintegrate`: the noise sources are the stream samples (the boundary samples are
/// combinations of them). Samples outside the perturbed range have no effect (checked on the
/// first one outside).
#[test]
fn window_covariance_equals_linearisation_of_the_stream() {
    for jitter in [false, true] {
        let s = stream(80, jitter);
        let t = |k: usize| s[k].t_ns;
        let windows = [
            (t(10) + 2_500_000, t(50) + 1),
            (t(3) + 1_000, t(40) - 1_000),
            (t(4) - 1_000, t(41) + 1_000),
            (t(12), t(47)),
            (t(20) + 1_200_000, t(20) + 3_000_000),
            (t(20) + 1_000, t(21)),
        ];
        for scheme in Scheme::ALL.iter().copied() {
            for aniso in [false, true] {
                let prm = params(scheme, aniso);
                let fast = prm.clone().with_level(Level::Deltas);
                for &(ti, tj) in &windows {
                    let f = |x: &[ImuSample]| of(&preintegrate(&fast, &bias(), x, ti, tj).unwrap());
                    let lo = s.partition_point(|x| x.t_ns < ti) - 4;
                    let hi = s.partition_point(|x| x.t_ns <= tj) + 4;
                    let code = preintegrate(&prm, &bias(), &s, ti, tj).unwrap().cov;
                    let exact = brute(scheme, &prm, &s, lo..hi, &f);
                    let outside = brute(scheme, &prm, &s, hi..hi + 1, &f);
                    assert_eq!(outside.amax(), 0.0, "sample {hi} influences the window");
                    check(
                        &format!(
                            "{scheme:?} window [{:.3}, {:.3}] ms jitter={jitter} aniso={aniso}",
                            (ti - s[0].t_ns) as f64 * 1e-6,
                            (tj - s[0].t_ns) as f64 * 1e-6
                        ),
                        &code,
                        &exact,
                    );
                }
            }
        }
    }
}

/// Merged windows: the merged covariance is the linearisation of the composed deltas with
/// respect to every stream sample (the shared samples' covariance included), for keyframes
/// on a sample, between samples and 1 µs from one, and for three windows merged both ways.
#[test]
fn merged_covariance_equals_linearisation_of_the_composition() {
    let s = stream(90, true);
    let t = |k: usize| s[k].t_ns;
    let compose = |a: &PreintegratedImu, b: &PreintegratedImu| {
        (
            a.delta_r * b.delta_r,
            a.delta_v + a.delta_r.act(&b.delta_v),
            a.delta_p + a.delta_v * b.delta_t + a.delta_r.act(&b.delta_p),
        )
    };
    for scheme in Scheme::ALL.iter().copied() {
        for aniso in [false, true] {
            let prm = params(scheme, aniso);
            let fast = prm.clone().with_level(Level::Deltas);
            let (ta, tc) = (t(5) + 1_700_000, t(70) + 300_000);
            for tb in [t(30), t(30) + 2_000_000, t(30) + 1_000, t(30) - 1_000] {
                let w = |p: &PreintParams, x: &[ImuSample], t0, t1| {
                    preintegrate(p, &bias(), x, t0, t1).unwrap()
                };
                let m = merge(&w(&prm, &s, ta, tb), &w(&prm, &s, tb, tc)).unwrap();
                let f = |x: &[ImuSample]| compose(&w(&fast, x, ta, tb), &w(&fast, x, tb, tc));
                let exact = brute(scheme, &prm, &s, 0..76, &f);
                check(
                    &format!(
                        "{scheme:?} merge at {:.3} ms aniso={aniso}",
                        (tb - t(0)) as f64 * 1e-6
                    ),
                    &m.cov,
                    &exact,
                );
                // Independence would be wrong by more than the tolerance (the test has power).
                let mut indep = w(&prm, &s, ta, tb);
                indep.edge_noise = preint::edges::EdgeNoise::default();
                let mi = merge(&indep, &w(&prm, &s, tb, tc)).unwrap();
                let e = block_rel(&mi.cov, &exact);
                eprintln!("{scheme:?}   … merged as independent windows: block rel {e:.2e}");
                // Euler and Galilean (held samples) share a sample only through an
                // interpolated boundary; 1 µs from a sample its weight or gain is ~1e-4 and the
                // effect below the tolerance.
                let held = matches!(scheme, Scheme::Euler | Scheme::Galilean);
                if !held || tb == t(30) + 2_000_000 {
                    assert!(
                        e > 100.0 * TOL,
                        "{scheme:?}: sharing not detectable ({e:e})"
                    );
                }
            }
            // Three windows, merged left- and right-associatively.
            let (tb, tb2) = (t(25) + 2_100_000, t(48));
            let (x, y, z) = (
                preintegrate(&prm, &bias(), &s, ta, tb).unwrap(),
                preintegrate(&prm, &bias(), &s, tb, tb2).unwrap(),
                preintegrate(&prm, &bias(), &s, tb2, tc).unwrap(),
            );
            let l = merge(&merge(&x, &y).unwrap(), &z).unwrap();
            let r = merge(&x, &merge(&y, &z).unwrap()).unwrap();
            let f = |q: &[ImuSample]| {
                let (a, b, c) = (
                    preintegrate(&fast, &bias(), q, ta, tb).unwrap(),
                    preintegrate(&fast, &bias(), q, tb, tb2).unwrap(),
                    preintegrate(&fast, &bias(), q, tb2, tc).unwrap(),
                );
                let (r1, v1, p1) = compose(&a, &b);
                let ab = PreintegratedImu {
                    delta_r: r1,
                    delta_v: v1,
                    delta_p: p1,
                    delta_t: a.delta_t + b.delta_t,
                    ..a
                };
                compose(&ab, &c)
            };
            let exact = brute(scheme, &prm, &s, 0..76, &f);
            check(&format!("{scheme:?} 3 windows, left merge"), &l.cov, &exact);
            check(
                &format!("{scheme:?} 3 windows, right merge"),
                &r.cov,
                &exact,
            );
        }
    }
}

/// Samples pushed directly, split at a shared sample of a jittered stream: each window sees
/// one neighbour of the shared sample only; the merge uses both (the whole stream's cell).
#[test]
fn merged_direct_windows_equal_linearisation() {
    let s = stream(41, true);
    for scheme in Scheme::ALL.iter().copied() {
        let prm = params(scheme, true);
        let fast = prm.clone().with_level(Level::Deltas);
        for k in [1usize, 2, 17, 39] {
            let m = merge(&direct(&prm, &s[..=k]), &direct(&prm, &s[k..])).unwrap();
            let f = |x: &[ImuSample]| {
                let (a, b) = (direct(&fast, &x[..=k]), direct(&fast, &x[k..]));
                (
                    a.delta_r * b.delta_r,
                    a.delta_v + a.delta_r.act(&b.delta_v),
                    a.delta_p + a.delta_v * b.delta_t + a.delta_r.act(&b.delta_p),
                )
            };
            let exact = brute(scheme, &prm, &s, 0..s.len(), &f);
            check(
                &format!("{scheme:?} direct windows merged at sample {k}"),
                &m.cov,
                &exact,
            );
        }
    }
}

/// The model this replaced treated an interpolated boundary sample as an independent noise
/// source with a cell of its own (what integrating `window_samples` directly does). Its
/// error against the exact linearisation, for keyframes 1 µs before and after a sample and
/// mid-interval, is printed, and its largest value must be well above the tolerance (or the
/// tests above could not tell the models apart).
#[test]
fn independent_boundary_model_is_measurably_off() {
    let s = stream(80, false);
    let t = |k: usize| s[k].t_ns;
    for scheme in Scheme::ALL.iter().copied() {
        let prm = params(scheme, false);
        let fast = prm.clone().with_level(Level::Deltas);
        let mut worst: f64 = 0.0;
        for (what, ti, tj) in [
            ("1 µs before a sample", t(4) - 1_000, t(41) - 1_000),
            ("1 µs after a sample", t(3) + 1_000, t(40) + 1_000),
            ("mid-interval", t(3) + 2_500_000, t(40) + 2_500_000),
        ] {
            let f = |x: &[ImuSample]| of(&preintegrate(&fast, &bias(), x, ti, tj).unwrap());
            let exact = brute(scheme, &prm, &s, 0..48, &f);
            let old = direct(&prm, &window_samples(scheme, &s, ti, tj, i64::MAX).unwrap()).cov;
            let ratio = |i: usize| {
                let tr = |m: &M9| m[(i, i)] + m[(i + 1, i + 1)] + m[(i + 2, i + 2)];
                tr(&old) / tr(&exact) - 1.0
            };
            let e = block_rel(&old, &exact);
            eprintln!(
                "{scheme:?} keyframes {what}: independent-boundary model off by {e:.2e} (block rel); variance traces rot {:+.2}%, v {:+.2}%, p {:+.2}%",
                100.0 * ratio(0),
                100.0 * ratio(3),
                100.0 * ratio(6)
            );
            worst = worst.max(e);
        }
        assert!(worst > 1e-3, "{scheme:?}: {worst}");
    }
}
