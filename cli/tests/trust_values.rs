//! Values with a physical range, through the binary: a reading beyond any IMU's range is
//! refused naming the line and sample (and is an audit defect), flag values outside their
//! range are refused naming the flag, noise-file values naming the file, line and key; audit
//! calls a spike a spike and a recording too short to judge too short; a window outside the
//! recording names the recording's real first and last samples.

mod common;

use common::{json, repo, run, tmp, write, write_imu_csv, write_noise_yaml};
use serde_json::Value;
use std::path::{Path, PathBuf};

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const NOISE: &str = "tests/data/euroc/imu.yaml";
const GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";
const FROM: &str = "1403715280000000000";
const TO: &str = "1403715281000000000";

/// The first `n` rows of EuRoC V1_01 with the stamps moved to start at 1000 ns, and `edit`
/// applied to each row's values.
fn euroc_rows(n: usize, edit: impl Fn(usize, &mut [f64; 6])) -> Vec<(i64, [f64; 6])> {
    let text = std::fs::read_to_string(repo(EUROC)).unwrap();
    let mut t0 = None;
    (text.lines().skip(1).take(n).enumerate())
        .map(|(k, line)| {
            let f: Vec<&str> = line.split(',').collect();
            let t: i64 = f[0].parse().unwrap();
            let t0 = *t0.get_or_insert(t);
            let mut v = [0.0; 6];
            for (x, s) in v.iter_mut().zip(&f[1..]) {
                *x = s.parse().unwrap();
            }
            edit(k, &mut v);
            (t - t0 + 1000, v)
        })
        .collect()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `args` and returns its stderr, asserting it failed with exit code 2.
fn refused(args: &[&str]) -> String {
    let o = run(args);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    assert!(o.stdout.is_empty(), "{args:?}");
    stderr(&o)
}

fn spiked(dir: &Path) -> PathBuf {
    let rows = euroc_rows(3000, |k, v| {
        if k == 1000 {
            v[3] = 1e308;
        }
    });
    write_imu_csv(dir, "spiked.csv", &rows)
}

#[test]
fn a_reading_beyond_any_imu_is_refused_by_every_command_and_never_reaches_imu_yaml() {
    let d = tmp("values-1e308");
    let f = spiked(&d);
    let imu = f.to_str().unwrap();
    let out = d.join("allan");
    let e = refused(&[
        "allan",
        "--imu",
        imu,
        "--no-still-check",
        "--out",
        out.to_str().unwrap(),
    ]);
    // Header on line 1: sample 1000 is on line 1002.
    assert!(
        e.contains("spiked.csv:1002: sample 1000") && e.contains("beyond any IMU's range"),
        "{e}"
    );
    assert!(!out.join("imu.yaml").exists());
    let e = refused(&["integrate", "--imu", imu, "--no-unit-check"]);
    assert!(e.contains("spiked.csv:1002: sample 1000"), "{e}");
    // The audit reads on and lists it as a defect.
    let a = json(&["audit", "--imu", imu]);
    assert_eq!(a["verdict"], "defects");
    let first = &a["impossible"]["first"][0];
    assert_eq!(
        (first["index"].as_u64(), first["line"].as_u64()),
        (Some(1000), Some(1002))
    );
    assert!(
        a["findings"][0]["message"]
            .as_str()
            .unwrap()
            .contains("index 1000 (line 1002)"),
        "{a:#}"
    );
}

#[test]
fn audit_names_a_single_sample_spike_in_robust_sigmas() {
    let d = tmp("values-spike");
    let rows = euroc_rows(3000, |k, v| {
        if k == 2000 {
            v[4] += 30.0; // acc y, 30 m/s² for one sample
        }
    });
    let f = write_imu_csv(&d, "spike.csv", &rows);
    let a = json(&["audit", "--imu", f.to_str().unwrap()]);
    assert_eq!(a["spikes"]["count"], 1, "{a:#}");
    let s = &a["spikes"]["first"][0];
    assert_eq!(
        (s["index"].as_u64(), s["line"].as_u64()),
        (Some(2000), Some(2002))
    );
    assert_eq!(s["axis"], "acc y");
    assert!(s["sigmas"].as_f64().unwrap() > 20.0, "{s}");
    // The recording as it is has none.
    let clean = json(&["audit", "--imu", &repo(EUROC)]);
    assert_eq!(clean["spikes"]["count"], 0);
}

#[test]
fn a_recording_too_short_to_judge_is_not_clean() {
    let d = tmp("values-short");
    let one = write_imu_csv(&d, "one.csv", &euroc_rows(1, |_, _| {}));
    let imu = one.to_str().unwrap();
    let a = json(&["audit", "--imu", imu]);
    assert_eq!(
        (&a["verdict"], &a["clean"]),
        (&Value::from("too_short"), &Value::from(false))
    );
    let text = String::from_utf8_lossy(&run(&["audit", "--imu", imu]).stdout).into_owned();
    assert!(text.contains("verdict: too short to judge"), "{text}");
    assert!(
        !text.contains("clean") && !text.contains("1 windows"),
        "{text}"
    );
    let o = run(&["audit", "--imu", imu, "--strict"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("too short to judge: 1 sample"),
        "{}",
        stderr(&o)
    );
    // 300 samples over 1.5 s are judged.
    let ok = write_imu_csv(&d, "ok.csv", &euroc_rows(300, |_, _| {}));
    assert_eq!(
        json(&["audit", "--imu", ok.to_str().unwrap()])["verdict"],
        "clean"
    );
}

#[test]
fn a_window_outside_the_recording_names_its_real_first_and_last_samples() {
    let d = tmp("values-outside");
    let rows = euroc_rows(2000, |_, _| {});
    let f = write_imu_csv(&d, "near0.csv", &rows);
    let last = rows[rows.len() - 1].0;
    for (from, to) in [("60", "61"), ("60000000000", "61000000000")] {
        let e = refused(&[
            "integrate",
            "--imu",
            f.to_str().unwrap(),
            "--from",
            from,
            "--to",
            to,
        ]);
        assert!(e.contains(&format!("[1000, {last}]")), "{from}: {e}");
    }
}

#[test]
fn flags_outside_their_physical_range_are_refused_naming_the_flag() {
    let imu = repo(EUROC);
    let window = ["--imu", &imu, "--from", FROM, "--to", TO];
    let state = ["--initial-state", "0,0,0,0,0,0,1,0,0,0"];
    let integrate = |extra: &[&str]| {
        let mut a = vec!["integrate"];
        a.extend(window);
        a.extend(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let d = tmp("values-flags");
    let sim = d.to_str().unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            integrate(&[&["--gravity", "1e308"][..], &state].concat()),
            "--gravity",
        ),
        (integrate(&["--gravity=-1"]), "--gravity"),
        (
            integrate(&["--omega-coriolis", "1e10,0,0"]),
            "--omega-coriolis",
        ),
        (
            integrate(&["--body-p-sensor", "0,0,5000,1,0,0,0"]),
            "--body-p-sensor",
        ),
        (
            integrate(&["--initial-state", "0,0,0,3e8,0,0,1,0,0,0"]),
            "--initial-state",
        ),
        (
            integrate(&["--initial-state", "1e300,0,0,0,0,0,1,0,0,0"]),
            "--initial-state",
        ),
        (
            ["calibrate", "--imu", &imu, "--gravity", "1e308"]
                .map(String::from)
                .to_vec(),
            "--gravity",
        ),
        (
            ["simulate", "--out", sim, "--earth-rate", "0,0,1000"]
                .map(String::from)
                .to_vec(),
            "--earth-rate",
        ),
        (
            ["simulate", "--out", sim, "--latitude", "91"]
                .map(String::from)
                .to_vec(),
            "--latitude",
        ),
    ];
    for (args, flag) in &cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let e = refused(&a);
        assert!(e.contains(&format!("'{flag} ")), "{args:?}: {e}");
    }
    // Zero gravity (GTSAM's tests), another planet's and the Earth's rate are accepted.
    for extra in [
        &["--gravity", "0"][..],
        &["--gravity", "3.72"],
        &["--omega-coriolis", "0,0,7.292115e-5"],
    ] {
        let v = json(
            &integrate(&[extra, &state].concat())
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
        );
        let p = common::nums(&v["predicted"]["position"]);
        assert!(p.iter().all(|x| x.is_finite()), "{extra:?}: {v}");
    }
}

#[test]
fn noise_file_values_are_refused_naming_the_file_line_and_key() {
    let d = tmp("values-noise");
    let imu = repo(EUROC);
    let gt = repo(GT);
    let factor = |noise: &Path, extra: &[&str]| {
        let mut a = vec![
            "factor", "--imu", &imu, "--poses", &gt, "--from", FROM, "--to", TO,
        ];
        a.extend(["--noise", noise.to_str().unwrap()]);
        a.extend(extra);
        refused(&a)
    };
    // Lines: 1 gyroscope_noise_density, 2 gyroscope_random_walk, 3 accelerometer_noise_density,
    // 4 accelerometer_random_walk, 5 update_rate.
    let zero = write_noise_yaml(&d, "zero.yaml", [0.0, 1.9393e-5, 2.0e-3, 3.0e-3], 200.0);
    let e = factor(&zero, &[]);
    assert!(
        e.contains("zero.yaml:1: `gyroscope_noise_density` is 0"),
        "{e}"
    );
    let e = refused(&[
        "integrate",
        "--imu",
        &imu,
        "--noise",
        zero.to_str().unwrap(),
    ]);
    assert!(e.contains("zero.yaml:1:"), "{e}");
    let huge = write_noise_yaml(
        &d,
        "huge.yaml",
        [1.6968e-4, 1.9393e-5, 1e308, 3.0e-3],
        200.0,
    );
    let e = factor(&huge, &[]);
    assert!(
        e.contains("huge.yaml:3: `accelerometer_noise_density` is 1e308") && !e.contains("imu0"),
        "{e}"
    );
    let walk = write_noise_yaml(&d, "walk.yaml", [1.6968e-4, 0.0, 2.0e-3, 3.0e-3], 200.0);
    let e = factor(&walk, &["--combined"]);
    assert!(
        e.contains("walk.yaml:2: `gyroscope_random_walk` is 0"),
        "{e}"
    );
    // Without --combined a constant bias (zero random walks) weights the 9-dim factor.
    let mut a = vec!["factor", "--imu", &imu, "--from", FROM, "--to", TO];
    a.extend(["--poses", &gt, "--noise", walk.to_str().unwrap()]);
    assert!(json(&a)["chi2"].as_f64().unwrap().is_finite());
    let rate = write(
        &d,
        "rate.yaml",
        &std::fs::read_to_string(repo(NOISE))
            .unwrap()
            .replace("update_rate: 200.0", "update_rate: 0"),
    );
    let e = refused(&[
        "integrate",
        "--imu",
        &imu,
        "--noise",
        rate.to_str().unwrap(),
    ]);
    assert!(
        e.contains("rate.yaml:8: `update_rate` must be positive"),
        "{e}"
    );
}
