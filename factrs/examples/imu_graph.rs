//! One second of a simulated IMU as a preint IMU factor in a factrs graph, with priors on
//! the first keyframe and the second keyframe started 1.7 m off: factrs' Gauss–Newton
//! recovers it.
//!
//! `cargo run --release -p preint-factrs --example imu_graph`

use factrs::core::{GaussNewton, Graph, PriorResidual, SE3, Values, VectorVar3};
use factrs::{assign_symbols, fac, traits::Optimizer, variables::ImuBias};
use preint::{ImuBias as Bias, ImuFactor, NavState, PreintParams, preintegrate};
use preint_factrs::{ImuResidual, nav_state, to_factrs, to_factrs_bias};
use preint_sim::{SimConfig, scene_by_name, simulate};

assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);

fn main() {
    let scene = scene_by_name("aggressive").unwrap();
    let noise = preint::ImuNoise::euroc();
    let sim = simulate(scene.as_ref(), 200.0, 1.5, &SimConfig::with_noise(noise), 1).unwrap();
    let params = PreintParams::from_noise(&noise);
    let m = preintegrate(&params, &Bias::zero(), &sim.samples, 0, 1_000_000_000).unwrap();
    let (s0, s1) = (scene.state(0.0), scene.state(1.0));
    let (x0, v0) = to_factrs(&NavState::new(s0.r_wb, s0.p, s0.v));
    let (x1, v1) = to_factrs(&NavState::new(s1.r_wb, s1.p.add_scalar(1.0), s1.v));
    let b0 = to_factrs_bias(&Bias::zero());
    let mut graph = Graph::new();
    graph.add_factor(fac![PriorResidual::new(x0.clone()), X(0), 1e-3 as std]);
    graph.add_factor(fac![PriorResidual::new(v0.clone()), V(0), 1e-3 as std]);
    graph.add_factor(fac![PriorResidual::new(b0.clone()), B(0), 1e-2 as std]);
    let imu = ImuResidual::new(ImuFactor::new(m).unwrap());
    graph.add_factor(fac![imu, (X(0), V(0), X(1), V(1), B(0))]);
    let mut values = Values::new();
    values.insert(X(0), x0);
    values.insert(V(0), v0);
    values.insert(B(0), b0);
    values.insert(X(1), x1);
    values.insert(V(1), v1);
    let mut solver = GaussNewton::new_default(graph);
    let result = solver.optimize(values).expect("converges");
    let x1 = nav_state(result.get(X(1)).unwrap(), result.get(V(1)).unwrap());
    let err = (x1.p - s1.p).norm();
    println!("keyframe 1: position error {err:.4} m (started 1.7 m off)");
    assert!(err < 0.01, "position error {err} m");
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
