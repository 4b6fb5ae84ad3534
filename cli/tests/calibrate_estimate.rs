//! `calibrate --poses --estimate`: the time offset and intrinsics from known poses (8-column
//! `t,p,q` file) or attitudes (5-column `t,q` file), their σ and excitation in the output, the
//! calibration file `--out` writes, and refusals.
//!
//! Recording: 12 s of the `aggressive` scene at 200 Hz with EuRoC densities, read by a sensor
//! with a 1 % / 2 mrad `kalibr` model, g-sensitivity and a clock 5 ms ahead (as
//! `preint-calib`'s `known_pose_intrinsics` test); the poses are the simulator's truth.

mod common;

use common::{json, run, tmp, write_imu_csv};
use nalgebra::{Matrix3, Vector3};
use preint::ImuNoise;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::lie::SO3;
use preint_sim::{EulerScene, SimConfig, simulate};
use std::path::{Path, PathBuf};

const TD_NS: i64 = 5_000_000;

fn truth() -> ImuIntrinsics {
    let mut x = ImuIntrinsics::identity(IntrinsicsModel::Kalibr);
    x.t_w = Matrix3::new(1.01, 0.0, 0.0, 2e-3, 0.99, 0.0, -2e-3, 2e-3, 1.005);
    x.r_imu_to_gyro = *SO3::exp(&Vector3::new(2e-3, -1e-3, 1.5e-3)).matrix();
    x.t_a = Matrix3::new(0.99, 0.0, 0.0, -2e-3, 1.01, 0.0, 2e-3, 1e-3, 0.995);
    x.t_g = Matrix3::new(2e-4, 0.0, 1e-4, 0.0, -3e-4, 0.0, 1e-4, 0.0, 2e-4);
    x
}

/// Writes the recording, an 8-column pose file and a 5-column attitude file (truth every
/// 50 ms); returns their paths.
fn recording(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let cfg = SimConfig {
        noise: ImuNoise::euroc(),
        bias_random_walk: false,
        ..SimConfig::default()
    };
    let out = simulate(&EulerScene::aggressive(), 200.0, 12.0, &cfg, 5).unwrap();
    let x = truth();
    let rows: Vec<(i64, [f64; 6])> = out
        .samples
        .iter()
        .map(|s| {
            let w = x.t_w * x.r_imu_to_gyro * s.gyro
                + x.t_g * s.acc
                + Vector3::new(0.004, -0.003, 0.006);
            let a = x.t_a * s.acc + Vector3::new(0.08, -0.05, 0.12);
            (s.t_ns + TD_NS, [w.x, w.y, w.z, a.x, a.y, a.z])
        })
        .collect();
    let imu = write_imu_csv(dir, "imu.csv", &rows);
    let (mut poses, mut atts) = (String::from("#t,x,y,z,qw,qx,qy,qz\n"), String::new());
    for s in out.truth.iter().step_by(10) {
        let q = s.q.quaternion();
        let qs = format!("{:?},{:?},{:?},{:?}", q.w, q.i, q.j, q.k);
        poses.push_str(&format!(
            "{},{:?},{:?},{:?},{qs}\n",
            s.t_ns, s.p.x, s.p.y, s.p.z
        ));
        atts.push_str(&format!("{},{qs}\n", s.t_ns));
    }
    (
        imu,
        common::write(dir, "poses.csv", &poses),
        common::write(dir, "attitudes.csv", &atts),
    )
}

/// `calibrate --json` with poses every 0.25 s, `--estimate estimate` and `extra` flags.
fn calibrate(imu: &Path, poses: &Path, estimate: &str, extra: &[&str]) -> serde_json::Value {
    let (imu, poses) = (imu.to_str().unwrap(), poses.to_str().unwrap());
    let mut args = vec![
        "calibrate",
        "--imu",
        imu,
        "--poses",
        poses,
        "--pose-spacing",
        "0.25",
    ];
    args.extend(["--estimate", estimate]);
    args.extend_from_slice(extra);
    json(&args)
}

fn param<'a>(out: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    out["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("{name} in {}", out["parameters"]))
}

/// Within 3σ of the truth, and excited.
fn check(out: &serde_json::Value, name: &str, truth: f64) {
    let p = param(out, name);
    let (v, s) = (p["value"].as_f64().unwrap(), p["std"].as_f64().unwrap());
    assert_eq!(p["excited"], true, "{p}");
    assert!((v - truth).abs() <= 3.0 * s, "{name}: {v} ± {s} vs {truth}");
}

#[test]
fn time_offset_and_intrinsics_from_poses_and_from_attitudes() {
    let dir = tmp("calibrate-estimate");
    let (imu, poses, atts) = recording(&dir);
    let cal = dir.join("calib.yaml");
    let out = calibrate(
        &imu,
        &poses,
        "time-offset,gyro-intrinsics,g-sensitivity,accel-intrinsics",
        &["--out", cal.to_str().unwrap()],
    );
    assert_eq!(out["model"], "known-poses");
    assert_eq!(out["parameters"].as_array().unwrap().len(), 25);
    let x = truth();
    check(&out, "t_d", TD_NS as f64 * 1e-9);
    check(&out, "T_w[0,0]", x.t_w[(0, 0)]);
    check(&out, "T_w[2,1]", x.t_w[(2, 1)]);
    check(&out, "T_a[1,1]", x.t_a[(1, 1)]);
    check(&out, "T_g[1,1]", x.t_g[(1, 1)]);
    check(&out, "R_IMUtoGYRO.θz", 1.5e-3);
    // The file holds what the JSON says, and the time offset.
    let file = preint_io::read_openvins_imu_chain(&cal).unwrap();
    let td = out["time_offset_s"].as_f64().unwrap();
    assert!((file.time_offset_s.unwrap() - td).abs() <= 1e-18);
    let tw = common::matrix(&out["intrinsics"]["Tw"]);
    for (r, row) in tw.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            // serde_json's parser may round the last digit differently.
            assert!((file.intrinsics.t_w[(r, c)] - v).abs() <= 2e-16);
        }
    }
    // Attitudes only: the gyroscope's parameters; the accelerometer's are refused.
    let a = calibrate(
        &imu,
        &atts,
        "time-offset,gyro-intrinsics,g-sensitivity",
        &[],
    );
    assert_eq!(a["model"], "known-attitudes");
    assert_eq!(a["parameters"].as_array().unwrap().len(), 19);
    check(&a, "t_d", TD_NS as f64 * 1e-9);
    check(&a, "T_w[1,1]", x.t_w[(1, 1)]);
    check(&a, "T_g[2,2]", x.t_g[(2, 2)]);
    let o = run(&[
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        atts.to_str().unwrap(),
        "--estimate",
        "accel-intrinsics",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(0));
    assert!(
        err.contains("accel-intrinsics need known positions"),
        "{err}"
    );
}

/// A recording at rest excites no time offset: the output says so (`excited: false`, `value`
/// null, the initial 0 `kept`), not a number the data did not give; unknown names and
/// `--estimate` without `--poses` are usage errors.
#[test]
fn unexcited_parameters_are_withheld_and_bad_lists_refused() {
    let dir = tmp("calibrate-estimate-static");
    common::simulate(&dir, &["--scene", "static", "--duration", "6"]);
    let imu = dir.join("imu.csv");
    let gt = dir.join("groundtruth.csv");
    let out = json(&[
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
        "--estimate",
        "time-offset",
    ]);
    let td = param(&out, "t_d");
    assert_eq!(td["excited"], false, "{td}");
    assert_eq!(td["value"], serde_json::Value::Null);
    assert_eq!(td["kept"], 0.0);
    let text = String::from_utf8_lossy(
        &run(&[
            "calibrate",
            "--imu",
            imu.to_str().unwrap(),
            "--poses",
            gt.to_str().unwrap(),
            "--estimate",
            "time-offset",
        ])
        .stdout,
    )
    .to_string();
    assert!(text.contains("t_d: not excited by the motion"), "{text}");
    let usage = |a: &[&str], needle: &str| {
        let o = run(a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{err}");
    };
    let (imu, gt) = (imu.to_str().unwrap(), gt.to_str().unwrap());
    usage(
        &[
            "calibrate",
            "--imu",
            imu,
            "--poses",
            gt,
            "--estimate",
            "time-ofset",
        ],
        "unknown parameter `time-ofset`",
    );
    usage(
        &["calibrate", "--imu", imu, "--estimate", "time-offset"],
        "--poses",
    );
}
