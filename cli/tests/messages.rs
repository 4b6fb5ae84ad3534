//! Messages a user would sign, through the binary: each refusal's headline agrees with its
//! numbers and the data, each names the file and line (or the flag); and the answers that
//! used to be refusals for no reason (a long static simulation, a recording with a short
//! gap at low rates, 1 Hz in `bench-steps`, quoted CSV fields) are answers.

mod common;
use common::{json, repo, run, simulate, tmp, write};
use std::fmt::Write as _;

const EUROC_IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";

/// The first `n` data rows of the shipped EuRoC recording, as lines without the header.
fn euroc_rows(n: usize) -> Vec<String> {
    std::fs::read_to_string(repo(EUROC_IMU))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .take(n)
        .map(str::to_string)
        .collect()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `allan` on four hours of the project's own static simulation (EuRoC densities, bias random
/// walk on): the accelerometer bias walk turns the gravity direction by several degrees, and
/// the recording is still recognised as static (its norm moves as much as its direction).
#[test]
fn allan_takes_a_long_static_simulation_for_static() {
    let dir = tmp("messages-allan-static");
    let sim = dir.join("sim");
    simulate(
        &sim,
        &["--scene", "static", "--rate", "20", "--duration", "14400"],
    );
    let imu = sim.join("imu.csv");
    let out = json(&["allan", "--imu", imu.to_str().unwrap()]);
    let c = &out["checks"];
    assert!(c["max_tilt_deg"].as_f64().unwrap() > 2.0, "{c}");
    assert_eq!(c["tilt_is_bias_walk"], true, "{c}");
    assert!(c["step_tilt_deg"].as_f64().unwrap() < 0.5, "{c}");
}

/// A recording too short for two stillness windows is "too short", not "100.0 % of its 0
/// windows".
#[test]
fn allan_on_a_short_recording_says_it_is_too_short() {
    let dir = tmp("messages-allan-short");
    let mut csv = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
    for r in euroc_rows(300) {
        let _ = writeln!(csv, "{r}");
    }
    let f = write(&dir, "short.csv", &csv);
    let o = run(&["allan", "--imu", f.to_str().unwrap()]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("too short") && !e.contains("0 windows"), "{e}");
}

/// `advise` on a recording with a 110 ms gap (within preintegration's 250 ms limit): the rates
/// at which decimation would widen it beyond the limit are not evaluated, and the note names
/// the file, the data's own gap and where it is, instead of failing with the decimated
/// stream's gap at a sample index of that stream.
#[test]
fn advise_names_the_recordings_gap_that_stops_the_lower_rates() {
    let dir = tmp("messages-advise-gap");
    let rows = euroc_rows(1600);
    let mut csv = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
    for (k, r) in rows.iter().enumerate() {
        if !(600..621).contains(&k) {
            let _ = writeln!(csv, "{r}");
        }
    }
    let f = write(&dir, "gap.csv", &csv);
    let noise = repo("tests/data/euroc/imu.yaml");
    let out = json(&[
        "advise",
        "--imu",
        f.to_str().unwrap(),
        "--noise",
        &noise,
        "--window",
        "1",
    ]);
    let note = out["rates_not_evaluated"].as_str().expect("a note");
    assert!(note.contains("gap.csv"), "{note}");
    assert!(note.contains("0.110000 s before sample 600"), "{note}");
    assert!(
        note.contains("above preintegration's gap limit of 0.25 s"),
        "{note}"
    );
    let lowest = out["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["rate"].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest > 20.0,
        "rates below the note's were evaluated: {lowest}"
    );
}

/// `bench-steps --rates 1`: a uniform grid at 1 Hz is that rate, not a gap.
#[test]
fn bench_steps_runs_at_one_hertz() {
    let out = json(&["bench-steps", "--rates", "1,2", "--window", "4"]);
    let rows = out["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8, "{out}");
    assert!(rows.iter().all(|r| r["rot_err"].as_f64().unwrap() > 0.0));
}

/// Quoted CSV fields (as spreadsheets export them) read as the same samples as unquoted ones.
#[test]
fn quoted_csv_fields_read_as_numbers() {
    let dir = tmp("messages-quoted");
    let rows = euroc_rows(400);
    let mut plain = String::from("t,wx,wy,wz,ax,ay,az\n");
    let mut quoted = String::from("\"t\",\"wx\",\"wy\",\"wz\",\"ax\",\"ay\",\"az\"\n");
    for r in &rows {
        let _ = writeln!(plain, "{r}");
        let q: Vec<String> = r.split(',').map(|f| format!("\"{f}\"")).collect();
        let _ = writeln!(quoted, "{}", q.join(","));
    }
    let p = write(&dir, "plain.csv", &plain);
    let q = write(&dir, "quoted.csv", &quoted);
    let args = |f: &std::path::Path| {
        json(&[
            "integrate",
            "--imu",
            f.to_str().unwrap(),
            "--time-unit",
            "ns",
        ])
    };
    let (a, b) = (args(&p), args(&q));
    assert_eq!(a["samples"], 400, "{a}");
    assert_eq!(a["delta_v"], b["delta_v"]);
    assert_eq!(a["delta_R"], b["delta_R"]);
}

/// A pose file of 16 columns: the message says the first row has 16 columns and which layouts
/// a pose file has, not "expected the first row's 16 columns … found 16".
#[test]
fn a_pose_file_of_the_wrong_width_is_named_by_its_width() {
    let dir = tmp("messages-poses");
    let gt = std::fs::read_to_string(repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"))
        .unwrap();
    let cut: String = gt
        .lines()
        .take(50)
        .map(|l| l.split(',').take(16).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let f = write(&dir, "p16.csv", &cut);
    let o = run(&[
        "calibrate",
        "--imu",
        &repo(EUROC_IMU),
        "--poses",
        f.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("p16.csv:2: the first row has 16 columns"), "{e}");
    assert!(!e.contains("found 16"), "{e}");
}

/// Split streams that overlap over part of the recording: `integrate` and `convert` say the
/// result is that of the overlap and how many gyro samples were dropped, in text and JSON; the
/// shipped split fixture (a 63 Hz accelerometer inside a 200 Hz gyro's span) gives no warning.
#[test]
fn split_streams_shortened_to_their_overlap_say_so() {
    let dir = tmp("messages-split");
    let rows = euroc_rows(2000);
    let (mut g, mut a) = (String::new(), String::new());
    for (k, r) in rows.iter().enumerate() {
        let f: Vec<&str> = r.split(',').collect();
        let _ = writeln!(g, "{},{},{},{}", f[0], f[1], f[2], f[3]);
        if (600..1400).contains(&k) {
            let _ = writeln!(a, "{},{},{},{}", f[0], f[4], f[5], f[6]);
        }
    }
    let (g, a) = (write(&dir, "g.csv", &g), write(&dir, "a.csv", &a));
    let (g, a) = (g.to_str().unwrap(), a.to_str().unwrap());
    let out = dir.join("m.csv");
    for args in [
        vec!["integrate", "--gyro", g, "--accel", a],
        vec![
            "convert",
            "--gyro",
            g,
            "--accel",
            a,
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let text = String::from_utf8_lossy(&run(&args).stdout).into_owned();
        assert!(
            text.contains("warning: the split streams overlap over 3.980 s only")
                && text.contains("so 601 gyro samples before and 602 after it are dropped"),
            "{args:?}: {text}"
        );
        let w = &json(&args)["input"]["warnings"];
        assert_eq!(w.as_array().map(Vec::len), Some(1), "{args:?}: {w}");
    }
    let mcap = repo("tests/data/ros/split.mcap");
    let j = json(&[
        "integrate",
        "--imu",
        &mcap,
        "--gyro-topic",
        "/camera/gyro/sample",
        "--accel-topic",
        "/camera/accel/sample",
    ]);
    assert_eq!(
        j["input"]["warnings"],
        serde_json::json!([]),
        "{}",
        j["input"]
    );
}

/// A calibration file `calibrate --out` writes when the data supports no intrinsics (the
/// identity, stated) is read back by `--calibration`; a file with no calibration key at all
/// (`model:` alone) is refused naming it.
#[test]
fn a_calibration_file_of_our_own_is_read_back() {
    let dir = tmp("messages-calibration");
    let sim = dir.join("sim");
    simulate(
        &sim,
        &["--scene", "static", "--rate", "50", "--duration", "20"],
    );
    let imu = sim.join("imu.csv");
    let imu = imu.to_str().unwrap();
    let out = dir.join("calib.yaml");
    json(&["calibrate", "--imu", imu, "--out", out.to_str().unwrap()]);
    let back = json(&[
        "integrate",
        "--imu",
        imu,
        "--to",
        "2000000000",
        "--calibration",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        back["calibration"]["Tw"][0][0], 1.0,
        "{}",
        back["calibration"]
    );
    let bare = write(&dir, "bare.yaml", "imu0:\n  model: \"kalibr\"\n");
    let o = run(&[
        "integrate",
        "--imu",
        imu,
        "--calibration",
        bare.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("bare.yaml") && e.contains("nothing to apply"),
        "{e}"
    );
}
