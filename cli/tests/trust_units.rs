//! The unit checks through the binary: a window of a recording in deg/s is refused even when
//! its own samples could not tell; rad/s declared deg/s and seconds read as milliseconds are
//! refused where gravity turns; where nothing can tell, every command that reads a recording
//! says `unit check inconclusive` (text) and `input.unit_check.verdict = "inconclusive"`
//! (JSON) instead of passing silently.

mod common;

use common::{json, repo, run, tmp, write};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const ADIS: &str = "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv";
const DEG: f64 = 180.0 / std::f64::consts::PI;

/// EuRoC V1_01 rewritten with the gyro columns scaled by `gyro` (rows `rows`, all by default),
/// under EuRoC's header (which says rad/s).
fn euroc_scaled(dir: &Path, name: &str, gyro: f64, rows: Option<usize>) -> PathBuf {
    let text = std::fs::read_to_string(repo(EUROC)).unwrap();
    let mut out = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
    for line in text.lines().skip(1).take(rows.unwrap_or(usize::MAX)) {
        let f: Vec<&str> = line.split(',').collect();
        let w: Vec<f64> = f[1..4]
            .iter()
            .map(|x| x.parse::<f64>().unwrap() * gyro)
            .collect();
        let _ = writeln!(
            out,
            "{},{},{},{},{}",
            f[0],
            w[0],
            w[1],
            w[2],
            f[4..].join(",")
        );
    }
    write(dir, name, &out)
}

/// A body rocking about its x axis, θ(t) = 0.3 sin(2π · 0.2 Hz · t) rad, for 60 s (gravity on
/// z at θ = 0, no other acceleration): gravity turns by up to 20° between quasi-static moments
/// 1 s apart, and slowly enough at the turning points for still windows. `t` gives a sample's
/// stamp as written from its time in s.
fn rocking(dir: &Path, name: &str, rate_hz: f64, t: impl Fn(f64) -> String) -> PathBuf {
    let mut out = String::from("t,wx,wy,wz,ax,ay,az\n");
    let (amplitude, w0) = (0.3, 2.0 * std::f64::consts::PI * 0.2);
    for k in 0..=(60.0 * rate_hz) as usize {
        let s = k as f64 / rate_hz;
        let (th, w) = (amplitude * (w0 * s).sin(), amplitude * w0 * (w0 * s).cos());
        let (a_y, a_z) = (9.81 * th.sin(), 9.81 * th.cos());
        let _ = writeln!(out, "{},{w},0,0,0,{a_y},{a_z}", t(s));
    }
    write(dir, name, &out)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn unit_check(out: &Value) -> &Value {
    &out["input"]["unit_check"]
}

#[test]
fn a_one_second_window_of_a_deg_per_s_recording_is_refused() {
    let d = tmp("trust-window");
    let deg = euroc_scaled(&d, "deg.csv", DEG, None);
    let (from, to) = ("1403715280000000000", "1403715281000000000");
    let o = run(&[
        "integrate",
        "--imu",
        deg.to_str().unwrap(),
        "--from",
        from,
        "--to",
        to,
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("deg.csv") && e.contains("--gyro-unit deg/s"),
        "{e}"
    );
    // The same window in rad/s: the checks read on past the window and pass.
    let out = json(&[
        "integrate",
        "--imu",
        &repo(EUROC),
        "--from",
        from,
        "--to",
        to,
    ]);
    assert_eq!(unit_check(&out)["verdict"], "passed", "{out:#}");
    assert_eq!(unit_check(&out)["samples"], 29_120);
    let phi = common::nums(&out["delta_R_log"]);
    let deg_phi = phi.iter().map(|x| x * x).sum::<f64>().sqrt().to_degrees();
    assert!((deg_phi - 14.85).abs() < 0.01, "{deg_phi}");
}

#[test]
fn a_short_excerpt_that_cannot_be_told_is_inconclusive_in_every_command() {
    let d = tmp("trust-short");
    let deg = euroc_scaled(&d, "deg2s.csv", DEG, Some(400));
    let imu = deg.to_str().unwrap();
    let noise = repo("tests/data/euroc/imu.yaml");
    let out = d.join("conv.csv");
    let commands: [Vec<&str>; 5] = [
        vec!["integrate", "--imu", imu],
        vec!["allan", "--imu", imu, "--no-still-check"],
        vec!["advise", "--imu", imu, "--noise", &noise],
        vec!["convert", "--imu", imu, "--out", out.to_str().unwrap()],
        vec!["audit", "--imu", imu],
    ];
    for args in &commands {
        let o = run(args);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.contains("unit check inconclusive") && text.contains("rad/s not told from deg/s"),
            "{args:?}: {text}{}",
            stderr(&o)
        );
        let v = json(args);
        assert_eq!(unit_check(&v)["verdict"], "inconclusive", "{args:?}: {v:#}");
        let why = unit_check(&v)["why"].as_str().unwrap();
        assert!(
            why.contains("no still part") && why.contains("0 pairs"),
            "{why}"
        );
    }
    // --no-unit-check: skipped, and no line of text.
    let v = json(&["integrate", "--imu", imu, "--no-unit-check"]);
    assert_eq!(unit_check(&v)["verdict"], "skipped");
    let o = run(&["integrate", "--imu", imu, "--no-unit-check"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("unit check"));
}

#[test]
fn rad_per_s_declared_deg_per_s_is_refused_where_gravity_turns_and_questioned_where_not() {
    let d = tmp("trust-declared");
    let f = rocking(&d, "tilt.csv", 200.0, |s| {
        format!("{}", (s * 1e9).round() as i64)
    });
    let imu = f.to_str().unwrap();
    let base = ["integrate", "--imu", imu, "--time-unit", "ns"];
    let v = json(&base);
    assert_eq!(unit_check(&v)["verdict"], "passed", "{v:#}");
    let mut deg = base.to_vec();
    deg.extend(["--gyro-unit", "deg/s"]);
    let o = run(&deg);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(
        e.contains("tilt.csv") && e.contains("looks like rad/s, not deg/s: set --gyro-unit rad/s"),
        "{e}"
    );
    // EuRoC declared deg/s: its bias would be plausible in rad/s too, and too few moments of
    // it are quasi-static to tell by the gyro: questioned, not passed (factor here).
    let v = json(&[
        "factor",
        "--imu",
        &repo(EUROC),
        "--gyro-unit",
        "deg/s",
        "--poses",
        &repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"),
        "--from",
        "1403715280000000000",
        "--to",
        "1403715281000000000",
    ]);
    assert_eq!(unit_check(&v)["verdict"], "inconclusive", "{v:#}");
    let why = unit_check(&v)["why"].as_str().unwrap();
    assert!(
        why.contains("gyro unit: deg/s not told from rad/s"),
        "{why}"
    );
}

#[test]
fn seconds_read_as_milliseconds_are_refused_where_gravity_turns_and_questioned_where_not() {
    let d = tmp("trust-time");
    let f = rocking(&d, "tilt10.csv", 10.0, |s| format!("{s:.1}"));
    let imu = f.to_str().unwrap();
    let v = json(&["integrate", "--imu", imu, "--time-unit", "s"]);
    assert_eq!(unit_check(&v)["verdict"], "passed", "{v:#}");
    let o = run(&["integrate", "--imu", imu, "--time-unit", "ms"]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(
        e.contains("the timestamps look like s: set --time-unit s"),
        "{e}"
    );
    // The static ADIS hour at 10 Hz: nothing turns gravity, so its seconds cannot be told
    // from milliseconds (10 kHz); calibrate says so beside its answer.
    let o = run(&["calibrate", "--imu", &repo(ADIS), "--time-unit", "ms"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        text.starts_with("unit check inconclusive")
            && text.contains(
                "time unit: the median interval of 0.0001 s (read as ms) would be in s 0.1 s"
            ),
        "{text}"
    );
}
