//! `integrate_slice` with `Level::Deltas` runs every scheme straight from the slice
//! (the `fast` module of `preint`). It must be indistinguishable from pushing the
//! samples one by one:
//! the same deltas bit for bit (across ΔR's re-orthonormalisation every 1024 intervals, the
//! generic scheme contract, `scheme_contract.rs`), the same stored samples, the same error at
//! the same index for a bad sample, and the same state after it.

mod common;

use nalgebra::Vector3;

use common::slices::{deltas_only as make, jittered as stream, one_by_one};
use preint::{ImuBias, ImuSample, Level, PreintError, PreintParams, Preintegrator, Scheme};

/// Makes sample `s` invalid, given the sample before it.
type Spoil = fn(&mut ImuSample, &ImuSample);

const SCHEMES: &[Scheme] = Scheme::ALL;

#[test]
fn a_bad_sample_stops_the_slice_where_one_by_one_stops() {
    let good = stream(3000);
    let bad_at = 1234;
    let variants: [(&str, Spoil); 4] = [
        ("NaN gyro", |s, _| s.gyro.y = f64::NAN),
        ("infinite acc", |s, _| s.acc.z = f64::INFINITY),
        ("duplicate stamp", |s, prev| s.t_ns = prev.t_ns),
        ("decreasing stamp", |s, prev| s.t_ns = prev.t_ns - 1),
    ];
    for &scheme in SCHEMES {
        for (what, spoil) in variants {
            let mut s = good.clone();
            let prev = s[bad_at - 1];
            spoil(&mut s[bad_at], &prev);
            let mut a = make(scheme, true);
            let ea = one_by_one(&mut a, &s).unwrap_err();
            let mut b = make(scheme, true);
            let eb = b.integrate_slice(&s).unwrap_err();
            assert_eq!(eb, ea, "{scheme:?} {what}");
            assert_eq!(
                b.len(),
                bad_at,
                "{scheme:?} {what}: samples before the bad one"
            );
            assert_eq!(
                b.finish().unwrap(),
                a.finish().unwrap(),
                "{scheme:?} {what}"
            );
            // Both go on with the rest.
            one_by_one(&mut a, &good[bad_at + 1..]).unwrap();
            b.integrate_slice(&good[bad_at + 1..]).unwrap();
            assert_eq!(
                b.finish().unwrap(),
                a.finish().unwrap(),
                "{scheme:?} {what}: rest"
            );
            assert_eq!(b.samples(), a.samples());
        }
    }
}

#[test]
fn valid_samples_outside_the_quick_test_take_the_exact_checks() {
    // Finite readings whose sum overflows fail the one-test common case; they are valid and
    // must be integrated, not rejected, on both paths.
    let mut s = stream(600);
    s[300].gyro = Vector3::new(1e308, 1e308, 0.0);
    s[300].acc = Vector3::new(1e308, 0.0, 0.0);
    for scheme in [Scheme::Euler, Scheme::Midpoint] {
        let mut a = make(scheme, false);
        one_by_one(&mut a, &s).unwrap();
        let mut b = make(scheme, false);
        b.integrate_slice(&s).unwrap();
        assert_eq!(b.len(), 600);
        // Both paths integrate the samples and then overflow: the same typed error.
        let (ma, mb) = (a.finish(), b.finish());
        assert!(
            matches!(ma, Err(PreintError::NonFiniteResult { .. })),
            "{scheme:?}: {ma:?}"
        );
        assert_eq!(format!("{ma:?}"), format!("{mb:?}"), "{scheme:?}");
    }
}

/// `Level::Deltas` accumulates ΔR as a unit quaternion, the other levels as a matrix: the two must agree to round-off over a long window, on both branches of the
/// quaternion Exp (per-step angles below and above 0.1 rad) and across the renormalisations.
#[test]
fn quaternion_deltas_agree_with_the_matrix_deltas() {
    let n = 40_000i64; // 200 s at 200 Hz: ~40 renormalisations
    let s: Vec<ImuSample> = (0..n)
        .map(|k| {
            let t = k as f64 * 5e-3;
            // Tumbling at up to ~4 rad/s, with a 2-s burst at 30 rad/s (0.15 rad per step).
            let burst = if (100.0..102.0).contains(&t) {
                30.0
            } else {
                0.0
            };
            ImuSample::new(
                k * 5_000_000,
                Vector3::new(
                    2.0 * (0.31 * t).sin() + burst,
                    1.5 * (0.17 * t).cos(),
                    0.8 + 2.0 * (0.05 * t).sin(),
                ),
                Vector3::new(
                    1.5 * (0.9 * t).sin(),
                    0.7 * t.cos(),
                    9.81 + 0.5 * (2.1 * t).sin(),
                ),
            )
        })
        .collect();
    for &scheme in SCHEMES {
        let run = |level| {
            let mut prm = PreintParams::default()
                .with_scheme(scheme)
                .with_level(level);
            prm.keep_samples = false;
            let mut pi = Preintegrator::new(prm, ImuBias::zero()).unwrap();
            pi.integrate_slice(&s).unwrap();
            pi.finish().unwrap()
        };
        let (q, m) = (run(Level::Deltas), run(Level::Covariance));
        let er = (q.delta_r.matrix() - m.delta_r.matrix()).amax();
        let ev = (q.delta_v - m.delta_v).norm() / m.delta_v.norm();
        let ep = (q.delta_p - m.delta_p).norm() / m.delta_p.norm();
        let orth = q.delta_r.orthonormality_error();
        println!(
            "{scheme:?}: |ΔR_q − ΔR_m| {er:.1e}, Δv rel {ev:.1e}, Δp rel {ep:.1e}, \
             |ΔRᵀΔR − I| {orth:.1e}"
        );
        assert!(
            er < 1e-13 && ev < 1e-13 && ep < 1e-13,
            "{scheme:?}: {er:e} {ev:e} {ep:e}"
        );
        assert!(orth < 1e-15, "{scheme:?}: ΔR orthonormality {orth:e}");
    }
}
