//! `preint allan` refuses what it cannot answer (exit 2, saying why): a moving recording
//! (EuRoC V1_01, a flying MAV), data whose units are not the ones it is read in (the ADIS16405
//! block means in deg/s and g read as rad/s and m/s²), a gap. And it answers on the static
//! ADIS16405 hour read with the unit flags, the same as when the units come from the header.

mod common;

use common::{json, repo, run, tmp, vec3, write};

const EUROC_IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const ADIS: &str = "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv";

/// The ADIS16405 block means with a header that names no units (`t,wx,wy,wz,ax,ay,az`),
/// without the data rows `drop`, written to a temporary file.
fn adis_plain(name: &str, drop: std::ops::Range<usize>) -> String {
    let text = std::fs::read_to_string(repo(ADIS)).unwrap();
    let mut out = String::from("t,wx,wy,wz,ax,ay,az\n");
    for (k, line) in text.lines().skip(1).enumerate() {
        if !drop.contains(&k) {
            out.push_str(line);
            out.push('\n');
        }
    }
    write(&tmp("allan"), name, &out).display().to_string()
}

fn stderr_of(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// EuRoC V1_01 (a MAV flying for most of its 145 s): refused with exit 2, the message giving
/// the fraction of still windows (a third) and naming the file; `--no-still-check` overrides.
#[test]
fn a_moving_recording_is_refused() {
    let o = run(&["allan", "--imu", &repo(EUROC_IMU)]);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(o.stdout.is_empty());
    assert!(
        e.contains("V1_01_easy_imu0.csv") && e.contains("not static") && e.contains("% of its"),
        "{e}"
    );
    let pct: f64 = e
        .split(" % of its")
        .next()
        .unwrap()
        .rsplit(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(pct < 50.0, "{e}");
    let out = json(&["allan", "--imu", &repo(EUROC_IMU), "--no-still-check"]);
    let frac = out["checks"]["still_fraction"].as_f64().unwrap();
    assert!((frac - pct / 100.0).abs() < 1e-3, "{frac} vs {pct} %");
}

/// The static ADIS16405 hour (10 Hz block means, deg/s and g) with a unit-less header: read
/// as rad/s and m/s² it is refused by the unit check (the accelerometer reads 1.02, "set
/// --accel-unit g"); with `--accel-unit g` alone, by the gyro check (a bias of 0.59 "rad/s");
/// with both flags it is analysed, and gives the same densities as the committed file whose
/// header names the units. The run is still (every window) and the gravity direction turns by
/// less than 1° (0.41°, a temperature drift).
#[test]
fn units_are_checked_and_the_flags_fix_them() {
    let f = adis_plain("adis_plain.csv", 0..0);
    let o = run(&["allan", "--imu", &f, "--time-unit", "s"]);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("adis_plain.csv") && e.contains("--accel-unit g"),
        "{e}"
    );
    let o = run(&[
        "allan",
        "--imu",
        &f,
        "--time-unit",
        "s",
        "--accel-unit",
        "g",
    ]);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--gyro-unit deg/s"), "{e}");
    let flags = json(&[
        "allan",
        "--imu",
        &f,
        "--time-unit",
        "s",
        "--gyro-unit",
        "deg/s",
        "--accel-unit",
        "g",
    ]);
    let header = json(&["allan", "--imu", &repo(ADIS)]);
    for key in ["gyroscope_noise_density", "accelerometer_noise_density"] {
        assert_eq!(flags[key], header[key], "{key}");
    }
    let c = &flags["checks"];
    assert_eq!(c["still_fraction"], 1.0, "{c}");
    assert!(c["windows"].as_u64().unwrap() > 3500, "{c}");
    assert!(c["max_tilt_deg"].as_f64().unwrap() < 1.0, "{c}");
    assert_eq!(flags["block_len"], 1);
    assert_eq!(flags["base_tau_s"], 0.1);
    // Gyro N against the curators' σ(1 s) of the raw 100 Hz run (0.041 / 0.043 / 0.039
    // deg/s), within 10 %.
    let n = vec3(&flags["gyroscope_noise_density"]);
    for (i, r) in [0.041f64, 0.043, 0.039].iter().enumerate() {
        assert!((n[i] / r.to_radians() - 1.0).abs() < 0.1, "{i}: {}", n[i]);
    }
}

/// Ten minutes missing from the hour: refused with exit 2, naming the interval.
#[test]
fn a_gap_is_refused() {
    let f = adis_plain("adis_gap.csv", 10_000..16_000);
    let o = run(&[
        "allan",
        "--imu",
        &f,
        "--time-unit",
        "s",
        "--gyro-unit",
        "deg/s",
        "--accel-unit",
        "g",
    ]);
    let e = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("adis_gap.csv") && e.contains("interval 9999") && e.contains("600.1"),
        "{e}"
    );
}
