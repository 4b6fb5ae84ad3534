//! Split gyro / accelerometer files merged into IMU samples: values against hand
//! computations, dropped edge samples, and the typed errors.

use preint_io::split::{MergeReport, effective_noise, open_split, open_split_with_report};
use preint_io::{IoError, ReadOptions};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("preint-io-split-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(d: &Path, name: &str, text: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Accelerometer every 10 ms: x = (t / 10 ms)², y = 2 + t / 10 ms, z = 9.81 (a quadratic, a
/// line and a constant, reproduced exactly by the cubic interpolation).
const ACCEL: &str = "t_ns,ax,ay,az\n\
    1000000000,0,2,9.81\n\
    1010000000,1,3,9.81\n\
    1020000000,4,4,9.81\n\
    1030000000,9,5,9.81\n\
    1040000000,16,6,9.81\n";

const GYRO: &str = "# t [ns], w [rad/s]\n\
    1005000000,0.1,0.2,0.3\n\
    1010000000,0.1,0.2,0.3\n\
    1015000000,0.2,0.2,0.3\n\
    1025000000,0.3,0.2,0.3\n\
    1030000000,0.4,0.2,0.3\n\
    1035000000,0.5,0.2,0.3\n";

fn opts_ns() -> ReadOptions {
    ReadOptions {
        time_unit: Some(preint_io::TimeUnit::Ns),
        ..ReadOptions::default()
    }
}

#[test]
fn merged_values_are_the_interpolated_accelerometer_at_the_gyro_stamps() {
    let d = dir("values");
    let (g, a) = (write(&d, "g.csv", GYRO), write(&d, "a.csv", ACCEL));
    let (reader, handle) = open_split_with_report(&g, &a, &opts_ns()).unwrap();
    let s = reader.read_all().unwrap();
    // Merged: stamps t with two accelerometer samples at or before and two after, i.e.
    // 1010 ms ≤ t < 1030 ms: 1010, 1015, 1025 ms. 1005 ms is before, 1030 and 1035 after.
    let t: Vec<i64> = s.iter().map(|x| x.t_ns).collect();
    assert_eq!(t, [1_010_000_000, 1_015_000_000, 1_025_000_000]);
    // At an accelerometer stamp: that sample.
    assert_eq!(s[0].acc.x, 1.0);
    // At 15 ms, λ = ½: Catmull–Rom (−a0 + 9a1 + 9a2 − a3)/16 = (−0 + 9 + 36 − 9)/16 = 2.25,
    // which is (1.5)² (exact for the quadratic); y = 2 + 1.5; z constant.
    assert!((s[1].acc.x - 2.25).abs() < 1e-12, "{}", s[1].acc.x);
    assert!((s[1].acc.y - 3.5).abs() < 1e-12);
    assert!((s[1].acc.z - 9.81).abs() < 1e-12);
    // At 25 ms: (−1 + 36 + 81 − 16)/16 = 6.25 = 2.5².
    assert!((s[2].acc.x - 6.25).abs() < 1e-12, "{}", s[2].acc.x);
    assert!((s[2].acc.y - 4.5).abs() < 1e-12);
    // The gyro readings are the gyro file's, unchanged.
    assert_eq!(s[1].gyro.x, 0.2);
    assert_eq!(s[2].gyro.x, 0.3);
    let r = handle.report();
    assert_eq!(
        (
            r.gyro_samples,
            r.accel_samples,
            r.merged,
            r.dropped_before,
            r.dropped_after
        ),
        (6, 5, 3, 1, 2)
    );
}

#[test]
fn units_from_flags_and_headers_apply_to_their_own_file() {
    let d = dir("units");
    let g = write(
        &d,
        "g.csv",
        "t_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s\n1.010,180,0,0\n1.015,90,0,0\n",
    );
    let a = write(
        &d,
        "a.txt",
        "1.000 0 0 1\n1.010 0 0 1\n1.020 0 0 1\n1.030 0 0 1\n",
    );
    let opts = ReadOptions {
        accel_unit: Some(preint_io::AccelUnit::G),
        time_unit: Some(preint_io::TimeUnit::S),
        ..ReadOptions::default()
    };
    let reader = open_split(&g, &a, &opts).unwrap();
    assert_eq!(
        reader.info().describe(),
        "delimited (time s, gyro deg/s, accel g)",
        "gyro unit from the header, accelerometer unit from the flag"
    );
    let s = reader.read_all().unwrap();
    assert_eq!(s[0].t_ns, 1_010_000_000);
    assert_eq!(s[0].gyro.x, std::f64::consts::PI);
    assert_eq!(s[0].acc.z, 9.80665);
    assert_eq!(s[1].gyro.x, std::f64::consts::FRAC_PI_2);
}

fn err(gyro: &str, accel: &str) -> IoError {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = dir(&format!("e{n}"));
    let (g, a) = (write(&d, "gyro.csv", gyro), write(&d, "accel.csv", accel));
    match open_split(&g, &a, &opts_ns()).and_then(|r| r.read_all()) {
        Ok(_) => panic!("accepted bad input"),
        Err(e) => e,
    }
}

#[test]
fn decreasing_or_repeated_stamps_are_named_by_file_and_line() {
    let bad_gyro = GYRO.replace("1025000000,0.3", "1012000000,0.3");
    let e = err(&bad_gyro, ACCEL);
    assert_eq!(e.line(), Some(5), "{e}");
    let m = e.to_string();
    assert!(m.contains("gyro.csv:5:") && m.contains("decreases"), "{m}");
    let bad_accel = ACCEL.replace("1020000000,4", "1005000000,4");
    let e = err(GYRO, &bad_accel);
    let m = e.to_string();
    assert!(m.contains("accel.csv:4:") && m.contains("decreases"), "{m}");
    let dup_accel = ACCEL.replace("1020000000,4", "1010000000,4");
    let m = err(GYRO, &dup_accel).to_string();
    assert!(m.contains("accel.csv:4:") && m.contains("duplicate"), "{m}");
}

#[test]
fn a_nan_row_an_empty_file_and_disjoint_files_are_errors() {
    let nan = ACCEL.replace("4,4,9.81", "4,nan,9.81");
    let m = err(GYRO, &nan).to_string();
    assert!(
        m.contains("accel.csv:4:") && m.contains("not finite"),
        "{m}"
    );
    let nan = GYRO.replace("0.3,0.2,0.3\n", "NaN,0.2,0.3\n");
    let m = err(&nan, ACCEL).to_string();
    assert!(m.contains("gyro.csv:5:") && m.contains("not finite"), "{m}");
    match err(GYRO, "t_ns,ax,ay,az\n") {
        IoError::Empty { source_name } => assert!(source_name.ends_with("accel.csv")),
        e => panic!("{e}"),
    }
    let three: String = ACCEL.lines().take(4).map(|l| format!("{l}\n")).collect();
    let m = err(GYRO, &three).to_string();
    assert!(
        m.contains("accel.csv") && m.contains("3 accelerometer samples"),
        "{m}"
    );
    let late = GYRO.replace("\n10", "\n20");
    let m = err(&late, ACCEL).to_string();
    assert!(m.contains("do not overlap"), "{m}");
    let short = "1000000000,1,2\n";
    let m = err(GYRO, &format!("t_ns,ax,ay,az\n{short}")).to_string();
    assert!(
        m.contains("accel.csv:2:") && m.contains("expected 4 columns"),
        "{m}"
    );
}

#[test]
fn the_effective_density_scales_only_the_accelerometer_white_noise() {
    let noise = preint::ImuNoise::euroc();
    // ρ = Σ W²/c ÷ T = 1.21 over 1 s, no third differences: σ_a,eff = 1.1 σ_a.
    let r = MergeReport {
        gyro_samples: 201,
        merged: 201,
        gyro_span_ns: (0, 1_000_000_000),
        merged_span_ns: (0, 1_000_000_000),
        white_weight_sq: 1.21,
        ..MergeReport::default()
    };
    let e = effective_noise(&noise, &r);
    assert!((e.acc_noise_density - 1.1 * noise.acc_noise_density).abs() < 1e-15);
    assert_eq!(e.gyro_noise_density, noise.gyro_noise_density);
    assert_eq!(e.acc_random_walk, noise.acc_random_walk);
    assert!((e.update_rate_hz - 200.0).abs() < 1e-9);
}

#[test]
fn white_ratio_on_stamps_alone() {
    use preint_io::split::white_ratio_for_rates;
    // Gyro 100 Hz, accelerometer 400 Hz on the same grid (one phase, offset 0): each merged
    // sample is one accelerometer sample (weight 1), so over 1 s (100 intervals, trapezoid
    // cells h_g inside and h_g/2 at the two ends) Σ W²/h_a = (99 + 2/4)·h_g²/h_a and
    // ρ = 99.5/100 · h_g/h_a = 3.98.
    let r = white_ratio_for_rates(100.0, 400.0, 1.0, 1).unwrap();
    assert!((r - 3.98).abs() < 1e-9, "{r}");
    // Accelerometer slower than the gyro: ρ = 1 − κ h_a/T with κ = 0.309 for the cubic kernel
    // (an independent quadrature of the Catmull–Rom weights over 400 random phases;
    // docs/SPLIT_STREAMS.md, eq. 5): 1 − 0.309/63 = 0.99510 for 1 s windows.
    let r = white_ratio_for_rates(200.0, 63.0, 1.0, 64).unwrap();
    assert!((r - 0.99510).abs() < 5e-4, "{r}");
    let n =
        preint_io::split::effective_noise_for_rates(&preint::ImuNoise::euroc(), 200.0, 63.0, 1.0)
            .unwrap();
    assert!((n.acc_noise_density / 2.0e-3 - 0.99510f64.sqrt()).abs() < 3e-4);
    for bad in [
        (0.0, 63.0, 1.0),
        (200.0, f64::NAN, 1.0),
        (200.0, 63.0, -1.0),
        (1e9, 63.0, 1e3),
    ] {
        assert_eq!(
            white_ratio_for_rates(bad.0, bad.1, bad.2, 4),
            None,
            "{bad:?}"
        );
    }
}
