//! Two seconds of a simulated IMU as two preint IMU factors in a factrs graph, priors on the
//! first keyframe, keyframes 1 and 2 started 0.5 m off: factrs' Gauss–Newton recovers them.
//!
//! `cargo run --release -p preint-factrs --example imu_graph`

use factrs::core::{GaussNewton, Graph, PriorResidual, SE3, Values, VectorVar3};
use factrs::{assign_symbols, fac, traits::Optimizer, variables::ImuBias};
use preint::{ImuFactor, NavState, PreintParams, preintegrate};
use preint_factrs::{ImuResidual, nav_state, to_factrs, to_factrs_bias};
use preint_sim::{SimConfig, scene_by_name, simulate, t_s};

assign_symbols!(X: SE3; V: VectorVar3; B: ImuBias);

fn main() {
    let (scene, noise) = (
        scene_by_name("aggressive").unwrap(),
        preint::ImuNoise::euroc(),
    );
    let sim = simulate(scene.as_ref(), 200.0, 2.5, &SimConfig::with_noise(noise), 1).unwrap();
    let truth = |k: u32| scene.state(t_s(i64::from(k) * 1_000_000_000));
    let (mut graph, mut values) = (Graph::new(), Values::new());
    for k in 0..3 {
        let s = truth(k);
        let (x, v) = to_factrs(&NavState::new(
            s.r_wb,
            s.p.add_scalar(0.5 * f64::from(k)),
            s.v,
        ));
        (
            values.insert(X(k), x.clone()),
            values.insert(V(k), v.clone()),
        );
        if k == 0 {
            graph.add_factor(fac![PriorResidual::new(x), X(0), 1e-3 as std]);
            graph.add_factor(fac![PriorResidual::new(v), V(0), 1e-3 as std]);
        } else {
            let (t_i, t_j) = (
                i64::from(k - 1) * 1_000_000_000,
                i64::from(k) * 1_000_000_000,
            );
            let m = preintegrate(
                &PreintParams::from_noise(&noise),
                &preint::ImuBias::zero(),
                &sim.samples,
                t_i,
                t_j,
            );
            let residual = ImuResidual::new(ImuFactor::new(m.unwrap()).unwrap());
            graph.add_factor(fac![residual, (X(k - 1), V(k - 1), X(k), V(k), B(0))]);
        }
    }
    let zero = to_factrs_bias(&preint::ImuBias::zero());
    graph.add_factor(fac![PriorResidual::new(zero.clone()), B(0), 1e-2 as std]);
    values.insert(B(0), zero);
    let result = GaussNewton::new_default(graph)
        .optimize(values)
        .expect("converges");
    let x2 = nav_state(result.get(X(2)).unwrap(), result.get(V(2)).unwrap());
    let err = (x2.p - truth(2).p).norm();
    println!("keyframe 2: position error {err:.4} m (started 1 m off)");
    assert!(err < 0.02, "position error {err} m");
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs() {
        super::main();
    }
}
