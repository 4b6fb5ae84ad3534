//! An IMU mounted 0.3 m from the body origin (the body being the camera, the lidar or the
//! centre of gravity), on a rig that moves in a rotating (Earth) frame: preintegrate with
//! `body_p_sensor`, predict the body's state with the Earth rate, and compare with the truth.
//!
//! `cargo run --release --example imu_on_a_rig`

use nalgebra::Vector3;
use preint::earth::earth_rate_enu;
use preint::{ImuBias, NavState, PreintParams, Scheme, SensorPose, predict, preintegrate};
use preint_sim::{SimConfig, scene_by_name, simulate, t_s};

fn main() {
    // The IMU: 0.3 m from the body origin, rotated by 60° about (1, 1, 1) (sensor → body).
    let rotation =
        preint::lie::SO3::exp(&(Vector3::new(1.0, 1.0, 1.0).normalize() * 60f64.to_radians()));
    let pose = SensorPose::new(rotation, Vector3::new(0.1, -0.2, 0.2));
    // Noise-free readings of that IMU on the `aggressive` scene at 45° N (the scene is the
    // body's motion in the local east-north-up frame).
    let omega_ie = earth_rate_enu(45.0);
    let cfg = SimConfig {
        body_p_sensor: Some(pose),
        earth_rate: Some(omega_ie),
        ..SimConfig::noise_free()
    };
    let scene = scene_by_name("aggressive").expect("built-in scene");
    let sim = simulate(scene.as_ref(), 200.0, 3.0, &cfg, 1).expect("simulation");

    // The window [1 s, 2 s] with the 4th-order scheme, as the body's measurement.
    let (t_i, t_j) = (1_000_000_000, 2_000_000_000);
    let params = PreintParams::default()
        .with_scheme(Scheme::Hermite4)
        .with_body_p_sensor(pose)
        .with_omega_coriolis(omega_ie);
    let m = preintegrate(&params, &ImuBias::zero(), &sim.samples, t_i, t_j).expect("window");

    // Predict the body's state at t_j from its true state at t_i.
    let truth = |t_ns: i64| {
        let s = scene.state(t_s(t_ns));
        NavState::new(s.r_wb, s.p, s.v)
    };
    let xj = predict(&m, &truth(t_i), &ImuBias::zero());
    let (ep, ev) = ((xj.p - truth(t_j).p).norm(), (xj.v - truth(t_j).v).norm());
    println!("body state predicted at t_j: position error {ep:.2e} m, velocity error {ev:.2e} m/s");

    // The same samples taken as if the IMU were at the body origin: the lever arm's
    // accelerations and the rotation of the axes end up in the body's motion.
    let naive = PreintParams {
        body_p_sensor: None,
        ..params.clone()
    };
    let m0 = preintegrate(&naive, &ImuBias::zero(), &sim.samples, t_i, t_j).expect("window");
    let x0 = predict(&m0, &truth(t_i), &ImuBias::zero());
    let e0 = (x0.p - truth(t_j).p).norm();
    println!("without body_p_sensor: position error {e0:.2e} m");
    assert!(ep < 1e-5 && ev < 1e-5, "{ep:e} {ev:e}");
    assert!(e0 > 0.1, "{e0:e}");
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
