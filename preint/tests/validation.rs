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

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Garbage in (any f64 including NaN/∞, any timestamps): typed errors or finite output.
    #[test]
    fn garbage_never_panics(
        raw in prop::collection::vec((any::<i64>(), prop::array::uniform6(any::<f64>())), 0..12),
        scheme in prop::sample::select(vec![Scheme::Euler, Scheme::Midpoint, Scheme::Rk4]),
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
