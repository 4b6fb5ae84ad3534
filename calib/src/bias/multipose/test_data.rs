//! Simulated recordings shared by the unit tests of this module.

use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample};
use preint_lie::SO3;
use preint_sim::{MultiPoseStaticScene, SimConfig, scale_misalignment, simulate};

/// The 5-pose protocol used by these tests: identity, ±90° about each axis, and two
/// generic attitudes.
pub(super) fn five_poses() -> Vec<SO3> {
    let rx = |a: f64| SO3::exp(&Vector3::new(a, 0.0, 0.0));
    let ry = |a: f64| SO3::exp(&Vector3::new(0.0, a, 0.0));
    let rz = |a: f64| SO3::exp(&Vector3::new(0.0, 0.0, a));
    let h = std::f64::consts::FRAC_PI_2;
    vec![
        SO3::identity(),
        rx(h),
        rx(h).compose(&rz(h)),
        ry(-h).compose(&rz(0.7)),
        rz(-h).compose(&rx(1.1)),
    ]
}

/// The 5-pose protocol (2 s holds, 1.5 s moves, 200 Hz) with EuRoC white noise, constant
/// biases and non-trivial `S_a`, `S_g`.
pub(super) fn data() -> (Vec<ImuSample>, ImuNoise) {
    let poses = five_poses();
    let scene = MultiPoseStaticScene::new(poses, 2.0, 1.5, Vector3::zeros()).unwrap();
    let noise = ImuNoise::euroc();
    let cfg = SimConfig {
        noise,
        initial_bias: ImuBias::new(
            Vector3::new(0.003, -0.002, 0.004),
            Vector3::new(0.05, -0.04, 0.08),
        ),
        bias_random_walk: false,
        acc_scale: scale_misalignment(
            &Vector3::new(0.01, -0.01, 0.005),
            &Vector3::new(0.01, -0.005, 0.008),
        ),
        gyro_scale: Matrix3::new(1.01, 0.01, -0.005, 0.004, 0.99, 0.006, -0.008, 0.003, 1.005),
        ..SimConfig::default()
    };
    let out = simulate(&scene, 200.0, scene.duration_s(), &cfg, 7).unwrap();
    (out.samples, noise)
}
