//! The IMU factor at the true states of a moving rig in a rotating frame, with the IMU away
//! from the body origin: both frame effects at once, with noise.
//!
//! Setup. Scene `aggressive` (the body's motion in the navigation frame), simulated in a frame
//! rotating at ω = (0.02, −0.03, 0.035) rad/s (|ω| = 0.05 rad/s, about 700 times the Earth
//! rate, so that ignoring it shows), the IMU at r = 0.3 m along (1, −2, 2)/3 rotated by
//! Exp(0.3, −0.5, 0.8); 200 Hz, window [1 s, 2 s], EuRoC densities, fixed zero bias. Each of
//! N realisations adds white noise (`evidence::noisy_stream`, its own seeded generator) to the
//! noise-free readings; the factor (`body_p_sensor`, `omega_coriolis`, exact mode) is evaluated
//! at the scene's true body states, NEES = `ImuFactor::chi2`. Asserted: mean within 9 ± 0.3
//! (std of the mean √(18/N) = 0.095 at N = 2 000) for midpoint and hermite4; without the
//! frame's rate, or without the sensor pose, the mean is reported and must be far outside.
//!
//! Output: `target/evidence/earth_factor.json`.

use evidence::monte_carlo::{MonteCarlo, SampleNoise};
use evidence::{full_run, mean, true_state, write_json};
use nalgebra::Vector3;
use preint::{ImuBias, ImuFactor, ImuNoise, Level, PreintParams, Scheme, SensorPose, preintegrate};
use preint_lie::SO3;
use preint_sim::{SimConfig, scene_by_name, simulate};

#[test]
fn factor_nees_of_a_rig_moving_in_a_rotating_frame() {
    let n_real = if full_run() { 20_000 } else { 2_000 };
    let omega = Vector3::new(0.02, -0.03, 0.035);
    let pose = SensorPose::new(
        SO3::exp(&Vector3::new(0.3, -0.5, 0.8)),
        Vector3::new(0.1, -0.2, 0.2),
    );
    let scene = scene_by_name("aggressive").unwrap();
    let cfg = SimConfig {
        body_p_sensor: Some(pose),
        earth_rate: Some(omega),
        ..SimConfig::noise_free()
    };
    let clean = simulate(scene.as_ref(), 200.0, 3.0, &cfg, 1)
        .unwrap()
        .samples;
    let noise = ImuNoise::euroc();
    let mc = MonteCarlo {
        clean: &clean,
        noise: SampleNoise::at(&noise, 0.005),
        n: n_real,
    };
    let (t_i, t_j) = (1_000_000_000, 2_000_000_000);
    let (xi, xj) = (
        true_state(scene.as_ref(), t_i),
        true_state(scene.as_ref(), t_j),
    );
    let b0 = ImuBias::zero();
    let mut out = serde_json::Map::new();
    for scheme in [Scheme::Midpoint, Scheme::Hermite4] {
        let full = PreintParams::from_noise(&noise)
            .with_scheme(scheme)
            .with_level(Level::Covariance)
            .with_body_p_sensor(pose)
            .with_omega_coriolis(omega);
        let variants = [
            ("both frames", full.clone()),
            (
                "no frame rate",
                PreintParams {
                    omega_coriolis: None,
                    ..full.clone()
                },
            ),
            (
                "no sensor pose",
                PreintParams {
                    body_p_sensor: None,
                    ..full.clone()
                },
            ),
        ];
        for (name, p) in variants {
            let chi2 = mc.white(0xEA27_0000, |noisy| {
                let m = preintegrate(&p, &b0, noisy, t_i, t_j).unwrap();
                [ImuFactor::new(m).unwrap().chi2(&xi, &xj, &b0)]
            });
            let m = mean(&chi2[0]);
            println!(
                "{:<9} {name:<14} N = {n_real}: mean NEES {m:.3}",
                scheme.name()
            );
            if name == "both frames" {
                assert!((m - 9.0).abs() <= 0.3, "{scheme:?}: {m}");
            } else {
                assert!(m > 100.0, "{scheme:?} {name}: {m}");
            }
            out.insert(format!("{}/{name}", scheme.name()), serde_json::json!(m));
        }
    }
    write_json("earth_factor", &serde_json::Value::Object(out));
}
