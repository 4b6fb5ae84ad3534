//! End-to-end tests of `preint calibrate` on simulated recordings (`preint simulate`, whose
//! `groundtruth.csv` carries the true biases at every sample): each of the three problems is
//! chosen from the data, and its estimates agree with the truth within their reported σ.
//!
//! The simulated biases follow a random walk (EuRoC densities), so the reference for a constant
//! bias estimate is the time average of the true bias over the samples used.

mod common;

use common::{json, run, tmp, vec3, write, write_imu_csv};
use nalgebra::Vector3;
use preint_io::read_euroc_groundtruth;
use std::path::Path;

/// Mean true bias (gyro, acc) over the ground-truth rows with `from ≤ t ≤ to`.
fn mean_true_bias(gt: &Path, from: i64, to: i64) -> (Vector3<f64>, Vector3<f64>) {
    let rows = read_euroc_groundtruth(gt).expect("read groundtruth.csv");
    let sel: Vec<_> = rows
        .iter()
        .filter(|r| r.t_ns >= from && r.t_ns <= to)
        .collect();
    assert!(!sel.is_empty());
    let n = sel.len() as f64;
    (
        sel.iter().map(|r| r.bias.gyro).sum::<Vector3<f64>>() / n,
        sel.iter().map(|r| r.bias.acc).sum::<Vector3<f64>>() / n,
    )
}

fn simulate(scene: &str, duration: &str, seed: &str, name: &str) -> std::path::PathBuf {
    let d = tmp(name);
    common::simulate(
        &d,
        &["--scene", scene, "--duration", duration, "--seed", seed],
    );
    d
}

fn within(est: [f64; 3], std: [f64; 3], truth: &Vector3<f64>, k: f64, what: &str) {
    for i in 0..3 {
        let z = (est[i] - truth[i]) / std[i];
        assert!(
            std[i] > 0.0 && z.abs() <= k,
            "{what}[{i}]: estimate {:.3e}, truth {:.3e}, σ {:.1e} ({z:.2}σ)",
            est[i],
            truth[i],
            std[i]
        );
    }
}

/// Both bias estimates of `out` within `k`σ of the truth `(bg, ba)`.
fn biases_within(out: &serde_json::Value, bg: &Vector3<f64>, ba: &Vector3<f64>, k: f64) {
    within(
        vec3(&out["gyro_bias"]),
        vec3(&out["gyro_bias_std"]),
        bg,
        k,
        "gyro bias",
    );
    within(
        vec3(&out["acc_bias"]),
        vec3(&out["acc_bias_std"]),
        ba,
        k,
        "acc bias",
    );
}

#[test]
fn static_single_attitude_reports_acc_bias_unobservable() {
    let d = simulate("static", "120", "11", "cal-static");
    let out = json(&["calibrate", "--imu", d.join("imu.csv").to_str().unwrap()]);
    assert_eq!(out["model"], "static-single-attitude", "{out}");
    assert!(out["acc_bias"].is_null(), "{out}");
    let unobs: Vec<&str> = out["unobservable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(
        unobs.contains(&"acc_bias") && unobs.contains(&"yaw"),
        "{unobs:?}"
    );
    // The estimate refers to the bias at mid-recording (the random walk's time average has
    // variance σ_bg²T/12 about it): reported σ² = σ_g²/T + σ_bg²T/12 (EuRoC densities, T = 120 s).
    let (bg, _) = mean_true_bias(&d.join("groundtruth.csv"), 60_000_000_000, 60_000_000_000);
    within(
        vec3(&out["gyro_bias"]),
        vec3(&out["gyro_bias_std"]),
        &bg,
        4.0,
        "gyro bias",
    );
    let t = 120.0;
    let expect = (1.6968e-4f64.powi(2) / t + 1.9393e-5f64.powi(2) * t / 12.0).sqrt();
    for s in vec3(&out["gyro_bias_std"]) {
        assert!((s / expect - 1.0).abs() < 0.01, "σ {s:e} vs {expect:e}");
    }
}

#[test]
fn multi_pose_recording_estimates_both_biases() {
    let d = simulate("multi-pose-static", "120", "12", "cal-multi");
    let out = json(&["calibrate", "--imu", d.join("imu.csv").to_str().unwrap()]);
    let model = out["model"].as_str().unwrap();
    assert!(model.starts_with("multi-pose/"), "{out}");
    assert!(out["still_intervals"].as_u64().unwrap() >= 6, "{out}");
    // The simulation has no scale error: the model selection must not invent one.
    assert_eq!(model, "multi-pose/BiasOnly", "reason: {}", out["reason"]);
    // The bias random walk is marginalised: the estimates refer to the bias at the reported
    // reference time.
    assert_eq!(out["random_walk_marginalised"], true);
    let t_ref = out["bias_reference_time_ns"].as_i64().unwrap();
    let (bg, ba) = mean_true_bias(
        &d.join("groundtruth.csv"),
        t_ref - 2_500_000,
        t_ref + 2_500_000,
    );
    biases_within(&out, &bg, &ba, 4.0);
}

#[test]
fn known_poses_estimate_biases_and_gravity() {
    let d = simulate("aggressive", "30", "13", "cal-poses");
    let gt = d.join("groundtruth.csv");
    let out = json(&[
        "calibrate",
        "--imu",
        d.join("imu.csv").to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
    ]);
    assert_eq!(out["model"], "known-poses", "{out}");
    assert!(out["poses"].as_u64().unwrap() >= 55, "{out}");
    let (bg, ba) = mean_true_bias(&gt, 0, i64::MAX);
    biases_within(&out, &bg, &ba, 4.0);
    // The simulated world has g = (0, 0, −9.81) exactly.
    let g = vec3(&out["gravity"]);
    let tilt = (g[2] / 9.81).abs().min(1.0).acos();
    assert!(g[2] < 0.0 && tilt < 1e-3, "gravity {g:?}");

    // A time range restricts samples and poses alike.
    let part = json(&[
        "calibrate",
        "--imu",
        d.join("imu.csv").to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
        "--from",
        "5000000000",
        "--to",
        "15000000000",
    ]);
    let n = part["poses"].as_u64().unwrap();
    assert!(
        (19..=21).contains(&n),
        "poses in 10 s at ≥ 0.5 s spacing: {n}"
    );
}

#[test]
fn calibrate_bad_input_is_a_usage_error() {
    let d = simulate("static", "5", "1", "cal-bad");
    let imu = d.join("imu.csv");
    for args in [
        vec!["--pose-rot-std=-1"],
        vec!["--gravity", "0"],
        vec!["--from", "9000000000000"],
    ] {
        let mut a = vec!["calibrate", "--imu", imu.to_str().unwrap()];
        a.extend(args.iter());
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with("preint: error:"), "{a:?}: {err}");
    }
    // Poses that do not overlap the samples.
    let poses = write(
        &d,
        "few.csv",
        "#t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz\n\
         99000000000,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0\n",
    );
    let o = run(&[
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        poses.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("few.csv") && err.contains("fewer than three poses"),
        "{err}"
    );
    // A solver error names the IMU file it came from.
    let at_rest = [0.0, 0.0, 0.0, 0.0, 0.0, 9.81];
    let short = write_imu_csv(&d, "two.csv", &[(1000, at_rest), (5_001_000, at_rest)]);
    let o = run(&["calibrate", "--imu", short.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && err.contains("two.csv: too few samples"),
        "{err}"
    );
}

/// Rows of an EuRoC IMU file as `write_imu_csv` takes them.
fn rows(path: &Path) -> Vec<(i64, [f64; 6])> {
    preint_io::read_euroc_imu(path)
        .unwrap()
        .iter()
        .map(|s| {
            let (g, a) = (s.gyro, s.acc);
            (s.t_ns, [g.x, g.y, g.z, a.x, a.y, a.z])
        })
        .collect()
}

/// 20 s at rest followed by 20 s of motion: without poses, the static problem runs on the
/// still part only (its gyro bias agrees with the truth there), not on every sample.
#[test]
fn static_calibration_uses_only_the_still_part() {
    let still = simulate("static", "20", "21", "cal-mixed-still");
    let moving = simulate("seed-ellipse", "20", "22", "cal-mixed-moving");
    let mut all = rows(&still.join("imu.csv"));
    let end = all.last().unwrap().0;
    all.extend(
        rows(&moving.join("imu.csv"))
            .iter()
            .map(|&(t, v)| (t + end + 5_000_000, v)),
    );
    let f = write_imu_csv(&still, "mixed.csv", &all);
    let out = json(&["calibrate", "--imu", f.to_str().unwrap()]);
    assert_eq!(out["model"], "static-single-attitude", "{out}");
    let [t0, t1] = [0, 1].map(|k| out["interval_ns"][k].as_i64().unwrap());
    assert!(
        t0 >= 0 && t1 <= end && t1 - t0 > 18_000_000_000,
        "{t0}..{t1}"
    );
    let mid = (t0 + t1) / 2;
    let (bg, _) = mean_true_bias(
        &still.join("groundtruth.csv"),
        mid - 2_500_000,
        mid + 2_500_000,
    );
    within(
        vec3(&out["gyro_bias"]),
        vec3(&out["gyro_bias_std"]),
        &bg,
        4.0,
        "gyro bias",
    );
    let recorded = out["recording_s"].as_f64().unwrap();
    assert!((recorded - 40.0).abs() < 0.1, "{recorded}");
}

/// A moving recording has no still interval: a static method cannot answer, so `calibrate`
/// without poses refuses (exit 2) and says why, on the flying EuRoC MAV.
#[test]
fn moving_recording_without_poses_is_refused() {
    let imu = common::repo("tests/data/euroc/V1_01_easy_imu0.csv");
    let noise = common::repo("tests/data/euroc/imu.yaml");
    let o = run(&["calibrate", "--imu", &imu, "--noise", &noise]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && err.contains("no still interval") && err.contains("--poses"),
        "{err}"
    );
}

/// A gap of 1 s is refused, naming the samples around it.
#[test]
fn gaps_are_refused() {
    let d = simulate("static", "5", "23", "cal-gap");
    let kept: Vec<_> = rows(&d.join("imu.csv"))
        .into_iter()
        .filter(|&(t, _)| !(2_000_000_000..3_000_000_000).contains(&t))
        .collect();
    let f = write_imu_csv(&d, "gap.csv", &kept);
    let o = run(&["calibrate", "--imu", f.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2)
            && err.contains("gap.csv: gap of 1.005000 s between samples 399 (t = 1995000000 ns)"),
        "{err}"
    );
}
