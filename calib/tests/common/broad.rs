//! The BROAD trial 10 excerpts of tests/data/broad: the IMU samples with the motion capture's
//! attitudes, and the white-noise densities of the rest before 36.5 s.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint::{ImuNoise, ImuSample};
use preint_lie::SO3;
use std::path::PathBuf;

/// The text of `tests/data/broad/NAME`.
pub fn file(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/broad")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

/// `t_s` = sample index / 285.714… Hz written with six decimals: the index, then exact ns at
/// 3.5 ms.
pub fn t_ns(t_s: &str) -> i64 {
    (t_s.parse::<f64>().unwrap() / 0.0035).round() as i64 * 3_500_000
}

/// The samples of [35, 160) s and the motion capture's attitude at each (`None` where it lost
/// the body).
pub fn samples_and_attitudes() -> (Vec<ImuSample>, Vec<Option<SO3>>) {
    let text = file("broad_10_undisturbed_slow_translation_A_35s_160s_imu_q.csv");
    let (mut samples, mut q) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let v: Vec<f64> = f[1..11].iter().map(|x| x.parse().unwrap()).collect();
        samples.push(ImuSample::new(
            t_ns(f[0]),
            Vector3::new(v[0], v[1], v[2]),
            Vector3::new(v[3], v[4], v[5]),
        ));
        q.push(v[6].is_finite().then(|| {
            SO3::from_quaternion(&UnitQuaternion::from_quaternion(Quaternion::new(
                v[6], v[7], v[8], v[9],
            )))
        }));
    }
    (samples, q)
}

/// White-noise densities from the rest before 36.5 s: per-axis standard deviation × √Δt, the
/// largest axis; random walks EuRoC's.
pub fn noise(samples: &[ImuSample]) -> ImuNoise {
    let end = samples.partition_point(|s| s.t_ns < 36_500_000_000);
    let rest = &samples[..end];
    let n = rest.len() as f64;
    let density = |f: &dyn Fn(&ImuSample) -> Vector3<f64>| {
        let mean = rest.iter().map(f).sum::<Vector3<f64>>() / n;
        let var = rest
            .iter()
            .map(|s| (f(s) - mean).map(|x| x * x))
            .sum::<Vector3<f64>>()
            / (n - 1.0);
        var.max().sqrt() * 0.0035f64.sqrt()
    };
    ImuNoise {
        gyro_noise_density: density(&|s| s.gyro),
        acc_noise_density: density(&|s| s.acc),
        update_rate_hz: 1.0 / 0.0035,
        ..ImuNoise::euroc()
    }
}
