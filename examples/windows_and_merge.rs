//! Consecutive keyframe windows of one stream and their merge: ten 1 s windows merged equal
//! the 10 s window to round-off (deltas, covariance and bias Jacobians), because the windows
//! share their boundary samples and record the gains of their edge samples.
//!
//! `cargo run --release --example windows_and_merge`

use preint::{ImuBias, PreintParams, Scheme, merge, preintegrate};
use preint_sim::{SimConfig, scene_by_name, simulate};

fn main() {
    let scene = scene_by_name("seed-ellipse").expect("built-in scene");
    let noise = preint::ImuNoise::euroc();
    let sim = simulate(
        scene.as_ref(),
        200.0,
        12.0,
        &SimConfig::with_noise(noise),
        3,
    )
    .expect("simulation");
    let params = PreintParams::from_noise(&noise).with_scheme(Scheme::Hermite4);
    let bias = ImuBias::zero();
    let second = 1_000_000_000;
    // Keyframes every second, on sample times. (Between samples, each window interpolates a
    // boundary sample there, and the merge equals the whole stream with those samples
    // inserted instead.)
    let t0 = second;
    let whole = preintegrate(&params, &bias, &sim.samples, t0, t0 + 10 * second).expect("window");
    let mut merged = preintegrate(&params, &bias, &sim.samples, t0, t0 + second).expect("window");
    for k in 1..10 {
        let w = preintegrate(
            &params,
            &bias,
            &sim.samples,
            t0 + k * second,
            t0 + (k + 1) * second,
        )
        .expect("window");
        merged = merge(&merged, &w).expect("consecutive windows");
    }
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    let dr = (merged.delta_r.matrix() - whole.delta_r.matrix()).amax();
    let dv = (merged.delta_v - whole.delta_v).amax();
    let dcov = (merged.cov - whole.cov).amax() / whole.cov.amax();
    let djac = (merged.jac.d_p_d_bg - whole.jac.d_p_d_bg).amax() / whole.jac.d_p_d_bg.amax();
    println!("10 merged windows against the 10 s window:");
    println!(
        "  ΔR {dr:.1e}, Δv {dv:.1e} m/s, covariance {dcov:.1e} (relative), ∂Δp/∂b_g {djac:.1e}"
    );
    println!(
        "  Δt {} s, σ_p of the whole window {:.3e} m",
        merged.delta_t,
        whole.cov[(6, 6)].sqrt()
    );
    assert_eq!(merged.delta_t, whole.delta_t);
    assert!(dr < 1e-13 && dv < 1e-11 && dcov < 1e-11 && djac < 1e-11);
    assert!(rel(merged.cov15[(9, 9)], whole.cov15[(9, 9)]) < 1e-9);
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
