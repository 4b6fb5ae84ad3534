//! `calibrate --estimate extrinsic-rotation,lever-arm` through the binary: `simulate` mounts
//! the IMU at a hidden pose in the body (the ground truth is the body's); `calibrate` recovers
//! it without an initial guess (JSON `extrinsics`), `--out` writes it into the calibration file
//! and Kalibr's `camchain-imucam.yaml`, and `integrate --calibration` applies it exactly as
//! `--body-p-sensor` would.

mod common;

use common::{json, nums, run, simulate, tmp};

/// 0.3 m lever arm along (1, −2, 2)/3; rotation 60° about (1, 1, 1)/√3 (sensor → body).
const POSE: [f64; 7] = [
    0.1,
    -0.2,
    0.2,
    0.8660254037844387,
    0.28867513459481287,
    0.28867513459481287,
    0.28867513459481287,
];

#[test]
fn a_hidden_imu_pose_is_recovered_written_and_applied() {
    let dir = tmp("calibrate-extrinsics");
    let pose: Vec<String> = POSE.iter().map(|v| v.to_string()).collect();
    let pose = pose.join(",");
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--duration",
            "8",
            "--body-p-sensor",
            &pose,
        ],
    );
    let (imu, gt) = (dir.join("imu.csv"), dir.join("groundtruth.csv"));
    let out = dir.join("cal.yaml");
    let args = [
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
        "--pose-spacing",
        "0.1",
        "--scheme",
        "hermite4",
        "--estimate",
        "extrinsic-rotation,lever-arm",
        "--out",
        out.to_str().unwrap(),
    ];
    let c = json(&args);
    let e = &c["extrinsics"];
    assert_eq!(e["start"], "hand-eye", "{e}");
    assert_eq!(e["excited"]["rotation"], true, "{e}");
    assert_eq!(e["excited"]["lever_arm"], true, "{e}");
    assert!(e["tangent"].as_str().unwrap().contains("R_bs*Exp"), "{e}");
    let est = nums(&e["body_p_sensor"]);
    let std = nums(&e["std"]);
    // The lever arm within 3σ; the quaternion within 3σ of the rotation (|δq| ≈ |δθ|/2).
    for k in 0..3 {
        assert!(
            (est[k] - POSE[k]).abs() <= 3.0 * std[3 + k],
            "{k}: {est:?} ± {std:?}"
        );
        assert!(
            (est[4 + k] - POSE[4 + k]).abs() <= 3.0 * std[..3].iter().cloned().fold(0.0, f64::max),
            "{k}: {est:?} ± {std:?}"
        );
    }
    let cov = &e["covariance"];
    assert_eq!(cov.as_array().unwrap().len(), 6);
    let text = String::from_utf8_lossy(&run(&args[..args.len() - 2]).stdout).to_string();
    assert!(
        text.contains("IMU in the frame of the poses: --body-p-sensor")
            && text.contains("p_bs.x ="),
        "{text}"
    );
    // The files: the calibration file's key and Kalibr's T_cam_imu (its last column the lever
    // arm, its rotation R_bs).
    let file = std::fs::read_to_string(&out).unwrap();
    assert!(file.contains("preint_body_p_sensor: ["), "{file}");
    let cc = std::fs::read_to_string(dir.join("cal-camchain-imucam.yaml")).unwrap();
    assert!(
        cc.contains("T_cam_imu:") && cc.contains("timeshift_cam_imu: 0.0"),
        "{cc}"
    );
    let row0: Vec<f64> = cc
        .lines()
        .nth(2)
        .unwrap()
        .trim()
        .trim_start_matches("- [")
        .trim_end_matches(']')
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert!((row0[3] - est[0]).abs() < 1e-12, "{cc}");
    // integrate --calibration applies it as --body-p-sensor does, to the last bit.
    let window = ["--from", "2000000000", "--to", "3000000000"];
    let mut with_file = vec![
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--calibration",
        out.to_str().unwrap(),
    ];
    with_file.extend_from_slice(&window);
    let a = json(&with_file);
    // The flag from the file's text (serde_json's float parsing may differ by an ulp).
    let line = file
        .lines()
        .find(|l| l.contains("preint_body_p_sensor"))
        .unwrap();
    let flag: String = line[line.find('[').unwrap() + 1..line.find(']').unwrap()]
        .split(',')
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(",");
    let mut with_flag = vec![
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--body-p-sensor",
        &flag,
    ];
    with_flag.extend_from_slice(&window);
    let b = json(&with_flag);
    assert_eq!(a["delta_v"], b["delta_v"], "{a} {b}");
    assert_eq!(a["delta_p"], b["delta_p"]);
    let applied = nums(&a["calibration"]["body_p_sensor"]);
    assert!(
        applied.iter().zip(&est).all(|(a, b)| (a - b).abs() < 1e-15),
        "{applied:?}"
    );
    // Both at once is a usage error naming the two.
    let mut both = with_file.clone();
    both.extend_from_slice(&["--body-p-sensor", &flag]);
    let o = run(&both);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(
        msg.contains("preint_body_p_sensor") && msg.contains("--body-p-sensor"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
