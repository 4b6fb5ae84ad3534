//! The gyro-axis check (`preint_io::plausibility::axes`) through the binary: on a simulated
//! recording that turns gravity about x and y (`multi-pose-static`), `audit` says the axes
//! agree; with the gyro's y column negated, `audit` reports a defect naming it and `integrate`
//! refuses the file (exit 2) with the same words and the flags that fix or skip it.

mod common;

use common::{json, run, simulate, tmp};
use std::path::Path;

/// `imu.csv` of `dir` with its gyro y column (the third) negated, written to `name`.
fn negated_gyro_y(dir: &Path, name: &str) -> String {
    let text = std::fs::read_to_string(dir.join("imu.csv")).unwrap();
    let out: String = text
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                return format!("{l}\n");
            }
            let mut c: Vec<String> = l.split(',').map(str::to_string).collect();
            let v: f64 = c[2].parse().unwrap();
            c[2] = format!("{}", -v);
            format!("{}\n", c.join(","))
        })
        .collect();
    common::write(dir, name, &out).to_str().unwrap().to_string()
}

#[test]
fn audit_names_an_inverted_gyro_axis_and_integrate_refuses_it() {
    let d = tmp("axes");
    simulate(&d, &["--scene", "multi-pose-static", "--duration", "33"]);
    let imu = d.join("imu.csv");
    let ok = json(&["audit", "--imu", imu.to_str().unwrap()]);
    let axes = &ok["units"]["gyro_axes"];
    assert_eq!(axes["verdict"], "agree", "{axes}");
    let flipped = negated_gyro_y(&d, "flipped.csv");
    let o = run(&["audit", "--imu", &flipped, "--json"]);
    let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let axes = &a["units"]["gyro_axes"];
    assert_eq!(axes["verdict"], "mismatch", "{axes}");
    let text = axes["text"].as_str().unwrap();
    assert!(text.contains("gyro y looks inverted"), "{text}");
    assert_eq!(a["verdict"], "defects", "{}", a["verdict"]);
    let o = run(&["integrate", "--imu", &flipped]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("gyro y looks inverted") && e.contains("--no-unit-check"),
        "{e}"
    );
    let o = run(&["integrate", "--imu", &flipped, "--no-unit-check"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
