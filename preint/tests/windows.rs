//! Keyframe windows between samples: consecutive windows compose to the whole.

mod common;

use common::*;
use preint::window_samples;
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

/// The stream with the boundary sample at `b` (as the windows build it) inserted; for hermite4,
/// stream samples closer to `b` than 1/8 of the interval around it removed (documented rule).
/// A `b` on a sample leaves the stream as it is.
fn with_boundary(scheme: Scheme, stream: &[ImuSample], b: i64) -> Vec<ImuSample> {
    if stream.iter().any(|x| x.t_ns == b) {
        return stream.to_vec();
    }
    let k = stream.iter().position(|x| x.t_ns > b).unwrap();
    let step = stream[k].t_ns - stream[k - 1].t_ns;
    let boundary = *window_samples(scheme, stream, stream[0].t_ns, b, i64::MAX)
        .unwrap()
        .last()
        .unwrap();
    let mut out: Vec<_> = stream
        .iter()
        .filter(|x| scheme != Scheme::Hermite4 || (x.t_ns - b).abs() * 8 >= step)
        .copied()
        .collect();
    let k = out.iter().position(|x| x.t_ns > b).unwrap();
    out.insert(k, boundary);
    out
}

/// Consecutive windows `[a, b]`, `[b, c]` compose to the integration of `[a, c]` over the
/// stream with the boundary sample inserted, for every scheme, to round-off: each interval's
/// increment is computed from the same samples and stencils in both, so only the
/// accumulation order differs (≈ 1e-16 per step over 300 steps: 1e-13 asserted).
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
    let (a, c) = (12_345_678, 1_500_001_234);
    // Mid-interval, 1 µs after and before a sample, and on a sample.
    for b in [777_777_777, 775_001_000, 779_999_000, 780_000_000] {
        for &scheme in Scheme::ALL {
            let p = prm(scheme);
            let ab = preintegrate(&p, &bias, &stream, a, b).unwrap();
            let bc = preintegrate(&p, &bias, &stream, b, c).unwrap();
            assert_eq!((ab.t_i_ns, ab.t_j_ns, bc.t_i_ns, bc.t_j_ns), (a, b, b, c));
            assert_eq!(ab.delta_t, (b - a) as f64 * 1e-9);
            let (r, v, pp) = compose(&ab, &bc);
            let whole = with_boundary(scheme, &stream, b);
            let ac = preintegrate(&p, &bias, &whole, a, c).unwrap();
            let (er, ev, ep) = (
                ac.delta_r.minus(&r).norm(),
                rel(&v, &ac.delta_v),
                rel(&pp, &ac.delta_p),
            );
            eprintln!(
                "{scheme:?} b = {b} ns: composed vs whole: rot {er:.1e} rad, v {ev:.1e}, p {ep:.1e} (relative)"
            );
            assert!(er < 1e-13 && ev < 1e-13 && ep < 1e-13, "{scheme:?} b = {b}");
            // And against the exact motion (the windows lose nothing at the boundaries).
            let (rx, vx, px) = scene.exact(a as f64 * 1e-9, c as f64 * 1e-9);
            let exact_tol = match scheme {
                Scheme::Euler | Scheme::Galilean => 2e-2,
                Scheme::Midpoint => 1e-4,
                Scheme::Hermite4 => 1e-8,
            };
            assert!(
                r.minus(&rx).norm() < exact_tol
                    && rel(&v, &vx) < exact_tol
                    && rel(&pp, &px) < exact_tol,
                "{scheme:?} vs exact"
            );
        }
    }
}

/// hermite4 with one-sided stencils at every window edge (samples pushed into preintegrators
/// directly) composes only to the scheme's O(h⁴) error; the context samples of the window
/// path remove that. Measured here so the module doc's figure is checked.
#[test]
fn rk4_one_sided_edges_compose_only_to_the_integration_error() {
    let stream = Scene::smooth().samples(5_000_000, 2_000_000_000);
    let p = prm(Scheme::Hermite4);
    let run = |s: &[ImuSample]| {
        let mut pi = preint::Preintegrator::new(p.clone(), ImuBias::zero()).unwrap();
        pi.integrate_slice(s).unwrap();
        pi.finish().unwrap()
    };
    let (ab, bc, ac) = (
        run(&stream[2..=150]),
        run(&stream[150..=300]),
        run(&stream[2..=300]),
    );
    let (r, v, pp) = compose(&ab, &bc);
    let (er, ev, ep) = (
        ac.delta_r.minus(&r).norm(),
        rel(&v, &ac.delta_v),
        rel(&pp, &ac.delta_p),
    );
    eprintln!(
        "hermite4 one-sided edges: composed vs whole: rot {er:.1e} rad, v {ev:.1e}, p {ep:.1e}"
    );
    assert!(er.max(ev).max(ep) > 1e-12 && er.max(ev).max(ep) < 1e-8);
    let w = |t0: i64, t1: i64| preintegrate(&p, &ImuBias::zero(), &stream, t0, t1).unwrap();
    let (t0, t1, t2) = (stream[2].t_ns, stream[150].t_ns, stream[300].t_ns);
    let (r, v, pp) = compose(&w(t0, t1), &w(t1, t2));
    let ac = w(t0, t2);
    let e = ac
        .delta_r
        .minus(&r)
        .norm()
        .max(rel(&v, &ac.delta_v))
        .max(rel(&pp, &ac.delta_p));
    eprintln!("hermite4 window path (context samples): composed vs whole: {e:.1e}");
    assert!(e < 1e-13);
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
    // hermite4: cubic boundary sample, 4th-order accurate on the smooth signal.
    let w = window_samples(Scheme::Hermite4, &s, 12_000_000, 47_500_000, i64::MAX).unwrap();
    let truth = scene.sample(12_000_000);
    assert!(
        (w[0].gyro - truth.gyro).norm() < 1e-6,
        "{}",
        (w[0].gyro - truth.gyro).norm()
    );
    assert!((lerp(&s, 12_000_000).gyro - truth.gyro).norm() > 1e-5);
    // hermite4 drops a stream sample closer than 1/8 interval to the boundary.
    let w = window_samples(Scheme::Hermite4, &s, 14_500_000, 47_500_000, i64::MAX).unwrap();
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
