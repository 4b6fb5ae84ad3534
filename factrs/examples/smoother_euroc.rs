//! A visual-inertial-style smoother on EuRoC V1_01 with preint's IMU factor inside factrs.
//!
//! Keyframes at 10 Hz (every other ground-truth row); between consecutive keyframes a
//! [`CombinedImuResidual`] (midpoint windows, the biases a random walk); at each keyframe a
//! pose measurement from the ground truth with added noise (0.5°, 2 cm: a visual odometry
//! front end) and a 3 s dropout without poses (20–23 s after the first keyframe); priors on
//! the first velocity and bias. Solved in batch by factrs' Levenberg–Marquardt (factrs has no
//! fixed-lag smoother; `examples/python/smoother_euroc.py` has GTSAM's). Prints the RMS
//! rotation, position and velocity errors against the ground truth and the mean estimated
//! biases beside the ground truth's.
//!
//! `cargo run --release -p preint-factrs --example smoother_euroc [-- SECONDS]`

use factrs::core::{LevenMarquardt, PriorResidual, SE3, Values, VectorVar3};
use factrs::noise::GaussianNoise;
use factrs::{assign_symbols, core::Graph, fac, traits::Optimizer, variables::ImuBias};
use preint::nalgebra::Vector3;
use preint::{CombinedImuFactor, ImuNoise, NavState, NavTangent, PreintParams, preintegrate};
use preint_factrs::{CombinedImuResidual, bias, nav_state, to_factrs, to_factrs_bias};
use rand::RngExt;
use rand_distr::StandardNormal;
use std::path::PathBuf;

assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);

const POSE_SIGMA: (f64, f64) = (0.5 * std::f64::consts::PI / 180.0, 0.02);
const DROPOUT_S: (f64, f64) = (20.0, 23.0);

/// RMS errors (rotation °, position m, velocity m/s) and mean biases of a smoother run.
#[derive(Debug)]
pub struct Errors {
    pub rot_deg: f64,
    pub pos_m: f64,
    pub vel_m_s: f64,
    pub bias_gyro: Vector3<f64>,
    pub bias_acc: Vector3<f64>,
    /// The ground truth's mean biases over the keyframes (gyro, accelerometer).
    pub truth_bias: (Vector3<f64>, Vector3<f64>),
    pub keyframes: usize,
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/euroc")
        .join(name)
}

/// The smoother over the first `seconds` of keyframes (module docs).
pub fn run(seconds: f64) -> Errors {
    let imu = preint_io::read_euroc_imu(&data("V1_01_easy_imu0.csv")).unwrap();
    let gt =
        preint_io::read_euroc_groundtruth(&data("V1_01_easy_groundtruth_vicon2gt.csv")).unwrap();
    let t0 = imu[0].t_ns + 100_000_000;
    let kf: Vec<_> = gt
        .iter()
        .step_by(2)
        .filter(|s| s.t_ns >= t0 && (s.t_ns - t0) as f64 * 1e-9 <= seconds)
        .copied()
        .collect();
    let params = PreintParams::from_noise(&ImuNoise::euroc());
    let mut rng = preint_sim::rng_from_seed(3);
    let mut graph = Graph::new();
    let mut values = Values::new();
    let pose_noise = GaussianNoise::<6>::from_split_sigma(POSE_SIGMA.0, POSE_SIGMA.1);
    for (k, s) in kf.iter().enumerate() {
        let mut n = |sigma: f64| sigma * rng.sample::<f64, _>(StandardNormal);
        let d = NavTangent::from_fn(|i, _| match i {
            0..3 => n(POSE_SIGMA.0),
            3..6 => n(POSE_SIGMA.1),
            _ => 0.0,
        });
        let noisy = NavState::new(s.rotation(), s.p, s.v).retract(&d);
        let (pose, _) = to_factrs(&noisy);
        let t_s = (s.t_ns - kf[0].t_ns) as f64 * 1e-9;
        let k = k as u32;
        if k == 0 || !(DROPOUT_S.0..=DROPOUT_S.1).contains(&t_s) {
            graph.add_factor(fac![
                PriorResidual::new(pose.clone()),
                X(k),
                pose_noise.clone()
            ]);
        }
        values.insert(X(k), pose);
        values.insert(V(k), VectorVar3::new(0.0, 0.0, 0.0));
        values.insert(B(k), to_factrs_bias(&preint::ImuBias::zero()));
    }
    let (_, v0) = to_factrs(&NavState::new(kf[0].rotation(), kf[0].p, kf[0].v));
    graph.add_factor(fac![
        PriorResidual::new(v0),
        V(0),
        GaussianNoise::<3>::from_scalar_sigma(0.05)
    ]);
    let zero = to_factrs_bias(&preint::ImuBias::zero());
    graph.add_factor(fac![
        PriorResidual::new(zero),
        B(0),
        GaussianNoise::<6>::from_split_sigma(0.01, 0.1)
    ]);
    for (k, w) in kf.windows(2).enumerate() {
        let m = preintegrate(
            &params,
            &preint::ImuBias::zero(),
            &imu,
            w[0].t_ns,
            w[1].t_ns,
        )
        .unwrap();
        let r = CombinedImuResidual::new(CombinedImuFactor::new(m).unwrap());
        let (i, j) = (k as u32, k as u32 + 1);
        graph.add_factor(fac![r, (X(i), V(i), X(j), V(j), B(i), B(j))]);
    }
    let mut solver = LevenMarquardt::new_default(graph);
    let est = solver.optimize(values).expect("converges");
    errors(&kf, &est)
}

fn errors(kf: &[preint_io::GroundTruthState], est: &Values) -> Errors {
    let (mut rot, mut pos, mut vel) = (0.0, 0.0, 0.0);
    let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
    let (mut tg, mut ta) = (Vector3::zeros(), Vector3::zeros());
    for (k, s) in kf.iter().enumerate() {
        let k = k as u32;
        let x = nav_state(est.get(X(k)).unwrap(), est.get(V(k)).unwrap());
        rot += x.r.minus(&s.rotation()).norm_squared();
        pos += (x.p - s.p).norm_squared();
        vel += (x.v - s.v).norm_squared();
        let b = bias(est.get(B(k)).unwrap());
        bg += b.gyro;
        ba += b.acc;
        tg += s.bias.gyro;
        ta += s.bias.acc;
    }
    let n = kf.len() as f64;
    Errors {
        rot_deg: (rot / n).sqrt().to_degrees(),
        pos_m: (pos / n).sqrt(),
        vel_m_s: (vel / n).sqrt(),
        bias_gyro: bg / n,
        bias_acc: ba / n,
        truth_bias: (tg / n, ta / n),
        keyframes: kf.len(),
    }
}

fn main() {
    let seconds = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(150.0);
    let t = std::time::Instant::now();
    let e = run(seconds);
    println!(
        "EuRoC V1_01, {} keyframes at 10 Hz, poses ±{:.0} cm ± {:.1}°, none over {:.0}–{:.0} s",
        e.keyframes,
        POSE_SIGMA.1 * 100.0,
        POSE_SIGMA.0.to_degrees(),
        DROPOUT_S.0,
        DROPOUT_S.1
    );
    println!(
        "preint midpoint, CombinedImuResidual, factrs LM: rotation {:.3}°, position {:.4} m, \
         velocity {:.4} m/s; mean b_g {:+.4?} rad/s, b_a {:+.3?} m/s² (ground truth {:+.4?}, \
         {:+.3?}); {:.1} s",
        e.rot_deg,
        e.pos_m,
        e.vel_m_s,
        e.bias_gyro.as_slice(),
        e.bias_acc.as_slice(),
        e.truth_bias.0.as_slice(),
        e.truth_bias.1.as_slice(),
        t.elapsed().as_secs_f64()
    );
}

#[cfg(test)]
mod tests {
    /// 25 s (251 keyframes, the dropout included): the smoother beats the 2 cm / 0.5° poses it
    /// is given, and the mean gyro bias matches the ground truth's to 1e-3 rad/s.
    #[test]
    fn twenty_five_seconds_beat_the_pose_noise() {
        let e = super::run(25.0);
        println!("{e:?}");
        assert!(
            e.pos_m < 0.02 && e.rot_deg < 0.5 && e.vel_m_s < 0.05,
            "{e:?}"
        );
        assert!((e.bias_gyro - e.truth_bias.0).norm() < 1e-3, "{e:?}");
    }
}
