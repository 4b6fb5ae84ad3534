//! End-to-end: the ROS 1 bag, MCAP and ROS 2 `.db3` fixtures of `tests/data/ros` (the first 500 rows of
//! EuRoC V1_01 imu0, written by `tests/data/ros/generate.py`) through `integrate` and
//! `convert` give what the same rows give as EuRoC CSV.

mod common;

use common::{json, repo, run, tmp, write};
use serde_json::Value;

const EUROC_IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const ROWS: usize = 500;

/// The CSV's header and first [`ROWS`] rows, unchanged.
fn first_rows() -> String {
    let text = std::fs::read_to_string(repo(EUROC_IMU)).unwrap();
    let mut out = String::new();
    for line in text.lines().take(ROWS + 1) {
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// `v` without the fields that say which file was read and how.
fn without_source(mut v: Value) -> Value {
    if let Some(o) = v.as_object_mut() {
        for k in ["imu", "input", "source"] {
            o.remove(k);
        }
    }
    v
}

#[test]
fn integrate_bag_and_mcap_equals_integrate_csv() {
    let dir = tmp("containers-integrate");
    let csv = write(&dir, "first_rows.csv", &first_rows());
    let from_csv = json(&["integrate", "--imu", csv.to_str().unwrap()]);
    assert!(from_csv["delta_R"].is_array(), "{from_csv}");
    for (file, topic) in [
        ("euroc_imu.bag", "/imu0"),
        ("euroc_imu.mcap", "/imu0"),
        ("euroc_imu.db3", "/imu0"),
    ] {
        let path = repo(&format!("tests/data/ros/{file}"));
        let out = json(&["integrate", "--imu", &path, "--topic", topic]);
        assert_eq!(
            without_source(out.clone()),
            without_source(from_csv.clone()),
            "{file}"
        );
        let notes = out.to_string();
        assert!(notes.contains("header.stamp"), "{notes}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn convert_mcap_and_bag_reproduce_the_csv_rows() {
    let dir = tmp("containers-convert");
    let expected: Vec<String> = first_rows().lines().skip(1).map(str::to_string).collect();
    for file in ["euroc_imu.mcap", "euroc_imu.bag", "euroc_imu.db3"] {
        let out = dir.join(format!("{file}.csv"));
        let j = json(&[
            "convert",
            "--imu",
            &repo(&format!("tests/data/ros/{file}")),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(j["samples"], ROWS as u64);
        let written = std::fs::read_to_string(&out).unwrap();
        let rows: Vec<&str> = written.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(rows.len(), ROWS);
        // Same numbers: timestamps identical, values equal as f64 (the CSV's digits may be
        // longer than the shortest round-trip form the writer prints).
        for (got, want) in rows.iter().zip(&expected) {
            let g: Vec<f64> = got.split(',').map(|x| x.trim().parse().unwrap()).collect();
            let w: Vec<f64> = want.split(',').map(|x| x.trim().parse().unwrap()).collect();
            assert_eq!(got.split(',').next(), want.split(',').next());
            assert_eq!(g, w, "{got} vs {want}");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn container_errors_exit_non_zero_and_name_the_problem() {
    let split = repo("tests/data/ros/split.mcap");
    let o = run(&["integrate", "--imu", &split]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2 sensor_msgs/Imu topics"), "{err}");
    let o = run(&["integrate", "--imu", &split, "--topic", "/status"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("carries std_msgs"), "{err}");
    assert!(err.contains("split.mcap"), "{err}");
}

/// The split fixtures (gyro at 200 Hz and accelerometer at 63 Hz on two topics, from the first
/// 400 EuRoC rows) merge to the same samples from every container; the window's rotation is
/// that of the 200 Hz rows (the gyro samples are those rows), and the accelerometer density
/// used is the effective one of the merge.
#[test]
fn split_topics_of_every_container_merge_and_preintegrate() {
    let (from, to) = ("1403715274000000000", "1403715275000000000");
    let mut results = Vec::new();
    for file in ["split.bag", "split.mcap", "split.db3"] {
        let v = json(&[
            "integrate",
            "--imu",
            &repo(&format!("tests/data/ros/{file}")),
            "--gyro-topic",
            "/camera/gyro/sample",
            "--accel-topic",
            "/camera/accel/sample",
            "--from",
            from,
            "--to",
            to,
        ]);
        let notes = v["input"]["notes"].to_string();
        assert!(notes.contains("cubic Hermite"), "{file}: {notes}");
        let used = v["noise"]["accelerometer_noise_density"].as_f64().unwrap();
        // √(ρσ² + q_int): ρ ≈ 0.995 at 200/63 Hz, and the interpolation term of a vibrating
        // MAV's accelerometer sampled at 63 Hz is of the order of the white noise.
        assert!(
            used > 0.99 * 2e-3 && used < 1e-2 && used != 2e-3,
            "{file}: {used}"
        );
        results.push(without_source(v));
    }
    assert_eq!(results[0], results[1], "bag vs MCAP");
    assert_eq!(results[0], results[2], "bag vs db3");
    let full = json(&[
        "integrate",
        "--imu",
        &repo("tests/data/ros/euroc_imu.mcap"),
        "--from",
        from,
        "--to",
        to,
    ]);
    assert_eq!(results[0]["delta_R"], full["delta_R"]);
    assert_eq!(results[0]["samples"], full["samples"]);
}

#[test]
fn audit_reads_the_split_topics_of_a_container() {
    let o = run(&[
        "audit",
        "--imu",
        &repo("tests/data/ros/split.mcap"),
        "--gyro-topic",
        "/camera/gyro/sample",
        "--accel-topic",
        "/camera/accel/sample",
        "--strict",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // 400 gyro rows at EuRoC's 200 Hz; the accelerometer stamps at round(k·1e9/63) ns.
    assert!(out.contains("gyro: 400 samples"), "{out}");
    assert!(
        out.contains("accel: 126 samples") && out.contains("63.0000 Hz"),
        "{out}"
    );
}
