//! Still-interval detection and multi-pose calibration on synthetic multi-position data.
//!
//! Generator (the `sim` multi-pose-static model, written out here): the IMU rests in K
//! attitudes for `still_s` seconds each and rotates between them about a fixed body axis a with
//! the smooth rest-to-rest profile θ(t) = Θ(t/T − sin(2πt/T)/2π) over T = `move_s` (ω = a·θ̇, no
//! translation). Readings: ω_m = S_g ω + b_g + n_g, a_m = S_a R(t)ᵀ(0, 0, 9.81) + b_a + n_a.

use lie::SO3;
use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use solver::bias::multipose::rotation_preintegration;
use solver::bias::{
    BiasError, MultiPoseModel, MultiPoseOptions, StillOptions, calibrate_multi_pose,
    detect_still_intervals,
};

const RATE: f64 = 200.0;

/// Rotation steps (body axis, angle [rad]) of the protocol: 11 moves, 12 attitudes covering
/// rotations about every body axis (so that each gyro scale is observable) and diagonals.
fn moves() -> Vec<(Vector3<f64>, f64)> {
    let h = std::f64::consts::FRAC_PI_2;
    let x = Vector3::x();
    let y = Vector3::y();
    let z = Vector3::z();
    let d = Vector3::new(1.0, 1.0, 1.0).normalize();
    vec![
        (x, h),
        (x, h),
        (z, h),
        (y, h),
        (y, h),
        (z, -h),
        (d, 0.8),
        (x, -1.1),
        (z, 0.7),
        (d, -1.3),
        (y, 0.9),
    ]
}

struct Truth {
    bias: ImuBias,
    s_a: Vector3<f64>,
    s_g: Vector3<f64>,
    /// (start, end) of every still span [ns].
    still: Vec<(i64, i64)>,
}

fn multipose_data(
    seed: u64,
    noise: &ImuNoise,
    s_a: Vector3<f64>,
    s_g: Vector3<f64>,
) -> (Vec<ImuSample>, Truth) {
    let bias = ImuBias::new(
        Vector3::new(0.003, -0.002, 0.005),
        Vector3::new(0.05, -0.08, 0.1),
    );
    let (still_s, move_s) = (4.0, 2.0);
    let dt = 1.0 / RATE;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut gauss = || -> Vector3<f64> {
        Vector3::new(
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
        )
    };
    let (sg_n, sa_n) = (
        noise.gyro_noise_density / dt.sqrt(),
        noise.acc_noise_density / dt.sqrt(),
    );
    let sa_m = Matrix3::from_diagonal(&(Vector3::repeat(1.0) + s_a));
    let sg_m = Matrix3::from_diagonal(&(Vector3::repeat(1.0) + s_g));
    let up = Vector3::new(0.0, 0.0, 9.81);
    let mut out = Vec::new();
    let mut still = Vec::new();
    let mut r = SO3::exp(&Vector3::new(0.1, -0.05, 0.3));
    let mut k: i64 = 0;
    let mut push = |r_t: &SO3, w: Vector3<f64>, k: &mut i64, out: &mut Vec<ImuSample>| {
        let t_ns = (*k as f64 * dt * 1e9).round() as i64;
        let gyro = sg_m * w + bias.gyro + gauss() * sg_n;
        let acc = sa_m * r_t.inverse().act(&up) + bias.acc + gauss() * sa_n;
        out.push(ImuSample::new(t_ns, gyro, acc));
        *k += 1;
    };
    let ms = moves();
    for i in 0..=ms.len() {
        let n_still = (still_s * RATE) as usize;
        let t0 = (k as f64 * dt * 1e9).round() as i64;
        for _ in 0..n_still {
            push(&r, Vector3::zeros(), &mut k, &mut out);
        }
        still.push((t0, ((k - 1) as f64 * dt * 1e9).round() as i64));
        if i == ms.len() {
            break;
        }
        let (a, th) = ms[i];
        let n_move = (move_s * RATE) as usize;
        let tp = 2.0 * std::f64::consts::PI;
        for j in 0..n_move {
            let s = j as f64 / n_move as f64;
            let theta = th * (s - (tp * s).sin() / tp);
            let rate = th / move_s * (1.0 - (tp * s).cos());
            push(
                &r.compose(&SO3::exp(&(a * theta))),
                a * rate,
                &mut k,
                &mut out,
            );
        }
        r = r.compose(&SO3::exp(&(a * th)));
    }
    (
        out,
        Truth {
            bias,
            s_a,
            s_g,
            still,
        },
    )
}

fn white() -> ImuNoise {
    ImuNoise {
        gyro_random_walk: 0.0,
        acc_random_walk: 0.0,
        ..ImuNoise::euroc()
    }
}

#[test]
fn still_intervals_match_the_protocol() {
    let noise = white();
    let (s, truth) = multipose_data(1, &noise, Vector3::zeros(), Vector3::zeros());
    let ivs = detect_still_intervals(&s, &StillOptions::from_noise(&noise, RATE)).unwrap();
    assert_eq!(ivs.len(), truth.still.len(), "{ivs:?}");
    for (iv, (a, b)) in ivs.iter().zip(&truth.still) {
        // Inside the true still span, and covering it but for ≤ ½ window (0.25 s) at each side
        // adjoining a motion (plus a sample).
        assert!(
            iv.t_start_ns >= *a && iv.t_end_ns <= *b,
            "{iv:?} vs {a}..{b}"
        );
        assert!(iv.t_start_ns - a <= 260_000_000 && b - iv.t_end_ns <= 260_000_000);
    }
}

#[test]
fn still_detection_synthetic_edges_and_errors() {
    // Pure white noise: one interval from sample h to N−1−h.
    let noise = white();
    let (s, _) = multipose_data(2, &noise, Vector3::zeros(), Vector3::zeros());
    let quiet = &s[..800]; // 4 s still
    let ivs = detect_still_intervals(quiet, &StillOptions::from_noise(&noise, RATE)).unwrap();
    assert_eq!(ivs.len(), 1);
    assert_eq!((ivs[0].start, ivs[0].end), (50, 750));
    // Minimum duration longer than the record: nothing.
    let long = StillOptions {
        min_duration_s: 10.0,
        ..StillOptions::from_noise(&noise, RATE)
    };
    assert!(detect_still_intervals(quiet, &long).unwrap().is_empty());
    let bad = StillOptions {
        window_s: -1.0,
        ..StillOptions::from_noise(&noise, RATE)
    };
    assert!(matches!(
        detect_still_intervals(quiet, &bad),
        Err(BiasError::InvalidParameter { .. })
    ));
    assert!(matches!(
        detect_still_intervals(&quiet[..2], &long),
        Err(BiasError::TooFew { .. })
    ));
}

/// The rotation preintegration used for the links equals preint's midpoint preintegration and
/// its bias Jacobian (independent implementation).
#[test]
fn link_rotation_matches_preint_midpoint() {
    let noise = white();
    let (s, _) = multipose_data(3, &noise, Vector3::zeros(), Vector3::zeros());
    let seg = &s[700..1300];
    let bg = Vector3::new(0.002, -0.001, 0.003);
    let (dr, jb, _) = rotation_preintegration(seg, &bg, &Vector3::zeros());
    let params = PreintParams::from_noise(&noise).with_scheme(Scheme::Midpoint);
    let pim = preintegrate(
        &params,
        &ImuBias::new(bg, Vector3::zeros()),
        seg,
        seg[0].t_ns,
        seg[seg.len() - 1].t_ns,
    )
    .unwrap();
    assert!(dr.minus(&pim.delta_r).norm() < 1e-12);
    assert!((jb - pim.jac.d_r_d_bg).amax() < 1e-10);
}

fn check_within_3_sigma(c: &solver::bias::MultiPoseCalibration, t: &Truth) {
    for i in 0..3 {
        let (eg, ea) = (
            c.gyro_bias[i] - t.bias.gyro[i],
            c.acc_bias[i] - t.bias.acc[i],
        );
        println!(
            "axis {i}: b_g err {eg:.2e} (σ {:.2e}), b_a err {ea:.2e} (σ {:.2e})",
            c.gyro_bias_std[i], c.acc_bias_std[i]
        );
        assert!(eg.abs() <= 3.0 * c.gyro_bias_std[i]);
        assert!(ea.abs() <= 3.0 * c.acc_bias_std[i]);
    }
}

#[test]
fn bias_only_chosen_without_scale_error() {
    let noise = white();
    let (s, truth) = multipose_data(11, &noise, Vector3::zeros(), Vector3::zeros());
    let c = calibrate_multi_pose(&s, &noise, &MultiPoseOptions::default()).unwrap();
    println!("{}", c.reason);
    assert_eq!(c.intervals.len(), 12);
    assert_eq!(c.model, MultiPoseModel::BiasOnly);
    assert!(c.fits.iter().all(|f| f.identifiable));
    check_within_3_sigma(&c, &truth);
    // The fit is consistent with the noise: χ²/dof near 1.
    assert!((c.chi2 / c.dof as f64) < 2.0);
}

#[test]
fn scale_chosen_with_one_percent_scale_error() {
    let noise = white();
    let sa = Vector3::new(0.01, -0.01, 0.01);
    let sg = Vector3::new(-0.01, 0.01, 0.01);
    let (s, truth) = multipose_data(12, &noise, sa, sg);
    let c = calibrate_multi_pose(&s, &noise, &MultiPoseOptions::default()).unwrap();
    println!("{}", c.reason);
    assert_eq!(c.model, MultiPoseModel::Scale);
    check_within_3_sigma(&c, &truth);
    let (ea, es) = (c.acc_scale.unwrap(), c.acc_scale_std.unwrap());
    for i in 0..3 {
        assert!(
            (ea[i] - truth.s_a[i]).abs() <= 3.0 * es[i],
            "s_a {ea:?} ± {es:?}"
        );
    }
    let (eg, gs) = (c.gyro_scale.unwrap(), c.gyro_scale_std.unwrap());
    for i in 0..3 {
        assert!(
            (eg[i] - truth.s_g[i]).abs() <= 3.0 * gs[i],
            "s_g {eg:?} ± {gs:?}"
        );
    }
}

#[test]
fn acc_scale_alone_is_preferred_to_full_scale() {
    let noise = white();
    let (s, _) = multipose_data(
        13,
        &noise,
        Vector3::new(0.01, 0.01, -0.01),
        Vector3::zeros(),
    );
    let c = calibrate_multi_pose(&s, &noise, &MultiPoseOptions::default()).unwrap();
    println!("{}", c.reason);
    assert_eq!(c.model, MultiPoseModel::AccScale);
}

#[test]
fn too_few_intervals_is_a_typed_error() {
    let noise = white();
    let (s, _) = multipose_data(4, &noise, Vector3::zeros(), Vector3::zeros());
    // The first still span and part of the first move: one interval.
    assert!(matches!(
        calibrate_multi_pose(&s[..1000], &noise, &MultiPoseOptions::default()),
        Err(BiasError::TooFew {
            what: "still intervals",
            ..
        })
    ));
}
