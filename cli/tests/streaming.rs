//! `preint integrate` reads the recording once: the whole recording through a preintegrator
//! that stores nothing, a `--from/--to` window from the part of the file it needs (reading
//! stops after `--to`), with gaps outside the window's edge stencil ignored.

mod common;

use common::{json, repo, run, tmp, write};
use serde_json::Value;

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";

/// The EuRoC file's lines: header, then data rows.
fn euroc_lines() -> (String, Vec<String>) {
    let text = std::fs::read_to_string(repo(EUROC)).unwrap();
    let mut lines = text.lines().map(str::to_string);
    let header = lines.next().unwrap();
    (header, lines.collect())
}

fn t_of(row: &str) -> i64 {
    row.split(',').next().unwrap().parse().unwrap()
}

/// Every key of two `integrate --json` outputs, except the file names and the unit checks'
/// verdict (the checks read on past a window as far as each file lets them).
fn assert_same_result(a: &Value, b: &Value, what: &str) {
    for (k, v) in a.as_object().unwrap() {
        if k == "input" {
            let (mut x, mut y) = (v.clone(), b[k].clone());
            (x["unit_check"], y["unit_check"]) = (Value::Null, Value::Null);
            assert_eq!(x, y, "{what}: {k}");
        } else if k != "imu" {
            assert_eq!(v, &b[k], "{what}: {k}");
        }
    }
}

#[test]
fn the_whole_recording_equals_the_window_from_its_first_to_its_last_sample() {
    let (_, rows) = euroc_lines();
    let (first, last) = (t_of(&rows[0]), t_of(&rows[rows.len() - 1]));
    for scheme in ["euler", "midpoint", "rk4"] {
        let whole = json(&["integrate", "--imu", &repo(EUROC), "--scheme", scheme]);
        let window = json(&[
            "integrate",
            "--imu",
            &repo(EUROC),
            "--scheme",
            scheme,
            "--from",
            &first.to_string(),
            "--to",
            &last.to_string(),
        ]);
        assert_eq!(whole["samples"], rows.len());
        assert_same_result(&whole, &window, scheme);
    }
}

#[test]
fn a_window_reads_the_file_only_up_to_three_samples_after_to() {
    let (header, rows) = euroc_lines();
    let dir = tmp("early-stop");
    // 2000 good rows (10 s), then a malformed row.
    let mut text = format!("{header}\n");
    for r in &rows[..2000] {
        text.push_str(r);
        text.push('\n');
    }
    text.push_str("this row is not a sample\n");
    let file = write(&dir, "imu.csv", &text);
    let f = file.to_str().unwrap();
    let (from, to) = (t_of(&rows[100]) + 1_000_000, t_of(&rows[1996]));
    let out = json(&[
        "integrate",
        "--imu",
        f,
        "--from",
        &from.to_string(),
        "--to",
        &to.to_string(),
    ]);
    assert_eq!(out["samples"], 1996 - 100);
    // The same window of the clean file gives the same result.
    let clean = json(&[
        "integrate",
        "--imu",
        &repo(EUROC),
        "--from",
        &from.to_string(),
        "--to",
        &to.to_string(),
    ]);
    assert_same_result(&out, &clean, "early stop");
    // One row later, the malformed row (line 2002) is needed and named.
    let o = run(&[
        "integrate",
        "--imu",
        f,
        "--from",
        &from.to_string(),
        "--to",
        &t_of(&rows[1997]).to_string(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("imu.csv") && err.contains("2002"), "{err}");
}

#[test]
fn a_gap_a_few_samples_before_from_does_not_fail_the_window() {
    let (header, rows) = euroc_lines();
    let dir = tmp("gap-before");
    // Rows 0..1000, then a 0.5 s gap (rows 1000..1100 left out), then rows 1100..2000.
    let kept: Vec<&String> = rows[..1000].iter().chain(&rows[1100..2000]).collect();
    let mut text = format!("{header}\n");
    for r in &kept {
        text.push_str(r);
        text.push('\n');
    }
    let file = write(&dir, "gap.csv", &text);
    let f = file.to_str().unwrap();
    let to = t_of(&rows[1900]).to_string();
    for scheme in ["euler", "midpoint", "rk4"] {
        // t_i 1 ms after the third sample after the gap (rows 1102, 1103).
        let from = (t_of(&rows[1102]) + 1_000_000).to_string();
        let args = |file: &str| {
            vec![
                "integrate".to_string(),
                "--imu".into(),
                file.into(),
                "--scheme".into(),
                scheme.into(),
                "--from".into(),
                from.clone(),
                "--to".into(),
                to.clone(),
            ]
        };
        let a = args(f);
        let with_gap = json(&a.iter().map(String::as_str).collect::<Vec<_>>());
        let clean_args = args(&repo(EUROC));
        let clean = json(&clean_args.iter().map(String::as_str).collect::<Vec<_>>());
        assert_same_result(&with_gap, &clean, scheme);
        // t_i just after the first sample after the gap: the edge needs the gap's interval;
        // the error names that sample by its index in the whole file (1000).
        let from = (t_of(&rows[1100]) + 1_000_000).to_string();
        let o = run(&[
            "integrate",
            "--imu",
            f,
            "--scheme",
            scheme,
            "--from",
            &from,
            "--to",
            &to,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{scheme}");
        assert!(
            err.contains("gap.csv") && err.contains("sample 1000") && err.contains("gap"),
            "{scheme}: {err}"
        );
    }
}

#[test]
fn advise_refuses_a_gap_naming_the_file_and_the_samples() {
    let (header, rows) = euroc_lines();
    let dir = tmp("advise-gap");
    // Rows 0..1000, a 1 s gap (rows 1000..1200 left out), rows 1200..3000.
    let mut text = format!("{header}\n");
    for r in rows[..1000].iter().chain(&rows[1200..3000]) {
        text.push_str(r);
        text.push('\n');
    }
    let file = write(&dir, "gap.csv", &text);
    let o = run(&[
        "advise",
        "--imu",
        file.to_str().unwrap(),
        "--noise",
        &repo("tests/data/euroc/imu.yaml"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("gap.csv") && err.contains("gap of 1.005") && err.contains("999"),
        "{err}"
    );
    // The part after the gap (9 s) is analysed with --from.
    let from = t_of(&rows[1200]).to_string();
    let out = json(&[
        "advise",
        "--imu",
        file.to_str().unwrap(),
        "--noise",
        &repo("tests/data/euroc/imu.yaml"),
        "--from",
        &from,
    ]);
    assert_eq!(out["samples"], 1800);
}
