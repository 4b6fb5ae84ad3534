//! Known-pose calibration on EuRoC V1_01 (tests/data/euroc, vicon2gt ground truth at 20 Hz,
//! which carries bias estimates) and typed errors.

use nalgebra::Vector3;
use preint::io::{read_euroc_groundtruth, read_euroc_imu};
use preint::{ImuNoise, PreintParams};
use solver::bias::{BiasError, KnownPose, KnownPoseOptions, calibrate_known_poses};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/euroc")
        .join(name)
}

/// 20 s of V1_01 (from 10 s after the start of the ground truth), poses every 0.5 s (every 10th
/// ground-truth row), EuRoC noise densities, pose noise σ_R = 0.1° and σ_p = 5 mm (the data
/// README's measured consistency of this pair: 0.10° median rotation error per 1 s window).
///
/// Tolerances against the vicon2gt biases (averaged over the segment): |Δb_g| ≤ 2e-3 rad/s
/// per axis, |Δb_a| ≤ 0.1 m/s² per axis. Why: the ground-truth biases are themselves
/// estimates (vicon2gt's batch fit with its own gravity and pose-noise model), the ground-truth
/// world frame is tilted ≈ 0.23° w.r.t. gravity (≈ 0.04 m/s² of horizontal specific force that
/// a different gravity model moves between b_a and the gravity direction), and over 20 s of
/// gentle motion b_a is only weakly separable from the gravity direction (its σ here is a few
/// 0.01 m/s²). 2e-3 rad/s is ≈ 0.1°/s, the ADIS16448 bias stability class.
#[test]
fn euroc_v1_01_biases_close_to_ground_truth() {
    let imu = read_euroc_imu(&data("V1_01_easy_imu0.csv")).unwrap();
    let gt = read_euroc_groundtruth(&data("V1_01_easy_groundtruth_vicon2gt.csv")).unwrap();
    let t_start = gt[0].t_ns + 10_000_000_000;
    let t_end = t_start + 20_000_000_000;
    let sel: Vec<_> = gt
        .iter()
        .filter(|s| s.t_ns >= t_start && s.t_ns <= t_end)
        .step_by(10)
        .collect();
    let poses: Vec<KnownPose> = sel
        .iter()
        .map(|s| KnownPose {
            t_ns: s.t_ns,
            r: s.rotation(),
            p: s.p,
        })
        .collect();
    let n = sel.len() as f64;
    let gt_bg = sel.iter().map(|s| s.bias.gyro).sum::<Vector3<f64>>() / n;
    let gt_ba = sel.iter().map(|s| s.bias.acc).sum::<Vector3<f64>>() / n;
    let lo = imu.partition_point(|s| s.t_ns < t_start - 100_000_000);
    let hi = imu.partition_point(|s| s.t_ns <= t_end + 100_000_000);
    let mut opts = KnownPoseOptions::new(PreintParams::from_noise(&ImuNoise::euroc()));
    opts.pose_rot_std = 0.1f64.to_radians();
    opts.pose_pos_std = 0.005;
    let c = calibrate_known_poses(&imu[lo..hi], &poses, &opts).unwrap();
    println!(
        "poses {}, b_g {:?} ± {:?} (gt {:?})\nb_a {:?} ± {:?} (gt {:?})\ngravity {:?} ± {:?}, tilt {:.3}°, χ²/dof {:.2}, solves {}, iterations {}",
        poses.len(),
        c.bias.gyro.as_slice(),
        c.gyro_bias_std.as_slice(),
        gt_bg.as_slice(),
        c.bias.acc.as_slice(),
        c.acc_bias_std.as_slice(),
        gt_ba.as_slice(),
        c.gravity.as_slice(),
        c.gravity_std.as_slice(),
        c.gravity_tilt.to_degrees(),
        c.chi2 / c.dof as f64,
        c.solves,
        c.iterations
    );
    assert!(c.stop.converged());
    for i in 0..3 {
        assert!((c.bias.gyro[i] - gt_bg[i]).abs() <= 2e-3, "b_g axis {i}");
        assert!((c.bias.acc[i] - gt_ba[i]).abs() <= 0.1, "b_a axis {i}");
    }
    // Gravity keeps its magnitude and stays within 1° of the z axis.
    assert!((c.gravity.norm() - 9.81).abs() < 1e-9);
    assert!(c.gravity_tilt < 1f64.to_radians());
    // Velocities against the ground truth's (not used as input): printed only. Known open
    // issue: the first poses' velocities differ from vicon2gt's by up to ≈ 0.3 m/s (decaying
    // along the segment) while the biases agree; not yet understood.
    let verr: Vec<f64> = c
        .velocities
        .iter()
        .zip(&sel)
        .map(|(v, s)| (v - s.v).norm())
        .collect();
    println!("velocity errors [m/s]: {verr:.3?}");
}

#[test]
fn known_poses_bad_input() {
    let imu = read_euroc_imu(&data("V1_01_easy_imu0.csv")).unwrap();
    let gt = read_euroc_groundtruth(&data("V1_01_easy_groundtruth_vicon2gt.csv")).unwrap();
    let pose = |k: usize| KnownPose {
        t_ns: gt[k].t_ns,
        r: gt[k].rotation(),
        p: gt[k].p,
    };
    let opts = KnownPoseOptions::new(PreintParams::from_noise(&ImuNoise::euroc()));
    let few = [pose(10), pose(20)];
    assert!(matches!(
        calibrate_known_poses(&imu[..2000], &few, &opts),
        Err(BiasError::TooFew { what: "poses", .. })
    ));
    let unordered = [pose(10), pose(30), pose(20)];
    assert!(matches!(
        calibrate_known_poses(&imu[..2000], &unordered, &opts),
        Err(BiasError::InvalidParameter { .. })
    ));
    let outside = [pose(10), pose(20), pose(2000)];
    assert!(matches!(
        calibrate_known_poses(&imu[..2000], &outside, &opts),
        Err(BiasError::InvalidParameter { .. })
    ));
    let mut bad = opts.clone();
    bad.pose_rot_std = f64::NAN;
    assert!(matches!(
        calibrate_known_poses(&imu[..2000], &[pose(10), pose(20), pose(30)], &bad),
        Err(BiasError::InvalidParameter { .. })
    ));
}
