//! The contract every scheme of the registry keeps, checked for each [`Scheme::ALL`] entry (a
//! scheme added to the registry runs these tests unchanged):
//!
//! - its linearisation (the transition and noise gains it hands the propagator) equals central
//!   differences of its deltas on the manifold: the covariance against `Σ_k J_k Q_k J_kᵀ`
//!   (`common/linearisation.rs`), the bias Jacobians against re-integration at shifted biases;
//! - its deltas alone (`Level::Deltas`, through its fast path where one attaches itself) are
//!   the same bits whether the samples come in one slice, in chunks or one by one, and equal its
//!   plain step's deltas (the other levels) to round-off;
//! - its measured order on smooth analytic motion is the order of its registry row
//!   ([`preint::SchemeInfo::order`]).

mod common;

use common::linearisation::{brute, check, direct, of, params, stream};
use common::slices::{deltas_only, jittered, one_by_one};
use common::*;
use nalgebra::{Matrix3, SMatrix};
use preint::{ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Preintegrator, Scheme};

fn run(params: &PreintParams, bias: &ImuBias, s: &[ImuSample]) -> PreintegratedImu {
    let mut pi = Preintegrator::new(params.clone(), *bias).unwrap();
    pi.integrate_slice(s).unwrap();
    pi.finish().unwrap()
}

/// The parameters for the analytic scene (its gravity).
fn scene_params(scheme: Scheme, level: Level) -> PreintParams {
    PreintParams::default()
        .with_scheme(scheme)
        .with_level(level)
        .with_gravity(gravity())
}

/// The covariance (the scheme's transition and noise gains, propagated) against
/// `Σ_k J_k Q_k J_kᵀ` with `J_k` the central differences of its deltas on the manifold: samples
/// pushed into a preintegrator, n = 2, 3, 5, 60, uniform and jittered, isotropic and
/// anisotropic noise (the two noise paths of the code).
#[test]
fn covariance_equals_the_linearisation_by_central_differences() {
    for &scheme in Scheme::ALL {
        for aniso in [false, true] {
            let prm = params(scheme, aniso);
            let fast = prm.clone().with_level(Level::Deltas);
            for jitter in [false, true] {
                for n in [2usize, 3, 5, 60] {
                    let s = stream(n, jitter);
                    let code = direct(&prm, &s).cov;
                    let exact = brute(scheme, &prm, &s, 0..n, &|x| of(&direct(&fast, x)));
                    check(
                        &format!("{scheme:?} direct n={n} jitter={jitter} aniso={aniso}"),
                        &code,
                        &exact,
                    );
                }
            }
        }
    }
}

/// Central differences: error ≤ ε²/6·|f'''| + 2·u·|f|/ε. With ε = 1e-4 (rad/s or m/s²) and
/// deltas of order 1 over 1 s the truncation is ~1e-9 and round-off ~1e-12, so 1e-6 relative
/// (Frobenius, per Jacobian) leaves margin while a wrong term (≥1e-3 relative) fails.
#[test]
fn bias_jacobians_equal_central_differences() {
    let scene = Scene::smooth();
    let samples = scene.samples(5_000_000, 1_000_000_000);
    let b0 = ImuBias::new(V3::new(0.01, -0.02, 0.015), V3::new(0.1, -0.05, 0.2));
    for &scheme in Scheme::ALL {
        let prm = scene_params(scheme, Level::Covariance);
        let m0 = run(&prm, &b0, &samples);
        let eps = 1e-4;
        let mut num = SMatrix::<f64, 9, 6>::zeros();
        for i in 0..6 {
            let shifted = |s: f64| {
                let mut b = b0;
                if i < 3 {
                    b.gyro[i] += s;
                } else {
                    b.acc[i - 3] += s;
                }
                run(&prm, &b, &samples)
            };
            let (mp, mm) = (shifted(eps), shifted(-eps));
            let col_r =
                (mp.delta_r.minus(&m0.delta_r) - mm.delta_r.minus(&m0.delta_r)) / (2.0 * eps);
            let col_v = (mp.delta_v - mm.delta_v) / (2.0 * eps);
            let col_p = (mp.delta_p - mm.delta_p) / (2.0 * eps);
            num.fixed_view_mut::<3, 1>(0, i).copy_from(&col_r);
            num.fixed_view_mut::<3, 1>(3, i).copy_from(&col_v);
            num.fixed_view_mut::<3, 1>(6, i).copy_from(&col_p);
        }
        let j = &m0.jac;
        let blocks: [(&str, Matrix3<f64>, Matrix3<f64>); 6] = [
            ("dR/dbg", j.d_r_d_bg, num.fixed_view::<3, 3>(0, 0).into()),
            (
                "dR/dba",
                Matrix3::zeros(),
                num.fixed_view::<3, 3>(0, 3).into(),
            ),
            ("dv/dbg", j.d_v_d_bg, num.fixed_view::<3, 3>(3, 0).into()),
            ("dv/dba", j.d_v_d_ba, num.fixed_view::<3, 3>(3, 3).into()),
            ("dp/dbg", j.d_p_d_bg, num.fixed_view::<3, 3>(6, 0).into()),
            ("dp/dba", j.d_p_d_ba, num.fixed_view::<3, 3>(6, 3).into()),
        ];
        for (name, ana, fd) in blocks {
            let err = (ana - fd).norm();
            let scale = fd.norm().max(1e-9);
            eprintln!("{scheme:?} {name}: |analytic − FD| = {err:.2e} (|FD| = {scale:.2e})");
            assert!(
                err <= 1e-6 * scale.max(1.0),
                "{scheme:?} {name}: {err} vs {scale}"
            );
            assert!(
                err <= 1e-6 * scale || name == "dR/dba",
                "{scheme:?} {name}: rel {}",
                err / scale
            );
        }
    }
}

/// `Level::Deltas` (the scheme's fast path where one attaches itself): a slice, chunks and single
/// samples give the bits of pushing the samples one by one, across ΔR's re-orthonormalisation
/// every 1024 intervals.
#[test]
fn fast_path_slice_equals_one_by_one_bit_for_bit() {
    let s = jittered(5000); // > 4 re-orthonormalisations
    for &scheme in Scheme::ALL {
        for keep in [false, true] {
            let mut a = deltas_only(scheme, keep);
            one_by_one(&mut a, &s).unwrap();
            let ma = a.finish().unwrap();
            // All at once.
            let mut b = deltas_only(scheme, keep);
            b.integrate_slice(&s).unwrap();
            assert_eq!(b.finish().unwrap(), ma, "{scheme:?} keep={keep}: one slice");
            assert_eq!(b.samples(), a.samples());
            assert_eq!(b.len(), a.len());
            // Uneven chunks, single samples in between, and finish() on the way (it does not
            // consume the preintegrator).
            let mut c = deltas_only(scheme, keep);
            let (mut i, mut k) = (0, 0usize);
            while i < s.len() {
                // Short slices (taken one interval at a time) and block lengths of every
                // residue modulo 4 (taken four, two and one at a time).
                let len = if k % 2 == 0 {
                    k * 37 % 61
                } else {
                    64 + k * 37 % 71
                };
                let len = len.min(s.len() - i);
                c.integrate_slice(&s[i..i + len]).unwrap();
                i += len;
                if i < s.len() {
                    c.integrate(&s[i]).unwrap();
                    i += 1;
                }
                if k % 17 == 3 && c.len() >= 2 {
                    let mid = c.finish().unwrap();
                    let mut r = deltas_only(scheme, keep);
                    one_by_one(&mut r, &s[..i]).unwrap();
                    assert_eq!(mid, r.finish().unwrap(), "{scheme:?}: after {i} samples");
                }
                k += 1;
            }
            assert_eq!(c.finish().unwrap(), ma, "{scheme:?} keep={keep}: chunks");
            assert_eq!(c.samples(), a.samples());
        }
    }
}

/// The deltas alone (the fast path where there is one) equal the deltas of the other levels
/// (the scheme's plain step) to round-off over 25 s: ΔR to 1e-13 (entries of a rotation),
/// Δv and Δp to 1e-13 of their size.
#[test]
fn deltas_alone_equal_the_plain_steps_deltas() {
    let s = jittered(5000);
    for &scheme in Scheme::ALL {
        let fast = deltas_only(scheme, false);
        let mut fast = fast;
        fast.integrate_slice(&s).unwrap();
        let f = fast.finish().unwrap();
        let mut prm = PreintParams::default()
            .with_scheme(scheme)
            .with_level(Level::Covariance);
        prm.keep_samples = false;
        let b = ImuBias::new(V3::new(0.01, -0.02, 0.005), V3::new(0.1, 0.05, -0.2));
        let p = run(&prm, &b, &s);
        let dr = (f.delta_r.matrix() - p.delta_r.matrix()).amax();
        let dv = (f.delta_v - p.delta_v).amax() / p.delta_v.amax();
        let dp = (f.delta_p - p.delta_p).amax() / p.delta_p.amax();
        eprintln!("{scheme:?}: deltas alone vs plain step: ΔR {dr:.1e}, Δv {dv:.1e}, Δp {dp:.1e}");
        assert!(
            dr < 1e-13 && dv < 1e-13 && dp < 1e-13,
            "{scheme:?}: {dr} {dv} {dp}"
        );
    }
}

/// The global error of the deltas against the analytic motion's exact deltas over 1 s, at four
/// rates an octave apart (from 100/q Hz, so that every error is far above round-off): its
/// log–log slope in each of ΔR, Δv, Δp is the registry's order `q` within 0.1 (measured within
/// 0.03 for the four schemes).
#[test]
fn measured_order_is_the_registered_order() {
    let scene = Scene::smooth();
    let (r, v, p) = scene.exact(0.0, 1.0);
    for &scheme in Scheme::ALL {
        let q = scheme.info().order;
        let base = 100.0 / f64::from(q);
        let prm = scene_params(scheme, Level::Deltas);
        let mut hs = vec![];
        let mut errs = [vec![], vec![], vec![]];
        for rate in [base, 2.0 * base, 4.0 * base, 8.0 * base] {
            let step = (1e9 / rate) as i64;
            let m = run(&prm, &ImuBias::zero(), &scene.samples(step, 1_000_000_000));
            let e = errors(&m, &r, &v, &p);
            hs.push(1.0 / rate);
            errs[0].push(e.0);
            errs[1].push(e.1);
            errs[2].push(e.2);
        }
        for (name, e) in ["rotation", "velocity", "position"].iter().zip(&errs) {
            let slope = loglog_slope(&hs, e);
            eprintln!("{scheme:?} {name}: slope {slope:.3} (order {q}), errors {e:?}");
            assert!(
                (slope - f64::from(q)).abs() <= 0.1,
                "{scheme:?} {name}: slope {slope}, registered order {q}"
            );
        }
    }
}
