//! Dead-reckoning integrators on noise-free scenes: convergence orders of the Euler and midpoint
//! rules, agreement of the attitude representations, and the Euler-angle failure at gimbal lock.

use nalgebra::Vector3;
use preint::{ImuBias, NavState};
use sim::{Attitude, Rule, Scene, SimConfig, dead_reckon, rotation_error, simulate, t_s};

const G: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

/// Final (rotation error [rad], position error [m]) after integrating `scene` noise-free at
/// `rate` over `dur` seconds, started from the exact initial state.
fn final_errors(scene: &dyn Scene, rate: f64, dur: f64, rule: Rule, att: Attitude) -> (f64, f64) {
    let out = simulate(scene, rate, dur, &SimConfig::noise_free(), 0).unwrap();
    let s0 = scene.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let traj = dead_reckon(&out.samples, &init, &ImuBias::zero(), &G, rule, att);
    let last = traj.last().unwrap();
    let truth = scene.state(t_s(out.samples.last().unwrap().t_ns));
    (
        rotation_error(&last.r, &truth.r_wb),
        (last.p - truth.p).norm(),
    )
}

fn ratios(rule: Rule, att: Attitude) -> Vec<(f64, f64)> {
    let scene = sim::SeedEllipseScene;
    let e: Vec<_> = [100.0, 200.0, 400.0]
        .iter()
        .map(|&r| final_errors(&scene, r, 4.0, rule, att))
        .collect();
    println!("{rule:?} {att:?}: errors (rot, pos) at 100/200/400 Hz = {e:?}");
    e.windows(2)
        .map(|w| (w[0].0 / w[1].0, w[0].1 / w[1].1))
        .collect()
}

#[test]
fn midpoint_error_shrinks_4x_per_rate_doubling() {
    for att in [Attitude::Matrix, Attitude::Quaternion, Attitude::EulerZyx] {
        for (rot, pos) in ratios(Rule::Midpoint, att) {
            println!("  midpoint {att:?}: ratio rot {rot:.3}, pos {pos:.3}");
            assert!(
                (3.5..=4.5).contains(&pos),
                "{att:?}: position error ratio {pos}"
            );
            assert!(
                (3.5..=4.5).contains(&rot),
                "{att:?}: rotation error ratio {rot}"
            );
        }
    }
}

#[test]
fn euler_error_shrinks_2x_per_rate_doubling() {
    for att in [Attitude::Matrix, Attitude::Quaternion, Attitude::EulerZyx] {
        for (rot, pos) in ratios(Rule::Euler, att) {
            println!("  euler {att:?}: ratio rot {rot:.3}, pos {pos:.3}");
            assert!(
                (1.7..=2.3).contains(&pos),
                "{att:?}: position error ratio {pos}"
            );
            assert!(
                (1.7..=2.3).contains(&rot),
                "{att:?}: rotation error ratio {rot}"
            );
        }
    }
}

/// Largest rotation error [rad] along the whole run (+∞ once non-finite).
fn max_rot_error(scene: &dyn Scene, rate: f64, dur: f64, rule: Rule, att: Attitude) -> f64 {
    let out = simulate(scene, rate, dur, &SimConfig::noise_free(), 0).unwrap();
    let s0 = scene.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let traj = dead_reckon(&out.samples, &init, &ImuBias::zero(), &G, rule, att);
    traj.iter()
        .zip(&out.samples)
        .map(|(x, s)| rotation_error(&x.r, &scene.state(t_s(s.t_ns)).r_wb))
        .fold(0.0, f64::max)
}

#[test]
fn quaternion_and_matrix_agree_to_second_order() {
    // Both midpoint variants are second order; their difference (the quaternion update's
    // θ³/12 angle error per step) must shrink 4× per rate doubling, and be far below the
    // step-independent scale of the motion.
    let scene = sim::SeedEllipseScene;
    let diffs: Vec<f64> = [100.0, 200.0, 400.0]
        .iter()
        .map(|&rate| {
            let out = simulate(&scene, rate, 4.0, &SimConfig::noise_free(), 0).unwrap();
            let s0 = scene.state(0.0);
            let init = NavState::new(s0.r_wb, s0.p, s0.v);
            let run = |att| {
                dead_reckon(
                    &out.samples,
                    &init,
                    &ImuBias::zero(),
                    &G,
                    Rule::Midpoint,
                    att,
                )
            };
            let (a, b) = (run(Attitude::Quaternion), run(Attitude::Matrix));
            a.iter()
                .zip(&b)
                .map(|(x, y)| rotation_error(&x.r, &y.r))
                .fold(0.0, f64::max)
        })
        .collect();
    println!("max |quat ⊖ matrix| at 100/200/400 Hz: {diffs:?}");
    assert!(diffs[0] < 1e-5, "{diffs:?}");
    for w in diffs.windows(2) {
        let r = w[0] / w[1];
        assert!((3.5..=4.5).contains(&r), "difference ratio {r} ({diffs:?})");
    }
}

#[test]
fn euler_angles_match_away_from_gimbal_lock() {
    // seed-ellipse keeps |pitch| ≤ 0.2 rad: the Euler-angle integrator is as accurate as the
    // matrix one (same order, comparable constant).
    let scene = sim::SeedEllipseScene;
    for rule in [Rule::Euler, Rule::Midpoint] {
        let e_zyx = max_rot_error(&scene, 200.0, 6.0, rule, Attitude::EulerZyx);
        let e_mat = max_rot_error(&scene, 200.0, 6.0, rule, Attitude::Matrix);
        println!("{rule:?} seed-ellipse 200 Hz max rot err: zyx {e_zyx:.3e}, matrix {e_mat:.3e}");
        assert!(
            e_zyx.is_finite() && e_zyx < 3.0 * e_mat,
            "{rule:?}: {e_zyx} vs {e_mat}"
        );
    }
}

/// Runs the three representations on `gimbal-lock` from the exact state at sample `k0`.
fn gimbal_runs(rate: f64, dur: f64, t0_ns: i64, rule: Rule) -> Vec<(Attitude, Vec<NavState>, f64)> {
    let scene = sim::GimbalLockScene;
    let out = simulate(&scene, rate, dur, &SimConfig::noise_free(), 0).unwrap();
    let k0 = out.samples.iter().position(|s| s.t_ns == t0_ns).unwrap();
    let samples = &out.samples[k0..];
    let s0 = scene.state(t_s(t0_ns));
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    [Attitude::EulerZyx, Attitude::Quaternion, Attitude::Matrix]
        .into_iter()
        .map(|att| {
            let traj = dead_reckon(samples, &init, &ImuBias::zero(), &G, rule, att);
            let err = traj
                .iter()
                .zip(samples)
                .map(|(x, s)| rotation_error(&x.r, &scene.state(t_s(s.t_ns)).r_wb))
                .fold(0.0, f64::max);
            (att, traj, err)
        })
        .collect()
}

#[test]
fn euler_angles_lose_accuracy_through_gimbal_lock() {
    // ZYX pitch is exactly +90° at t = 2 s: 3 s at 1 kHz includes the lock. The Euler-angle
    // roll and yaw must jump there (by ≈ π in one step), and the midpoint integrator loses its
    // second-order accuracy, while quaternion and matrix stay at their usual error.
    for rule in [Rule::Euler, Rule::Midpoint] {
        let runs = gimbal_runs(1000.0, 3.0, 0, rule);
        let (e_zyx, e_q, e_m) = (runs[0].2, runs[1].2, runs[2].2);
        println!(
            "{rule:?} gimbal-lock 1 kHz max rot err: zyx {e_zyx:.3e}, quat {e_q:.3e}, matrix {e_m:.3e}"
        );
        let max_jump = runs[0]
            .1
            .windows(2)
            .map(|w| {
                let (a, b) = (sim::euler_zyx_of(&w[0].r), sim::euler_zyx_of(&w[1].r));
                let wrap = |x: f64| {
                    (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI
                };
                wrap(b.x - a.x).abs().max(wrap(b.z - a.z).abs())
            })
            .fold(0.0, f64::max);
        println!("  largest one-step roll/yaw change of the Euler-angle state: {max_jump:.3} rad");
        assert!(
            max_jump > 1.0,
            "{rule:?}: roll/yaw should jump at the lock, max {max_jump}"
        );
        let tol = if rule == Rule::Euler { 1e-3 } else { 1e-6 };
        assert!(e_q < tol && e_m < tol, "{rule:?}: quat {e_q}, matrix {e_m}");
        if rule == Rule::Midpoint {
            assert!(
                e_zyx.is_nan() || e_zyx >= 100.0 * e_m,
                "midpoint zyx {e_zyx} vs matrix {e_m}"
            );
        }
    }
}

#[test]
fn euler_angles_started_at_gimbal_lock_fail_at_every_rate() {
    // Starting exactly at the lock (t = 2 s, then through the locks at 6, 10, 14 s), the first Euler-rule step uses E(θ = π/2)
    // (tan θ ≈ 1.6e16): the error is O(1) rad and does not shrink with the rate, while the
    // quaternion and matrix errors shrink ∝ Δt.
    for rate in [100.0, 200.0, 1000.0] {
        let runs = gimbal_runs(rate, 16.0, 2_000_000_000, Rule::Euler);
        let (e_zyx, e_q, e_m) = (runs[0].2, runs[1].2, runs[2].2);
        println!(
            "start at lock, Euler rule, {rate} Hz: zyx {e_zyx:.3e}, quat {e_q:.3e}, matrix {e_m:.3e}"
        );
        assert!(
            e_zyx.is_nan() || e_zyx > 0.3,
            "{rate} Hz: Euler angles should fail, error {e_zyx}"
        );
        assert!(
            e_zyx.is_nan() || e_zyx > 40.0 * e_m,
            "{rate} Hz: zyx {e_zyx} vs matrix {e_m}"
        );
        let tol = 1.0 / rate;
        assert!(
            e_q < tol && e_m < tol,
            "{rate} Hz: quat {e_q}, matrix {e_m}"
        );
    }
}
