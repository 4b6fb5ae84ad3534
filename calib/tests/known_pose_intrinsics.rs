//! Time offset and IMU intrinsics from known poses ([`calibrate_known_poses`] with
//! [`Estimate`]), on simulated trials with every parameter known.
//!
//! # Trials
//! The `aggressive` scene, 20.5 s at 200 Hz, EuRoC densities, constant biases; seed = trial.
//! The simulator's samples `(ω_s, a_s)` (true rate and specific force plus white noise) are
//! read by a sensor with OpenVINS' `kalibr` intrinsics and stamped on a clock 5 ms ahead:
//!
//! ```text
//! ω_m = T_w R_IMUtoGYRO ω_s + T_g a_s + b_g,   a_m = T_a a_s + b_a,   t_imu = t + 5 ms
//! ```
//!
//! with ±1 % scales, 2 mrad misalignments (lower-triangular entries and the axis rotation),
//! a g-sensitivity of 1–3e-4 (rad/s)/(m/s²) (0.1–0.3 °/s per g) and biases of a few mrad/s and
//! 0.1 m/s². The noise then has exactly the densities of the corrected samples, as the model
//! says ([`preint::intrinsics`]). Exact poses every 0.25 s over [0.2, 9.8] s calibrate (hermite4);
//! the ten 1 s windows of [10, 20] s evaluate.
//!
//! # Asserted
//! - every one of the 25 parameters (t_d, 6 + 3 gyro, 9 g-sensitivity, 6 accelerometer) is
//!   within 3σ of the truth in ≥ 95 % of the trials;
//! - on the held-out windows the Δv error with the estimate applied is ≥ 10× smaller (RMS) than
//!   with the biases-only known-pose calibration of the same data;
//! - the NEES of the held-out windows' deltas `[δφ, δv, δp]` against the true states, with the
//!   estimate applied and its covariance added to the window's (`Σ + J Σ_c Jᵀ`,
//!   [`KnownPoseCalibration::covariance`]), is 9 ± 0.3 over the 2 000 windows (standard error
//!   0.09).
//!
//! Measured (200 trials, about 12 s): 0.990–1.000 of the trials within 3σ per parameter; Δv RMS
//! 0.133 → 0.0041 m/s (32×); NEES 8.95, and 10.56 with the window's covariance alone (the
//! calibration's own error is then unaccounted for).

use nalgebra::{DMatrix, Matrix3, SVector, Vector3};
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};
use preint_calib::bias::known_poses::extras::{Estimate, Param};
use preint_calib::{KnownPose, KnownPoseCalibration, KnownPoseOptions, calibrate_known_poses};
use preint_lie::SO3;
use preint_sim::{EulerScene, GroundTruthState, SimConfig, simulate};

const RATE: f64 = 200.0;
const TD_S: f64 = 5e-3;

fn truth_intrinsics() -> ImuIntrinsics {
    let mut x = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    x.t_w = Matrix3::new(1.01, 0.0, 0.0, 2e-3, 0.99, 0.0, -2e-3, 2e-3, 1.005);
    x.r_imu_to_gyro = *SO3::exp(&Vector3::new(2e-3, -1e-3, 1.5e-3)).matrix();
    x.t_a = Matrix3::new(0.99, 0.0, 0.0, -2e-3, 1.01, 0.0, 2e-3, 1e-3, 0.995);
    x.t_g = Matrix3::new(2e-4, 0.0, 1e-4, 0.0, -3e-4, 0.0, 1e-4, 0.0, 2e-4);
    x
}

fn truth_bias() -> ImuBias {
    ImuBias::new(
        Vector3::new(0.004, -0.003, 0.006),
        Vector3::new(0.08, -0.05, 0.12),
    )
}

struct Trial {
    samples: Vec<ImuSample>,
    truth: Vec<GroundTruthState>,
}

/// One trial (module docs): the sensor's samples on its clock and the truth on the pose clock.
fn trial(seed: u64) -> Trial {
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&EulerScene::aggressive(), RATE, 20.5, &cfg, seed).unwrap();
    let x = truth_intrinsics();
    let b = truth_bias();
    let td_ns = (TD_S * 1e9).round() as i64;
    let samples = out
        .samples
        .iter()
        .map(|s| {
            let w = x.t_w * x.r_imu_to_gyro * s.gyro + x.t_g * s.acc + b.gyro;
            let a = x.t_a * x.r_imu_to_acc * s.acc + b.acc;
            ImuSample::new(s.t_ns + td_ns, w, a)
        })
        .collect();
    Trial {
        samples,
        truth: out.truth,
    }
}

fn params() -> PreintParams {
    PreintParams::from_noise(&ImuNoise::euroc()).with_scheme(Scheme::Hermite4)
}

/// Exact poses every 0.25 s over [0.2, 9.8] s.
fn poses(t: &Trial) -> Vec<KnownPose> {
    (4..=196)
        .step_by(5)
        .map(|k| {
            let s = &t.truth[10 * k];
            KnownPose {
                t_ns: s.t_ns,
                r: s.rotation(),
                p: s.p,
            }
        })
        .collect()
}

fn all() -> Estimate {
    Estimate {
        time_offset: true,
        gyro_intrinsics: true,
        g_sensitivity: true,
        accel_intrinsics: true,
        ..Estimate::default()
    }
}

/// The true value of `p` in the result's convention (the rotation as its angle from identity).
fn true_value(p: Param) -> f64 {
    let x = truth_intrinsics();
    match p {
        Param::TimeOffset => TD_S,
        Param::Intrinsic(i) if (12..15).contains(&i) => {
            SO3::from_matrix(&x.r_imu_to_gyro).log()[i - 12]
        }
        Param::Intrinsic(i) => x.params()[i],
        Param::ExtrinsicRotation(_) | Param::LeverArm(_) | Param::Scale => {
            unreachable!("not estimated here")
        }
    }
}

/// The true deltas of the window `[t_i, t_j]` (truth indices) from the true states.
fn true_deltas(
    truth: &[GroundTruthState],
    i: usize,
    j: usize,
) -> (SO3, Vector3<f64>, Vector3<f64>) {
    let (a, b) = (&truth[i], &truth[j]);
    let g = Vector3::new(0.0, 0.0, -9.81);
    let dt = (b.t_ns - a.t_ns) as f64 * 1e-9;
    let rit = a.rotation().inverse();
    (
        rit.compose(&b.rotation()),
        rit.act(&(b.v - a.v - g * dt)),
        rit.act(&(b.p - a.p - a.v * dt - g * (0.5 * dt * dt))),
    )
}

/// Held-out windows [10 + k, 11 + k] s preintegrated with `p`, bias `b` and offset `td_s`:
/// per window, the Δv error [m/s], the NEES against the true deltas with the window's
/// covariance, and, given the calibration `c`, with its uncertainty added (`Σ + J Σ_c Jᵀ`).
fn held_out(
    t: &Trial,
    p: &PreintParams,
    b: &ImuBias,
    td_s: f64,
    c: Option<&KnownPoseCalibration>,
) -> Vec<(f64, f64, f64)> {
    let td_ns = (td_s * 1e9).round() as i64;
    (0..10)
        .map(|k| {
            let (i, j) = (2000 + 200 * k, 2200 + 200 * k);
            let (ti, tj) = (t.truth[i].t_ns, t.truth[j].t_ns);
            let (m, cov) = match c {
                None => {
                    let m = preintegrate(p, b, &t.samples, ti + td_ns, tj + td_ns).unwrap();
                    let cov = m.cov;
                    (m, cov)
                }
                Some(c) => with_calibration_cov(p, b, t, (ti + td_ns, tj + td_ns), c),
            };
            let (r, v, q) = true_deltas(&t.truth, i, j);
            let e = SVector::<f64, 9>::from_iterator(
                m.delta_r
                    .minus(&r)
                    .iter()
                    .chain((m.delta_v - v).iter())
                    .chain((m.delta_p - q).iter())
                    .copied(),
            );
            let nees = |cov: &preint::Cov9| e.dot(&cov.cholesky().unwrap().solve(&e));
            ((m.delta_v - v).norm(), nees(&m.cov), nees(&cov))
        })
        .collect()
}

/// A window and its covariance with the calibration's uncertainty added: `Σ + J Σ_c Jᵀ`,
/// `J = [J_b, J_e]` (the bias Jacobians, then the excited parameters' columns).
fn with_calibration_cov(
    p: &PreintParams,
    b: &ImuBias,
    t: &Trial,
    (ti, tj): (i64, i64),
    c: &KnownPoseCalibration,
) -> (preint::PreintegratedImu, preint::Cov9) {
    let mut pj = p.clone();
    pj.intrinsics = pj.intrinsics.map(|a| a.with_jacobians());
    let (m, ji) = preint::preintegrate_with_intrinsic_jacobian(&pj, b, &t.samples, ti, tj).unwrap();
    let excited: Vec<Param> = c
        .parameters
        .iter()
        .filter(|e| e.excited)
        .map(|e| e.param)
        .collect();
    let mut j = DMatrix::zeros(9, 6 + excited.len());
    let jb = &m.jac;
    for (col, block) in [jb.d_r_d_bg, jb.d_v_d_bg, jb.d_p_d_bg].iter().enumerate() {
        j.view_mut((3 * col, 0), (3, 3)).copy_from(block);
    }
    j.view_mut((3, 3), (3, 3)).copy_from(&jb.d_v_d_ba);
    j.view_mut((6, 3), (3, 3)).copy_from(&jb.d_p_d_ba);
    for (k, q) in excited.iter().enumerate() {
        match q {
            Param::TimeOffset => j.column_mut(6 + k).copy_from(&m.jac_td),
            Param::Intrinsic(i) => j.column_mut(6 + k).copy_from(&ji.column(*i)),
            // Not estimated here; they move the poses, not the deltas.
            Param::ExtrinsicRotation(_) | Param::LeverArm(_) | Param::Scale => {}
        }
    }
    let add = &j * &c.covariance * j.transpose();
    let cov = m.cov + preint::Cov9::from_fn(|r, s| add[(r, s)]);
    (m, cov)
}

#[test]
fn time_offset_and_intrinsics_are_recovered_within_their_sigma() {
    let trials: u64 = 200;
    let mut within = [0usize; 25];
    let (mut dv_before, mut dv_after, mut windows) = (0.0, 0.0, 0usize);
    let (mut nees, mut nees_window) = (0.0, 0.0);
    for seed in 0..trials {
        let t = trial(seed);
        let kp = poses(&t);
        let mut opts = KnownPoseOptions::new(params());
        opts.estimate = all();
        let c = calibrate_known_poses(&t.samples, &kp, &opts).unwrap();
        assert_eq!(c.parameters.len(), 25);
        for (k, e) in c.parameters.iter().enumerate() {
            assert!(
                e.excited,
                "seed {seed}: {:?} not excited (σ {:.3e})",
                e.param, e.std
            );
            if (e.value - true_value(e.param)).abs() <= 3.0 * e.std {
                within[k] += 1;
            }
        }
        // Held out: biases only (today's known-pose calibration) against the estimate applied.
        let plain =
            calibrate_known_poses(&t.samples, &kp, &KnownPoseOptions::new(params())).unwrap();
        let before = held_out(&t, &params(), &plain.bias, 0.0, None);
        let applied = PreintParams {
            intrinsics: Some(preint::intrinsics::AppliedIntrinsics::new(c.intrinsics)),
            ..params()
        };
        let after = held_out(&t, &applied, &c.bias, c.time_offset_s, Some(&c));
        for (b, a) in before.iter().zip(&after) {
            dv_before += b.0 * b.0;
            dv_after += a.0 * a.0;
            nees_window += a.1;
            nees += a.2;
            windows += 1;
        }
        if seed == 0 {
            for e in &c.parameters {
                println!(
                    "{:>16}: {:+.6e} ± {:.2e} (truth {:+.6e})",
                    e.param.name(IntrinsicsModel::Kalibr),
                    e.value,
                    e.std,
                    true_value(e.param)
                );
            }
            println!("χ²/dof {:.3}, solves {}", c.chi2_per_dof(), c.solves);
        }
    }
    let rate: Vec<f64> = within.iter().map(|&w| w as f64 / trials as f64).collect();
    let (rms_b, rms_a) = (
        (dv_before / windows as f64).sqrt(),
        (dv_after / windows as f64).sqrt(),
    );
    let nees = nees / windows as f64;
    let nees_window = nees_window / windows as f64;
    println!(
        "{trials} trials: within 3σ {:.3}..{:.3}; held-out 1 s Δv RMS {rms_b:.3e} → {rms_a:.3e} m/s \
         ({:.1}×); NEES {nees:.3} with the calibration's covariance ({nees_window:.3} with the \
         window's alone) over {windows} windows",
        rate.iter().cloned().fold(1.0, f64::min),
        rate.iter().cloned().fold(0.0, f64::max),
        rms_b / rms_a
    );
    for (k, r) in rate.iter().enumerate() {
        assert!(*r >= 0.95, "parameter {k}: {r:.3} within 3σ");
    }
    assert!(rms_b >= 10.0 * rms_a, "Δv {rms_b:.3e} → {rms_a:.3e}");
    assert!((nees - 9.0).abs() <= 0.3, "NEES {nees:.3}");
    assert!(
        nees_window > nees + 0.5,
        "the calibration's covariance matters: {nees_window:.3}"
    );
}

/// A motion that excites nothing: 10 s at rest (the `static` scene). The gyroscope
/// intrinsics, g-sensitivity and time offset are all withheld (`excited: false`, the initial
/// value returned, an infinite or over-limit σ), while the biases are still estimated.
#[test]
fn a_static_recording_excites_no_calibration_parameter() {
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        initial_bias: truth_bias(),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&preint_sim::StaticScene::default(), RATE, 10.0, &cfg, 7).unwrap();
    let kp: Vec<KnownPose> = (4..=36)
        .step_by(2)
        .map(|k| {
            let s = &out.truth[25 * k];
            KnownPose {
                t_ns: s.t_ns,
                r: s.rotation(),
                p: s.p,
            }
        })
        .collect();
    let mut opts = KnownPoseOptions::new(params());
    opts.estimate = Estimate {
        time_offset: true,
        gyro_intrinsics: true,
        g_sensitivity: true,
        ..Estimate::default()
    };
    let c = calibrate_known_poses(&out.samples, &kp, &opts).unwrap();
    assert_eq!(c.parameters.len(), 1 + 9 + 9);
    for e in &c.parameters {
        println!(
            "{:>16}: excited {} σ {:.3e}",
            e.param.name(IntrinsicsModel::Kalibr),
            e.excited,
            e.std
        );
        assert!(!e.excited, "{:?} σ {:.3e}", e.param, e.std);
        let initial = match e.param {
            Param::TimeOffset => 0.0,
            Param::Intrinsic(i) if (12..15).contains(&i) => 0.0,
            Param::Intrinsic(i) => ImuIntrinsics::default().params()[i],
            Param::ExtrinsicRotation(_) | Param::LeverArm(_) | Param::Scale => {
                unreachable!("not estimated here")
            }
        };
        assert_eq!(e.value, initial);
    }
    assert_eq!(c.intrinsics, ImuIntrinsics::default());
    assert_eq!(c.time_offset_s, 0.0);
    assert_eq!(c.covariance.nrows(), 6);
    for k in 0..3 {
        assert!((c.bias.gyro[k] - truth_bias().gyro[k]).abs() < 4.0 * c.gyro_bias_std[k]);
    }
}

/// Orientation-only poses (`calibrate_known_attitudes`): the same trials' attitudes every
/// 0.25 s over [0.2, 9.8] s with 0.2 mrad noise (`R̃ = R·Exp(n)`, σ_R = 2e-4 per axis, told to the
/// estimator); the time offset, gyro intrinsics and g-sensitivity (19 parameters) are each
/// within 3σ of the truth in ≥ 95 % of 100 trials, and the χ²/dof averages 1 ± 0.05.
#[test]
fn attitudes_alone_calibrate_the_gyroscope() {
    use preint_calib::bias::known_poses::{KnownAttitude, calibrate_known_attitudes};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let trials = 100u64;
    let mut within = [0usize; 19];
    let mut chi2 = 0.0;
    for seed in 0..trials {
        let t = trial(1000 + seed);
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let n = Normal::new(0.0, 2e-4).unwrap();
        let atts: Vec<KnownAttitude> = poses(&t)
            .iter()
            .map(|p| KnownAttitude {
                t_ns: p.t_ns,
                r: p.r.plus(&Vector3::from_fn(|_, _| n.sample(&mut rng))),
            })
            .collect();
        let mut opts = KnownPoseOptions::new(params());
        opts.pose_rot_std = 2e-4;
        opts.estimate = Estimate {
            accel_intrinsics: false,
            ..all()
        };
        let c = calibrate_known_attitudes(&t.samples, &atts, &opts).unwrap();
        assert_eq!(c.parameters.len(), 19);
        for (k, e) in c.parameters.iter().enumerate() {
            assert!(e.excited, "seed {seed}: {:?} σ {:.3e}", e.param, e.std);
            if (e.value - true_value(e.param)).abs() <= 3.0 * e.std {
                within[k] += 1;
            }
        }
        chi2 += c.chi2_per_dof();
        if seed == 0 {
            println!(
                "attitudes only: t_d {:.4e} ± {:.1e} s, T_w[0,0] {:.5} ± {:.1e}, χ²/dof {:.3}",
                c.parameters[0].value,
                c.parameters[0].std,
                c.parameters[1].value,
                c.parameters[1].std,
                c.chi2_per_dof()
            );
        }
    }
    let rate: Vec<f64> = within.iter().map(|&w| w as f64 / trials as f64).collect();
    let chi2 = chi2 / trials as f64;
    println!(
        "attitudes only, {trials} trials: within 3σ {:.2}..{:.2}, mean χ²/dof {chi2:.3}",
        rate.iter().cloned().fold(1.0, f64::min),
        rate.iter().cloned().fold(0.0, f64::max)
    );
    for (k, r) in rate.iter().enumerate() {
        assert!(*r >= 0.95, "parameter {k}: {r:.2} within 3σ");
    }
    assert!((chi2 - 1.0).abs() < 0.05, "χ²/dof {chi2:.3}");
}
