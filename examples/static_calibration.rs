//! Gyro bias and roll/pitch from a static recording (one attitude): the accelerometer bias
//! cannot be told apart from a tilt there, so it is reported as unobservable.
//!
//! `cargo run --release --example static_calibration`

use nalgebra::Vector3;
use preint::{ImuBias, ImuNoise};
use preint_calib::bias::{StaticOptions, calibrate_static};
use preint_sim::{SimConfig, StaticScene, simulate};

fn main() {
    // Ten minutes at rest at 200 Hz, EuRoC noise densities with the bias random walk.
    let noise = ImuNoise::euroc();
    let bias = ImuBias::new(
        Vector3::new(0.004, -0.002, 0.007),
        Vector3::new(0.05, -0.03, 0.02),
    );
    let cfg = SimConfig {
        initial_bias: bias,
        ..SimConfig::with_noise(noise)
    };
    let sim = simulate(&StaticScene::default(), 200.0, 600.0, &cfg, 11).expect("simulation");
    let cal =
        calibrate_static(&sim.samples, &noise, &StaticOptions::default()).expect("static data");
    // The estimate refers to mid-recording (the random walk moves the bias meanwhile).
    let mid = &sim.truth[sim.truth.len() / 2];
    println!("gyro bias [rad/s]:");
    for k in 0..3 {
        let (est, sd, truth) = (cal.gyro_bias[k], cal.gyro_bias_std[k], mid.bias.gyro[k]);
        println!(
            "  {est:+.6} ± {sd:.1e} (truth {truth:+.6}, {:+.1} σ)",
            (est - truth) / sd
        );
        assert!((est - truth).abs() < 4.0 * sd);
    }
    println!(
        "roll {:.4}° ± {:.1e}°, pitch {:.4}° ± {:.1e}°",
        cal.roll.to_degrees(),
        cal.roll_std.to_degrees(),
        cal.pitch.to_degrees(),
        cal.pitch_std.to_degrees()
    );
    println!(
        "accelerometer bias: {}",
        match cal.acc_bias {
            Some(b) => format!("{b:?}"),
            None => "unobservable from one attitude (give a prior or several attitudes)".into(),
        }
    );
    assert!(cal.acc_bias.is_none());
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
