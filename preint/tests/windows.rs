//! Keyframe windows between samples: consecutive windows compose to the whole.

mod common;

use common::*;
use preint::window::window_samples;
use preint::{ImuBias, ImuSample, Level, PreintError, PreintParams, Scheme, preintegrate};

fn prm(scheme: Scheme) -> PreintParams {
    PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Deltas)
        .with_gravity(gravity())
}

/// Linear interpolation written independently of the crate.
fn lerp(s: &[ImuSample], t: i64) -> ImuSample {
    let k = s.iter().position(|x| x.t_ns > t).unwrap();
    let (a, b) = (&s[k - 1], &s[k]);
    let l = (t - a.t_ns) as f64 / (b.t_ns - a.t_ns) as f64;
    ImuSample::new(
        t,
        a.gyro * (1.0 - l) + b.gyro * l,
        a.acc * (1.0 - l) + b.acc * l,
    )
}

fn rel(a: &V3, b: &V3) -> f64 {
    (a - b).norm() / b.norm()
}

#[test]
fn consecutive_windows_compose_to_the_whole() {
    let scene = Scene::smooth();
    let bias = ImuBias::new(V3::new(0.01, 0.0, -0.01), V3::new(0.1, 0.2, -0.1));
    // A biased sensor, integrated with the right bias estimate.
    let stream: Vec<_> = scene
        .samples(5_000_000, 2_000_000_000)
        .iter()
        .map(|s| ImuSample::new(s.t_ns, s.gyro + bias.gyro, s.acc + bias.acc))
        .collect();
    let (a, b, c) = (12_345_678, 777_777_777, 1_500_001_234);
    for scheme in [Scheme::Euler, Scheme::Midpoint, Scheme::Rk4] {
        let p = prm(scheme);
        let ab = preintegrate(&p, &bias, &stream, a, b).unwrap();
        let bc = preintegrate(&p, &bias, &stream, b, c).unwrap();
        assert_eq!((ab.t_i_ns, ab.t_j_ns, bc.t_i_ns, bc.t_j_ns), (a, b, b, c));
        assert_eq!(ab.delta_t, (b - a) as f64 * 1e-9);
        let (r, v, pp) = compose(&ab, &bc);
        // The stream with the boundary sample at b inserted.
        let mut with_b = stream.clone();
        let k = with_b.iter().position(|x| x.t_ns > b).unwrap();
        with_b.insert(k, lerp(&stream, b));
        // rk4 interpolates its boundary with a cubic: compare with the plain stream instead.
        let whole = if scheme == Scheme::Rk4 {
            &stream
        } else {
            &with_b
        };
        let ac = preintegrate(&p, &bias, whole, a, c).unwrap();
        let (er, ev, ep) = (
            ac.delta_r.minus(&r).norm(),
            rel(&v, &ac.delta_v),
            rel(&pp, &ac.delta_p),
        );
        eprintln!(
            "{scheme:?}: composed vs whole: rot {er:.1e} rad, v {ev:.1e}, p {ep:.1e} (relative)"
        );
        let tol = if scheme == Scheme::Rk4 { 1e-9 } else { 1e-13 };
        assert!(er < tol && ev < tol && ep < tol, "{scheme:?}");
        // And against the exact motion (the windows lose nothing at the boundaries).
        let (rx, vx, px) = scene.exact(a as f64 * 1e-9, c as f64 * 1e-9);
        let exact_tol = match scheme {
            Scheme::Euler => 2e-2,
            Scheme::Midpoint => 1e-4,
            Scheme::Rk4 => 1e-8,
        };
        assert!(
            r.minus(&rx).norm() < exact_tol
                && rel(&v, &vx) < exact_tol
                && rel(&pp, &px) < exact_tol,
            "{scheme:?} vs exact"
        );
    }
}

#[test]
fn window_boundaries_use_samples_at_keyframe_times_and_interpolate_otherwise() {
    let scene = Scene::smooth();
    let s = scene.samples(5_000_000, 100_000_000);
    // Exactly on samples: the window is the sub-slice.
    let w = window_samples(Scheme::Midpoint, &s, 10_000_000, 50_000_000, i64::MAX).unwrap();
    assert_eq!(w, s[2..=10].to_vec());
    // Between samples: boundary samples interpolated linearly (Euler, midpoint).
    let w = window_samples(Scheme::Euler, &s, 12_000_000, 47_500_000, i64::MAX).unwrap();
    assert_eq!(w.first().unwrap().t_ns, 12_000_000);
    assert_eq!(w.last().unwrap().t_ns, 47_500_000);
    assert_eq!(w[1..w.len() - 1], s[3..=9]);
    assert!((w[0].gyro - lerp(&s, 12_000_000).gyro).norm() < 1e-15);
    // rk4: cubic boundary sample, 4th-order accurate on the smooth signal.
    let w = window_samples(Scheme::Rk4, &s, 12_000_000, 47_500_000, i64::MAX).unwrap();
    let truth = scene.sample(12_000_000);
    assert!(
        (w[0].gyro - truth.gyro).norm() < 1e-6,
        "{}",
        (w[0].gyro - truth.gyro).norm()
    );
    assert!((lerp(&s, 12_000_000).gyro - truth.gyro).norm() > 1e-5);
    // rk4 drops a stream sample closer than 1/8 interval to the boundary.
    let w = window_samples(Scheme::Rk4, &s, 14_500_000, 47_500_000, i64::MAX).unwrap();
    assert_eq!(w[1].t_ns, 20_000_000);
}

#[test]
fn window_errors_are_typed() {
    let s = Scene::smooth().samples(5_000_000, 100_000_000);
    let p = prm(Scheme::Euler);
    let b = ImuBias::zero();
    assert_eq!(
        preintegrate(&p, &b, &s, 50, 50),
        Err(PreintError::NonPositiveWindow {
            t_i_ns: 50,
            t_j_ns: 50
        })
    );
    assert_eq!(
        preintegrate(&p, &b, &s, -1, 50),
        Err(PreintError::KeyframeOutsideSamples {
            t_ns: -1,
            first_ns: 0,
            last_ns: 100_000_000
        })
    );
    assert_eq!(
        preintegrate(&p, &b, &s, 0, 100_000_001),
        Err(PreintError::KeyframeOutsideSamples {
            t_ns: 100_000_001,
            first_ns: 0,
            last_ns: 100_000_000
        })
    );
    assert!(matches!(
        preintegrate(&p, &b, &[], 0, 1),
        Err(PreintError::KeyframeOutsideSamples { .. })
    ));
    let mut bad = s.clone();
    bad[4].acc.y = f64::NAN;
    assert_eq!(
        preintegrate(&p, &b, &bad, 0, 50_000_000),
        Err(PreintError::NonFinite {
            index: 4,
            t_ns: 20_000_000,
            field: "acc"
        })
    );
}
