//! The goodness of fit at the surface: `calibrate` names the convention error of a pose file
//! whose fit is not credible (EuRoC V1_01's ground truth transformed by each error), raises no
//! alarm on the ground truth as it is nor on simulated data, prints σ modelled and scaled, and
//! `--strict` refuses a fit that is not credible; `factor` and `allan` print their fit.

mod common;

use common::{json, repo, run, tmp, vec3, write};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;

const IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";
/// 5 s of the motion (10 poses 0.5 s apart).
const SPAN: [&str; 4] = [
    "--from",
    "1403715280000000000",
    "--to",
    "1403715285000000000",
];
/// EuRoC's motion-capture noise.
const POSE_STD: [&str; 4] = ["--pose-rot-std", "1.75e-3", "--pose-pos-std", "0.005"];

/// The ground truth's rows `(t, p, q body → world)`.
fn ground_truth() -> Vec<(String, Vector3<f64>, UnitQuaternion<f64>)> {
    std::fs::read_to_string(repo(GT))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let v: Vec<f64> = f[1..8].iter().map(|x| x.parse().unwrap()).collect();
            let q = Quaternion::new(v[3], v[4], v[5], v[6]);
            (
                f[0].to_string(),
                Vector3::new(v[0], v[1], v[2]),
                UnitQuaternion::from_quaternion(q),
            )
        })
        .collect()
}

/// The ground truth with each pose mapped by `f`, as `t,x,y,z,qw,qx,qy,qz` (or, with
/// `xyzw`, the quaternion columns in x,y,z,w order).
fn poses_file(
    name: &str,
    xyzw: bool,
    f: impl Fn(Vector3<f64>, UnitQuaternion<f64>) -> (Vector3<f64>, UnitQuaternion<f64>),
) -> String {
    let mut out = String::from("#t,x,y,z,q0,q1,q2,q3\n");
    for (t, p, q) in ground_truth() {
        let (p, q) = f(p, q);
        let c = if xyzw {
            [q.i, q.j, q.k, q.w]
        } else {
            [q.w, q.i, q.j, q.k]
        };
        out.push_str(&format!(
            "{t},{},{},{},{},{},{},{}\n",
            p.x, p.y, p.z, c[0], c[1], c[2], c[3]
        ));
    }
    write(&tmp("calibrate-fit"), name, &out)
        .display()
        .to_string()
}

fn calibrate(poses: &str, extra: &[&str]) -> Value {
    let imu = repo(IMU);
    let mut a = vec!["calibrate", "--imu", &imu, "--poses", poses];
    a.extend_from_slice(&SPAN);
    a.extend_from_slice(&POSE_STD);
    a.extend_from_slice(extra);
    json(&a)
}

fn why(out: &Value) -> String {
    out["fit"]["why"].as_str().unwrap().to_string()
}

/// Each convention error of the poses makes the fit not credible, and the diagnosis names it
/// with the χ²/dof the poses would have without it.
#[test]
fn pose_convention_errors_are_named() {
    // 180° about x: a world with z down.
    let ned = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
    let x =
        UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 0.0, 0.4) * (30f64.to_radians() / 0.5));
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "xyzw",
            poses_file("xyzw.csv", true, |p, q| (p, q)),
            "x,y,z,w order",
        ),
        (
            "inverse",
            poses_file("inverse.csv", false, |p, q| (p, q.inverse())),
            "world → body rotations",
        ),
        (
            "z down",
            poses_file("ned.csv", false, |p, q| (ned * p, ned * q)),
            "z down",
        ),
        (
            "frame",
            poses_file("frame.csv", false, |p, q| (p, q * x.inverse())),
            "another frame, rotated by",
        ),
    ];
    for (name, file, expect) in &cases {
        let out = calibrate(file, &[]);
        let w = why(&out);
        assert_eq!(out["fit"]["credible"], false, "{name}: {out}");
        assert!(w.contains(expect), "{name}: {w}");
        assert!(w.contains("instead of"), "{name}: {w}");
    }
    // The frame's rotation is given as --body-p-sensor's quaternion, within 2° (the hand-eye
    // fit of 9 windows, gyro bias removed as their mean).
    let w = why(&calibrate(&cases[3].1, &[]));
    let tail = w.split("--body-p-sensor 0,0,0,").nth(1).unwrap();
    let q: Vec<f64> = tail
        .split(' ')
        .next()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let found = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
    assert!(found.angle_to(&x).to_degrees() < 2.0, "{found} vs {x}");
    // Text: a warning line; --strict: the same output, then exit 2.
    let imu = repo(IMU);
    let mut a = vec!["calibrate", "--imu", &imu, "--poses", &cases[0].1];
    a.extend_from_slice(&SPAN);
    a.extend_from_slice(&POSE_STD);
    let text = String::from_utf8(run(&a).stdout).unwrap();
    assert!(
        text.lines().any(|l| l
            .starts_with("warning: the known-pose calibration fit is not credible")
            && l.contains("x,y,z,w")),
        "{text}"
    );
    a.push("--strict");
    let o = run(&a);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stdout).contains("warning:"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("(--strict)"));
}

/// Attitudes only (a 5-column file, the gyroscope problem) in x,y,z,w order: named too; in
/// w,x,y,z order credible.
#[test]
fn attitude_convention_errors_are_named() {
    let file = |name: &str, xyzw: bool| {
        let mut out = String::from("#t,q0,q1,q2,q3\n");
        for (t, _, q) in ground_truth() {
            let c = if xyzw {
                [q.i, q.j, q.k, q.w]
            } else {
                [q.w, q.i, q.j, q.k]
            };
            out.push_str(&format!("{t},{},{},{},{}\n", c[0], c[1], c[2], c[3]));
        }
        write(&tmp("calibrate-fit"), name, &out)
            .display()
            .to_string()
    };
    let bad = calibrate(&file("att_xyzw.csv", true), &[]);
    assert_eq!(bad["model"], "known-attitudes", "{bad}");
    assert_eq!(bad["fit"]["credible"], false, "{bad}");
    assert!(why(&bad).contains("x,y,z,w order"), "{}", why(&bad));
    let good = calibrate(&file("att.csv", false), &["--strict"]);
    assert_eq!(good["fit"]["credible"], true, "{good}");
}

/// The ground truth as it is, with EuRoC's motion-capture noise, and simulated data: credible,
/// no warning, `--strict` passes; every σ has its scaled twin, `σ·√(χ²/dof)`.
#[test]
fn credible_fits_raise_no_alarm() {
    let gt = repo(GT);
    let out = calibrate(&gt, &["--estimate", "time-offset", "--strict"]);
    assert_eq!(out["fit"]["credible"], true, "{out}");
    assert_eq!(out["notes"], serde_json::json!([]));
    let scale = out["fit"]["scale"].as_f64().unwrap();
    let chi2_dof = out["chi2"].as_f64().unwrap() / out["dof"].as_f64().unwrap();
    assert!((scale - chi2_dof.sqrt()).abs() < 1e-12, "{out}");
    for key in ["gyro_bias_std", "acc_bias_std", "gravity_std"] {
        let (s, t) = (vec3(&out[key]), vec3(&out[&format!("{key}_scaled")]));
        for k in 0..3 {
            assert!((t[k] - s[k] * scale).abs() <= 1e-12 * s[k].abs(), "{key}");
        }
    }
    let p = &out["parameters"][0];
    assert_eq!(p["name"], "t_d");
    let (s, t) = (
        p["std"].as_f64().unwrap(),
        p["std_scaled"].as_f64().unwrap(),
    );
    assert!((t - s * scale).abs() <= 1e-12 * s, "{p}");
    let imu = repo(IMU);
    let mut a = vec!["calibrate", "--imu", &imu, "--poses", &gt];
    a.extend_from_slice(&SPAN);
    a.extend_from_slice(&POSE_STD);
    let text = String::from_utf8(run(&a).stdout).unwrap();
    assert!(!text.contains("warning:"), "{text}");
    assert!(text.contains("scaled by √(χ²/dof) = "), "{text}");
    assert!(
        text.contains("fit of the known-pose calibration: credible"),
        "{text}"
    );

    let d = tmp("calibrate-fit-sim");
    common::simulate(
        &d,
        &["--scene", "aggressive", "--duration", "10", "--seed", "5"],
    );
    let out = json(&[
        "calibrate",
        "--imu",
        d.join("imu.csv").to_str().unwrap(),
        "--poses",
        d.join("groundtruth.csv").to_str().unwrap(),
        "--strict",
    ]);
    assert_eq!(out["fit"]["credible"], true, "{out}");
}

/// `--scheme` is the known-pose windows' and is recorded by `--out`; `integrate --calibration`
/// warns when its scheme lags differently (half of 5 ms at 200 Hz), and notes an unknown one.
#[test]
fn the_scheme_is_recorded_and_checked() {
    let d = tmp("calibrate-fit-scheme");
    common::simulate(
        &d,
        &["--scene", "aggressive", "--duration", "6", "--seed", "7"],
    );
    let imu = d.join("imu.csv").display().to_string();
    let cal = d.join("calib.yaml").display().to_string();
    let out = json(&[
        "calibrate",
        "--imu",
        &imu,
        "--poses",
        d.join("groundtruth.csv").to_str().unwrap(),
        "--estimate",
        "time-offset",
        "--scheme",
        "euler",
        "--out",
        &cal,
    ]);
    assert_eq!(out["scheme"], "euler", "{out}");
    let text = std::fs::read_to_string(&cal).unwrap();
    assert!(text.contains("preint_scheme: \"euler\""), "{text}");
    let window = ["--from", "2000000000", "--to", "3000000000"];
    let integrate = |cal: &str, scheme: &str| {
        let mut a = vec![
            "integrate",
            "--imu",
            &imu,
            "--calibration",
            cal,
            "--scheme",
            scheme,
        ];
        a.extend_from_slice(&window);
        json(&a)["calibration"].clone()
    };
    let c = integrate(&cal, "midpoint");
    assert_eq!(c["scheme"], "euler");
    let note = c["scheme_note"].as_str().unwrap();
    assert!(
        note.starts_with("warning:") && note.contains("2.500 ms"),
        "{note}"
    );
    assert!(note.contains("calibrate --scheme midpoint"), "{note}");
    assert!(integrate(&cal, "galilean")["scheme_note"].is_null());
    // Without the key: a note that the scheme is unknown.
    let without: String = text
        .lines()
        .filter(|l| !l.contains("preint_scheme"))
        .map(|l| format!("{l}\n"))
        .collect();
    let bare = write(&d, "bare.yaml", &without);
    let c = integrate(bare.to_str().unwrap(), "euler");
    assert!(c["scheme"].is_null());
    let note = c["scheme_note"].as_str().unwrap();
    assert!(
        note.starts_with("note:") && note.contains("does not record"),
        "{note}"
    );
}

/// A calibration file with nothing to apply, or with intrinsics no IMU has, is refused naming
/// the file (and the line and key).
#[test]
fn empty_and_implausible_calibration_files_are_refused() {
    let d = tmp("calibrate-fit-files");
    let imu = repo(IMU);
    let refused = |file: &std::path::Path| {
        let o = run(&[
            "integrate",
            "--imu",
            &imu,
            "--calibration",
            file.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let empty = write(&d, "empty.yaml", "");
    let e = refused(&empty);
    assert!(
        e.contains("empty.yaml") && e.contains("nothing to apply"),
        "{e}"
    );
    let noise_only = write(&d, "noise.yaml", "imu0:\n  model: \"kalibr\"\n");
    assert!(refused(&noise_only).contains("nothing to apply"));
    let big = write(
        &d,
        "big.yaml",
        "imu0:\n  model: \"kalibr\"\n  Ta:\n    - [ 1.0, 0.0, 0.0 ]\n    - [ 0.0, 1.0, 0.0 ]\n    \
         - [ 0.0, 0.0, 9.81 ]\n",
    );
    let e = refused(&big);
    assert!(e.contains("big.yaml:4:") && e.contains("`imu0.Ta`"), "{e}");
    assert!(e.contains("preint_unusual_intrinsics"), "{e}");
}

/// `factor` and `allan` print their fit: the factor's χ² against χ²₉ (with noise densities a
/// hundred times too small and the ground truth taken as exact it is not credible, and `--strict` refuses it), the Allan model
/// against the real ADIS16405 curve (credible).
#[test]
fn factor_and_allan_print_their_fit() {
    let (imu, gt) = (repo(IMU), repo(GT));
    let d = tmp("calibrate-fit-factor");
    let tiny = common::write_noise_yaml(&d, "tiny.yaml", [1.7e-6, 1.9e-7, 2e-5, 3e-5], 200.0);
    let mut a = vec![
        "factor",
        "--imu",
        &imu,
        "--poses",
        &gt,
        "--from",
        "1403715280000000000",
        "--to",
        "1403715281000000000",
        "--pose-rot-std",
        "1.75e-3",
        "--pose-pos-std",
        "0.005",
        "--vel-std",
        "0.01",
    ];
    let out = json(&a);
    assert_eq!(out["fit"]["dof"], 9);
    assert_eq!(
        out["fit"]["credible"],
        out["fit"]["p_value"].as_f64().unwrap() >= 1e-6
    );
    let tiny = tiny.display().to_string();
    // The ground truth taken as exact, so that the IMU noise alone weighs the factor.
    a.truncate(9);
    a.extend_from_slice(&["--noise", &tiny]);
    let bad = json(&a);
    assert_eq!(bad["fit"]["credible"], false, "{bad}");
    assert!(why(&bad).contains("block"), "{bad}");
    a.push("--strict");
    assert_eq!(run(&a).status.code(), Some(2));

    let adis = repo("tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv");
    let out = json(&["allan", "--imu", &adis, "--strict"]);
    assert_eq!(out["fit"]["credible"], true, "{}", out["fit"]);
    assert!(out["fit"]["p_value"].is_null());
    assert!(why(&out).contains("statistical errors"));
}
