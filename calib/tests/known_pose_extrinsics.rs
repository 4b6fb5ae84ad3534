//! The IMU's pose in the frame of the known poses (`extrinsic-rotation`, `lever-arm`,
//! [`preint_calib::bias::known_poses::extrinsic`]), with the time offset, on simulated trials
//! with the transform known, on a planar motion that cannot see all of it, and on EuRoC V1_01
//! with its ground truth re-expressed in another frame.
//!
//! # Trials
//! The `aggressive` scene, 10.4 s at 200 Hz, EuRoC densities, constant biases; per trial a
//! uniformly random rotation `R_bs`, a lever arm of random direction and length 0.05–0.5 m, a
//! time offset of ±20 ms (`t_imu = t_pose + t_d`), and poses of the frame b every 0.1 s over
//! [0.2, 10.2] s with noise σ_R = 1 mrad, σ_p = 2 mm. No initial guess is given: the rotation
//! starts at the hand-eye solution.
//!
//! Asserted: each of the 7 scalars (`δθ` as `Log(R_trueᵀR̂)`, the lever arm, `t_d`) within 3σ
//! of the truth in ≥ 95 % of the trials, and the mean χ²/dof within 0.05 of 1. CI runs 20
//! trials; `PREINT_FULL=1` runs 200.

use nalgebra::{Rotation3, Unit, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, SensorPose};
use preint_calib::bias::known_poses::extras::Estimate;
use preint_calib::bias::known_poses::extrinsic::{ExtrinsicEstimate, ExtrinsicStart};
use preint_calib::{KnownPose, KnownPoseCalibration, KnownPoseOptions, calibrate_known_poses};
use preint_io::{read_euroc_groundtruth, read_euroc_imu};
use preint_lie::SO3;
use preint_sim::scenes::Sines;
use preint_sim::{EulerScene, GroundTruthState, SimConfig, rng_from_seed, simulate};
use rand::RngExt;
use rand_distr::StandardNormal;
use std::path::PathBuf;

const RATE: f64 = 200.0;
const POSE_ROT_STD: f64 = 1e-3;
const POSE_POS_STD: f64 = 2e-3;

/// The poses of the frame b of IMU truth states (`R_b = R_s R_bsᵀ`, `p_b = p_s − R_b p_bs`),
/// with attitude and position noise of `std` from `rng`.
fn given_poses(
    truth: &[GroundTruthState],
    x: &SensorPose,
    std: (f64, f64),
    rng: &mut impl rand::Rng,
) -> Vec<KnownPose> {
    truth
        .iter()
        .map(|s| {
            let r = s.rotation().compose(&x.rotation.inverse());
            let p = s.p - r.act(&x.translation);
            let mut n = || Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
            let (nr, np) = (n() * std.0, n() * std.1);
            KnownPose {
                t_ns: s.t_ns,
                r: r.plus(&nr),
                p: p + np,
            }
        })
        .collect()
}

struct Trial {
    samples: Vec<ImuSample>,
    poses: Vec<KnownPose>,
    x: SensorPose,
    td_s: f64,
}

/// One trial (module docs).
fn trial(seed: u64) -> Trial {
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        initial_bias: ImuBias::new(
            Vector3::new(0.004, -0.003, 0.006),
            Vector3::new(0.08, -0.05, 0.12),
        ),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&EulerScene::aggressive(), RATE, 10.4, &cfg, seed).unwrap();
    let mut rng = rng_from_seed(70_000 + seed);
    let mut unit = || {
        let v = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
        v.normalize()
    };
    let axis = unit();
    let dir = unit();
    let angle = rng.random_range(0.0..std::f64::consts::PI);
    let len = rng.random_range(0.05..0.5);
    let td_s = rng.random_range(-0.02..0.02);
    let x = SensorPose::new(SO3::exp(&(axis * angle)), dir * len);
    let td_ns = (td_s * 1e9f64).round() as i64;
    let samples = out
        .samples
        .iter()
        .map(|s| ImuSample::new(s.t_ns + td_ns, s.gyro, s.acc))
        .collect();
    let at: Vec<GroundTruthState> = (1..=51).map(|k| out.truth[20 * k]).collect();
    let poses = given_poses(&at, &x, (POSE_ROT_STD, POSE_POS_STD), &mut rng);
    Trial {
        samples,
        poses,
        x,
        td_s: td_ns as f64 * 1e-9,
    }
}

fn params() -> PreintParams {
    PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(Scheme::Hermite4)
}

fn extrinsic_and_time() -> Estimate {
    Estimate {
        time_offset: true,
        extrinsic_rotation: true,
        lever_arm: true,
        ..Estimate::default()
    }
}

/// `[δθ, δp]` of the estimate against `x` (δθ = Log(R_xᵀ R̂)) and the time offset's error.
fn errors(c: &KnownPoseCalibration, x: &SensorPose, td_s: f64) -> ([f64; 6], f64) {
    let e = c.extrinsic.as_ref().expect("extrinsic estimated");
    let dth = e.body_p_sensor.rotation.minus(&x.rotation);
    let dp = e.body_p_sensor.translation - x.translation;
    (
        [dth.x, dth.y, dth.z, dp.x, dp.y, dp.z],
        c.time_offset_s - td_s,
    )
}

fn trials() -> u64 {
    if std::env::var("PREINT_FULL").is_ok_and(|v| v == "1") {
        200
    } else {
        20
    }
}

#[test]
fn extrinsics_and_time_offset_are_recovered_within_their_sigma() {
    let n = trials();
    let mut within = [0usize; 7];
    let mut chi2 = 0.0;
    for seed in 0..n {
        let t = trial(seed);
        let mut opts = KnownPoseOptions::new(params());
        opts.pose_rot_std = POSE_ROT_STD;
        opts.pose_pos_std = POSE_POS_STD;
        opts.estimate = extrinsic_and_time();
        let c = calibrate_known_poses(&t.samples, &t.poses, &opts).unwrap();
        let e = c.extrinsic.unwrap();
        assert_eq!(e.start, ExtrinsicStart::HandEye, "seed {seed}");
        assert!(
            e.rotation_excited && e.lever_arm_excited,
            "seed {seed}: {e:?}"
        );
        let (err, td_err) = errors(&c, &t.x, t.td_s);
        let std = e.std();
        for k in 0..6 {
            if err[k].abs() <= 3.0 * std[k] {
                within[k] += 1;
            }
        }
        let td_std = c.parameters[0].std;
        if td_err.abs() <= 3.0 * td_std {
            within[6] += 1;
        }
        chi2 += c.chi2_per_dof();
        if seed == 0 {
            println!(
                "seed 0: R_bs {:.1}° from the truth's start, error {:.2e} rad (σ {:.1e}); lever \
                 arm {:.3} m, error {:.2e} m (σ {:.1e}); t_d error {:.2e} s (σ {:.1e}); χ²/dof {:.3}",
                t.x.rotation.log().norm().to_degrees(),
                Vector3::new(err[0], err[1], err[2]).norm(),
                std[0],
                t.x.translation.norm(),
                Vector3::new(err[3], err[4], err[5]).norm(),
                std[3],
                td_err,
                td_std,
                c.chi2_per_dof()
            );
        }
    }
    let rate: Vec<f64> = within.iter().map(|&w| w as f64 / n as f64).collect();
    let chi2 = chi2 / n as f64;
    println!("{n} trials: within 3σ per scalar {rate:.3?} (δθ, δp, t_d); mean χ²/dof {chi2:.3}");
    for (k, r) in rate.iter().enumerate() {
        assert!(*r >= 0.95, "scalar {k}: {r:.3} within 3σ");
    }
    assert!((chi2 - 1.0).abs() < 0.05, "χ²/dof {chi2:.3}");
}

/// A motion that turns about z only (yaw, roll and pitch zero) leaves the lever arm along z
/// unobservable: it is withheld (σ over its limit) while x and y are recovered.
#[test]
fn a_rotation_about_one_axis_leaves_the_lever_arm_along_it_withheld() {
    let flat = Sines::hz(0.0, 0.0, &[]);
    let scene = EulerScene {
        name: "planar".into(),
        euler: [
            flat.clone(),
            flat,
            Sines::hz(0.0, 0.2, &[(0.8, 0.3, 0.0), (0.2, 1.1, 0.4)]),
        ],
        ..EulerScene::aggressive()
    };
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&scene, RATE, 10.4, &cfg, 5).unwrap();
    let x = SensorPose::new(SO3::identity(), Vector3::new(0.2, -0.1, 0.3));
    let at: Vec<GroundTruthState> = (1..=51).map(|k| out.truth[20 * k]).collect();
    let poses = given_poses(&at, &x, (POSE_ROT_STD, POSE_POS_STD), &mut rng_from_seed(9));
    let mut opts = KnownPoseOptions::new(params());
    opts.pose_rot_std = POSE_ROT_STD;
    opts.pose_pos_std = POSE_POS_STD;
    opts.estimate = Estimate {
        extrinsic_rotation: true,
        lever_arm: true,
        ..Estimate::default()
    };
    let c = calibrate_known_poses(&out.samples, &poses, &opts).unwrap();
    let e: ExtrinsicEstimate = c.extrinsic.unwrap();
    println!(
        "planar: rotation RMS {:.3?} rad/s; parameters {:?}",
        e.rotation_rms_rad_s,
        c.parameters
            .iter()
            .map(|p| (p.param.name(c.intrinsics.model), p.excited, p.std))
            .collect::<Vec<_>>()
    );
    assert!(!e.lever_arm_excited);
    // About x and y the poses turn only by their noise (1 mrad per 0.2 s).
    assert!(e.rotation_rms_rad_s.z > 0.5 && e.rotation_rms_rad_s.x < 0.03);
    let by_name = |n: &str| {
        c.parameters
            .iter()
            .find(|p| p.param.name(c.intrinsics.model) == n)
            .copied()
            .unwrap()
    };
    let z = by_name("p_bs.z");
    assert!(!z.excited && z.value == 0.0, "{z:?}");
    assert!(e.covariance[(5, 5)].is_nan());
    for (k, name) in ["p_bs.x", "p_bs.y"].iter().enumerate() {
        let p = by_name(name);
        assert!(p.excited, "{p:?}");
        assert!((p.value - x.translation[k]).abs() <= 3.0 * p.std, "{p:?}");
    }
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/euroc")
        .join(name)
}

/// EuRoC V1_01, [10, 30] s, vicon2gt poses every 0.5 s (datasheet densities, pose noise 0.1°
/// and 5 mm): the ground truth (the IMU's poses) re-expressed in a frame b turned by 90° about
/// (1, 1, 0)/√2 with the IMU 0.2 m from its origin. The recording turns mostly about the IMU's
/// x axis (RMS 0.30 rad/s against 0.07 and 0.14), so the lever arm along it is not excited
/// (σ over 1 cm) and is withheld. Asserted: the rotation is excited and every excited
/// component is within 3σ scaled by `√(χ²/dof)` (the datasheet densities are optimistic on
/// this recording) of the hidden transform, and of the identity on the poses as given; two
/// lever-arm components are excited.
#[test]
fn euroc_v1_01_a_hidden_transform_is_recovered() {
    let imu = read_euroc_imu(&data("V1_01_easy_imu0.csv")).unwrap();
    let gt = read_euroc_groundtruth(&data("V1_01_easy_groundtruth_vicon2gt.csv")).unwrap();
    let t_start = gt[0].t_ns + 10_000_000_000;
    let t_end = t_start + 20_000_000_000;
    let sel: Vec<_> = gt
        .iter()
        .filter(|s| s.t_ns >= t_start && s.t_ns <= t_end)
        .step_by(10)
        .collect();
    let lo = imu.partition_point(|s| s.t_ns < t_start - 100_000_000);
    let hi = imu.partition_point(|s| s.t_ns <= t_end + 100_000_000);
    let axis = Unit::new_normalize(Vector3::new(1.0, 1.0, 0.0));
    let r = Rotation3::from_axis_angle(&axis, std::f64::consts::FRAC_PI_2);
    let hidden = SensorPose::new(
        SO3::from_matrix(r.matrix()),
        Vector3::new(1.0, -1.0, 1.0).normalize() * 0.2,
    );
    let identity = SensorPose::new(SO3::identity(), Vector3::zeros());
    for (name, x) in [("as given", identity), ("re-expressed", hidden)] {
        let poses: Vec<KnownPose> = sel
            .iter()
            .map(|s| {
                let rb = s.rotation().compose(&x.rotation.inverse());
                KnownPose {
                    t_ns: s.t_ns,
                    r: rb,
                    p: s.p - rb.act(&x.translation),
                }
            })
            .collect();
        let mut opts = KnownPoseOptions::new(PreintParams::from_noise(&ImuNoise::euroc()));
        opts.pose_rot_std = 0.1f64.to_radians();
        opts.pose_pos_std = 0.005;
        opts.estimate = Estimate {
            extrinsic_rotation: true,
            lever_arm: true,
            ..Estimate::default()
        };
        let c = calibrate_known_poses(&imu[lo..hi], &poses, &opts).unwrap();
        let e = c.extrinsic.unwrap();
        let scale = c.chi2_per_dof().sqrt().max(1.0);
        let (err, _) = errors(&c, &x, 0.0);
        let std = e.std();
        println!(
            "EuRoC V1_01 {name}: δθ {:.2e} rad, δp {:.2e} m; σ {:.1e}..{:.1e}; χ²/dof {:.2}",
            Vector3::new(err[0], err[1], err[2]).norm(),
            Vector3::new(err[3], err[4], err[5]).norm(),
            std.iter().cloned().fold(f64::INFINITY, f64::min),
            std.iter().cloned().fold(0.0, f64::max),
            c.chi2_per_dof()
        );
        assert!(e.rotation_excited, "{name}: {e:?}");
        assert_eq!(
            std.iter().filter(|s| s.is_finite()).count(),
            5,
            "{name}: {std:?}"
        );
        for k in (0..6).filter(|&k| std[k].is_finite()) {
            assert!(
                err[k].abs() <= 3.0 * scale * std[k],
                "{name}: component {k} error {:.3e} σ {:.3e} × {scale:.2}",
                err[k],
                std[k]
            );
        }
    }
}
