//! End-to-end tests of the `preint` binary on real recordings (`tests/data`, see its README):
//! `integrate` and `calibrate` on EuRoC V1_01 against its ground truth, `allan` on the static
//! ADIS16405 hour against the curators' Allan deviations, and `speed`'s output contract.

mod common;

use common::{json, matrix, repo, run, tmp, vec3, write_imu_csv};
use nalgebra::{Matrix3, Vector3};
use preint_io::read_euroc_groundtruth;

const EUROC_IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const EUROC_GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";

fn arg3(v: &Vector3<f64>) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

fn mat(v: &serde_json::Value) -> Matrix3<f64> {
    let r = matrix(v);
    Matrix3::from_fn(|i, j| r[i][j])
}

/// `integrate` on 1 s EuRoC windows from the ground-truth biases reproduces the ground truth's
/// relative rotation and velocity change. The pair's own floor (data README, curators' midpoint
/// run) is 0.10° and 0.045 m/s median; we allow 0.3° and 0.15 m/s per window (a sign, frame or
/// unit error gives degrees and metres per second).
#[test]
fn integrate_follows_euroc_ground_truth() {
    let gt = read_euroc_groundtruth(std::path::Path::new(&repo(EUROC_GT))).unwrap();
    let g = Vector3::new(0.0, 0.0, -9.81);
    let mut checked = 0;
    for i in (20..gt.len()).step_by(500).take(5) {
        let gi = &gt[i];
        let gj = &gt[i + 20]; // 20 Hz rows: 1 s later
        let dt = (gj.t_ns - gi.t_ns) as f64 * 1e-9;
        assert!((dt - 1.0).abs() < 1e-3);
        let out = json(&[
            "integrate",
            "--imu",
            &repo(EUROC_IMU),
            "--from",
            &gi.t_ns.to_string(),
            "--to",
            &gj.t_ns.to_string(),
            &format!("--bias-gyro={}", arg3(&gi.bias.gyro)),
            &format!("--bias-acc={}", arg3(&gi.bias.acc)),
        ]);
        assert_eq!(out["t_i_ns"], gi.t_ns);
        assert_eq!(out["t_j_ns"], gj.t_ns);
        let dr = mat(&out["delta_R"]);
        let (ri, rj) = (*gi.rotation().matrix(), *gj.rotation().matrix());
        let e = (dr.transpose() * ri.transpose() * rj).trace();
        let ang = ((e - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(ang < 0.3, "window {i}: rotation error {ang}°");
        let dv_gt = ri.transpose() * (gj.v - gi.v - g * dt);
        let dv = Vector3::from(vec3(&out["delta_v"]));
        assert!(
            (dv - dv_gt).norm() < 0.15,
            "window {i}: Δv {dv:?} vs ground truth {dv_gt:?}"
        );
        checked += 1;
    }
    assert_eq!(checked, 5);
}

/// `calibrate --poses` on 40 s of EuRoC with the vicon2gt attitudes and positions as known
/// poses (pose noise 0.1° and 5 mm, as preint-calib's EuRoC test). vicon2gt estimates a
/// time-varying bias; our constant-bias estimate is compared with its average over the segment: within 2e-3 rad/s for the gyro (about 20× our σ; the
/// reference's own bias varies by ≈ 1e-3 rad/s over the segment) and 0.05 m/s² for the
/// accelerometer (its bias reference varies by several 0.01 m/s² over the run).
#[test]
fn calibrate_with_known_poses_on_euroc() {
    let gt = read_euroc_groundtruth(std::path::Path::new(&repo(EUROC_GT))).unwrap();
    let (from, to) = (gt[100].t_ns, gt[100].t_ns + 40_000_000_000);
    let out = json(&[
        "calibrate",
        "--imu",
        &repo(EUROC_IMU),
        "--poses",
        &repo(EUROC_GT),
        "--from",
        &from.to_string(),
        "--to",
        &to.to_string(),
        "--pose-rot-std",
        "1.75e-3",
        "--pose-pos-std",
        "0.005",
    ]);
    assert_eq!(out["model"], "known-poses");
    let sel: Vec<_> = gt
        .iter()
        .filter(|r| r.t_ns >= from && r.t_ns <= to)
        .collect();
    let n = sel.len() as f64;
    let bg = sel.iter().map(|r| r.bias.gyro).sum::<Vector3<f64>>() / n;
    let ba = sel.iter().map(|r| r.bias.acc).sum::<Vector3<f64>>() / n;
    let (eg, ea) = (
        Vector3::from(vec3(&out["gyro_bias"])),
        Vector3::from(vec3(&out["acc_bias"])),
    );
    assert!((eg - bg).amax() < 2e-3, "b_g {eg:?} vs vicon2gt {bg:?}");
    assert!((ea - ba).amax() < 0.05, "b_a {ea:?} vs vicon2gt {ba:?}");
}

/// `allan` on the real static ADIS16405 hour (tests/data/adis16405: 10 Hz block means, gyro in
/// deg/s, accelerometer in g, seconds). The reader takes the units from the header's names;
/// the result must equal that of the same data converted here by hand to EuRoC (ns, rad/s,
/// m/s²). The fitted white-noise densities are checked against the curators' overlapping Allan
/// deviations of the raw 100 Hz run (source and x-axis figures in tests/data/README.md), which
/// do not come from this code:
/// - gyro: white noise dominates from 0.1 to 1 s (σ falls by √10 there: 0.125 → 0.041 deg/s on
///   x), so N = σ(1 s) within 15 % (0.041/0.043/0.039 deg/s);
/// - accelerometer: σ falls by only ≈ 2 between 0.1 and 1 s, so other noise matters at 1 s. Allan
///   variances of independent noises add, so the white part can nowhere exceed the total:
///   N ≤ min(σ(1 s)·1, σ(0.1 s)·√0.1) (+5 % for the estimate's own scatter) and, as the
///   dominant term at 0.1 s, N ≥ half that bound. σ(0.1 s) = 0.0014/0.0012/0.0015 g,
///   σ(1 s) = 0.00072/0.00051/0.00062 g.
#[test]
fn allan_on_the_static_adis16405_hour() {
    let src = repo("tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv");
    let direct = json(&["allan", "--imu", &src]);
    let text = std::fs::read_to_string(&src).unwrap();
    let d2r = std::f64::consts::PI / 180.0;
    let rows: Vec<(i64, [f64; 6])> = text
        .lines()
        .skip(1)
        .enumerate()
        .map(|(k, line)| {
            let c: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let (w, a) = (d2r, 9.80665);
            let v = [c[1] * w, c[2] * w, c[3] * w, c[4] * a, c[5] * a, c[6] * a];
            (k as i64 * 100_000_000, v)
        })
        .collect();
    let d = tmp("adis");
    let f = write_imu_csv(&d, "adis_euroc.csv", &rows);
    let out = json(&[
        "allan",
        "--imu",
        f.to_str().unwrap(),
        "--out",
        d.to_str().unwrap(),
    ]);
    for key in ["gyroscope_noise_density", "accelerometer_noise_density"] {
        assert_eq!(
            direct[key], out[key],
            "{key}: read directly vs converted by hand"
        );
    }
    let n_g = vec3(&out["gyroscope_noise_density"]);
    for (i, r) in [0.041, 0.043, 0.039].iter().enumerate() {
        let r = f64::to_radians(*r);
        assert!(
            (n_g[i] / r - 1.0).abs() < 0.15,
            "gyroscope_noise_density[{i}]: {:.3e} vs curators' σ(1 s) {r:.3e}",
            n_g[i]
        );
    }
    let n_a = vec3(&out["accelerometer_noise_density"]);
    let (s1, s01) = ([0.00072, 0.00051, 0.00062], [0.0014, 0.0012, 0.0015]);
    for i in 0..3 {
        let bound = 9.80665 * f64::min(s1[i], s01[i] * 0.1f64.sqrt());
        assert!(
            n_a[i] <= 1.05 * bound && n_a[i] >= 0.5 * bound,
            "accelerometer_noise_density[{i}]: {:.3e} outside [0.5, 1.05]·{bound:.3e} (the white \
             part of the curators' Allan deviation)",
            n_a[i]
        );
    }
    let yaml = std::fs::read_to_string(d.join("imu.yaml")).unwrap();
    let noise = preint_io::parse_kalibr_yaml(&yaml, "imu.yaml").expect("valid Kalibr yaml");
    assert!((noise.update_rate_hz - 10.0).abs() < 1e-9, "{noise:?}");
}

/// `speed` prints every scheme at every level, as finite positive ns/sample (no timing is
/// asserted: speed is measured by `speed` itself and the criterion benches).
#[test]
fn speed_reports_every_scheme_and_level() {
    let out = json(&["speed", "--samples", "2000"]);
    let schemes = out["schemes"].as_array().unwrap();
    let names: Vec<&str> = schemes
        .iter()
        .map(|s| s["scheme"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["euler", "midpoint", "hermite4", "galilean"]);
    for s in schemes {
        for level in ["deltas", "covariance", "combined"] {
            let v = s["ns_per_sample"][level].as_f64().unwrap();
            assert!(v.is_finite() && v > 0.0, "{s}");
        }
    }
    let o = run(&["speed", "--samples", "3"]);
    assert_eq!(o.status.code(), Some(2));
}

/// `convert` checks units before it writes rad/s and m/s²: the ADIS block means (deg/s, g)
/// under a header that names no unit are refused as read; with the unit flags they convert to
/// the hand-scaled values.
#[test]
fn convert_refuses_undeclared_deg_per_s_and_g_and_converts_them_when_declared() {
    let src = std::fs::read_to_string(repo(
        "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv",
    ))
    .unwrap();
    let mut lines = src.lines();
    lines.next();
    let rows: Vec<&str> = lines.take(3000).collect();
    let dir = tmp("convert-units");
    let input = dir.join("plain.csv");
    std::fs::write(
        &input,
        format!("t,wx,wy,wz,ax,ay,az\n{}\n", rows.join("\n")),
    )
    .unwrap();
    let out = dir.join("imu.csv");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let refused = run(&["convert", "--imu", i, "--out", o, "--time-unit", "s"]);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2));
    assert!(err.contains("--accel-unit g"), "{err}");
    json(&[
        "convert",
        "--imu",
        i,
        "--out",
        o,
        "--time-unit",
        "s",
        "--gyro-unit",
        "deg/s",
        "--accel-unit",
        "g",
    ]);
    let written = std::fs::read_to_string(&out).unwrap();
    let written: Vec<&str> = written.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(written.len(), rows.len());
    for (w, r) in written.iter().zip(&rows) {
        let w: Vec<f64> = w.split(',').map(|x| x.parse().unwrap()).collect();
        let r: Vec<f64> = r.split(',').map(|x| x.parse().unwrap()).collect();
        for k in 0..3 {
            assert!(
                (w[1 + k] - r[1 + k].to_radians()).abs() <= 1e-15,
                "{w:?} {r:?}"
            );
            assert!(
                (w[4 + k] - r[4 + k] * 9.80665).abs() <= 1e-14,
                "{w:?} {r:?}"
            );
        }
    }
}
