//! `--body-p-sensor` end to end: `simulate` mounts the IMU at a pose in the body, `integrate`
//! gives the body's deltas (checked against the body's ground truth written by `simulate`),
//! `calibrate` reports the body's roll and pitch, and malformed poses are refused.

mod common;

use common::{json, nums, run, simulate, tmp, true_delta_v, truth_at};
use nalgebra::Vector3;

/// 0.3 m lever arm along (1, −2, 2)/3; rotation 60° about (1, 1, 1)/√3 (sensor → body).
const POSE: &str =
    "0.1,-0.2,0.2,0.8660254037844387,0.28867513459481287,0.28867513459481287,0.28867513459481287";

#[test]
fn integrate_gives_the_body_deltas_of_an_imu_mounted_away_from_the_body_origin() {
    let dir = tmp("extrinsics-integrate");
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--noise",
            "none",
            "--duration",
            "3",
            "--body-p-sensor",
            POSE,
        ],
    );
    let imu = dir.join("imu.csv");
    let window = |extra: &[&str]| {
        let mut a = vec![
            "integrate",
            "--imu",
            imu.to_str().unwrap(),
            "--scheme",
            "hermite4",
            "--from",
            "1000000000",
            "--to",
            "2000000000",
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let truth_dv = true_delta_v(&dir, 1_000_000_000, 2_000_000_000);
    let err = |out: &serde_json::Value| {
        let v = nums(&out["delta_v"]);
        (Vector3::new(v[0], v[1], v[2]) - truth_dv).norm()
    };
    let body = window(&["--body-p-sensor", POSE]);
    let as_is = window(&[]);
    let gtsam_like = window(&["--body-p-sensor", POSE, "--lever-arm", "centripetal"]);
    println!(
        "Δv error with --lever-arm centripetal (GTSAM's model): {:.2e}",
        err(&gtsam_like)
    );
    assert!(
        err(&gtsam_like) > 1e-2,
        "ω̇ × r left out: {}",
        err(&gtsam_like)
    );
    assert_eq!(gtsam_like["body_p_sensor"]["lever_arm"], "centripetal");
    assert_eq!(body["body_p_sensor"]["lever_arm"], "exact");
    println!(
        "Δv error: with --body-p-sensor {:.2e} m/s, without {:.2e}",
        err(&body),
        err(&as_is)
    );
    assert!(err(&body) < 1e-4, "{}", err(&body));
    assert!(err(&as_is) > 0.1, "{}", err(&as_is));
    assert_eq!(
        nums(&body["body_p_sensor"]["translation"]),
        vec![0.1, -0.2, 0.2]
    );
    assert!(as_is["body_p_sensor"].is_null());
    // The human output says which frame the deltas are in.
    let o = run(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--from",
        "1000000000",
        "--to",
        "2000000000",
        "--body-p-sensor",
        POSE,
    ]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("the deltas are the body's"));
}

#[test]
fn malformed_body_p_sensor_is_refused_with_the_reason() {
    let dir = tmp("extrinsics-bad");
    simulate(
        &dir,
        &["--scene", "static", "--noise", "none", "--duration", "1"],
    );
    let imu = dir.join("imu.csv");
    for (bad, says) in [
        ("0,0,0,1,0,0", "seven comma-separated numbers"),
        ("0,0,0,2,0,0,0", "unit norm"),
        ("0,0,nan,1,0,0,0", "finite"),
        ("0,0,x,1,0,0,0", "is not a number"),
    ] {
        for cmd in ["integrate", "calibrate"] {
            let o = run(&[cmd, "--imu", imu.to_str().unwrap(), "--body-p-sensor", bad]);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                !o.status.success() && err.contains(says),
                "{cmd} {bad}: {err}"
            );
        }
        let o = run(&[
            "simulate",
            "--out",
            dir.to_str().unwrap(),
            "--body-p-sensor",
            bad,
        ]);
        assert!(!o.status.success(), "simulate {bad}");
    }
}

#[test]
fn static_calibration_reports_the_body_roll_and_pitch() {
    let dir = tmp("extrinsics-static");
    simulate(
        &dir,
        &[
            "--scene",
            "static",
            "--noise",
            "none",
            "--duration",
            "20",
            "--body-p-sensor",
            POSE,
        ],
    );
    let imu = dir.join("imu.csv");
    let out = json(&[
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--body-p-sensor",
        POSE,
    ]);
    let (roll, pitch, _) = truth_at(&dir, 0).q.euler_angles();
    let (br, bp) = (
        out["body_roll"].as_f64().unwrap(),
        out["body_pitch"].as_f64().unwrap(),
    );
    println!(
        "body roll {br} pitch {bp}; truth {roll} {pitch}; IMU roll {} pitch {}",
        out["roll"], out["pitch"]
    );
    assert!(
        (br - roll).abs() < 1e-6 && (bp - pitch).abs() < 1e-6,
        "{br} {bp} vs {roll} {pitch}"
    );
    let imu_roll = out["roll"].as_f64().unwrap();
    assert!(
        (imu_roll - roll).abs() > 0.1,
        "the IMU's own roll differs from the body's"
    );
}

/// Both frames at once: an IMU mounted away from the body origin on a rig moving in a rotating
/// (Earth) frame. `integrate --body-p-sensor … --omega-coriolis … --initial-state` (the body's
/// true state at t_i) predicts the body's state at t_j to the 4th-order scheme's accuracy.
#[test]
fn lever_arm_and_earth_rotation_together_predict_the_body_state() {
    let dir = tmp("extrinsics-earth");
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--noise",
            "none",
            "--duration",
            "3",
            "--body-p-sensor",
            POSE,
            "--latitude",
            "45",
        ],
    );
    let imu = dir.join("imu.csv");
    let (t_i, t_j) = (1_000_000_000i64, 2_000_000_000i64);
    let start = truth_at(&dir, t_i);
    let (p, q, v) = (start.p, start.q, start.v);
    let init = format!(
        "{},{},{},{},{},{},{},{},{},{}",
        p.x, p.y, p.z, v.x, v.y, v.z, q.w, q.i, q.j, q.k
    );
    let phi = 45f64.to_radians();
    let omega = 7.292115e-5;
    let rate = format!("0,{},{}", omega * phi.cos(), omega * phi.sin());
    let out = json(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--scheme",
        "hermite4",
        "--from",
        &t_i.to_string(),
        "--to",
        &t_j.to_string(),
        "--body-p-sensor",
        POSE,
        "--omega-coriolis",
        &rate,
        "--initial-state",
        &init,
    ]);
    let end = truth_at(&dir, t_j);
    let (pj, vj) = (end.p, end.v);
    let pp = nums(&out["predicted"]["position"]);
    let pv = nums(&out["predicted"]["velocity"]);
    let ep = (Vector3::new(pp[0], pp[1], pp[2]) - pj).norm();
    let ev = (Vector3::new(pv[0], pv[1], pv[2]) - vj).norm();
    println!("predicted body state at t_j: |δp| {ep:.2e} m, |δv| {ev:.2e} m/s");
    assert!(ep < 1e-5 && ev < 1e-5, "{ep:e} {ev:e}");
}

/// `--bias-correction` is read by the preintegrating subcommands: `additive` and `group` are
/// accepted (the window's deltas do not depend on it: the correction applies at another bias),
/// anything else is refused with a message naming the flag's values.
#[test]
fn bias_correction_flag_is_parsed() {
    let dir = tmp("bias-correction-flag");
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--noise",
            "none",
            "--duration",
            "2",
        ],
    );
    let imu = dir.join("imu.csv");
    let imu = imu.to_str().unwrap();
    let base = [
        "integrate",
        "--imu",
        imu,
        "--scheme",
        "galilean",
        "--from",
        "500000000",
        "--to",
        "1500000000",
    ];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a
    };
    let plain = json(&base);
    for c in ["additive", "group"] {
        let out = json(&with(&["--bias-correction", c]));
        assert_eq!(out["delta_v"], plain["delta_v"], "{c}");
    }
    let bad = run(&with(&["--bias-correction", "multiplicative"]));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("use additive or group"),
        "{err}"
    );
}
