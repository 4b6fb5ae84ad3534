//! `preint integrate --gyro FILE --accel FILE`: a split recording (gyro at 200 Hz, the
//! accelerometer at 63 Hz in its own file) merged by the input layer.

mod common;
use common::{json, run, tmp, vec3, write};
use std::path::PathBuf;

/// The columns `t, c, c+1, c+2` of a EuRoC `imu.csv` as a channel file.
fn channel(imu: &std::path::Path, c: usize, header: &str) -> String {
    let text = std::fs::read_to_string(imu).unwrap();
    let mut out = format!("{header}\n");
    for row in text.lines().filter(|l| !l.starts_with('#')) {
        let f: Vec<&str> = row.split(',').collect();
        out.push_str(&format!("{},{},{},{}\n", f[0], f[c], f[c + 1], f[c + 2]));
    }
    out
}

/// Noise-free `seed-ellipse` for 3 s: the gyro of the 200 Hz simulation and the
/// accelerometer of the 63 Hz one in two files, and the 200 Hz `imu.csv`.
fn split_sim(d: &std::path::Path) -> (PathBuf, PathBuf, PathBuf) {
    let (d200, d63) = (d.join("200"), d.join("63"));
    for (dir, rate) in [(&d200, "200"), (&d63, "63")] {
        common::simulate(dir, &["--rate", rate, "--duration", "3", "--noise", "none"]);
    }
    let g = channel(&d200.join("imu.csv"), 1, "#t [ns],w_x [rad s^-1],w_y,w_z");
    let a = channel(&d63.join("imu.csv"), 4, "#t [ns],a_x [m s^-2],a_y,a_z");
    (
        write(d, "gyro.csv", &g),
        write(d, "accel.csv", &a),
        d200.join("imu.csv"),
    )
}

const FROM: &str = "1000000000";
const TO: &str = "2000000000";

#[test]
fn integrate_reads_a_split_recording_and_reports_the_merge() {
    let d = tmp("split-integrate");
    let (g, a, full) = split_sim(&d);
    let (g, a) = (g.to_str().unwrap(), a.to_str().unwrap());
    let v = json(&[
        "integrate",
        "--gyro",
        g,
        "--accel",
        a,
        "--from",
        FROM,
        "--to",
        TO,
    ]);
    let notes: Vec<String> = v["input"]["notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    let all = notes.join("\n");
    assert!(all.contains("cubic Hermite"), "{all}");
    // 601 gyro stamps k·5 ms (0 … 3 s); 189 accelerometer stamps k·15 873 016 ns (0 …
    // 2.984 s). Merged: the gyro stamps with two accelerometer stamps at or before and two
    // after, [t_1, t_187) = [15.873 ms, 2.968 s): 20 ms … 2.965 s, 590 of them; dropped 0, 5,
    // 10, 15 ms before and 2.970 … 3.000 s (7) after.
    assert!(all.contains("onto 590 of 601 gyro stamps"), "{all}");
    assert!(
        all.contains("4 gyro samples dropped before and 7 after"),
        "{all}"
    );
    let rho_note = notes.iter().find(|n| n.contains("sqrt(rho) = ")).unwrap();
    let f: f64 = rho_note.split("sqrt(rho) = ").nth(1).unwrap()[..7]
        .parse()
        .unwrap();
    // Accelerometer slower than the gyro: √ρ within 1 % of 1 (docs/SPLIT_STREAMS.md, eq. 5).
    assert!((f - 1.0).abs() < 0.01, "{f}");
    // The window is preintegrated with that density: the default 2e-3 m/s²/√Hz times √ρ
    // (noise-free data: no interpolation term above the noise floor to add).
    let used = v["noise"]["accelerometer_noise_density"].as_f64().unwrap();
    assert!(
        (used - 2e-3 * f).abs() <= 2e-3 * 1e-4 + 1e-9 * used.abs().max(1.0) && used < 2e-3,
        "{used} vs {}",
        2e-3 * f
    );
    // Noise-free: the merged Δv equals the 200 Hz file's to the cubic interpolation error
    // (≈ 1e-7 m/s here; linear interpolation is off by 1.3e-3 m/s, tests/tests/split_streams.rs).
    let full = json(&[
        "integrate",
        "--imu",
        full.to_str().unwrap(),
        "--from",
        FROM,
        "--to",
        TO,
    ]);
    let (dv, dv_full) = (vec3(&v["delta_v"]), vec3(&full["delta_v"]));
    for k in 0..3 {
        assert!(
            (dv[k] - dv_full[k]).abs() < 1e-5,
            "axis {k}: {} vs {}",
            dv[k],
            dv_full[k]
        );
    }
    let (r, r_full) = (vec3(&v["delta_R_log"]), vec3(&full["delta_R_log"]));
    assert_eq!(r, r_full, "the gyro samples are the same");
}

#[test]
fn a_decreasing_accelerometer_stamp_is_an_error_naming_the_file_and_line() {
    let d = tmp("split-bad");
    let g = write(
        &d,
        "g.csv",
        "t_ns,wx,wy,wz\n0,0,0,0\n5000000,0,0,0\n10000000,0,0,0\n",
    );
    let a = write(
        &d,
        "a.csv",
        "t_ns,ax,ay,az\n0,0,0,9.8\n4000000,0,0,9.8\n3000000,0,0,9.8\n",
    );
    let o = run(&[
        "integrate",
        "--gyro",
        g.to_str().unwrap(),
        "--accel",
        a.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("a.csv:4:") && err.contains("decreases"),
        "{err}"
    );
}
