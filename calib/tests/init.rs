//! Visual-inertial initialisation ([`preint_calib::init`]) on simulated trials with poses known
//! up to scale, in a world frame of their own, of a frame away from the IMU.
//!
//! # Trials
//! The `aggressive` scene at 200 Hz, EuRoC densities, constant biases drawn from the default
//! prior (σ_g 0.05 rad/s, σ_a 0.2 m/s²). Per trial: a uniformly random world rotation and
//! offset, a scale `s` (metres per pose unit) log-uniform in [0.2, 5], an IMU at a random
//! attitude 0.05–0.3 m from the frame of the poses (given as `body_p_sensor`), and keyframe
//! poses every 0.1 s over a 4 s window with noise σ_R = 1 mrad and σ_p = 2 mm (in the poses'
//! unit, 2 mm / s).
//!
//! Asserted: the scale, each bias component and the gravity vector (its Mahalanobis distance
//! on the 2-DoF direction against χ²₂'s 3σ quantile, 11.83) within 3σ of the truth in ≥ 95 %
//! of the trials; the linear start within 10 % of the scale; every trial ready. CI runs 20
//! trials; `PREINT_FULL=1` runs 200.

use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, SensorPose};
use preint_calib::KnownPose;
use preint_calib::init::{InitOptions, Initialisation, ScaleMode, initialise};
use preint_lie::SO3;
use preint_sim::{EulerScene, GroundTruthState, SimConfig, rng_from_seed, simulate};
use rand::RngExt;
use rand_distr::StandardNormal;

const RATE: f64 = 200.0;
const POSE_ROT_STD: f64 = 1e-3;
const POSE_POS_STD_M: f64 = 2e-3;

struct Trial {
    samples: Vec<ImuSample>,
    poses: Vec<KnownPose>,
    x_bs: SensorPose,
    scale: f64,
    gravity: Vector3<f64>,
    bias: ImuBias,
}

fn normal3(rng: &mut impl rand::Rng) -> Vector3<f64> {
    Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal))
}

/// One trial (module docs), `t0` the window's start \[s\].
fn trial(seed: u64, window_s: f64) -> Trial {
    let mut rng = rng_from_seed(90_000 + seed);
    let bias = ImuBias::new(normal3(&mut rng) * 0.05, normal3(&mut rng) * 0.2);
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        initial_bias: bias,
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&EulerScene::aggressive(), RATE, window_s + 0.4, &cfg, seed).unwrap();
    let r_w =
        SO3::exp(&(normal3(&mut rng).normalize() * rng.random_range(0.0..std::f64::consts::PI)));
    let t_w = normal3(&mut rng) * 2.0;
    let scale = (rng.random_range(0.2f64.ln()..5f64.ln())).exp();
    let x_bs = SensorPose::new(
        SO3::exp(&(normal3(&mut rng).normalize() * rng.random_range(0.0..std::f64::consts::PI))),
        normal3(&mut rng).normalize() * rng.random_range(0.05..0.3),
    );
    let keyframes = (window_s / 0.1).round() as usize;
    let at: Vec<GroundTruthState> = (0..=keyframes).map(|k| out.truth[40 + 20 * k]).collect();
    let poses = at
        .iter()
        .map(|s| {
            // The frame b's pose in the world of the poses, then the noise and the scale.
            let r_b = s.rotation().compose(&x_bs.rotation.inverse());
            let p_b = s.p - r_b.act(&x_bs.translation);
            let r = r_w.compose(&r_b).plus(&(normal3(&mut rng) * POSE_ROT_STD));
            let p = (r_w.act(&p_b) + t_w + normal3(&mut rng) * POSE_POS_STD_M) / scale;
            KnownPose { t_ns: s.t_ns, r, p }
        })
        .collect();
    Trial {
        samples: out.samples,
        poses,
        x_bs,
        scale,
        gravity: r_w.act(&Vector3::new(0.0, 0.0, -9.81)),
        bias,
    }
}

fn options(t: &Trial) -> InitOptions {
    let mut o = InitOptions::new(
        PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(Scheme::Midpoint),
    );
    o.pose_rot_std = POSE_ROT_STD;
    o.pose_pos_std = POSE_POS_STD_M / t.scale;
    o.body_p_sensor = Some(t.x_bs);
    o
}

/// The gravity error's Mahalanobis distance on the covariance's range (rank 2).
fn gravity_nees(i: &Initialisation, truth: &Vector3<f64>) -> f64 {
    let cov: Matrix3<f64> =
        i.covariance.fixed_view::<3, 3>(1, 1).into_owned() * i.std_factor.powi(2);
    let pinv = cov.pseudo_inverse(1e-12 * cov.norm()).unwrap();
    let d = i.gravity - truth;
    (d.transpose() * pinv * d)[0]
}

fn trials() -> u64 {
    if std::env::var("PREINT_FULL").is_ok_and(|v| v == "1") {
        200
    } else {
        20
    }
}

#[test]
fn scale_gravity_and_biases_are_recovered_within_their_sigma() {
    let n = trials();
    // Scale, gravity, b_g (3), b_a (3).
    let mut within = [0usize; 8];
    let mut ready = 0;
    let mut worst_linear: f64 = 0.0;
    let mut rel_err = Vec::new();
    for seed in 0..n {
        let t = trial(seed, 4.0);
        let i = initialise(&t.samples, &t.poses, &options(&t)).unwrap();
        let checks = [
            (i.scale - t.scale).abs() <= 3.0 * i.scale_std,
            gravity_nees(&i, &t.gravity) <= 11.83,
        ];
        for (k, ok) in checks.iter().enumerate() {
            within[k] += usize::from(*ok);
        }
        for k in 0..3 {
            within[2 + k] +=
                usize::from((i.bias.gyro[k] - t.bias.gyro[k]).abs() <= 3.0 * i.gyro_bias_std[k]);
            within[5 + k] +=
                usize::from((i.bias.acc[k] - t.bias.acc[k]).abs() <= 3.0 * i.acc_bias_std[k]);
        }
        ready += usize::from(i.ready);
        worst_linear = worst_linear.max((i.linear.scale / t.scale - 1.0).abs());
        rel_err.push((i.scale / t.scale - 1.0).abs());
        if seed == 0 {
            println!(
                "seed 0: scale {:.4} (truth {:.4}, σ {:.1e}), gravity {:.3?} (truth {:.3?}), \
                 χ²/dof {:.3}; {}",
                i.scale,
                t.scale,
                i.scale_std,
                i.gravity.as_slice(),
                t.gravity.as_slice(),
                i.fit.chi2_dof,
                i.reason
            );
        }
    }
    rel_err.sort_by(f64::total_cmp);
    let rate: Vec<f64> = within.iter().map(|&w| w as f64 / n as f64).collect();
    println!(
        "{n} trials, 4 s: within 3σ {rate:.3?} (s, g, b_g, b_a); ready {ready}/{n}; scale \
         error median {:.2e}, max {:.2e}; linear start worst {worst_linear:.2e}",
        rel_err[rel_err.len() / 2],
        rel_err[rel_err.len() - 1]
    );
    for (k, r) in rate.iter().enumerate() {
        assert!(*r >= 0.95, "quantity {k}: {r:.3} within 3σ");
    }
    assert_eq!(ready as u64, n, "every 4 s window of this motion is ready");
    assert!(worst_linear < 0.1, "linear start {worst_linear:.3}");
}

/// A window too short to see the scale is not ready and says so.
#[test]
fn a_short_window_is_not_ready_and_says_why() {
    let t = trial(7, 0.3);
    let i = initialise(&t.samples, &t.poses, &options(&t)).unwrap();
    println!("0.3 s: {}", i.reason);
    assert!(!i.ready, "{}", i.reason);
    assert!(
        i.reason.contains("scale σ") && i.reason.contains("not ready"),
        "{}",
        i.reason
    );
    assert!(i.scale_std / i.scale > 0.01);
}

/// Metric poses (`ScaleMode::Known`): gravity, velocities and biases without a scale.
#[test]
fn metric_poses_give_gravity_and_biases_with_the_scale_held() {
    let mut t = trial(3, 2.0);
    for p in &mut t.poses {
        p.p *= t.scale;
    }
    let mut o = options(&t);
    o.scale = ScaleMode::Known;
    o.pose_pos_std = POSE_POS_STD_M;
    let i = initialise(&t.samples, &t.poses, &o).unwrap();
    println!("metric, 2 s: {}", i.reason);
    assert_eq!((i.scale, i.scale_std, i.linear.scale), (1.0, 0.0, 1.0));
    assert!(i.ready && !i.reason.contains("scale"), "{}", i.reason);
    assert!(gravity_nees(&i, &t.gravity) <= 11.83);
    for k in 0..3 {
        assert!((i.bias.acc[k] - t.bias.acc[k]).abs() <= 3.0 * i.acc_bias_std[k]);
    }
    assert_eq!(i.velocities.len(), t.poses.len());
}
