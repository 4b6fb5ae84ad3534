//! End-to-end tests of `preint audit`: the real recordings in tests/data are clean, with rates
//! and gaps equal to what their files give when read here; a duplicated row is a defect named
//! by its line, exit 0 without `--strict` and 2 with it; data read in the wrong units is a
//! units defect.

mod common;

use common::{json, repo, run, tmp, write};
use serde_json::Value;

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const KITTI: &str = "tests/data/kitti/KittiEquivBiasedImu_first120s.txt";
const ADIS: &str = "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv";

fn kinds(out: &Value, severity: &str) -> Vec<String> {
    out["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["severity"] == severity)
        .map(|f| f["kind"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn euroc_is_clean_at_the_rate_of_its_stamps() {
    let src = repo(EUROC);
    let out = json(&["audit", "--imu", &src]);
    assert_eq!(out["clean"], true, "{out:#}");
    assert_eq!(
        (out["defects"].as_u64(), out["warnings"].as_u64()),
        (Some(0), Some(0))
    );
    let text = std::fs::read_to_string(&src).unwrap();
    let t: Vec<i64> = (text.lines().skip(1))
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let n = t.len() as u64;
    assert_eq!(out["samples"].as_u64(), Some(n));
    assert_eq!(out["t_first_ns"].as_i64(), Some(t[0]));
    assert_eq!(out["t_last_ns"].as_i64(), Some(t[t.len() - 1]));
    let mean_rate = (n - 1) as f64 * 1e9 / (t[t.len() - 1] - t[0]) as f64;
    let rate = out["rate"]["nominal_hz"].as_f64().unwrap();
    assert!(
        (rate / mean_rate - 1.0).abs() < 2e-5,
        "{rate} vs {mean_rate}"
    );
    let binned: u64 = (out["histogram"].as_array().unwrap().iter())
        .map(|b| b["count"].as_u64().unwrap())
        .sum();
    assert_eq!(binned, n - 1);
    assert_eq!(out["gaps"]["count"], 0);
    assert_eq!(out["units"]["error"], Value::Null);
    let human = run(&["audit", "--imu", &src]);
    assert!(human.status.success());
    let stdout = String::from_utf8_lossy(&human.stdout);
    assert!(
        stdout.contains("verdict: clean (0 defects, 0 warnings)"),
        "{stdout}"
    );
}

#[test]
fn a_duplicated_row_is_a_defect_named_by_its_line_and_fails_only_with_strict() {
    // The first 1000 rows of EuRoC with row 300 (line 302) written twice: the copy is line 303.
    let text = std::fs::read_to_string(repo(EUROC)).unwrap();
    let mut lines: Vec<&str> = text.lines().take(1001).collect();
    lines.insert(302, lines[301]);
    let d = tmp("audit-dup");
    let f = write(&d, "dup.csv", &(lines.join("\n") + "\n"));
    let f = f.to_str().unwrap();
    let out = json(&["audit", "--imu", f]);
    assert_eq!(out["clean"], false);
    assert_eq!(kinds(&out, "defect"), ["duplicates"]);
    let dup = &out["duplicates"];
    assert_eq!(
        (dup["count"].as_u64(), dup["identical"].as_u64()),
        (Some(1), Some(1))
    );
    assert_eq!(dup["first"][0]["line"].as_u64(), Some(303));
    assert_eq!(dup["first"][0]["index"].as_u64(), Some(301));
    assert!(
        out["findings"][0]["message"]
            .as_str()
            .unwrap()
            .contains("index 301 (line 303)")
    );
    let strict = run(&["audit", "--imu", f, "--strict"]);
    assert_eq!(strict.status.code(), Some(2));
    let err = String::from_utf8_lossy(&strict.stderr);
    assert!(
        err.contains("1 duplicate timestamp: index 301 (line 303)"),
        "{err}"
    );
    // The report is printed with --strict too (stdout), with the JSON form under --json.
    let report = String::from_utf8_lossy(&strict.stdout);
    assert!(report.contains("index 301 (line 303)"), "{report}");
    let strict_json = run(&["audit", "--imu", f, "--strict", "--json"]);
    assert_eq!(strict_json.status.code(), Some(2));
    let v: serde_json::Value = serde_json::from_slice(&strict_json.stdout).unwrap();
    assert_eq!(v["findings"][0]["severity"], "defect");
    assert!(
        run(&["audit", "--imu", &repo(EUROC), "--strict"])
            .status
            .success()
    );
}

/// KITTI (GTSAM's text, seconds): clean, with one dropped sample whose place and size are found
/// here from the file's first column.
#[test]
fn kitti_is_read_with_its_format_and_its_dropped_sample_is_a_gap() {
    let src = repo(KITTI);
    let out = json(&["audit", "--imu", &src, "--format", "kitti"]);
    assert_eq!(out["clean"], true, "{out:#}");
    assert_eq!(out["input"]["format"], "kitti");
    let text = std::fs::read_to_string(&src).unwrap();
    let t: Vec<f64> = (text.lines().skip(1))
        .map(|l| l.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let gaps: Vec<usize> = (0..d.len()).filter(|&k| d[k] > 1.5 * 0.01).collect();
    assert_eq!(gaps.len(), 1);
    let g = &out["gaps"];
    assert_eq!(g["count"].as_u64(), Some(1));
    assert_eq!(g["largest"]["index"].as_u64(), Some(gaps[0] as u64 + 1));
    assert_eq!(g["largest"]["line"].as_u64(), Some(gaps[0] as u64 + 3));
    assert!((g["largest"]["dt_ns"].as_f64().unwrap() * 1e-9 - d[gaps[0]]).abs() < 1e-6);
    assert_eq!(kinds(&out, "warning"), ["gaps"]);
    d.sort_by(f64::total_cmp);
    let median = out["rate"]["median_interval_ns"].as_f64().unwrap();
    let resolution = out["rate"]["resolution_ns"].as_f64().unwrap();
    assert!(
        (median - d[d.len() / 2] * 1e9).abs() <= resolution,
        "{median} vs {}",
        d[d.len() / 2]
    );
}

/// The static ADIS16405 hour (seconds, deg/s, g): clean with its units given as flags; read as
/// m/s² instead of g, a units defect (exit 0, and 2 with --strict).
#[test]
fn adis_is_clean_in_its_units_and_a_units_defect_in_the_wrong_ones() {
    let src = repo(ADIS);
    let flags = ["--time-unit", "s", "--gyro-unit", "deg/s"];
    let mut args = vec!["audit", "--imu", &src, "--accel-unit", "g"];
    args.extend(flags);
    let out = json(&args);
    assert_eq!(out["clean"], true, "{out:#}");
    assert_eq!(out["samples"].as_u64(), Some(36_000));
    assert_eq!(out["rate"]["nominal_hz"].as_f64(), Some(10.0));
    assert_eq!(out["still"]["fraction"].as_f64(), Some(1.0));
    let g = out["units"]["gravity_median_m_s2"].as_f64().unwrap();
    assert!((g - 9.81).abs() < 0.2, "{g}");
    let mut wrong = vec!["audit", "--imu", &src, "--accel-unit", "m/s2"];
    wrong.extend(flags);
    let out = json(&wrong);
    assert_eq!(kinds(&out, "defect"), ["units"]);
    assert!(
        out["units"]["error"]
            .as_str()
            .unwrap()
            .contains("--accel-unit g")
    );
    wrong.push("--strict");
    assert_eq!(run(&wrong).status.code(), Some(2));
    wrong.push("--no-unit-check");
    assert!(run(&wrong).status.success());
}

/// A split recording's JSON: both channels' timing and the stamp offsets (hand-built streams:
/// gyro at 200 Hz, accelerometer at 100 Hz stamped 1 ms after every other gyro stamp).
#[test]
fn split_streams_print_each_channel_and_the_offsets() {
    use preint_analysis::audit::split_json;
    use preint_io::audit::{AuditOptions, audit_channels};
    use preint_io::{ChannelSample, ChannelStream, Location};
    let stream = |n: i64, dt: i64, t0: i64| -> ChannelStream {
        Box::new((0..n).map(move |k| {
            let value = preint::nalgebra::Vector3::new(k as f64 * 1e-3, 0.0, 9.81);
            let at = Location::Line(k as u64 + 1);
            Ok(ChannelSample {
                at,
                t_ns: t0 + k * dt,
                value,
            })
        }))
    };
    let a = audit_channels(
        stream(400, 5_000_000, 0),
        stream(199, 10_000_000, 1_000_000),
        "g+a",
        AuditOptions::default(),
    );
    assert!(a.is_clean(), "{:#?}", a.findings);
    let j = split_json(&a);
    assert_eq!(j["gyro"]["rate"]["nominal_hz"].as_f64(), Some(200.0));
    assert_eq!(j["accel"]["rate"]["nominal_hz"].as_f64(), Some(100.0));
    let o = &j["offsets"];
    assert_eq!(
        (o["count"].as_u64(), o["mean_ns"].as_f64()),
        (Some(199), Some(1e6))
    );
    assert_eq!(
        (
            o["min_ns"].as_i64(),
            o["max_ns"].as_i64(),
            o["coincident"].as_u64()
        ),
        (Some(1_000_000), Some(1_000_000), Some(0))
    );
    // Gyro stamps 0 and 1985 … 1995 ms lie outside the accelerometer's 1 … 1981 ms.
    assert_eq!(
        (o["gyro_before"].as_u64(), o["gyro_after"].as_u64()),
        (Some(1), Some(3))
    );
    assert_eq!(j["gyro"]["gaps"]["count"], 0);
}

#[test]
fn topics_of_a_split_recording_need_a_container() {
    let o = run(&[
        "audit",
        "--imu",
        &repo(EUROC),
        "--gyro-topic",
        "/g",
        "--accel-topic",
        "/a",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--gyro-topic and --accel-topic need a bag, MCAP or db3 file"),
        "{err}"
    );
}

/// `audit --calibration`: a still recording whose accelerometer reads 1 % high on every axis.
/// The right file (Ta = 1.01 I) brings the median norm back to |g| (info finding, both norms
/// in the JSON, no warning); a file with the opposite scale moves it away (a `calibration`
/// warning); a file beyond a MEMS sensor's range is a warning too; and the file is named in
/// the output.
#[test]
fn audit_checks_a_calibration_file_against_the_recording() {
    use nalgebra::Matrix3;
    let dir = tmp("audit-calibration");
    let cfg = preint_sim::SimConfig {
        noise: preint::ImuNoise::euroc(),
        bias_random_walk: false,
        acc_scale: Matrix3::identity() * 1.01,
        ..preint_sim::SimConfig::default()
    };
    let out =
        preint_sim::simulate(&preint_sim::StaticScene::default(), 200.0, 20.0, &cfg, 3).unwrap();
    let rows: Vec<(i64, [f64; 6])> = (out.samples.iter())
        .map(|s| {
            (
                s.t_ns,
                [s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z],
            )
        })
        .collect();
    let imu = common::write_imu_csv(&dir, "imu.csv", &rows);
    let file = |name: &str, ta: f64, tw: f64| {
        let x = preint::intrinsics::ImuIntrinsics {
            t_a: Matrix3::identity() * ta,
            t_w: Matrix3::identity() * tw,
            ..Default::default()
        };
        let p = dir.join(name);
        let cal = preint_io::ImuCalibration {
            intrinsics: x,
            noise: None,
            time_offset_s: Some(2e-3),
            rostopic: None,
            scheme: None,
            body_p_sensor: None,
        };
        preint_io::write_openvins_imu_chain(&p, &cal).unwrap();
        p
    };
    let audit = |cal: &std::path::Path| {
        json(&[
            "audit",
            "--imu",
            imu.to_str().unwrap(),
            "--calibration",
            cal.to_str().unwrap(),
        ])
    };
    let right = audit(&file("right.yaml", 1.01, 1.0));
    let (g, raw) = (
        right["units"]["gravity_median_m_s2"].as_f64().unwrap(),
        right["units"]["raw_gravity_median_m_s2"].as_f64().unwrap(),
    );
    assert!(
        (g - 9.81).abs() < 0.01 && (raw - 9.9081).abs() < 0.01,
        "{g} {raw}"
    );
    assert!(kinds(&right, "info").contains(&"calibration".to_string()));
    assert!(
        !kinds(&right, "warning").contains(&"calibration".to_string()),
        "{right:#}"
    );
    assert_eq!(right["calibration"]["time_offset_s"], 2e-3);
    assert!(
        right["calibration"]["file"]
            .as_str()
            .unwrap()
            .ends_with("right.yaml")
    );
    let wrong = audit(&file("wrong.yaml", 0.99, 1.0));
    assert!(
        kinds(&wrong, "warning").contains(&"calibration".to_string()),
        "{wrong:#}"
    );
    // A 15 % gyro scale: beyond a MEMS sensor's range, within what a calibration file may hold.
    let wild = audit(&file("wild.yaml", 1.01, 1.15));
    let msgs: Vec<&str> = (wild["findings"].as_array().unwrap().iter())
        .filter(|f| f["severity"] == "warning")
        .map(|f| f["message"].as_str().unwrap())
        .collect();
    assert!(
        msgs.iter()
            .any(|m| m.contains("beyond a MEMS sensor's range")),
        "{msgs:?}"
    );
    // Without the file: the raw norm, no calibration finding.
    let plain = json(&["audit", "--imu", imu.to_str().unwrap()]);
    assert_eq!(
        plain["units"]["gravity_median_m_s2"],
        plain["units"]["raw_gravity_median_m_s2"]
    );
    assert_eq!(plain["calibration"], Value::Null);
}
