//! The BROAD excerpt (seconds with six decimals, rad/s, m/s², eight reference columns) runs
//! through the subcommands with no reader flags, and reads as the same samples as its EuRoC
//! conversion done here by hand (decimal strings, not the crate's number parser).

mod common;

use common::{json, repo, run, tmp};

const BROAD: &str = "tests/data/broad/broad_10_undisturbed_slow_translation_A_30s_45s.csv";

/// `"30.002000"` s → 30 002 000 000 ns, by moving the decimal point in the string.
fn seconds_to_ns(t: &str) -> i64 {
    let (int, frac) = t.split_once('.').unwrap();
    let frac = format!("{frac:0<9}");
    format!("{int}{frac}").parse().unwrap()
}

#[test]
fn broad_converts_to_the_hand_made_euroc_rows() {
    let dir = tmp("broad");
    let out = dir.join("imu.csv");
    let o = run(&[
        "convert",
        "--imu",
        &repo(BROAD),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let src = std::fs::read_to_string(repo(BROAD)).unwrap();
    let got = std::fs::read_to_string(&out).unwrap();
    let got: Vec<&str> = got.lines().filter(|l| !l.starts_with('#')).collect();
    let rows: Vec<&str> = src.lines().skip(1).collect();
    assert_eq!(got.len(), rows.len());
    assert_eq!(rows.len(), 4286);
    for (g, r) in got.iter().zip(&rows) {
        let r: Vec<&str> = r.split(',').collect();
        let g: Vec<&str> = g.split(',').collect();
        assert_eq!(g[0].parse::<i64>().unwrap(), seconds_to_ns(r[0]), "{r:?}");
        for k in 1..7 {
            let (a, b): (f64, f64) = (g[k].parse().unwrap(), r[k].parse().unwrap());
            assert_eq!(a, b, "column {k} of {r:?}");
        }
    }
    // 285.714 Hz: the spacing is exactly 3.5 ms.
    assert_eq!(
        seconds_to_ns(rows[1].split(',').next().unwrap())
            - seconds_to_ns(rows[0].split(',').next().unwrap()),
        3_500_000
    );
}

#[test]
fn broad_runs_through_integrate_and_calibrate_without_flags() {
    let out = json(&["integrate", "--imu", &repo(BROAD)]);
    assert_eq!(out["samples"], 4286);
    assert_eq!(out["input"]["format"], "delimited");
    // 30.002 s to 44.9995 s.
    assert_eq!(out["delta_t"], 14.9975);
    // The recording rests for t < 36.8 s: the static problem on that interval.
    let cal = json(&["calibrate", "--imu", &repo(BROAD)]);
    assert_eq!(cal["model"], "static-single-attitude");
    let (t0, t1) = (
        cal["interval_ns"][0].as_i64().unwrap(),
        cal["interval_ns"][1].as_i64().unwrap(),
    );
    assert!(t0 >= 30_002_000_000 && t1 <= 36_800_000_000, "{t0} {t1}");
}
