//! Check 7 (`preint_io::plausibility::axes`) on real recordings and its words: none of the
//! shipped recordings turns gravity about every axis between quasi-static moments (a car, a
//! slow handheld translation, a multirotor whose accelerometer follows its thrust), so none
//! can call its axes wrong or confirm them; the maps are named as a user reads them. (The
//! check itself on a recording that does turn gravity about every axis:
//! `analysis/tests/axis_check.rs`.)

use preint::ImuSample;
use preint_io::plausibility::axes::{AxisMap, AxisVerdict, gyro_axes_fit};
use preint_io::plausibility::median_interval_ns;
use preint_io::{ImuReader, ReadOptions};
use std::path::PathBuf;

fn read(rel: &str) -> Vec<ImuSample> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    ImuReader::open(&p, &ReadOptions::default())
        .unwrap()
        .read_all()
        .unwrap()
}

#[test]
fn shipped_recordings_are_never_called_wrong() {
    for rel in [
        "tests/data/kitti/KittiEquivBiasedImu_first120s.txt",
        "tests/data/broad/broad_10_undisturbed_slow_translation_A_35s_160s_imu_q.csv",
        "tests/data/euroc/V1_01_easy_imu0.csv",
    ] {
        let s = read(rel);
        let fit = gyro_axes_fit(&s, median_interval_ns(&s) * 1e-9);
        if let Some(f) = &fit {
            assert!(
                !matches!(f.verdict(), AxisVerdict::Mismatch(_)),
                "{rel}: {:?}",
                f.verdict()
            );
        }
    }
}

#[test]
fn maps_are_named_as_read() {
    let m = |from, sign| AxisMap { from, sign }.describe();
    assert_eq!(
        m([0, 1, 2], [1, -1, 1]),
        "gyro y looks inverted (a left-handed gyro frame)"
    );
    assert_eq!(m([0, 1, 2], [-1, -1, 1]), "gyro x and y look inverted");
    assert_eq!(
        m([1, 0, 2], [1, 1, 1]),
        "gyro x and y look swapped (a left-handed gyro frame)"
    );
    assert_eq!(
        m([1, 0, 2], [-1, 1, 1]),
        "the gyro's axes look mapped: accelerometer x = −gyro y, accelerometer y = gyro x, \
         accelerometer z = gyro z"
    );
    assert_eq!(AxisMap::all().len(), 48);
    assert_eq!(AxisMap::all()[0], AxisMap::IDENTITY);
    let dets: usize = AxisMap::all().iter().filter(|a| a.left_handed()).count();
    assert_eq!(dets, 24);
}
