//! Dataset writer: EuRoC imu / ground truth and Kalibr yaml round trips are lossless.

use preint::ImuNoise;
use preint_sim::{SimConfig, simulate, write_dataset};

#[test]
fn euroc_and_kalibr_round_trip_is_bit_exact() {
    let noise = ImuNoise::euroc();
    let mut cfg = SimConfig::with_noise(noise);
    cfg.initial_bias.gyro.x = 1e-3;
    let scene = preint_sim::scene_by_name("aggressive").unwrap();
    let out = simulate(scene.as_ref(), 200.0, 3.0, &cfg, 9).unwrap();
    let dir = std::env::temp_dir().join(format!("sim-roundtrip-{}", std::process::id()));
    let files = write_dataset(&dir, &out, &noise).unwrap();
    let names: Vec<_> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_str().unwrap().to_owned())
        .collect();
    assert_eq!(names, ["imu.csv", "groundtruth.csv", "imu.yaml"]);
    let samples = preint_io::read_euroc_imu(&files[0]).unwrap();
    let truth = preint_io::read_euroc_groundtruth(&files[1]).unwrap();
    let noise_back = preint_io::read_kalibr_yaml(&files[2]).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(samples, out.samples);
    assert_eq!(noise_back, noise);
    assert_eq!(truth.len(), out.truth.len());
    for (a, b) in truth.iter().zip(&out.truth) {
        assert_eq!((a.t_ns, a.p, a.v, a.bias), (b.t_ns, b.p, b.v, b.bias));
        assert_eq!(
            a.q.coords, b.q.coords,
            "quaternion must survive bit-exactly"
        );
    }
}

#[test]
fn ground_truth_quaternion_is_body_to_world_wxyz() {
    let scene = preint_sim::StaticScene::default();
    let out = simulate(&scene, 10.0, 0.1, &SimConfig::noise_free(), 0).unwrap();
    let text = preint_io::euroc_groundtruth_string(&out.truth);
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .skip(1)
        .map(|x| x.parse().unwrap())
        .collect();
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        row[3], row[4], row[5], row[6],
    ));
    let v_b = nalgebra::Vector3::new(0.3, -1.0, 2.0);
    assert!((q * v_b - scene.r_wb * v_b).norm() < 1e-12);
}
