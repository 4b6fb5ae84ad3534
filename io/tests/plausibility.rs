//! The unit checks on real recordings: each passes as recorded, and each is refused (with the
//! flag that fixes it) when its gyro is in deg/s, its accelerometer in g or its time unit
//! wrong; where the checks cannot tell, the verdict says what was missing.

use preint::ImuSample;
use preint_io::plausibility::{
    UnitVerdict, check_units, check_units_read_as, gyro_scale_fit, median_interval_ns,
};
use preint_io::{GyroUnit, ImuReader, ReadOptions};
use std::path::PathBuf;

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

fn read(rel: &str, opts: &ReadOptions) -> Vec<ImuSample> {
    ImuReader::open(&repo(rel), opts)
        .unwrap()
        .read_all()
        .unwrap()
}

fn scaled(samples: &[ImuSample], gyro: f64, acc: f64) -> Vec<ImuSample> {
    samples
        .iter()
        .map(|s| ImuSample::new(s.t_ns, s.gyro * gyro, s.acc * acc))
        .collect()
}

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const KITTI: &str = "tests/data/kitti/KittiEquivBiasedImu_first120s.txt";
const ADIS: &str = "tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv";
const DEG: f64 = 180.0 / std::f64::consts::PI;

fn err(samples: &[ImuSample]) -> String {
    check_units(samples, "rec").unwrap_err().to_string()
}

#[test]
fn recordings_pass_as_recorded() {
    for rel in [EUROC, KITTI, ADIS] {
        let s = read(rel, &ReadOptions::default());
        assert!(
            check_units(&s, rel).is_ok(),
            "{rel}: {:?}",
            check_units(&s, rel)
        );
    }
}

#[test]
fn deg_per_s_is_refused_still_and_moving() {
    // EuRoC V1_01 starts on the ground: its gyro bias across the vertical is 0.075 rad/s
    // (mostly about body z, horizontal there), under the 0.1 rad/s bound; in deg/s it reads 4.3.
    let e = err(&scaled(&read(EUROC, &ReadOptions::default()), DEG, 1.0));
    assert!(
        e.contains("across the vertical") && e.contains("--gyro-unit deg/s"),
        "{e}"
    );
    // The ADIS hour is static; its header says deg/s. Declared rad/s, its bias reads 0.6.
    let opts = ReadOptions {
        gyro_unit: Some(GyroUnit::RadPerS),
        ..Default::default()
    };
    let e = err(&read(ADIS, &opts));
    assert!(e.contains("--gyro-unit deg/s"), "{e}");
    // KITTI: a car that stops, so the still check fires first; the tilt check alone also
    // tells: the gyro as read misses the turning of gravity by far more than the same gyro
    // scaled by π/180.
    let kitti_deg = scaled(&read(KITTI, &ReadOptions::default()), DEG, 1.0);
    assert!(err(&kitti_deg).contains("--gyro-unit deg/s"));
    let dt = median_interval_ns(&kitti_deg) * 1e-9;
    let fit = gyro_scale_fit(&kitti_deg, dt).unwrap();
    let msg = fit.verdict().expect("deg/s found by the tilt check");
    assert!(msg.contains("looks like deg/s"), "{msg}");
    let fit = gyro_scale_fit(&read(KITTI, &ReadOptions::default()), dt).unwrap();
    assert!(fit.verdict().is_none(), "{fit:?}");
    assert!(fit.median_error[1] < 10f64.to_radians(), "{fit:?}");
}

#[test]
fn g_and_time_units_are_refused() {
    let euroc = read(EUROC, &ReadOptions::default());
    let e = err(&scaled(&euroc, 1.0, 1.0 / 9.80665));
    assert!(e.contains("--accel-unit g"), "{e}");
    // Microseconds read as nanoseconds: 5 µs "intervals".
    let us: Vec<ImuSample> = euroc
        .iter()
        .map(|s| ImuSample::new(s.t_ns / 1000, s.gyro, s.acc))
        .collect();
    let e = err(&us);
    assert!(
        e.contains("median sample interval is 5000 ns") && e.contains("--time-unit"),
        "{e}"
    );
}

#[test]
fn a_gyro_of_exact_zeros_beside_a_live_accelerometer_is_refused() {
    let euroc = read(EUROC, &ReadOptions::default());
    let zero_gyro: Vec<ImuSample> = euroc
        .iter()
        .map(|s| ImuSample::new(s.t_ns, nalgebra::Vector3::zeros(), s.acc))
        .collect();
    let e = err(&zero_gyro);
    assert!(e.contains("exactly 0 on all 29120 samples"), "{e}");
    // Noise-free data at rest (zero gyro, constant accelerometer) is plausible.
    let rest: Vec<ImuSample> = (0..1000)
        .map(|k| {
            ImuSample::new(
                k * 5_000_000,
                nalgebra::Vector3::zeros(),
                nalgebra::Vector3::new(0.0, 0.0, 9.81),
            )
        })
        .collect();
    assert!(check_units(&rest, "rest").is_ok());
}

fn verdict(rel: &str, opts: &ReadOptions) -> Result<UnitVerdict, String> {
    let r = ImuReader::open(&repo(rel), opts).unwrap();
    let units = r.info().units;
    let s = r.read_all().unwrap();
    check_units_read_as(&s, rel, Some(units)).map_err(|e| e.to_string())
}

#[test]
fn recordings_with_a_still_part_or_turning_gravity_pass_and_the_others_say_why_not() {
    // EuRoC (200 Hz in ns: no other time unit gives an IMU's rate; still at the start) and
    // KITTI (100 Hz in s; still while the car stops).
    for rel in [EUROC, KITTI] {
        assert_eq!(
            verdict(rel, &ReadOptions::default()),
            Ok(UnitVerdict::Passed),
            "{rel}"
        );
    }
    // The static ADIS hour at 10 Hz: in ms it would be 10 kHz, and nothing turns gravity.
    let Ok(UnitVerdict::Inconclusive(why)) = verdict(ADIS, &ReadOptions::default()) else {
        panic!("ADIS passed")
    };
    assert_eq!(why.len(), 1, "{why:?}");
    assert!(
        why[0].starts_with("time unit:") && why[0].contains("in ms 0.0001 s"),
        "{why:?}"
    );
    // Its gyro is decided: declared deg/s, its 0.6 deg/s bias would be 0.6 rad/s in rad/s.
    // EuRoC declared deg/s: 0.0013 rad/s of bias would be plausible in rad/s too.
    let opts = ReadOptions {
        gyro_unit: Some(GyroUnit::DegPerS),
        ..Default::default()
    };
    let Ok(UnitVerdict::Inconclusive(why)) = verdict(EUROC, &opts) else {
        panic!("EuRoC declared deg/s passed")
    };
    assert!(
        why[0].starts_with("gyro unit: deg/s not told from rad/s"),
        "{why:?}"
    );
    // Two seconds of EuRoC: no still part, no pairs.
    let euroc = read(EUROC, &ReadOptions::default());
    let v = check_units_read_as(&euroc[..400], "rec", Some(preint_io::Units::SI_NS)).unwrap();
    assert!(v.why().unwrap().contains("no still part"), "{v:?}");
    // One sample decides nothing, but is no error.
    let v = check_units_read_as(&euroc[..1], "rec", None).unwrap();
    assert_eq!(v.name(), "inconclusive");
}

#[test]
fn one_still_window_with_the_gyro_of_a_fast_turn_is_refused() {
    // EuRoC's first 7.7 s hold one still window; in deg/s its bias reads 4.3 "rad/s" across
    // the vertical, which would tilt gravity by 120° within it.
    let deg = scaled(&read(EUROC, &ReadOptions::default())[..1500], DEG, 1.0);
    let e = err(&deg);
    assert!(
        e.contains("1 still 0.5 s window)") && e.contains("above 1 rad/s"),
        "{e}"
    );
}
