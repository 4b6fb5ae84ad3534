//! Hostile input, through the binary: every subcommand given files and flag values of the
//! kinds a real user gets wrong (wrong units, non-finite and absurd values, broken files,
//! convention errors, sizes that would exhaust memory). For every case, in text and in JSON:
//! - no panic (exit 101), no abort (134), no signal;
//! - nothing non-finite on stdout (no `inf`/`NaN` word in the text, no `null` in the JSON
//!   outside the keys that are `null` by design, [`NULLABLE`]), nor in any file written;
//! - a refusal (exit 2) names what it refuses: the file (and line) or the flag;
//! - an answer (exit 0) to a question the data cannot answer says so (the case's warning).
//!
//! `docs/EVIDENCE.md` ("Hostile input") lists the cases by class; this table is the source.

mod common;
use common::{bin, repo, tmp, write};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const EUROC_IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const EUROC_GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";
const EUROC_NOISE: &str = "tests/data/euroc/imu.yaml";

/// JSON keys whose value is `null` by design (not a number that went non-finite): an
/// estimate withheld or not asked for, a bound instead of a fit, an optional input not given.
const NULLABLE: &[&str] = &[
    // An optional input not given, or a setting that does not apply.
    "calibration",
    "omega_coriolis",
    "coriolis",
    "body_p_sensor",
    "time_offset_s",
    "extrinsics",
    // An estimate or a recommendation the data does not support (said in the text).
    "recommended_scheme",
    "recommended_rate",
    "exact_scheme",
    "ref_dist",
    "rates_not_evaluated",
    // `advise`'s denoising cutoff when no cutoff leaves white noise (`gyro`, `acc`).
    "gyro",
    "acc",
    // An Allan bound (no region of the slope) has no statistical error.
    "noise_density_err",
    "random_walk_err",
    // `audit`: an event that did not happen, a check that had nothing to measure.
    "first_index",
    "first_at",
    "largest",
    "stopped",
    "error",
    "gyro_scale",
    "gyro_axes",
    "why",
    "rate",
    "jitter",
    "units",
];

/// What a case must give.
#[derive(Clone, Copy, Debug)]
enum Expect {
    /// Exit 2, the message holding each string (the file or flag named).
    Refuse(&'static [&'static str]),
    /// Exit 0, the text and the JSON holding each string (a warning, a verdict).
    Answer(&'static [&'static str]),
    /// Either a refusal naming the first list, or an answer holding the second.
    RefuseOrWarn(&'static [&'static str], &'static [&'static str]),
}

struct Case {
    name: &'static str,
    args: Vec<String>,
    expect: Expect,
}

/// The shared input files, written once into `dir`.
struct Files {
    dir: PathBuf,
}

impl Files {
    fn path(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }
}

/// The first `n` data rows of the shipped EuRoC recording, as `[t, w, a]` values.
fn euroc(n: usize) -> Vec<(i64, [f64; 6])> {
    std::fs::read_to_string(repo(EUROC_IMU))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .take(n)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let v: Vec<f64> = f[1..7].iter().map(|x| x.parse().unwrap()).collect();
            (f[0].parse().unwrap(), [v[0], v[1], v[2], v[3], v[4], v[5]])
        })
        .collect()
}

fn csv(header: &str, rows: &[(i64, [f64; 6])]) -> String {
    let mut s = format!("{header}\n");
    for (t, v) in rows {
        let _ = writeln!(
            s,
            "{t},{},{},{},{},{},{}",
            v[0], v[1], v[2], v[3], v[4], v[5]
        );
    }
    s
}

const EUROC_HEADER: &str = "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z";

fn write_files(dir: &Path) -> Files {
    let rows = euroc(6000);
    let w = |name: &str, text: &str| {
        write(dir, name, text);
    };
    w("good.csv", &csv(EUROC_HEADER, &rows[..2000]));
    w("one.csv", &csv(EUROC_HEADER, &rows[..1]));
    w("header_only.csv", &format!("{EUROC_HEADER}\n"));
    w("empty.csv", "");
    let scaled = |r: &[(i64, [f64; 6])], gs: f64, asc: f64| -> Vec<(i64, [f64; 6])> {
        r.iter()
            .map(|(t, v)| {
                (
                    *t,
                    [
                        v[0] * gs,
                        v[1] * gs,
                        v[2] * gs,
                        v[3] * asc,
                        v[4] * asc,
                        v[5] * asc,
                    ],
                )
            })
            .collect()
    };
    let deg = 180.0 / std::f64::consts::PI;
    // deg/s written where the header says nothing: read as rad/s.
    w(
        "deg_2s.csv",
        &csv(EUROC_HEADER, &scaled(&rows[..400], deg, 1.0)),
    );
    w(
        "deg_2s_moving.csv",
        &csv(EUROC_HEADER, &scaled(&rows[1400..1800], deg, 1.0)),
    );
    w("deg.csv", &csv(EUROC_HEADER, &scaled(&rows, deg, 1.0)));
    w(
        "g_units.csv",
        &csv(EUROC_HEADER, &scaled(&rows[..2000], 1.0, 1.0 / 9.80665)),
    );
    // 10 Hz, timestamps in seconds (a delimited file whose unit must be stated).
    let mut s10 = String::from("t,wx,wy,wz,ax,ay,az\n");
    for (t, v) in rows.iter().step_by(20) {
        let _ = writeln!(
            s10,
            "{:.3},{},{},{},{},{},{}",
            (*t - rows[0].0) as f64 * 1e-9,
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5]
        );
    }
    w("s_10hz.csv", &s10);
    let mut nan = csv(EUROC_HEADER, &rows[..500]);
    nan = nan.replacen(&format!("{}", rows[100].1[3]), "NaN", 1);
    w("nan.csv", &nan);
    // A stuck sensor: every reading the same for 20 s.
    let still = vec![[0.0, 0.0, 0.0, 0.0, 0.0, 9.81]; 4000];
    let stuck: Vec<_> = rows[..4000]
        .iter()
        .zip(&still)
        .map(|((t, _), v)| (*t, *v))
        .collect();
    w("stuck.csv", &csv(EUROC_HEADER, &stuck));
    let mut inf = csv(EUROC_HEADER, &rows[..500]);
    inf = inf.replacen(&format!("{}", rows[100].1[0]), "inf", 1);
    w("inf.csv", &inf);
    let mut huge = rows[..2000].to_vec();
    huge[700].1[4] = 1e308;
    w("huge.csv", &csv(EUROC_HEADER, &huge));
    let mut spike = rows[..2000].to_vec();
    spike[900].1[1] = 40.0;
    w("spike.csv", &csv(EUROC_HEADER, &spike));
    let mut dup = rows[..500].to_vec();
    dup[200].0 = dup[199].0;
    w("dup.csv", &csv(EUROC_HEADER, &dup));
    let mut dec = rows[..500].to_vec();
    dec.swap(300, 301);
    w("decreasing.csv", &csv(EUROC_HEADER, &dec));
    let mut gap: Vec<_> = rows[..2000].to_vec();
    gap.drain(800..1200);
    w("gap.csv", &csv(EUROC_HEADER, &gap));
    let mut malformed = csv(EUROC_HEADER, &rows[..500]);
    let bad = format!("{},", rows[250].0);
    let pos = malformed.find(&bad).unwrap();
    malformed.insert_str(pos + bad.len(), "1.0.0x,");
    w("malformed.csv", &malformed);
    w("garbage.csv", "hello, world\nthis is not an IMU\n");
    std::fs::write(
        dir.join("binary.csv"),
        (0..4096)
            .map(|k| (k * 7919 % 251) as u8)
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    // Noise files.
    let yaml = |gn: &str, gw: &str, an: &str, aw: &str| {
        format!(
            "gyroscope_noise_density: {gn}\ngyroscope_random_walk: {gw}\n\
             accelerometer_noise_density: {an}\naccelerometer_random_walk: {aw}\nupdate_rate: 200.0\n"
        )
    };
    w(
        "noise_zero.yaml",
        &yaml("0", "1.9393e-05", "2.0e-3", "3.0e-3"),
    );
    w(
        "noise_neg.yaml",
        &yaml("1.6968e-04", "1.9393e-05", "-2.0e-3", "3.0e-3"),
    );
    w(
        "noise_huge.yaml",
        &yaml("1.6968e-04", "1.9393e-05", "1e308", "3.0e-3"),
    );
    w(
        "noise_nan.yaml",
        &yaml("nan", "1.9393e-05", "2.0e-3", "3.0e-3"),
    );
    w(
        "noise_text.yaml",
        &yaml("1.6968e-04", "small", "2.0e-3", "3.0e-3"),
    );
    w(
        "noise_missing.yaml",
        "gyroscope_noise_density: 1.6968e-04\nupdate_rate: 200.0\n",
    );
    // Calibration files.
    w("calib_empty.yaml", "");
    w(
        "calib_absurd.yaml",
        "%YAML:1.0\nimu0:\n  model: kalibr\n  Tw:\n    - [ 5.0, 0.0, 0.0 ]\n    - [ 0.0, 1.0, 0.0 ]\n    - [ 0.0, 0.0, 1.0 ]\n",
    );
    // Pose files: x,y,z,w quaternion order; a bad quaternion; 16 columns.
    let gt = std::fs::read_to_string(repo(EUROC_GT)).unwrap();
    let (mut xyzw, mut badq, mut w16) = (String::new(), String::new(), String::new());
    for (k, l) in gt
        .lines()
        .filter(|l| !l.starts_with('#'))
        .take(2000)
        .enumerate()
    {
        let f: Vec<&str> = l.split(',').collect();
        let _ = writeln!(
            xyzw,
            "{},{},{},{},{},{},{},{}",
            f[0], f[1], f[2], f[3], f[5], f[6], f[7], f[4]
        );
        let q = if k == 10 { "2,0,0,0" } else { "1,0,0,0" };
        let _ = writeln!(badq, "{},{},{},{},{q}", f[0], f[1], f[2], f[3]);
        let _ = writeln!(w16, "{}", f[..16].join(","));
    }
    w("poses_xyzw.csv", &xyzw);
    w("poses_badq.csv", &badq);
    w("poses_16.csv", &w16);
    Files {
        dir: dir.to_path_buf(),
    }
}

fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

#[rustfmt::skip]
fn cases(f: &Files) -> Vec<Case> {
    let p = |n: &str| f.path(n);
    let out = |n: &str| f.dir.join("out").join(n).display().to_string();
    let (imu, gt, noise) = (repo(EUROC_IMU), repo(EUROC_GT), repo(EUROC_NOISE));
    let t0 = "1403715280000000000";
    let t1 = "1403715281000000000";
    let c = |name, args: Vec<String>, expect| Case { name, args, expect };
    use Expect::*;
    vec![
        // Broken files, every reading subcommand.
        c("integrate empty file", s(&["integrate", "--imu", &p("empty.csv")]), Refuse(&["empty.csv"])),
        c("integrate header only", s(&["integrate", "--imu", &p("header_only.csv")]), Refuse(&["header_only.csv", "no data rows"])),
        c("integrate one row", s(&["integrate", "--imu", &p("one.csv")]), Refuse(&["one.csv", "1 sample"])),
        c("audit one row", s(&["audit", "--imu", &p("one.csv")]), RefuseOrWarn(&["one.csv"], &["too short"])),
        c("integrate NaN value", s(&["integrate", "--imu", &p("nan.csv")]), Refuse(&["nan.csv:"])),
        c("allan stuck sensor", s(&["allan", "--imu", &p("stuck.csv")]), Refuse(&["stuck.csv", "never change"])),
        c("allan inf value", s(&["allan", "--imu", &p("inf.csv")]), Refuse(&["inf.csv:"])),
        c("convert duplicate stamp", s(&["convert", "--imu", &p("dup.csv"), "--out", &out("dup.csv")]), Refuse(&["dup.csv:", "duplicate"])),
        c("integrate decreasing stamps", s(&["integrate", "--imu", &p("decreasing.csv")]), Refuse(&["decreasing.csv:", "decreases"])),
        c("calibrate gap", s(&["calibrate", "--imu", &p("gap.csv")]), Refuse(&["gap.csv", "gap"])),
        c("integrate malformed row", s(&["integrate", "--imu", &p("malformed.csv")]), Refuse(&["malformed.csv:"])),
        c("audit garbage text", s(&["audit", "--imu", &p("garbage.csv")]), Refuse(&["garbage.csv"])),
        c("integrate binary bytes", s(&["integrate", "--imu", &p("binary.csv")]), Refuse(&["binary.csv"])),
        c("factor missing file", s(&["factor", "--imu", &p("nope.csv"), "--poses", &gt, "--from", t0, "--to", t1]), Refuse(&["nope.csv"])),
        // Wrong units.
        c("integrate deg/s window", s(&["integrate", "--imu", &p("deg.csv"), "--from", "1403715280000000000", "--to", "1403715281000000000"]), Refuse(&["deg.csv", "--gyro-unit"])),
        c("integrate deg/s 2 s excerpt", s(&["integrate", "--imu", &p("deg_2s.csv")]), RefuseOrWarn(&["deg_2s.csv", "--gyro-unit"], &["inconclusive"])),
        c("allan deg/s 2 s excerpt", s(&["allan", "--imu", &p("deg_2s.csv"), "--no-still-check"]), RefuseOrWarn(&["deg_2s.csv"], &["inconclusive"])),
        c("advise deg/s 2 s excerpt", s(&["advise", "--imu", &p("deg_2s.csv"), "--noise", &noise, "--window", "0.5"]), RefuseOrWarn(&["deg_2s.csv"], &["inconclusive"])),
        c("audit deg/s 2 s excerpt", s(&["audit", "--imu", &p("deg_2s.csv")]), RefuseOrWarn(&["deg_2s.csv"], &["inconclusive"])),
        c("audit deg/s 2 s moving excerpt", s(&["audit", "--imu", &p("deg_2s_moving.csv")]), Answer(&["--gyro-unit deg/s"])),
        c("integrate rad/s declared deg/s", s(&["integrate", "--imu", &p("good.csv"), "--gyro-unit", "deg/s"]), RefuseOrWarn(&["good.csv", "--gyro-unit"], &["inconclusive"])),
        c("integrate g read as m/s2", s(&["integrate", "--imu", &p("g_units.csv")]), Refuse(&["g_units.csv", "--accel-unit"])),
        c("calibrate s read as ms", s(&["calibrate", "--imu", &p("s_10hz.csv"), "--time-unit", "ms"]), RefuseOrWarn(&["s_10hz.csv"], &["inconclusive"])),
        // Non-finite and absurd values.
        c("allan 1e308 accelerometer", s(&["allan", "--imu", &p("huge.csv"), "--no-still-check", "--out", &out("allan_huge")]), Refuse(&["huge.csv"])),
        c("audit 1e308 accelerometer", s(&["audit", "--imu", &p("huge.csv")]), RefuseOrWarn(&["huge.csv"], &["impossible"])),
        c("advise 1e308 accelerometer", s(&["advise", "--imu", &p("huge.csv"), "--noise", &noise]), Refuse(&["huge.csv"])),
        c("audit single-sample spike", s(&["audit", "--imu", &p("spike.csv")]), Answer(&["spike"])),
        c("integrate gravity 1e308", s(&["integrate", "--imu", &imu, "--to", t1, "--gravity", "1e308", "--initial-state", "0,0,0,0,0,0,1,0,0,0"]), Refuse(&["--gravity"])),
        c("integrate gravity NaN", s(&["integrate", "--imu", &imu, "--to", t1, "--gravity", "NaN"]), Refuse(&["--gravity"])),
        c("calibrate gravity negative", s(&["calibrate", "--imu", &imu, "--gravity", "-9.81"]), Refuse(&["--gravity"])),
        c("integrate omega-coriolis 1e10", s(&["integrate", "--imu", &imu, "--to", t1, "--omega-coriolis", "1e10,0,0"]), Refuse(&["--omega-coriolis"])),
        c("simulate earth-rate 1e10", s(&["simulate", "--scene", "static", "--duration", "1", "--earth-rate", "1e10,0,0", "--out", &out("sim_er")]), Refuse(&["--earth-rate"])),
        c("simulate latitude 91", s(&["simulate", "--latitude", "91", "--out", &out("sim_lat")]), Refuse(&["--latitude"])),
        c("integrate non-unit body quaternion", s(&["integrate", "--imu", &imu, "--to", t1, "--body-p-sensor", "0,0,0,2,0,0,0"]), Refuse(&["--body-p-sensor"])),
        c("integrate NaN initial state", s(&["integrate", "--imu", &imu, "--to", t1, "--initial-state", "nan,0,0,0,0,0,1,0,0,0"]), Refuse(&["--initial-state"])),
        c("integrate zero noise density", s(&["integrate", "--imu", &imu, "--to", t1, "--noise", &p("noise_zero.yaml")]), Refuse(&["noise_zero.yaml", "gyroscope_noise_density"])),
        c("factor zero noise density", s(&["factor", "--imu", &imu, "--poses", &gt, "--from", t0, "--to", t1, "--noise", &p("noise_zero.yaml")]), Refuse(&["noise_zero.yaml", "gyroscope_noise_density"])),
        c("integrate negative noise density", s(&["integrate", "--imu", &imu, "--to", t1, "--noise", &p("noise_neg.yaml")]), Refuse(&["noise_neg.yaml", "accelerometer_noise_density"])),
        c("integrate 1e308 noise density", s(&["integrate", "--imu", &imu, "--to", t1, "--noise", &p("noise_huge.yaml")]), Refuse(&["noise_huge.yaml", "accelerometer_noise_density"])),
        c("advise NaN noise density", s(&["advise", "--imu", &imu, "--noise", &p("noise_nan.yaml")]), Refuse(&["noise_nan.yaml", "gyroscope_noise_density"])),
        c("integrate text noise density", s(&["integrate", "--imu", &imu, "--to", t1, "--noise", &p("noise_text.yaml")]), Refuse(&["noise_text.yaml", "gyroscope_random_walk"])),
        c("simulate noise missing keys", s(&["simulate", "--noise", &p("noise_missing.yaml"), "--out", &out("sim_nm")]), Refuse(&["noise_missing.yaml"])),
        c("integrate empty calibration", s(&["integrate", "--imu", &imu, "--to", t1, "--calibration", &p("calib_empty.yaml")]), Refuse(&["calib_empty.yaml"])),
        c("integrate absurd calibration", s(&["integrate", "--imu", &imu, "--to", t1, "--calibration", &p("calib_absurd.yaml")]), Refuse(&["calib_absurd.yaml", "Tw"])),
        // Windows, spans and sizes.
        c("integrate window outside", s(&["integrate", "--imu", &p("good.csv"), "--from", "60", "--to", "61"]), Refuse(&["good.csv", "1403715273262142976"])),
        c("integrate from after to", s(&["integrate", "--imu", &imu, "--from", t1, "--to", t0]), Refuse(&["--from", "--to"])),
        c("simulate negative duration", s(&["simulate", "--duration", "-1", "--out", &out("sim_neg")]), Refuse(&["--duration"])),
        c("simulate memory-exhausting duration", s(&["simulate", "--duration", "1e9", "--out", &out("sim_big")]), Refuse(&["--duration"])),
        c("simulate zero rate", s(&["simulate", "--rate", "0", "--out", &out("sim_zero")]), Refuse(&["--rate"])),
        c("bench-steps absurd rate", s(&["bench-steps", "--rates", "1e12"]), Refuse(&["1e12"])),
        c("speed absurd sample count", s(&["speed", "--samples", "100000000000"]), Refuse(&["--samples"])),
        c("advise zero window", s(&["advise", "--imu", &imu, "--noise", &noise, "--window", "0"]), Refuse(&["--window"])),
        c("advise NaN fraction", s(&["advise", "--imu", &imu, "--noise", &noise, "--fraction", "NaN"]), Refuse(&["--fraction"])),
        c("simulate unknown scene", s(&["simulate", "--scene", "moon", "--out", &out("sim_moon")]), Refuse(&["--scene"])),
        c("report into a path under a file", s(&["report", "--out", &format!("{}/x", p("good.csv"))]), Refuse(&["good.csv/x"])),
        c("convert onto a directory", s(&["convert", "--imu", &p("good.csv"), "--out", &f.dir.display().to_string()]), Refuse(&["--out"])),
        // Ground truth and its conventions.
        c("calibrate poses in x,y,z,w order", s(&["calibrate", "--imu", &imu, "--poses", &p("poses_xyzw.csv"), "--from", "1403715280000000000", "--to", "1403715300000000000"]), Answer(&["x,y,z,w"])),
        c("calibrate non-unit quaternion", s(&["calibrate", "--imu", &imu, "--poses", &p("poses_badq.csv")]), Refuse(&["poses_badq.csv:", "norm"])),
        c("calibrate 16-column poses", s(&["calibrate", "--imu", &imu, "--poses", &p("poses_16.csv")]), Refuse(&["poses_16.csv:", "16 columns"])),
        c("factor window outside the poses", s(&["factor", "--imu", &imu, "--poses", &gt, "--from", "1", "--to", "2"]), Refuse(&["--from"])),
    ]
}

/// Every `null` in `v` at a key not in [`NULLABLE`], as `path`.
fn stray_nulls(v: &Value, path: &str, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                if x.is_null() && !NULLABLE.contains(&k.as_str()) {
                    out.push(format!("{path}.{k}"));
                }
                stray_nulls(x, &format!("{path}.{k}"), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                if x.is_null() {
                    out.push(format!("{path}[{i}]"));
                }
                stray_nulls(x, &format!("{path}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// Files under `dir` holding a non-finite number (`inf`, `NaN` as a word).
fn non_finite_files(dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return bad;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            bad.extend(non_finite_files(&p));
        } else if let Ok(text) = std::fs::read_to_string(&p)
            && let Some((line, t)) = preint_io::error::non_finite_line(&text)
        {
            bad.push(format!("{}:{line}: {t}", p.display()));
        }
    }
    bad
}

/// Runs one case in text and JSON form; returns what is wrong with it (empty when nothing).
fn check(case: &Case, out_dir: &Path) -> Vec<String> {
    let mut wrong = Vec::new();
    for json in [false, true] {
        let mut args = case.args.clone();
        if json {
            args.push("--json".into());
        }
        let o = bin()
            .args(&args)
            .current_dir(out_dir)
            .output()
            .expect("runs");
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        );
        let form = if json { "json" } else { "text" };
        let mut fail = |m: String| wrong.push(format!("{} [{form}]: {m}", case.name));
        let code = o.status.code();
        if code.is_none() || code == Some(101) || code == Some(134) || stderr.contains("panicked") {
            fail(format!("crashed ({code:?}): {stderr}"));
            continue;
        }
        if json && !stdout.trim().is_empty() {
            match serde_json::from_str::<Value>(&stdout) {
                Ok(v) => {
                    let mut nulls = Vec::new();
                    stray_nulls(&v, "", &mut nulls);
                    if !nulls.is_empty() {
                        fail(format!("null where a number belongs: {nulls:?}"));
                    }
                }
                Err(e) => fail(format!("stdout is not one JSON object: {e}")),
            }
        }
        if !json && let Some((line, t)) = preint_io::error::non_finite_line(&stdout) {
            fail(format!("non-finite number on line {line}: {t}"));
        }
        let text = &stdout;
        let needles_in = |hay: &str, n: &[&str]| n.iter().all(|x| hay.contains(x));
        match (case.expect, code) {
            (Expect::Refuse(n), Some(2)) | (Expect::RefuseOrWarn(n, _), Some(2)) => {
                if !needles_in(&stderr, n) {
                    fail(format!("the refusal does not name {n:?}: {stderr}"));
                }
            }
            (Expect::Answer(n), Some(0)) | (Expect::RefuseOrWarn(_, n), Some(0)) => {
                if !needles_in(text, n) {
                    fail(format!("the answer does not say {n:?}: {text}"));
                }
            }
            (e, c) => fail(format!(
                "expected {e:?}, exit {c:?}: {stderr}{}",
                &stdout[..stdout.len().min(600)]
            )),
        }
    }
    wrong
}

#[test]
fn hostile_input_gives_no_crash_no_non_finite_output_and_named_refusals() {
    let dir = tmp("hostile");
    let files = write_files(&dir);
    std::fs::create_dir_all(dir.join("out")).unwrap();
    let cases = cases(&files);
    assert!(cases.len() >= 50, "{} cases", cases.len());
    let mut wrong: Vec<String> = cases
        .iter()
        .flat_map(|c| check(c, &dir.join("out")))
        .collect();
    wrong.extend(
        non_finite_files(&dir.join("out"))
            .into_iter()
            .map(|f| format!("a file written holds a non-finite number: {f}")),
    );
    assert!(
        wrong.is_empty(),
        "{} of {} checks failed:\n{}",
        wrong.len(),
        2 * cases.len(),
        wrong.join("\n")
    );
}
