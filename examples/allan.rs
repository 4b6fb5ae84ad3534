//! The overlapping Allan deviation of a static recording and the Kalibr `imu.yaml` read from
//! it: white-noise density at τ = 1 s on a slope −½ run, random walk at τ = 3 s on a slope +½
//! run (IEEE Std 952).
//!
//! `cargo run --release --example allan`

use preint::ImuNoise;
use preint_calib::allan::ImuAllan;
use preint_sim::{SimConfig, StaticScene, simulate};

fn main() {
    // Two hours at 100 Hz, a noisy MEMS IMU with a strong bias random walk.
    let noise = ImuNoise {
        gyro_noise_density: 2e-3,
        gyro_random_walk: 2e-4,
        acc_noise_density: 2e-2,
        acc_random_walk: 2e-3,
        update_rate_hz: 100.0,
    };
    let sim = simulate(
        &StaticScene::default(),
        100.0,
        7200.0,
        &SimConfig::with_noise(noise),
        5,
    )
    .expect("simulation");
    let allan = ImuAllan::from_samples(&sim.samples, 10).expect("uniform samples");
    let fit = allan.to_imu_noise();
    println!("channel  white density (per √Hz)   random walk (per s/√Hz)");
    let names = ["gyro x", "gyro y", "gyro z", "acc x", "acc y", "acc z"];
    for (name, f) in names.iter().zip(&allan.fits) {
        let bound = |b: bool| if b { "≤ " } else { "" };
        println!(
            "{name:<8} {}{:.3e} ± {:.1e}        {}{:.3e}",
            bound(f.white_density_is_bound),
            f.white_density,
            f.white_density_err,
            bound(f.random_walk_is_bound),
            f.random_walk
        );
    }
    println!(
        "\nimu.yaml (the largest axis):\n{}",
        preint_io::kalibr_yaml_string(&allan.to_imu_noise())
    );
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(rel(fit.gyro_noise_density, noise.gyro_noise_density) < 0.1);
    assert!(rel(fit.acc_noise_density, noise.acc_noise_density) < 0.1);
    assert!(rel(fit.gyro_random_walk, noise.gyro_random_walk) < 0.35);
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
