//! The command line where users touch it, through the built binary: `--columns` on a
//! reordered file, negative numbers after a space, and output into a pipe closed early.

mod common;

use common::{bin, json, repo, run, tmp, write};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::Stdio;

const T_TO: &str = "1403715274262142976"; // 1 s after the first EuRoC V1_01 sample

fn euroc() -> String {
    repo("tests/data/euroc/V1_01_easy_imu0.csv")
}

/// `integrate --json` without what names the file and how it was read.
fn deltas(mut v: Value) -> Value {
    let o = v.as_object_mut().unwrap();
    o.remove("imu");
    o.remove("input");
    v
}

/// The first 400 EuRoC rows, once in EuRoC layout and once as `index;t;ax;ay;az;wx;wy;wz`
/// without a header (the same decimal text in every field): the two integrate to the same
/// numbers, the second read with `--columns skip,t,ax,ay,az,wx,wy,wz --time-unit ns`.
#[test]
fn columns_read_a_reordered_file_with_a_skipped_column() {
    let text = std::fs::read_to_string(euroc()).unwrap();
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .take(400)
        .collect();
    let d = tmp("columns");
    let mut eu = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
    let mut re = String::new();
    for (k, r) in rows.iter().enumerate() {
        let f: Vec<&str> = r.split(',').collect();
        eu.push_str(r);
        eu.push('\n');
        let fields = [f[0], f[4], f[5], f[6], f[1], f[2], f[3]];
        re.push_str(&format!("{k};{}\n", fields.join(";")));
    }
    let eu = write(&d, "euroc.csv", &eu);
    let re = write(&d, "reordered.txt", &re);
    let (eu, re) = (eu.to_str().unwrap(), re.to_str().unwrap());
    let columns = "skip,t,ax,ay,az,wx,wy,wz";
    let a = json(&["integrate", "--imu", eu, "--to", T_TO]);
    let cols = ["--columns", columns, "--time-unit", "ns"];
    let b = json(&[&["integrate", "--imu", re][..], &cols, &["--to", T_TO]].concat());
    assert_eq!(a["samples"], 201, "{a}");
    let read_as = b["input"]["read_as"].as_str().unwrap();
    assert!(read_as.contains(columns), "{read_as}");
    assert_eq!(deltas(a.clone()), deltas(b));
    // The same columns with the delimiter given, through another subcommand: convert writes
    // the EuRoC layout back, which integrates to the same numbers again.
    let back = d.join("back.csv");
    let back = back.to_str().unwrap();
    let delimiter = ["--delimiter", "semicolon", "--out", back];
    json(&[&["convert", "--imu", re][..], &cols, &delimiter].concat());
    let c = json(&["integrate", "--imu", back, "--to", T_TO]);
    assert_eq!(deltas(a), deltas(c));
}

#[test]
fn columns_errors_name_the_column_and_the_flag() {
    for (spec, want) in [
        ("t,wx,wy,wz,ax,ay,qq", "unknown column `qq`"),
        ("t,wx,wy,wz,ax,ay", "names `az` 0 times"),
        ("t,wx,wx,wy,wz,ax,ay,az", "names `wx` 2 times"),
    ] {
        let o = run(&["integrate", "--imu", &euroc(), "--columns", spec]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{spec}: {err}");
        assert!(
            err.contains(want) && err.contains("--columns"),
            "{spec}: {err}"
        );
        assert!(!err.contains("panicked"), "{spec}: {err}");
    }
}

/// `--flag -X` (a space, not `=`) reaches the flag's own validation, whose message names it.
#[test]
fn negative_numbers_after_a_space_reach_the_validation() {
    let d = tmp("negative");
    let out = d.to_str().unwrap();
    let (imu, gt) = (
        euroc(),
        repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"),
    );
    let noise = repo("tests/data/euroc/imu.yaml");
    let window = [
        "--from",
        "1403715280000000000",
        "--to",
        "1403715281000000000",
    ];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["simulate", "--out", out, "--duration", "-1"],
            "--duration",
        ),
        (vec!["simulate", "--out", out, "--rate", "-200"], "--rate"),
        (vec!["simulate", "--out", out, "--seed", "-1"], "--seed"),
        (
            vec!["integrate", "--imu", &imu, "--gravity", "-9.81"],
            "for '--gravity <GRAVITY>'",
        ),
        (vec!["bench-steps", "--window", "-1e-3"], "--window must be"),
        (vec!["bench-steps", "--rates", "-100,200"], "--rates"),
        (vec!["speed", "--samples", "-5"], "--samples"),
        (
            vec![
                "advise",
                "--imu",
                &imu,
                "--noise",
                &noise,
                "--fraction",
                "-0.1",
            ],
            "--fraction must be",
        ),
        (
            [
                &["factor", "--imu", &imu, "--poses", &gt][..],
                &window,
                &["--vel-std", "-0.01"],
            ]
            .concat(),
            "--vel-std must be",
        ),
        (
            vec![
                "calibrate",
                "--imu",
                &imu,
                "--poses",
                &gt,
                "--pose-spacing",
                "-0.5",
            ],
            "--pose-spacing must be",
        ),
    ];
    for (args, want) in cases {
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: want {want:?} in {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
    // A valid negative value after a space is the same value as with `=`.
    let to = ["--to", T_TO];
    let spaced = json(
        &[
            &["integrate", "--imu", &imu, "--bias-gyro", "-0.01,0,0"][..],
            &to,
        ]
        .concat(),
    );
    let joined = json(
        &[
            &["integrate", "--imu", &imu, "--bias-gyro=-0.01,0,0"][..],
            &to,
        ]
        .concat(),
    );
    assert_eq!(spaced["bias_hat"]["gyro"][0], -0.01);
    assert_eq!(spaced, joined);
}

/// Runs `preint ARGS` with stdout a pipe whose reading end is already closed: every write
/// fails with `BrokenPipe`. Returns the exit code and stderr.
fn into_closed_pipe(args: &[&str]) -> (Option<i32>, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = bin()
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Output into a pipe closed early ends quietly with the command's own status (0 on
/// success; `cli/src/main.rs`), with no panic and no "Broken pipe" message.
#[test]
fn a_pipe_closed_early_ends_quietly() {
    let imu = euroc();
    let integrate = ["integrate", "--imu", &imu, "--to", T_TO];
    let cases: [(Vec<&str>, i32); 5] = [
        (integrate.to_vec(), 0),
        ([&integrate[..], &["--json"]].concat(), 0),
        (vec!["--help"], 0),
        (vec!["integrate", "--help"], 0),
        (vec!["integrate", "--imu", "no/such/file.csv"], 2),
    ];
    for (args, code) in cases {
        let (status, err) = into_closed_pipe(&args);
        assert_eq!(status, Some(code), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(
            !err.to_lowercase().contains("broken pipe"),
            "{args:?}: {err}"
        );
        if code == 2 {
            assert!(err.contains("no/such/file.csv"), "{args:?}: {err}");
        }
    }
    // A reader that takes one line and goes away.
    let mut child = bin()
        .args(integrate)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.contains("201 samples"), "{first}");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
