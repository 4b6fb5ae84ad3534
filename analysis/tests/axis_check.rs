//! Check 7 of the unit checks (`preint_io::plausibility::axes`) on a simulated recording that
//! turns gravity about every body axis (`multi-pose-static`: still poses joined by 90°
//! rotations about x and y, EuRoC noise and bias): the gyro's axes agree with the
//! accelerometer's as simulated; read with an axis inverted, two swapped, or the axes cycled,
//! the check names the map.

use preint::{ImuNoise, ImuSample};
use preint_io::plausibility::axes::{AxisMap, AxisVerdict, gyro_axes_fit};
use preint_sim::{SimConfig, scene_by_name, simulate};

fn recording() -> Vec<ImuSample> {
    let scene = scene_by_name("multi-pose-static").unwrap();
    let cfg = SimConfig::with_noise(ImuNoise::euroc());
    simulate(scene.as_ref(), 200.0, 33.0, &cfg, 5)
        .unwrap()
        .samples
}

/// The gyro of `samples` as a sensor whose axes are `m` of the accelerometer's would read
/// it: `ω' = Mᵀ ω`, so that reading it through `m` gives `ω` back.
fn read_through(samples: &[ImuSample], m: &AxisMap) -> Vec<ImuSample> {
    let inv = m.matrix().transpose();
    samples
        .iter()
        .map(|s| ImuSample::new(s.t_ns, inv * s.gyro, s.acc))
        .collect()
}

fn verdict(samples: &[ImuSample]) -> AxisVerdict {
    let fit = gyro_axes_fit(samples, 0.005).expect("quasi-static pairs");
    eprintln!("{:?} {:?}", fit.identity, fit.best_other);
    fit.verdict()
}

#[test]
fn the_axes_agree_as_simulated_and_a_wrong_map_is_named() {
    let s = recording();
    assert_eq!(verdict(&s), AxisVerdict::Agree);
    let cases = [
        (
            AxisMap {
                from: [0, 1, 2],
                sign: [1, -1, 1],
            },
            "gyro y looks inverted (a left-handed gyro frame) relative to the accelerometer",
        ),
        (
            AxisMap {
                from: [1, 0, 2],
                sign: [1, 1, 1],
            },
            "gyro x and y look swapped (a left-handed gyro frame)",
        ),
        (
            AxisMap {
                from: [1, 2, 0],
                sign: [1, 1, 1],
            },
            "accelerometer x = gyro y, accelerometer y = gyro z, accelerometer z = gyro x",
        ),
        (
            AxisMap {
                from: [0, 1, 2],
                sign: [-1, -1, 1],
            },
            "gyro x and y look inverted relative",
        ),
    ];
    for (m, words) in cases {
        match verdict(&read_through(&s, &m)) {
            AxisVerdict::Mismatch(msg) => assert!(msg.contains(words), "{m:?}: {msg}"),
            v => panic!("{m:?}: {v:?}"),
        }
    }
}
