//! Dead-reckoning integrators on noise-free scenes: convergence orders of the Euler and midpoint
//! rules, agreement of the attitude representations (both rules), and how the ZYX Euler-angle
//! integrator fails at gimbal lock while quaternion and matrix stay at their discretisation
//! error.

use nalgebra::Vector3;
use preint::{ImuBias, NavState};
use preint_sim::{
    Attitude, Rule, Scene, SceneState, SimConfig, dead_reckon, euler_zyx_angles, euler_zyx_of,
    rotation_error, simulate, t_s,
};

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
    let scene = preint_sim::SeedEllipseScene;
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

/// Max over the run of `|quaternion ⊖ matrix|` [rad] and the matrix run's max rotation error
/// against the truth, on `seed-ellipse` (4 s) at `rate` with `rule`.
fn quat_vs_matrix(rate: f64, rule: Rule) -> (f64, f64) {
    let scene = preint_sim::SeedEllipseScene;
    let out = simulate(&scene, rate, 4.0, &SimConfig::noise_free(), 0).unwrap();
    let s0 = scene.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let run = |att| dead_reckon(&out.samples, &init, &ImuBias::zero(), &G, rule, att);
    let (a, b) = (run(Attitude::Quaternion), run(Attitude::Matrix));
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| rotation_error(&x.r, &y.r))
        .fold(0.0, f64::max);
    let err = b
        .iter()
        .zip(&out.samples)
        .map(|(x, s)| rotation_error(&x.r, &scene.state(t_s(s.t_ns)).r_wb))
        .fold(0.0, f64::max);
    (diff, err)
}

#[test]
fn quaternion_and_matrix_agree_to_second_order_under_both_rules() {
    // Both representations are fed the same rotation vector θ per step (ω_k Δt under the Euler
    // rule, ω̄ Δt under the midpoint rule); they differ only in the update: the quaternion's
    // q ⊗ [1, ½θ] + normalisation rotates by 2 atan(|θ|/2) = |θ| − |θ|³/12 + …, about the
    // same axis. That is an O(Δt³) local difference, so their global difference is O(Δt²)
    // under *either* rule — better than the first order the Euler rule itself has — and must
    // shrink 4× per rate doubling. Under the Euler rule it is also far below the rule's own
    // (common) error against the truth.
    for rule in [Rule::Euler, Rule::Midpoint] {
        let runs: Vec<(f64, f64)> = [100.0, 200.0, 400.0]
            .iter()
            .map(|&rate| quat_vs_matrix(rate, rule))
            .collect();
        let diffs: Vec<f64> = runs.iter().map(|r| r.0).collect();
        let errs: Vec<String> = runs.iter().map(|r| format!("{:.3e}", r.1)).collect();
        let ds: Vec<String> = diffs.iter().map(|d| format!("{d:.4e}")).collect();
        println!(
            "{rule:?}: max |quat ⊖ matrix| at 100/200/400 Hz {ds:?}, matrix error vs truth {errs:?}"
        );
        assert!(diffs[0] < 2e-6, "{rule:?}: {diffs:?}");
        for w in diffs.windows(2) {
            let r = w[0] / w[1];
            assert!(
                (3.9..=4.1).contains(&r),
                "{rule:?}: difference ratio {r} ({diffs:?})"
            );
        }
        if rule == Rule::Euler {
            for (d, e) in &runs {
                assert!(*d < 1e-3 * e, "Euler rule: difference {d} vs error {e}");
            }
        }
    }
}

#[test]
fn euler_angles_match_away_from_gimbal_lock() {
    // seed-ellipse keeps |pitch| ≤ 0.2 rad: the Euler-angle integrator is as accurate as the
    // matrix one (same order, comparable constant).
    let scene = preint_sim::SeedEllipseScene;
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

#[test]
fn euler_zyx_angles_are_the_states_dead_reckon_integrates() {
    // The raw-angle API used below must describe the same integration as dead_reckon.
    let scene = preint_sim::SeedEllipseScene;
    let out = simulate(&scene, 200.0, 2.0, &SimConfig::noise_free(), 0).unwrap();
    let s0 = scene.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let bias = ImuBias {
        gyro: Vector3::new(0.01, -0.02, 0.005),
        acc: Vector3::zeros(),
    };
    for rule in [Rule::Euler, Rule::Midpoint] {
        let traj = dead_reckon(&out.samples, &init, &bias, &G, rule, Attitude::EulerZyx);
        let angles = euler_zyx_angles(&out.samples, &euler_zyx_of(&s0.r_wb), &bias.gyro, rule);
        assert_eq!(angles.len(), traj.len());
        for (e, x) in angles.iter().zip(&traj) {
            assert_eq!(
                preint_sim::scene::rot_zyx(e).matrix(),
                x.r.matrix(),
                "{rule:?}"
            );
        }
    }
    assert!(euler_zyx_angles(&[], &Vector3::zeros(), &Vector3::zeros(), Rule::Euler).is_empty());
}

// ---------------------------------------------------------------------------------------
// Gimbal lock. The `gimbal-lock` scene's ZYX pitch is exactly +90° at t = 2 s. Its exact Euler
// rates stay below 0.85 rad/s (tests/scenes.rs), so a consistent integrator's angles would
// change by < 0.85·Δt rad per step; what the Euler-angle integrator does instead is measured
// below, each claim against the quaternion and matrix integrators on the same samples.
// ---------------------------------------------------------------------------------------

/// The gimbal-lock scene with its clock shifted by `shift` seconds, so that a sample grid
/// starting at 0 passes the lock (at scene time 2 s) at a chosen distance from a sample.
struct Shifted(f64);

impl Scene for Shifted {
    fn name(&self) -> &str {
        "gimbal-lock-shifted"
    }
    fn state(&self, t: f64) -> SceneState {
        preint_sim::GimbalLockScene.state(t + self.0)
    }
}

/// One noise-free run of `scene` at `rate` over `[0, dur]` s from the exact initial state.
struct LockRun {
    /// Max rotation error [rad] along the run: ZYX Euler angles, quaternion, matrix.
    zyx: f64,
    quat: f64,
    mat: f64,
    /// The Euler-angle states (unwrapped) and the largest one-step change of any angle [rad].
    angles: Vec<Vector3<f64>>,
    max_step: f64,
}

fn lock_run(scene: &dyn Scene, rate: f64, dur: f64, rule: Rule) -> LockRun {
    let out = simulate(scene, rate, dur, &SimConfig::noise_free(), 0).unwrap();
    let s0 = scene.state(0.0);
    let init = NavState::new(s0.r_wb, s0.p, s0.v);
    let err = |att| {
        dead_reckon(&out.samples, &init, &ImuBias::zero(), &G, rule, att)
            .iter()
            .zip(&out.samples)
            .map(|(x, s)| rotation_error(&x.r, &scene.state(t_s(s.t_ns)).r_wb))
            .fold(0.0, f64::max)
    };
    let angles = euler_zyx_angles(
        &out.samples,
        &euler_zyx_of(&s0.r_wb),
        &Vector3::zeros(),
        rule,
    );
    let max_step = angles
        .windows(2)
        .map(|w| (w[1] - w[0]).amax())
        .fold(0.0, f64::max);
    LockRun {
        zyx: err(Attitude::EulerZyx),
        quat: err(Attitude::Quaternion),
        mat: err(Attitude::Matrix),
        angles,
        max_step,
    }
}

/// Grid shifts [s] (distance of the lock from the nearest sample) used at `rate`: all below
/// half a period.
fn shifts(rate: f64) -> Vec<f64> {
    [0.0, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3]
        .into_iter()
        .filter(|&d| d < 0.5 / rate)
        .collect()
}

#[test]
fn midpoint_euler_angles_lose_second_order_through_gimbal_lock() {
    // 3 s through the lock at 250 Hz … 16 kHz, each with the lock at several sub-sample
    // distances from the grid. Quaternion and matrix are second order with a constant that
    // does not depend on the grid: e·rate² = 0.190 and 0.1270 rad·s⁻² (measured). The
    // Euler-angle error depends on where the samples fall (worst/best over the shifts ≥ 10×),
    // is ≥ 1000× the matrix error in the worst case at every rate, and its worst case does
    // not converge at second order: worst·rate² grows ≥ 10× from 250 Hz to 16 kHz (measured
    // ≈ 57×; second order would keep it constant).
    let mut worst_scaled = Vec::new();
    for rate in [250.0, 1000.0, 4000.0, 16000.0] {
        let (mut worst, mut best, mut mat) = (0.0f64, f64::INFINITY, 0.0f64);
        for d in shifts(rate) {
            let r = lock_run(&Shifted(d), rate, 3.0, Rule::Midpoint);
            let (cq, cm) = (r.quat * rate * rate, r.mat * rate * rate);
            assert!(
                (0.185..=0.195).contains(&cq),
                "{rate} Hz, shift {d}: quat e·rate² {cq}"
            );
            assert!(
                (0.125..=0.129).contains(&cm),
                "{rate} Hz, shift {d}: matrix e·rate² {cm}"
            );
            assert!(
                r.zyx.is_nan() || r.zyx > r.mat,
                "{rate} Hz, shift {d}: zyx {} vs matrix {}",
                r.zyx,
                r.mat
            );
            worst = worst.max(if r.zyx.is_nan() { f64::INFINITY } else { r.zyx });
            best = best.min(r.zyx);
            mat = mat.max(r.mat);
        }
        println!(
            "midpoint through the lock, {rate:>5} Hz: zyx worst {worst:.3e} best {best:.3e} (worst·rate² {:.3e}), matrix {mat:.3e}, worst/matrix {:.0}",
            worst * rate * rate,
            worst / mat
        );
        assert!(
            worst >= 1000.0 * mat,
            "{rate} Hz: zyx {worst} vs matrix {mat}"
        );
        assert!(
            worst >= 10.0 * best,
            "{rate} Hz: zyx worst {worst} best {best}"
        );
        worst_scaled.push(worst * rate * rate);
    }
    let growth = worst_scaled[worst_scaled.len() - 1] / worst_scaled[0];
    assert!(
        growth >= 10.0,
        "zyx worst·rate² grew only {growth}× ({worst_scaled:?})"
    );
}

#[test]
fn euler_rule_euler_angles_jump_at_gimbal_lock() {
    // Under the Euler rule the first-order error of the rule dominates: the Euler-angle
    // *rotation* error stays within 3× the matrix error (it does not blow up). But the angle
    // state itself breaks: at every rate and grid shift some step changes an angle by
    // ≥ 0.1 rad, i.e. an implied Euler rate ≥ 0.1/Δt (25 … 1600 rad/s here) that grows
    // without bound as Δt → 0, against exact Euler rates < 0.85 rad/s. (Roll and yaw jump
    // together, which leaves R unchanged exactly at the lock; the dynamics after the lock
    // pulls them back.)
    for rate in [250.0, 1000.0, 4000.0, 16000.0] {
        let (mut min_step, mut zyx, mut mat) = (f64::INFINITY, 0.0f64, 0.0f64);
        for d in shifts(rate) {
            let r = lock_run(&Shifted(d), rate, 3.0, Rule::Euler);
            let cm = r.mat * rate;
            assert!(
                (0.37..=0.38).contains(&cm),
                "{rate} Hz: matrix e·rate {cm} (first order)"
            );
            assert!((r.quat - r.mat).abs() < 1e-3 * r.mat);
            min_step = min_step.min(r.max_step);
            (zyx, mat) = (zyx.max(r.zyx), mat.max(r.mat));
        }
        println!(
            "Euler rule through the lock, {rate:>5} Hz: smallest (over shifts) largest one-step angle change {min_step:.3} rad = {:.0} rad/s; rotation error zyx {zyx:.3e}, matrix {mat:.3e}",
            min_step * rate
        );
        assert!(
            min_step >= 0.1,
            "{rate} Hz: largest one-step change only {min_step} rad"
        );
        assert!(
            zyx.is_finite() && zyx <= 3.0 * mat,
            "{rate} Hz: zyx {zyx} vs matrix {mat}"
        );
    }
}

#[test]
fn euler_angles_started_at_gimbal_lock_fail_at_every_rate() {
    // Started exactly at the lock (t = 2 s; then through the locks at 6, 10 and 14 s), the
    // Euler angles taken from R have pitch = 90° to the last bit and a roll/yaw split that R
    // does not determine, so E(Θ₀)ω₀ has entries ~1/cos(fl(π/2)) ≈ 1.6e16. The first Euler-rule
    // step moves the angles by ≥ 1e10 rad (non-finite also counts), and the rotation error is
    // O(1) rad and does not shrink with the rate. The midpoint rule evaluates E at the
    // half-step instead and survives the first step, but stays ≥ 500× the matrix error.
    // Quaternion and matrix: e·rate = 0.777 rad (Euler rule), e·rate² = 0.257 / 0.163 rad·s⁻²
    // (midpoint), i.e. their usual order and constant.
    let scene = Shifted(2.0);
    let s0 = scene.state(0.0);
    let e0 = euler_zyx_of(&s0.r_wb);
    let rate0 = (preint_sim::scene::body_rate_to_euler_rate(&e0) * s0.omega_b).amax();
    println!(
        "start at the lock: pitch − π/2 = {:e}, |E(Θ₀)ω₀|∞ = {rate0:.3e} rad/s, |ω₀| = {:.3} rad/s",
        e0.y - std::f64::consts::FRAC_PI_2,
        s0.omega_b.norm()
    );
    assert!(
        !rate0.is_finite() || rate0 > 1e15 * s0.omega_b.norm(),
        "{rate0}"
    );
    let rates = [100.0, 200.0, 400.0, 1000.0, 2000.0];
    let mut euler_errs = Vec::new();
    for rate in rates {
        let r = lock_run(&scene, rate, 14.0, Rule::Euler);
        let first = (r.angles[1] - r.angles[0]).amax();
        println!(
            "start at lock, Euler rule, {rate:>4} Hz: first step {first:.2e} rad; rot err zyx {:.3e}, quat {:.3e}, matrix {:.3e}",
            r.zyx, r.quat, r.mat
        );
        assert!(
            !first.is_finite() || first > 1e10,
            "{rate} Hz: first step {first}"
        );
        assert!(
            r.zyx.is_nan() || r.zyx > 0.2,
            "{rate} Hz: zyx error {}",
            r.zyx
        );
        for (name, e) in [("quat", r.quat), ("matrix", r.mat)] {
            let c = e * rate;
            assert!((0.75..=0.80).contains(&c), "{rate} Hz: {name} e·rate {c}");
        }
        euler_errs.push(r.zyx);

        let m = lock_run(&scene, rate, 14.0, Rule::Midpoint);
        println!(
            "start at lock, midpoint,   {rate:>4} Hz: rot err zyx {:.3e}, quat {:.3e}, matrix {:.3e}",
            m.zyx, m.quat, m.mat
        );
        assert!(
            m.zyx.is_nan() || m.zyx > 500.0 * m.mat,
            "{rate} Hz: zyx {} vs matrix {}",
            m.zyx,
            m.mat
        );
        let (cq, cm) = (m.quat * rate * rate, m.mat * rate * rate);
        assert!(
            (0.25..=0.265).contains(&cq) && (0.158..=0.168).contains(&cm),
            "{rate} Hz: quat {cq}, matrix {cm}"
        );
    }
    // Not converging: 20× the rate leaves the Euler-rule error at least half as large
    // (measured: 0.30 rad at the lowest rate, 1.14 rad at the highest), while quaternion and
    // matrix shrink 20×.
    let (lo, hi) = (euler_errs[0], euler_errs[rates.len() - 1]);
    assert!(
        lo.is_nan() || hi.is_nan() || hi >= 0.5 * lo,
        "{euler_errs:?}"
    );
}
