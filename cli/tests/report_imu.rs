//! `preint report --imu` through the binary, on short slices of real recordings: the page on
//! EuRoC V1_01 with its ground truth (conclusions first, the audit's verdict, the consistency
//! table per window length with the given and the fitted noise model, the fitted imu.yaml
//! written and readable), the page on a static recording (the Allan deviation and the static
//! calibration), and the refusals (a missing file, `--poses` without `--imu`).

mod common;

use common::{head_rows, json, run, tmp};

const IMU: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";
const ADIS: &str = "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv";

/// The first 25 s of EuRoC V1_01 (200 Hz), with its ground truth: the page, its order, its
/// tables and the fitted imu.yaml.
#[test]
fn euroc_slice_with_ground_truth() {
    let d = tmp("report-imu-euroc");
    let imu = head_rows(IMU, &d, "imu25.csv", 5000);
    let out = d.join("out");
    let j = json(&[
        "report",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        &common::repo(GT),
        "--out",
        out.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let at = |needle: &str| {
        html.find(needle)
            .unwrap_or_else(|| panic!("{needle} not in the page"))
    };
    // The conclusions box comes before every section heading but its own.
    let first_section = html.match_indices("<h2 id=").map(|(i, _)| i).min().unwrap();
    assert!(at("id=\"conclusions\"") < first_section);
    let verdict = j["summary"]["audit"]["verdict"].as_str().unwrap();
    assert_eq!(verdict, "clean", "{j}");
    assert!(at("Audit: clean") < first_section);
    // The consistency table: one row per window length, for both models.
    let section = &html[at("id=\"consistency-of-the-noise-model-per-window-length\"")..];
    assert_eq!(section.matches("With the given noise model").count(), 1);
    assert_eq!(section.matches("With the fitted noise model").count(), 1);
    for c in ["given", "fitted"] {
        let w = j["summary"]["consistency"][c]["windows"]
            .as_array()
            .unwrap();
        assert_eq!(w.len(), 4, "{c}: {j}");
        assert!(
            w.iter().all(|l| l["count"].as_u64().unwrap() >= 6),
            "{c}: {j}"
        );
    }
    assert!(section.matches("<th>KS p</th>").count() >= 2);
    // The fit makes the factor more consistent than the datasheet densities at 1 s.
    let mean_1s = |c: &str| {
        j["summary"]["consistency"][c]["windows"][1]["mean_chi2"]
            .as_f64()
            .unwrap()
            / 9.0
    };
    assert!(
        (mean_1s("fitted") - 1.0).abs() < (mean_1s("given") - 1.0).abs(),
        "{j}"
    );
    // The fitted Kalibr file, linked from the page and readable.
    assert!(html.contains("<a href=\"imu.yaml\">"));
    let yaml = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    for key in [
        "gyroscope_noise_density",
        "accelerometer_noise_density",
        "gyroscope_random_walk",
        "accelerometer_random_walk",
    ] {
        assert!(yaml.contains(key), "{key} not in {yaml}");
    }
    let noise = preint_io::read_kalibr_noise_model(&out.join("imu.yaml")).unwrap();
    assert!((noise.update_rate_hz - 200.0).abs() < 1.0, "{noise:?}");
    // The version and the machine the costs were timed on.
    assert!(html.contains(&format!("preint {}", env!("CARGO_PKG_VERSION"))));
    assert!(html.contains("logical cores"));
}

/// The first 600 s of the static ADIS16405 hour (10 Hz block means): static, so the page has
/// the Allan charts and the static calibration, and no ground-truth section.
#[test]
fn static_slice() {
    let d = tmp("report-imu-static");
    let imu = head_rows(ADIS, &d, "adis600.csv", 6000);
    let out = d.join("out");
    let j = json(&[
        "report",
        "--imu",
        imu.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        j["summary"]["audit"]["still_fraction"].as_f64().unwrap() > 0.9,
        "{j}"
    );
    for needle in [
        "Allan deviation of the static recording",
        "data-file=\"allan_gyro.svg\"",
        "data-file=\"allan_acc.svg\"",
        "Static calibration",
        "<a href=\"imu_allan.yaml\">",
    ] {
        assert!(html.contains(needle), "{needle} not in the page");
    }
    assert!(!html.contains("Consistency of the noise model"));
    let cal = &j["summary"]["static"]["calibration"];
    assert!(
        cal["gyro_bias"].is_array() || cal["calibration"].is_object(),
        "{cal}"
    );
    assert!(out.join("imu_allan.yaml").is_file());
}

/// A missing recording fails naming it; `--poses` without `--imu` is a usage error.
#[test]
fn refusals_name_the_cause() {
    let d = tmp("report-imu-bad");
    let missing = d.join("no-such-imu.csv");
    let o = run(&[
        "report",
        "--imu",
        missing.to_str().unwrap(),
        "--out",
        d.join("out").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("no-such-imu.csv"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let o = run(&["report", "--poses", &common::repo(GT)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("--poses needs --imu"), "{err}");
}
