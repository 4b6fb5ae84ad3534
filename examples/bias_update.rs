//! A new bias estimate after preintegration: the first-order correction (Forster et al. 2017,
//! eq. 44) for small changes, re-integration of the stored samples above the thresholds.
//!
//! `cargo run --release --example bias_update`

use nalgebra::Vector3;
use preint::{ImuBias, PreintParams, Preintegrator, Scheme};
use preint_sim::{SimConfig, scene_by_name, simulate};

fn main() {
    let scene = scene_by_name("aggressive").expect("built-in scene");
    let sim =
        simulate(scene.as_ref(), 200.0, 1.0, &SimConfig::noise_free(), 1).expect("simulation");
    let params = PreintParams::default().with_scheme(Scheme::Midpoint);
    let mut pi = Preintegrator::new(params.clone(), ImuBias::zero()).expect("parameters");
    pi.integrate_slice(&sim.samples).expect("valid samples");

    for dbg in [0.002, 0.05] {
        let bias = ImuBias::new(
            Vector3::new(dbg, -dbg, 0.5 * dbg),
            Vector3::new(0.05, 0.0, -0.05),
        );
        let update = pi.measurement_for_bias(&bias).expect("update");
        // Reference: integrate again with the new bias.
        let mut exact = Preintegrator::new(params.clone(), bias).expect("parameters");
        exact.integrate_slice(&sim.samples).expect("valid samples");
        let exact = exact.finish().expect("window");
        let err = (update.measurement.delta_p - exact.delta_p).norm();
        println!(
            "‖δb_g‖ = {:.3} rad/s: {}; Δp off by {err:.2e} m from re-integration",
            bias.gyro.norm(),
            if update.reintegrated {
                "re-integrated"
            } else {
                "first-order correction"
            }
        );
        if update.reintegrated {
            assert!(err < 1e-12);
        } else {
            assert!(err > 0.0 && err < 1e-4);
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
