//! IMU intrinsics applied in preintegration ([`preint::intrinsics`]): identity intrinsics change
//! no bit; non-identity intrinsics give the deltas of the samples corrected by OpenVINS'
//! equations (written out here independently of the crate); the per-sample Jacobian against
//! central differences; the bias map and its inverse; parameter validation; the deskew path.

use nalgebra::{Matrix3, SMatrix, Vector3};
use preint::intrinsics::{AppliedIntrinsics, ImuIntrinsics, IntrinsicsModel};
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, PreintError, PreintParams, Scheme, SensorPose, deskew,
    preintegrate,
};
use preint_lie::SO3;

/// The library's example intrinsics (1 % scale, 2 mrad misalignment and axis rotations,
/// g-sensitivity 1e-3 (rad/s)/(m/s²)).
fn realistic(model: IntrinsicsModel) -> ImuIntrinsics {
    ImuIntrinsics::example(model)
}

fn stream() -> Vec<ImuSample> {
    preint_sim::synthetic_stream(400)
}

fn with(params: &PreintParams, x: ImuIntrinsics, jacobians: bool) -> PreintParams {
    PreintParams {
        intrinsics: Some(AppliedIntrinsics {
            model: x,
            jacobians,
        }),
        ..params.clone()
    }
}

fn bias() -> ImuBias {
    ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.08),
    )
}

/// Keyframes between samples (boundary samples interpolated, context samples read).
const WINDOW: (i64, i64) = (12_345_678, 1_502_345_678);

#[test]
fn identity_intrinsics_change_no_bit_at_any_scheme_and_level() {
    let s = stream();
    for &scheme in Scheme::ALL {
        for level in [Level::Deltas, Level::Covariance, Level::Combined] {
            let p = PreintParams::from_noise(&ImuNoise::euroc())
                .with_scheme(scheme)
                .with_level(level);
            let none = preintegrate(&p, &bias(), &s, WINDOW.0, WINDOW.1).unwrap();
            for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
                for jac in [false, true] {
                    let q = with(&p, ImuIntrinsics::identity(model), jac);
                    let m = preintegrate(&q, &bias(), &s, WINDOW.0, WINDOW.1).unwrap();
                    assert_eq!(m, none, "{scheme:?} {level:?} {model:?} jacobians {jac}");
                }
            }
        }
    }
}

/// OpenVINS' correction (`Propagator.cpp`): `a = R_ACCtoIMU Ta⁻¹ (a_m − b_a)`,
/// `ω = R_GYROtoIMU Tw⁻¹ (ω_m − b_g − Tg a)`, with OpenVINS' (sensor-reading) biases.
fn openvins_corrected(x: &ImuIntrinsics, s: &ImuSample, b: &ImuBias) -> ImuSample {
    let inv = |m: &Matrix3<f64>| m.try_inverse().unwrap();
    let a = x.r_imu_to_acc.transpose() * inv(&x.t_a) * (s.acc - b.acc);
    let w = x.r_imu_to_gyro.transpose() * inv(&x.t_w) * (s.gyro - b.gyro - x.t_g * a);
    ImuSample::new(s.t_ns, w, a)
}

#[test]
fn applied_intrinsics_give_the_deltas_of_openvins_corrected_samples() {
    let s = stream();
    let raw_bias = bias();
    for &scheme in Scheme::ALL {
        for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
            let x = realistic(model);
            let p = PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(scheme);
            // OpenVINS' biases are in the sensors' readings; the preintegrator's in frame I.
            let imu_bias = x.bias_to_imu(&raw_bias);
            let m = preintegrate(&with(&p, x, false), &imu_bias, &s, WINDOW.0, WINDOW.1).unwrap();
            let corrected: Vec<_> = s
                .iter()
                .map(|v| openvins_corrected(&x, v, &raw_bias))
                .collect();
            let r = preintegrate(&p, &ImuBias::zero(), &corrected, WINDOW.0, WINDOW.1).unwrap();
            let dr = (m.delta_r.inverse().compose(&r.delta_r)).log().norm();
            assert!(dr < 1e-13, "{scheme:?} {model:?}: {dr:e}");
            assert!(
                (m.delta_v - r.delta_v).amax() < 1e-12,
                "{scheme:?} {model:?}"
            );
            assert!(
                (m.delta_p - r.delta_p).amax() < 1e-12,
                "{scheme:?} {model:?}"
            );
            assert!((m.cov - r.cov).amax() < 1e-9 * r.cov.amax());
            // And the intrinsics matter: 1 % scale moves ΔR by far more than round-off.
            let plain = preintegrate(&p, &imu_bias, &s, WINDOW.0, WINDOW.1).unwrap();
            assert!((plain.delta_r.inverse().compose(&m.delta_r)).log().norm() > 1e-4);
        }
    }
}

#[test]
fn the_bias_map_is_openvins_bias_in_frame_i_and_inverts() {
    for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
        let x = realistic(model);
        let raw = bias();
        let imu = x.bias_to_imu(&raw);
        // A sample read at rest with only the bias: OpenVINS corrects it to zero.
        let s = ImuSample::new(0, raw.gyro, raw.acc);
        let zero = openvins_corrected(&x, &s, &raw);
        assert!(zero.gyro.amax() < 1e-18 && zero.acc.amax() < 1e-18);
        // The crate's corrected sample minus the frame-I bias is OpenVINS' corrected sample.
        let t = ImuSample::new(0, Vector3::new(0.3, -0.2, 0.1), Vector3::new(0.5, 0.2, 9.7));
        let ov = openvins_corrected(&x, &t, &raw);
        let ours = x.apply(&t);
        assert!((ours.gyro - imu.gyro - ov.gyro).amax() < 1e-15);
        assert!((ours.acc - imu.acc - ov.acc).amax() < 1e-14);
        let back = x.bias_from_imu(&imu);
        assert!((back.gyro - raw.gyro).amax() < 1e-16 && (back.acc - raw.acc).amax() < 1e-15);
    }
}

#[test]
fn sample_jacobian_matches_central_differences() {
    let w = Vector3::new(0.7, -1.3, 0.4);
    let a = Vector3::new(1.2, -0.4, 9.6);
    let raw = ImuSample::new(0, w, a);
    for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
        let x = realistic(model);
        let u = x.apply(&raw);
        let j = x.sample_jacobian(&u.gyro, &u.acc);
        let h = 1e-6;
        for k in 0..ImuIntrinsics::PARAMS {
            let mut d = SMatrix::<f64, 24, 1>::zeros();
            d[k] = h;
            let up = x.perturbed(&d).apply(&raw);
            d[k] = -h;
            let dn = x.perturbed(&d).apply(&raw);
            for (r, num) in (up.gyro - dn.gyro)
                .iter()
                .chain((up.acc - dn.acc).iter())
                .enumerate()
            {
                let num = num / (2.0 * h);
                assert!(
                    (num - j[(r, k)]).abs() < 1e-7 * (1.0 + num.abs()),
                    "{model:?} row {r} param {k}: {num} vs {}",
                    j[(r, k)]
                );
            }
        }
    }
}

#[test]
fn parameters_vector_follows_openvins_state_order() {
    let x = realistic(IntrinsicsModel::Kalibr);
    let p = x.params();
    assert_eq!(p[1], x.t_w[(1, 0)]); // kalibr: lower triangle, column by column
    assert_eq!(p[6 + 4], x.t_a[(2, 1)]);
    assert_eq!(p[15 + 3], x.t_g[(0, 1)]); // T_g column by column
    let y = realistic(IntrinsicsModel::Rpng);
    assert_eq!(y.params()[1], y.t_w[(0, 1)]); // rpng: upper triangle, column by column
    assert_eq!(y.params()[4], y.t_w[(1, 2)]);
}

#[test]
fn invalid_intrinsics_and_unsupported_combinations_are_refused() {
    let p = PreintParams::default();
    let mut singular = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    singular.t_w[(1, 1)] = 0.0;
    let mut skewed = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    skewed.r_imu_to_acc[(0, 1)] = 0.1;
    let mut nan = ImuIntrinsics::identity(IntrinsicsModel::Rpng);
    nan.t_g[(2, 0)] = f64::NAN;
    for x in [singular, skewed, nan] {
        let err = with(&p, x, false).validate().unwrap_err();
        assert!(matches!(
            err,
            PreintError::InvalidParameter {
                name: "intrinsics",
                ..
            }
        ));
    }
    let body = PreintParams {
        body_p_sensor: Some(SensorPose::new(
            SO3::identity(),
            Vector3::new(0.1, 0.0, 0.0),
        )),
        ..with(&p, realistic(IntrinsicsModel::Kalibr), true)
    };
    assert!(matches!(
        body.validate(),
        Err(PreintError::InvalidParameter {
            name: "intrinsics",
            ..
        })
    ));
    // Applying them with body_p_sensor is fine (without the Jacobians).
    let body = PreintParams {
        intrinsics: Some(AppliedIntrinsics::new(realistic(IntrinsicsModel::Kalibr))),
        ..body
    };
    assert!(body.validate().is_ok());
    // Jacobians not requested: a typed error, not zeros.
    let mut pi =
        preint::Preintegrator::new(with(&p, realistic(IntrinsicsModel::Kalibr), false), bias())
            .unwrap();
    pi.integrate_slice(&stream()[..10]).unwrap();
    assert!(matches!(
        pi.finish_with_intrinsic_jacobian(),
        Err(PreintError::InvalidParameter {
            name: "intrinsics",
            ..
        })
    ));
}

#[test]
fn deskew_deltas_apply_the_intrinsics_as_preintegrate_does() {
    let s = stream();
    for &scheme in Scheme::ALL {
        let p = with(
            &PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(scheme),
            realistic(IntrinsicsModel::Rpng),
            false,
        );
        let t = [WINDOW.0 + 400_000_000, WINDOW.1];
        let at = deskew::deltas_at(&p, &bias(), &s, WINDOW, &t).unwrap();
        for (d, &tq) in at.iter().zip(&t) {
            let m = preintegrate(&p, &bias(), &s, WINDOW.0, tq).unwrap();
            assert_eq!(
                (d.delta_r, d.delta_v, d.delta_p),
                (m.delta_r, m.delta_v, m.delta_p)
            );
        }
    }
}

#[test]
fn the_slice_path_with_intrinsics_equals_pushing_one_by_one() {
    // 5 000 samples: several of the wrapper's chunks (2 048).
    let s = preint_sim::synthetic_stream(5000);
    for &scheme in Scheme::ALL {
        for level in [Level::Deltas, Level::Covariance] {
            let p = with(
                &PreintParams::from_noise(&ImuNoise::euroc())
                    .with_scheme(scheme)
                    .with_level(level),
                realistic(IntrinsicsModel::Kalibr),
                false,
            );
            let mut slice = preint::Preintegrator::new(p.clone(), bias()).unwrap();
            slice.integrate_slice(&s).unwrap();
            let mut push = preint::Preintegrator::new(p, bias()).unwrap();
            for x in &s {
                push.integrate(x).unwrap();
            }
            assert_eq!(
                slice.finish().unwrap(),
                push.finish().unwrap(),
                "{scheme:?} {level:?}"
            );
        }
    }
}

/// The correction's vector path (AVX2 and FMA, when this CPU has them) against its plain path:
/// identical bits on 10 000 samples spanning 12 orders of magnitude, one at a time and a slice
/// at a time, for both models and a g-sensitivity.
#[test]
fn the_correction_vector_path_equals_the_plain_path_bit_for_bit() {
    for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
        let c = realistic(model).correction();
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64;
            (u - 0.5) * 10f64.powi(((seed % 13) as i32) - 6)
        };
        let src: Vec<ImuSample> = (0..10_000i64)
            .map(|k| {
                ImuSample::new(
                    k,
                    Vector3::new(next(), next(), next()),
                    Vector3::new(next(), next(), next()),
                )
            })
            .collect();
        let mut dst = src.clone();
        c.apply_all(&src, &mut dst);
        for (s, d) in src.iter().zip(&dst) {
            let plain = c.apply_plain(s);
            assert_eq!(c.apply(s), plain, "{model:?} {s:?}");
            assert_eq!(*d, plain, "{model:?} {s:?}");
            assert_eq!(d.t_ns, s.t_ns);
        }
    }
}
