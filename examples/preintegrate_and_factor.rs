//! Preintegrate a window of a simulated recording and evaluate the IMU factor at the true
//! states: the residual, its whitened form and χ².
//!
//! `cargo run --release --example preintegrate_and_factor`

use preint::{ImuBias, ImuFactor, NavState, PreintParams, Scheme, preintegrate};
use preint_sim::{SimConfig, scene_by_name, simulate, t_s};

fn main() {
    // 12 s of the `aggressive` scene at 200 Hz with the EuRoC noise densities.
    let scene = scene_by_name("aggressive").expect("built-in scene");
    let noise = preint::ImuNoise::euroc();
    let cfg = SimConfig {
        bias_random_walk: false,
        ..SimConfig::with_noise(noise)
    };
    let sim = simulate(scene.as_ref(), 200.0, 12.0, &cfg, 7).expect("simulation");

    // The keyframe window [1 s, 2 s], midpoint scheme, covariance and bias Jacobians.
    let (t_i, t_j) = (1_000_000_000, 2_000_000_000);
    let params = PreintParams::from_noise(&noise).with_scheme(Scheme::Midpoint);
    let m = preintegrate(&params, &ImuBias::zero(), &sim.samples, t_i, t_j).expect("window");
    println!(
        "ΔR = Exp({:.6?}) rad, Δv = {:.6?} m/s, Δp = {:.6?} m (body frame at t_i, gravity excluded)",
        m.delta_r.log().as_slice(),
        m.delta_v.as_slice(),
        m.delta_p.as_slice()
    );

    // The factor at the simulator's true states.
    let truth = |t_ns: i64| {
        let s = scene.state(t_s(t_ns));
        NavState::new(s.r_wb, s.p, s.v)
    };
    let factor = ImuFactor::new(m).expect("a measurement with covariance");
    let bias = ImuBias::zero();
    let (xi, xj) = (truth(t_i), truth(t_j));
    let r = factor.residual(&xi, &xj, &bias);
    let (rw, _) = factor.evaluate_whitened(&xi, &xj, &bias);
    let chi2 = factor.chi2(&xi, &xj, &bias);
    let sci: Vec<String> = r.iter().map(|x| format!("{x:.3e}")).collect();
    println!("residual [r_φ rad, r_v m/s, r_p m] = [{}]", sci.join(", "));
    println!("whitened residual = {:.3?}", rw.as_slice());
    println!("χ² = {chi2:.2} with 9 degrees of freedom (99 % quantile 21.67)");
    assert!((rw.norm_squared() - chi2).abs() < 1e-9 * chi2);
    assert!(
        chi2 < 21.67 * 3.0,
        "far from the noise the covariance describes"
    );
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
