//! The IMU calibration file: `calibrate --out` writes the multi-position model it chose in
//! OpenVINS' kalibr_imu_chain.yaml, and `integrate --calibration` applies a file's intrinsics
//! and time offset.

mod common;

use common::{json, run, tmp, write_imu_csv};
use nalgebra::{Matrix3, Vector3};
use preint::intrinsics::AppliedIntrinsics;
use preint::lie::SO3;
use preint::{ImuBias, ImuNoise, Level, PreintParams, preintegrate};
use preint_sim::{MultiPoseStaticScene, SimConfig, simulate};

/// 12 attitudes, 4 s still each, 2 s moves (the calibration suite's layout).
fn scene() -> MultiPoseStaticScene {
    let h = std::f64::consts::FRAC_PI_2;
    let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
    let d = Vector3::new(1.0, 1.0, 1.0).normalize();
    let moves = [
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
    ];
    let mut poses = vec![SO3::exp(&Vector3::new(0.1, -0.05, 0.3))];
    for (a, th) in moves {
        let next = poses.last().unwrap().compose(&SO3::exp(&(a * th)));
        poses.push(next);
    }
    MultiPoseStaticScene::new(poses, 4.0, 2.0, Vector3::new(0.5, -0.2, 1.0)).unwrap()
}

fn num(v: &serde_json::Value, i: usize) -> f64 {
    v[i].as_f64().unwrap()
}

#[test]
fn multi_position_scale_is_written_and_applied() {
    let dir = tmp("calfile-multi");
    let (sa, sg) = (
        Vector3::new(0.01, -0.01, 0.01),
        Vector3::new(-0.01, 0.01, 0.01),
    );
    let cfg = SimConfig {
        noise: ImuNoise {
            gyro_random_walk: 0.0,
            acc_random_walk: 0.0,
            ..ImuNoise::euroc()
        },
        initial_bias: ImuBias::new(
            Vector3::new(0.003, -0.002, 0.005),
            Vector3::new(0.05, -0.08, 0.1),
        ),
        bias_random_walk: false,
        acc_scale: Matrix3::from_diagonal(&sa.add_scalar(1.0)),
        gyro_scale: Matrix3::from_diagonal(&sg.add_scalar(1.0)),
        ..SimConfig::default()
    };
    let sc = scene();
    let samples = simulate(&sc, 200.0, sc.duration_s(), &cfg, 12)
        .unwrap()
        .samples;
    let rows: Vec<(i64, [f64; 6])> = samples
        .iter()
        .map(|s| {
            let (w, a) = (s.gyro, s.acc);
            (s.t_ns, [w.x, w.y, w.z, a.x, a.y, a.z])
        })
        .collect();
    let imu = write_imu_csv(&dir, "imu.csv", &rows);
    let cal = dir.join("calib.yaml");
    let out = json(&[
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert_eq!(out["model"], "multi-pose/Scale", "{}", out["reason"]);
    let file = preint_io::read_openvins_imu_chain(&cal).unwrap();
    let x = file.intrinsics;
    // The file holds the estimates: diagonal of Ta = 1 + s_a, of Tw = 1 + s_g (no
    // misalignment in the chosen model: R_IMUtoGYRO = I, Tg = 0), each within 3σ of the truth.
    for i in 0..3 {
        let (ea, ga) = (num(&out["acc_scale"], i), num(&out["acc_scale_std"], i));
        let (eg, gg) = (num(&out["gyro_scale"], i), num(&out["gyro_scale_std"], i));
        assert_eq!(x.t_a[(i, i)], 1.0 + ea);
        assert!((x.t_w[(i, i)] - (1.0 + eg)).abs() < 1e-15);
        assert!((ea - sa[i]).abs() < 3.0 * ga && (eg - sg[i]).abs() < 3.0 * gg);
    }
    assert_eq!(x.r_imu_to_gyro, Matrix3::identity());
    assert_eq!(x.t_g, Matrix3::zeros());
    assert_eq!(file.noise, Some(ImuNoise::euroc()));

    // Applied by integrate: the library's preintegration with the same intrinsics, bit for bit.
    let (t_i, t_j) = (samples[100].t_ns + 2_500_000, samples[1500].t_ns);
    let r = json(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--calibration",
        cal.to_str().unwrap(),
        "--from",
        &t_i.to_string(),
        "--to",
        &t_j.to_string(),
    ]);
    let p = PreintParams {
        intrinsics: Some(AppliedIntrinsics::new(x)),
        ..PreintParams::from_noise(&ImuNoise::euroc()).with_level(Level::Combined)
    };
    let read = preint_io::read_euroc_imu(&imu).unwrap();
    let m = preintegrate(&p, &ImuBias::zero(), &read, t_i, t_j).unwrap();
    for k in 0..3 {
        assert_eq!(num(&r["delta_v"], k), m.delta_v[k]);
        assert_eq!(num(&r["delta_p"], k), m.delta_p[k]);
    }
    let plain = json(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--from",
        &t_i.to_string(),
        "--to",
        &t_j.to_string(),
    ]);
    assert_ne!(plain["delta_v"], r["delta_v"]);
    assert_eq!(r["calibration"]["time_offset_ns"], 0);
}

#[test]
fn the_time_offset_moves_the_keyframes_onto_the_imu_clock() {
    let dir = tmp("calfile-offset");
    common::simulate(&dir, &["--scene", "aggressive", "--duration", "3"]);
    let imu = dir.join("imu.csv");
    let cal = dir.join("offset.yaml");
    std::fs::write(
        &cal,
        "%YAML:1.0\nimu0:\n  model: \"kalibr\"\n  time_offset: 0.0123\n",
    )
    .unwrap();
    let window = |from: i64, to: i64, extra: &[&str]| {
        let (f, t) = (from.to_string(), to.to_string());
        let mut a = vec![
            "integrate",
            "--imu",
            imu.to_str().unwrap(),
            "--from",
            &f,
            "--to",
            &t,
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let shifted = window(
        1_000_000_000,
        2_000_000_000,
        &["--calibration", cal.to_str().unwrap()],
    );
    let direct = window(1_012_300_000, 2_012_300_000, &[]);
    assert_eq!(shifted["t_i_ns"], 1_012_300_000i64);
    for key in ["delta_R", "delta_v", "delta_p", "covariance"] {
        assert_eq!(shifted[key], direct[key], "{key}");
    }
    assert_eq!(shifted["calibration"]["time_offset_ns"], 12_300_000);

    // A malformed file: exit 2, naming the file and the field.
    std::fs::write(&cal, "%YAML:1.0\nimu0:\n  Tw:\n    - [1.0, 0.0]\n").unwrap();
    let o = run(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--calibration",
        cal.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("offset.yaml") && err.contains("Tw"), "{err}");
}

#[test]
fn advise_applies_the_calibrations_intrinsics() {
    let dir = tmp("calfile-advise");
    common::simulate(&dir, &["--scene", "aggressive", "--duration", "8"]);
    let imu = dir.join("imu.csv");
    // 1 % scale and 2 mrad misalignment on both sensors (the kalibr model's lower triangles).
    let x = preint::intrinsics::ImuIntrinsics {
        t_w: Matrix3::new(1.01, 0.0, 0.0, 0.002, 0.99, 0.0, -0.002, 0.001, 1.005),
        t_a: Matrix3::new(0.99, 0.0, 0.0, -0.002, 1.01, 0.0, 0.001, 0.002, 1.0),
        ..Default::default()
    };
    let cal = dir.join("calib.yaml");
    preint_io::write_openvins_imu_chain(
        &cal,
        &preint_io::ImuCalibration {
            intrinsics: x,
            noise: None,
            time_offset_s: None,
            rostopic: None,
            scheme: None,
            body_p_sensor: None,
        },
    )
    .unwrap();
    // The same recording corrected beforehand, written exactly.
    let c = x.correction();
    let rows: Vec<(i64, [f64; 6])> = preint_io::read_euroc_imu(&imu)
        .unwrap()
        .iter()
        .map(|s| {
            let s = c.apply(s);
            let (w, a) = (s.gyro, s.acc);
            (s.t_ns, [w.x, w.y, w.z, a.x, a.y, a.z])
        })
        .collect();
    let corrected = write_imu_csv(&dir, "corrected.csv", &rows);
    let noise = dir.join("imu.yaml");
    let advise = |file: &std::path::Path, extra: &[&str]| {
        let mut a = vec![
            "advise",
            "--imu",
            file.to_str().unwrap(),
            "--noise",
            noise.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let (with, pre, raw) = (
        advise(&imu, &["--calibration", cal.to_str().unwrap()]),
        advise(&corrected, &[]),
        advise(&imu, &[]),
    );
    let errs = |v: &serde_json::Value| -> Vec<serde_json::Value> {
        v["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| serde_json::json!([c["disc_err"], c["noise_sigma"], c["embedded_err"]]))
            .collect()
    };
    assert_eq!(errs(&with), errs(&pre));
    assert_ne!(errs(&with), errs(&raw));
    assert_eq!(with["calibration"], cal.to_str().unwrap());
}
