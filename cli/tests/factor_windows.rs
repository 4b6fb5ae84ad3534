//! `preint factor --window`: the factor at the ground truth over a whole recording, and the
//! ground truth's bias error in the weight (`--bias-gyro-std`, `--bias-acc-std`).

mod common;

use common::{EUROC_DENSITIES, json, repo, run, simulate, tmp, write_noise_yaml};
use serde_json::Value;

fn euroc(noise: &str, extra: &[&str]) -> Value {
    let (imu, gt) = (
        repo("tests/data/euroc/V1_01_easy_imu0.csv"),
        repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"),
    );
    let mut args = vec!["factor", "--imu", &imu, "--poses", &gt, "--noise", noise];
    args.extend_from_slice(extra);
    json(&args)
}

fn rows(v: &Value) -> &Vec<Value> {
    v["windows"].as_array().unwrap()
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// Three lengths, three rows; each length's count is the overlap span over the length (± 1);
/// the mean χ² grows with the length (the datasheet densities are optimistic on EuRoC, more
/// so over longer windows); each row's shares sum to 1; the verdict says optimistic.
#[test]
fn euroc_windows_grow_with_the_length() {
    let v = euroc(&repo("tests/data/euroc/imu.yaml"), &["--window", "0.5,1,2"]);
    let span = &v["span_ns"];
    let span_s = (span[1].as_i64().unwrap() - span[0].as_i64().unwrap()) as f64 * 1e-9;
    assert!(span_s > 100.0, "{span_s}");
    let r = rows(&v);
    assert_eq!(r.len(), 3);
    let mut last_mean = 0.0;
    for (row, length) in r.iter().zip([0.5, 1.0, 2.0]) {
        assert_eq!(f(row, "length_s"), length);
        let n = f(row, "count") + f(row, "skipped");
        assert!((n - span_s / length).abs() <= 1.0, "{row}");
        assert_eq!(row["dof"], 9);
        let mean = f(row, "mean_chi2");
        assert!(mean > last_mean, "{row}");
        last_mean = mean;
        let p = f(row, "ks_p_value");
        assert!((0.0..=1.0).contains(&p));
        let s = &row["block_share"];
        let sum = f(s, "rotation") + f(s, "velocity") + f(s, "position");
        assert!((sum - 1.0).abs() < 1e-9, "{s}");
    }
    assert_eq!(v["verdict"]["kind"], "optimistic", "{}", v["verdict"]);
    assert!(f(&v["verdict"], "factor") > 2.0);
    assert_eq!(v["fit"]["credible"], false);
    let dof: f64 = r.iter().map(|row| f(row, "count") * 9.0).sum();
    assert_eq!(f(&v["fit"], "dof"), dof);
}

/// Ten times the datasheet densities (χ² divided by 100): not optimistic over 0.5 s and 1 s
/// windows. (Over 2 s the inflated model is still optimistic, χ²/dof ≈ 1.5: the misfit grows
/// with the length faster than white noise does.)
#[test]
fn euroc_inflated_densities_are_not_optimistic() {
    let d = tmp("factor-windows-inflated");
    let ten: Vec<f64> = EUROC_DENSITIES.iter().map(|x| 10.0 * x).collect();
    let yaml = write_noise_yaml(&d, "imu10.yaml", [ten[0], ten[1], ten[2], ten[3]], 200.0);
    let v = euroc(yaml.to_str().unwrap(), &["--window", "0.5,1"]);
    assert_ne!(v["verdict"]["kind"], "optimistic", "{}", v["verdict"]);
    assert_eq!(rows(&v).len(), 2);
}

/// The ground truth's bias error in the weight strictly lowers the mean χ² at 2 s; the JSON
/// echoes both σ.
#[test]
fn bias_std_lowers_the_chi2() {
    let noise = repo("tests/data/euroc/imu.yaml");
    let plain = euroc(&noise, &["--window", "2"]);
    let with = euroc(
        &noise,
        &[
            "--window",
            "2",
            "--bias-gyro-std",
            "1e-4",
            "--bias-acc-std",
            "0.01",
        ],
    );
    let (a, b) = (
        f(&rows(&plain)[0], "mean_chi2"),
        f(&rows(&with)[0], "mean_chi2"),
    );
    assert!(b < a, "{b} !< {a}");
    assert_eq!(f(&with["ground_truth_noise"], "bias_acc_m_s2"), 0.01);
    // The one-window form takes them too.
    let one = |extra: &[&str]| {
        let mut a = vec![
            "--from",
            "1403715280000000000",
            "--to",
            "1403715282000000000",
        ];
        a.extend_from_slice(extra);
        f(&euroc(&noise, &a), "chi2")
    };
    assert!(one(&["--bias-gyro-std", "1e-4"]) < one(&[]));
}

fn refused(extra: &[&str]) -> String {
    let (imu, gt) = (
        repo("tests/data/euroc/V1_01_easy_imu0.csv"),
        repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv"),
    );
    let mut args = vec!["factor", "--imu", &imu, "--poses", &gt];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(2), "{args:?}");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `--window` with `--from` is refused naming both; a negative `--bias-acc-std` or
/// `--bias-gyro-std` naming the flag; a non-positive length naming `--window`.
#[test]
fn bad_flags_are_refused() {
    let e = refused(&["--window", "1", "--from", "1403715280000000000"]);
    assert!(e.contains("--window") && e.contains("--from"), "{e}");
    let e = refused(&["--window", "1", "--bias-acc-std", "-0.1"]);
    assert!(e.contains("--bias-acc-std"), "{e}");
    let e = refused(&[
        "--from",
        "1403715280000000000",
        "--to",
        "1403715281000000000",
        "--bias-gyro-std",
        "NaN",
    ]);
    assert!(e.contains("--bias-gyro-std"), "{e}");
    let e = refused(&["--window", "0,1"]);
    assert!(e.contains("--window"), "{e}");
    let e = refused(&[]);
    assert!(e.contains("--window") && e.contains("--from"), "{e}");
}

/// Simulated data with a constant bias and the EuRoC white-noise densities: the factor at the
/// simulator's truth with the true noise is consistent over 1 s and 2 s windows, and the
/// windows' χ² pass the Kolmogorov–Smirnov test against χ²₉; with the densities halved (σ
/// too small by 2) the verdict is optimistic by about ×2.
#[test]
fn simulated_truth_is_consistent() {
    let d = tmp("factor-windows-sim");
    let mut dens = EUROC_DENSITIES;
    (dens[1], dens[3]) = (0.0, 0.0);
    let yaml = write_noise_yaml(&d, "noise.yaml", dens, 200.0);
    simulate(
        &d,
        &[
            "--noise",
            yaml.to_str().unwrap(),
            "--scene",
            "aggressive",
            "--duration",
            "60",
            "--seed",
            "3",
        ],
    );
    let (imu, gt, noise) = (
        d.join("imu.csv"),
        d.join("groundtruth.csv"),
        d.join("imu.yaml"),
    );
    let factor = |noise: &str| {
        json(&[
            "factor",
            "--imu",
            imu.to_str().unwrap(),
            "--poses",
            gt.to_str().unwrap(),
            "--noise",
            noise,
            "--scheme",
            "rk4",
            "--window",
            "1,2",
        ])
    };
    let v = factor(noise.to_str().unwrap());
    assert_eq!(v["verdict"]["kind"], "consistent", "{v}");
    for row in rows(&v) {
        assert_eq!(row["skipped"], 0);
        assert!(f(row, "ks_p_value") > 1e-3, "{row}");
    }
    let half: Vec<f64> = dens.iter().map(|x| 0.5 * x).collect();
    let small = write_noise_yaml(&d, "half.yaml", [half[0], 0.0, half[2], 0.0], 200.0);
    let v = factor(small.to_str().unwrap());
    assert_eq!(v["verdict"]["kind"], "optimistic", "{v}");
    let k = f(&v["verdict"], "factor");
    assert!((1.6..2.4).contains(&k), "{k}");
}

/// `--in-window-drift` weights ImuFactor with the bias random walk within each window: at 2 s
/// the mean χ² is strictly lower than with the white noise alone, the JSON says which weight;
/// with `--combined` it is refused. `--gravity-vector 0,0,-9.81` is `--gravity 9.81` exactly
/// and echoed; a vector longer than 100 m/s² is refused naming the flag.
#[test]
fn in_window_drift_and_gravity_vector() {
    let noise = repo("tests/data/euroc/imu.yaml");
    let plain = euroc(&noise, &["--window", "2"]);
    let drift = euroc(&noise, &["--window", "2", "--in-window-drift"]);
    assert_eq!(plain["in_window_drift"], false);
    assert_eq!(drift["in_window_drift"], true);
    let (a, b) = (
        f(&rows(&plain)[0], "mean_chi2"),
        f(&rows(&drift)[0], "mean_chi2"),
    );
    assert!(b < a, "{b} !< {a}");
    let level = euroc(&noise, &["--window", "2", "--gravity-vector=0,0,-9.81"]);
    assert_eq!(f(&rows(&level)[0], "mean_chi2"), a);
    assert_eq!(level["gravity"], serde_json::json!([0.0, 0.0, -9.81]));
    let e = refused(&["--window", "2", "--in-window-drift", "--combined"]);
    assert!(
        e.contains("--in-window-drift") && e.contains("--combined"),
        "{e}"
    );
    let e = refused(&["--window", "2", "--gravity-vector", "0,0,-981"]);
    assert!(
        e.contains("--gravity-vector") && e.contains("another unit"),
        "{e}"
    );
}
