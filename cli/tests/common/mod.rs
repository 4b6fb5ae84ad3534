//! Helpers shared by the end-to-end tests of the `preint` binary: running it, temporary
//! directories, writing input files, reading JSON numbers.
#![allow(dead_code)]

use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The EuRoC (ADIS16448) densities: gyro noise [rad/s/√Hz], gyro random walk [rad/s²/√Hz],
/// accelerometer noise [m/s²/√Hz], accelerometer random walk [m/s³/√Hz].
pub const EUROC_DENSITIES: [f64; 4] = [1.6968e-4, 1.9393e-5, 2.0e-3, 3.0e-3];

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_preint"))
}

pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("binary runs")
}

/// Runs `preint ARGS --json`, asserts success and parses stdout.
pub fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    let o = run(&a);
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

/// `preint simulate --out DIR ARGS --json`.
pub fn simulate(dir: &Path, args: &[&str]) -> Value {
    let mut a = vec!["simulate", "--out", dir.to_str().unwrap()];
    a.extend_from_slice(args);
    json(&a)
}

pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("preint-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(p)
        .display()
        .to_string()
}

/// The header line and the first `rows` data rows of the repository file `src`, written to
/// `dir/name` (a short slice of a recording); returns the path.
pub fn head_rows(src: &str, dir: &Path, name: &str, rows: usize) -> PathBuf {
    let text = std::fs::read_to_string(repo(src)).unwrap();
    let kept: String = text
        .lines()
        .take(rows + 1)
        .map(|l| format!("{l}\n"))
        .collect();
    write(dir, name, &kept)
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Writes a EuRoC imu0 CSV file (header line, then `t_ns, w_x, w_y, w_z, a_x, a_y, a_z`).
pub fn write_imu_csv(dir: &Path, name: &str, rows: &[(i64, [f64; 6])]) -> PathBuf {
    let mut csv = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
    for (t, v) in rows {
        let _ = writeln!(
            csv,
            "{t},{},{},{},{},{},{}",
            v[0], v[1], v[2], v[3], v[4], v[5]
        );
    }
    write(dir, name, &csv)
}

/// Writes a Kalibr imu.yaml with the densities `[gyro noise, gyro random walk, acc noise,
/// acc random walk]` (units as [`EUROC_DENSITIES`]) and the update rate [Hz].
pub fn write_noise_yaml(dir: &Path, name: &str, d: [f64; 4], rate_hz: f64) -> PathBuf {
    let yaml = format!(
        "gyroscope_noise_density: {:e}\ngyroscope_random_walk: {:e}\n\
         accelerometer_noise_density: {:e}\naccelerometer_random_walk: {:e}\nupdate_rate: {:?}\n",
        d[0], d[1], d[2], d[3], rate_hz
    );
    write(dir, name, &yaml)
}

pub fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [
        a[0].as_f64().unwrap(),
        a[1].as_f64().unwrap(),
        a[2].as_f64().unwrap(),
    ]
}

/// A JSON list of numbers.
pub fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// A JSON list of rows of numbers.
pub fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().unwrap().iter().map(nums).collect()
}

/// The state of `simulate`'s `groundtruth.csv` in `dir` at `t_ns` (read by
/// `preint_io::read_euroc_groundtruth`).
pub fn truth_at(dir: &Path, t_ns: i64) -> preint_io::GroundTruthState {
    preint_io::read_euroc_groundtruth(&dir.join("groundtruth.csv"))
        .expect("groundtruth.csv")
        .into_iter()
        .find(|s| s.t_ns == t_ns)
        .expect("a ground-truth row at t_ns")
}

/// [`truth_at`] as arrays: position \[m\], quaternion w, x, y, z (body → world), velocity [m/s].
pub fn truth(dir: &Path, t_ns: i64) -> ([f64; 3], [f64; 4], [f64; 3]) {
    let s = truth_at(dir, t_ns);
    let q = s.q.quaternion();
    (
        [s.p.x, s.p.y, s.p.z],
        [q.w, q.i, q.j, q.k],
        [s.v.x, s.v.y, s.v.z],
    )
}

/// The body's true Δv [m/s] over `[t_i, t_j]` (frame at t_i, gravity `(0, 0, −9.81)`) from
/// the ground truth in `dir`.
pub fn true_delta_v(dir: &Path, t_i: i64, t_j: i64) -> nalgebra::Vector3<f64> {
    let (i, j) = (truth_at(dir, t_i), truth_at(dir, t_j));
    let dt = (t_j - t_i) as f64 * 1e-9;
    i.q.inverse() * (j.v - i.v - nalgebra::Vector3::new(0.0, 0.0, -9.81) * dt)
}
