//! Input validation: typed errors naming the sample and the problem, never a panic.

use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuSample, PreintError, PreintParams, Preintegrator, Scheme};
use proptest::prelude::*;

fn s(t_ns: i64) -> ImuSample {
    ImuSample::new(
        t_ns,
        Vector3::new(0.1, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 9.81),
    )
}

fn pi() -> Preintegrator {
    Preintegrator::new(PreintParams::default(), ImuBias::zero()).unwrap()
}

#[test]
fn each_bad_sample_is_named() {
    let mut p = pi();
    p.integrate_slice(&[s(0), s(5), s(10)]).unwrap();
    let mut nan = s(15);
    nan.gyro.y = f64::NAN;
    assert_eq!(
        p.integrate(&nan),
        Err(PreintError::NonFinite {
            index: 3,
            t_ns: 15,
            field: "gyro"
        })
    );
    let mut inf = s(15);
    inf.acc.z = f64::INFINITY;
    assert_eq!(
        p.integrate(&inf),
        Err(PreintError::NonFinite {
            index: 3,
            t_ns: 15,
            field: "acc"
        })
    );
    assert_eq!(
        p.integrate(&s(10)),
        Err(PreintError::DuplicateTimestamp { index: 3, t_ns: 10 })
    );
    assert_eq!(
        p.integrate(&s(7)),
        Err(PreintError::DecreasingTimestamp {
            index: 3,
            t_ns: 7,
            prev_t_ns: 10
        })
    );
    let big = 10 + PreintParams::default().max_gap_ns + 1;
    assert_eq!(
        p.integrate(&s(big)),
        Err(PreintError::GapTooLarge {
            index: 3,
            t_ns: big,
            gap_ns: big - 10,
            max_gap_ns: 250_000_000
        })
    );
    // Rejected samples leave the state unchanged.
    assert_eq!(p.len(), 3);
    p.integrate(&s(15)).unwrap();
    let msg = PreintError::GapTooLarge {
        index: 3,
        t_ns: 9,
        gap_ns: 9,
        max_gap_ns: 1,
    }
    .to_string();
    assert!(msg.contains("sample 3") && msg.contains("gap"), "{msg}");
}

#[test]
fn too_few_samples_and_bad_params() {
    let mut p = pi();
    assert_eq!(p.finish(), Err(PreintError::TooFewSamples { count: 0 }));
    p.integrate(&s(0)).unwrap();
    assert_eq!(p.finish(), Err(PreintError::TooFewSamples { count: 1 }));
    let prm = PreintParams {
        gyro_cov: Matrix3::identity() * -1.0,
        ..Default::default()
    };
    assert!(matches!(
        Preintegrator::new(prm, ImuBias::zero()),
        Err(PreintError::InvalidParameter {
            name: "gyro_cov",
            ..
        })
    ));
    let mut prm = PreintParams::default();
    prm.acc_cov[(0, 1)] = 1.0;
    assert!(matches!(
        Preintegrator::new(prm, ImuBias::zero()),
        Err(PreintError::InvalidParameter {
            name: "acc_cov",
            reason: "not symmetric"
        })
    ));
    let mut prm = PreintParams::default();
    prm.gravity.x = f64::NAN;
    assert!(Preintegrator::new(prm, ImuBias::zero()).is_err());
    let prm = PreintParams {
        max_gap_ns: 0,
        ..Default::default()
    };
    assert!(Preintegrator::new(prm, ImuBias::zero()).is_err());
    let bad_bias = ImuBias::new(Vector3::new(f64::NAN, 0.0, 0.0), Vector3::zeros());
    assert!(Preintegrator::new(PreintParams::default(), bad_bias).is_err());
}

/// Finite inputs of extreme magnitude (a bias estimate of 1e300 rad/s or m/s²) give a typed
/// error from `finish`, not NaN deltas, for every scheme.
#[test]
fn extreme_inputs_give_an_error_not_nan() {
    for &scheme in Scheme::ALL {
        for (gyro, acc) in [(1e300, 0.0), (0.0, 1e300)] {
            let bias = ImuBias::new(Vector3::new(gyro, 0.0, 0.0), Vector3::new(0.0, acc, 0.0));
            let params = PreintParams::default().with_scheme(scheme);
            let mut p = Preintegrator::new(params, bias).unwrap();
            p.integrate_slice(&(0..20).map(|k| s(k * 5_000_000)).collect::<Vec<_>>())
                .unwrap();
            assert!(
                matches!(p.finish(), Err(PreintError::NonFiniteResult { .. })),
                "{scheme:?} gyro {gyro} acc {acc}: {:?}",
                p.finish().map(|m| m.delta_v)
            );
        }
    }
}

/// The window path (`preintegrate`, `check_samples`) names the offending *stream* sample (its
/// index in the slice given and its time) for duplicate and decreasing timestamps, gaps and
/// non-finite values, for every scheme.
#[test]
fn window_path_errors_name_the_stream_sample() {
    let stream: Vec<_> = (0..40).map(|k| s(1_000_000_000 + k * 5_000_000)).collect();
    let (t_i, t_j) = (1_012_000_000, 1_150_000_000);
    for &scheme in Scheme::ALL {
        let prm = PreintParams::default().with_scheme(scheme);
        let run = |x: &[ImuSample]| preint::preintegrate(&prm, &ImuBias::zero(), x, t_i, t_j);
        assert!(run(&stream).is_ok());
        let mut dup = stream.clone();
        dup[9].t_ns = dup[8].t_ns;
        let e = run(&dup).unwrap_err();
        assert_eq!(
            e,
            PreintError::DuplicateTimestamp {
                index: 9,
                t_ns: 1_040_000_000
            }
        );
        assert!(
            e.to_string().contains("sample 9 (t = 1040000000 ns)"),
            "{e}"
        );
        let mut dec = stream.clone();
        dec[20].t_ns = dec[19].t_ns - 1;
        let e = run(&dec).unwrap_err();
        assert_eq!(
            e,
            PreintError::DecreasingTimestamp {
                index: 20,
                t_ns: 1_094_999_999,
                prev_t_ns: 1_095_000_000
            }
        );
        assert!(
            e.to_string().contains("sample 20 (t = 1094999999 ns)"),
            "{e}"
        );
        // A gap: samples 11..=15 missing (30 ms), maximum 20 ms.
        let gap: Vec<_> = stream
            .iter()
            .enumerate()
            .filter(|(k, _)| !(11..=15).contains(k))
            .map(|(_, x)| *x)
            .collect();
        let mut prm_gap = prm.clone();
        prm_gap.max_gap_ns = 20_000_000;
        let e = preint::preintegrate(&prm_gap, &ImuBias::zero(), &gap, t_i, t_j).unwrap_err();
        assert_eq!(
            e,
            PreintError::GapTooLarge {
                index: 11,
                t_ns: 1_080_000_000,
                gap_ns: 30_000_000,
                max_gap_ns: 20_000_000
            }
        );
        assert!(
            e.to_string().contains("sample 11 (t = 1080000000 ns)"),
            "{e}"
        );
        // The same gap is fine under the default maximum (250 ms).
        assert!(preint::preintegrate(&prm, &ImuBias::zero(), &gap, t_i, t_j).is_ok());
        // Just outside the window: the stencil neighbours are checked too (index 1 is two
        // samples before t_i).
        let mut near = stream.clone();
        near[1].acc.x = f64::INFINITY;
        assert_eq!(
            run(&near),
            Err(PreintError::NonFinite {
                index: 1,
                t_ns: 1_005_000_000,
                field: "acc"
            })
        );
    }
    // check_samples on its own, with a range.
    let mut dup = stream.clone();
    dup[30].t_ns = dup[29].t_ns;
    assert_eq!(preint::check_samples(&dup, 0..29, i64::MAX), Ok(()));
    assert_eq!(
        preint::check_samples(&dup, 25..35, i64::MAX),
        Err(PreintError::DuplicateTimestamp {
            index: 30,
            t_ns: dup[30].t_ns
        })
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Garbage in (any f64 including NaN/∞, any timestamps): typed errors or finite output.
    #[test]
    fn garbage_never_panics(
        raw in prop::collection::vec((any::<i64>(), prop::array::uniform6(any::<f64>())), 0..12),
        scheme in prop::sample::select(Scheme::ALL.to_vec()),
        t_i in any::<i64>(), t_j in any::<i64>(),
    ) {
        let samples: Vec<_> = raw.iter().map(|(t, v)| ImuSample::new(*t, Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]))).collect();
        let mut prm = PreintParams::default().with_scheme(scheme);
        prm.max_gap_ns = i64::MAX;
        let mut p = Preintegrator::new(prm.clone(), ImuBias::zero()).unwrap();
        for x in &samples { let _ = p.integrate(x); }
        let _ = p.finish();
        let _ = preint::preintegrate(&prm, &ImuBias::zero(), &samples, t_i, t_j);
    }
}

/// A gap a few samples before `t_i` (beyond the samples the window's first interval and its
/// noise cells use) does not fail the window, and the window equals the one cut from the
/// stream that starts after the gap; a gap inside the samples the edge uses does fail.
#[test]
fn a_gap_before_the_window_fails_only_within_the_edge_stencil() {
    // 5 ms stream with a 30 ms gap between samples 9 and 10 (index 10 is the first after it).
    let sample = |k: i64| {
        let t = k as f64 * 0.005;
        ImuSample::new(
            1_000_000_000 + k * 5_000_000 + if k >= 10 { 25_000_000 } else { 0 },
            Vector3::new(0.3 * t.sin(), 0.2, 0.1 * t),
            Vector3::new(0.5 * t.cos(), 0.1, 9.81),
        )
    };
    let stream: Vec<ImuSample> = (0..60).map(sample).collect();
    let prm = |scheme| PreintParams {
        max_gap_ns: 20_000_000,
        ..PreintParams::default().with_scheme(scheme)
    };
    for &scheme in Scheme::ALL {
        // t_i 2.5 ms after sample 12: the first sample in the window is the third after the gap.
        let (t_i, t_j) = (stream[12].t_ns + 2_500_000, stream[40].t_ns + 1_000_000);
        let whole = preint::preintegrate(&prm(scheme), &ImuBias::zero(), &stream, t_i, t_j)
            .unwrap_or_else(|e| panic!("{scheme:?}: {e}"));
        let after_gap =
            preint::preintegrate(&prm(scheme), &ImuBias::zero(), &stream[10..], t_i, t_j).unwrap();
        assert_eq!(whole.delta_v, after_gap.delta_v, "{scheme:?}");
        assert_eq!(whole.delta_p, after_gap.delta_p, "{scheme:?}");
        assert_eq!(whole.cov15, after_gap.cov15, "{scheme:?}");
        // t_i between samples 10 and 11: the edge interpolates from sample 10, whose noise
        // cell reaches back across the gap.
        let t_i = stream[10].t_ns + 2_500_000;
        assert!(
            matches!(
                preint::preintegrate(&prm(scheme), &ImuBias::zero(), &stream, t_i, t_j),
                Err(PreintError::GapTooLarge { index: 10, .. })
            ),
            "{scheme:?}"
        );
    }
}
