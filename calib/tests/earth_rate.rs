//! Static calibration in a rotating (Earth) frame: the Earth rate is not mistaken for gyro
//! bias. A tactical-grade gyro (σ_g = 5e-6 rad/s/√Hz, so the 60 s mean has σ ≈ 6.5e-7 rad/s,
//! a hundred times below Ω_E = 7.29e-5 rad/s) at rest at 45° N, simulated by `preint-sim` with
//! `earth_rate` (ENU); the scene's heading is known from its yaw.

use nalgebra::Vector3;
use preint::earth::earth_rate_enu;
use preint::{ImuBias, ImuNoise};
use preint_calib::bias::{StaticOptions, calibrate_static, earth_rate_in_body, remove_earth_rate};
use preint_sim::{SimConfig, StaticScene, simulate};

const LAT: f64 = 45.0;

fn calibrated() -> (
    preint_calib::bias::StaticCalibration,
    Vector3<f64>,
    StaticScene,
) {
    let noise = ImuNoise {
        gyro_noise_density: 5e-6,
        gyro_random_walk: 0.0,
        acc_noise_density: 2e-4,
        acc_random_walk: 0.0,
        update_rate_hz: 100.0,
    };
    let bias = Vector3::new(2e-4, -1e-4, 3e-4);
    let scene = StaticScene::default();
    let cfg = SimConfig {
        noise,
        initial_bias: ImuBias::new(bias, Vector3::zeros()),
        bias_random_walk: false,
        earth_rate: Some(earth_rate_enu(LAT)),
        ..SimConfig::default()
    };
    let rec = simulate(&scene, 100.0, 60.0, &cfg, 7).unwrap();
    let cal = calibrate_static(&rec.samples, &noise, &StaticOptions::default()).unwrap();
    (cal, bias, scene)
}

#[test]
fn the_earth_rate_is_not_mistaken_for_gyro_bias() {
    let (cal, bias, scene) = calibrated();
    let sigma = cal.gyro_bias_std;
    assert!(sigma.amax() < 1e-6, "{sigma:?}");
    // Uncorrected: the whole Earth rate (7.29e-5 rad/s) lands in the bias.
    let err = cal.gyro_bias - bias;
    assert!((err.norm() - 7.292115e-5).abs() < 5e-6, "{err:?}");

    // Latitude only: the vertical part is removed, the horizontal part is carried in σ.
    let e = earth_rate_in_body(&cal.up_body, (cal.roll, cal.pitch), LAT, None);
    let c = remove_earth_rate(&cal, &e);
    let up = cal.up_body;
    let err = c.gyro_bias - bias;
    assert!(
        err.dot(&up).abs() < 4.0 * sigma.amax(),
        "vertical {}",
        err.dot(&up)
    );
    let horizontal = err - up * err.dot(&up);
    assert!((horizontal.norm() - e.unresolved).abs() < 5.0 * sigma.amax());
    for k in 0..3 {
        assert!(
            err[k].abs() <= 3.0 * c.gyro_bias_std[k],
            "axis {k}: {err:?} σ {:?}",
            c.gyro_bias_std
        );
    }

    // With the heading (the scene's yaw 0.8 rad from east): all of it is removed.
    let heading = 90.0 - 0.8f64.to_degrees();
    let e = earth_rate_in_body(&cal.up_body, (cal.roll, cal.pitch), LAT, Some(heading));
    let c = remove_earth_rate(&cal, &e);
    let err = c.gyro_bias - bias;
    assert!(err.amax() < 4.0 * sigma.amax(), "{err:?} σ {sigma:?}");
    assert_eq!(c.gyro_bias_std, cal.gyro_bias_std);
    // The removed vector is the true Earth rate in the body frame (to the tilt error).
    let truth = scene.r_wb.inverse().act(&earth_rate_enu(LAT));
    assert!(
        (e.removed - truth).amax() < 1e-8,
        "{:?} vs {truth:?}",
        e.removed
    );
}
