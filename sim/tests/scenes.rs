//! Scenes: analytic derivatives against central finite differences of the scene's own position
//! and attitude, the seed-ellipse formulas against an independent Euler-angle construction,
//! the multi-pose coverage of ±g, and `exact_deltas` against independent quantities.

use nalgebra::{Rotation3, Vector3};
use preint::{ImuBias, NavState};
use sim::{
    Attitude, Rule, SCENE_NAMES, Scene, SimConfig, dead_reckon, exact_deltas, scene_by_name,
    simulate,
};

const G: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

fn check_close(what: &str, name: &str, t: f64, analytic: Vector3<f64>, numeric: Vector3<f64>) {
    let err = (analytic - numeric).norm();
    let tol = 1e-6 * (1.0 + analytic.norm());
    assert!(
        err <= tol,
        "{name} t={t}: {what} analytic {analytic:?} vs numeric {numeric:?} (err {err:e})"
    );
}

#[test]
fn analytic_derivatives_match_finite_differences_for_every_scene() {
    let h = 1e-4;
    // Times inside every phase of every scene (multi-pose transitions are at 3–5 s, 8–10 s, …;
    // gimbal-lock's pitch is ±90° at t = 2, 6 s).
    let times = [0.37, 1.3, 2.0, 3.9, 4.5, 6.0, 8.7, 14.2, 23.4, 27.1, 31.0];
    for name in SCENE_NAMES {
        let scene = scene_by_name(name).expect("registered scene");
        assert_eq!(scene.name(), *name);
        let mut max_omega = 0.0f64;
        for &t in &times {
            let (sm, s0, sp) = (scene.state(t - h), scene.state(t), scene.state(t + h));
            check_close("v = ṗ", name, t, s0.v, (sp.p - sm.p) / (2.0 * h));
            check_close("a = v̇", name, t, s0.a, (sp.v - sm.v) / (2.0 * h));
            // ω_b: R(t+h) = R(t−h)·Exp(2h ω_b(t) + O(h³)).
            let omega_fd = (sm.r_wb.inverse() * sp.r_wb).log() / (2.0 * h);
            check_close("ω_b", name, t, s0.omega_b, omega_fd);
            check_close(
                "ω̇_b",
                name,
                t,
                s0.omega_dot_b,
                (sp.omega_b - sm.omega_b) / (2.0 * h),
            );
            assert!(
                s0.r_wb.orthonormality_error() < 1e-12,
                "{name}: R not orthonormal"
            );
            max_omega = max_omega.max(s0.omega_b.norm());
        }
        if *name != "static" {
            assert!(
                max_omega > 0.1,
                "{name}: the scene should rotate ({max_omega})"
            );
        }
    }
    assert!(scene_by_name("no-such-scene").is_none());
}

#[test]
fn seed_ellipse_matches_the_course_formulas() {
    let scene = sim::SeedEllipseScene;
    let k = std::f64::consts::PI / 10.0;
    for t in [0.0, 0.8, 3.3, 17.0] {
        let s = scene.state(t);
        let p = Vector3::new(
            15.0 * (k * t).cos() + 5.0,
            20.0 * (k * t).sin() + 5.0,
            (10.0 * k * t).sin() + 5.0,
        );
        assert!((s.p - p).norm() < 1e-12);
        // nalgebra's from_euler_angles(roll, pitch, yaw) = Rz(yaw)·Ry(pitch)·Rx(roll).
        let r = Rotation3::from_euler_angles(0.1 * t.cos(), 0.2 * t.sin(), k * t);
        assert!((s.r_wb.matrix() - r.matrix()).norm() < 1e-14, "t={t}");
    }
}

#[test]
fn spin_scene_spins_at_10_rad_s_about_a_tilted_axis() {
    let s = scene_by_name("spin").unwrap().state(0.5);
    assert!((s.omega_b.norm() - 10.0).abs() < 1e-12);
    let axis_w = s.r_wb * s.omega_b.normalize();
    let tilt = axis_w.z.abs().acos();
    assert!(
        tilt > 0.2 && tilt < 1.4,
        "axis tilt from vertical {tilt} rad"
    );
}

#[test]
fn gimbal_lock_scene_reaches_pitch_90_degrees_exactly() {
    let scene = sim::GimbalLockScene;
    for t in sim::GimbalLockScene::LOCK_TIMES_S {
        let pitch = sim::euler_zyx_of(&scene.state(t).r_wb).y;
        assert!(
            (pitch.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-6,
            "t={t}: {pitch}"
        );
    }
    // …and is away from it in between.
    let pitch = sim::euler_zyx_of(&scene.state(4.0).r_wb).y;
    assert!(pitch.abs() < 1.4, "{pitch}");
}

#[test]
fn aggressive_scene_is_aggressive() {
    let scene = scene_by_name("aggressive").unwrap();
    let (mut w, mut a) = (0.0f64, 0.0f64);
    for k in 0..2000 {
        let s = scene.state(k as f64 * 0.01);
        w = w.max(s.omega_b.norm());
        a = a.max(s.a.norm());
    }
    assert!(
        w > 2.0 && a > 5.0,
        "peak rate {w} rad/s, peak acceleration {a} m/s²"
    );
}

#[test]
fn multi_pose_static_covers_plus_and_minus_g_on_each_axis() {
    let scene = sim::MultiPoseStaticScene::default();
    let mut seen = [[false; 2]; 3];
    for (t0, t1) in scene.static_intervals() {
        for t in [t0 + 0.1, 0.5 * (t0 + t1), t1 - 0.1] {
            let s = scene.state(t);
            assert_eq!(s.omega_b, Vector3::zeros(), "t={t}");
            assert_eq!(s.v, Vector3::zeros());
        }
        let f = scene.state(0.5 * (t0 + t1)).r_wb.inverse() * (-G);
        for i in 0..3 {
            if (f[i].abs() - 9.81).abs() < 1e-9 {
                seen[i][usize::from(f[i] < 0.0)] = true;
            }
        }
    }
    assert_eq!(seen, [[true; 2]; 3], "±g on each axis");
    assert!(scene.poses().len() >= 6);
    // Transitions are C²: ω and ω̇ vanish at both ends of a move.
    let (_, end0) = scene.static_intervals()[0];
    for t in [end0, end0 + 2.0 - 1e-12] {
        let s = scene.state(t);
        assert!(
            s.omega_b.norm() < 1e-9 && s.omega_dot_b.norm() < 1e-6,
            "t={t}"
        );
    }
    assert!(scene.state(end0 + 1.0).omega_b.norm() > 0.5);
}

#[test]
fn exact_deltas_of_a_static_body_are_the_accelerometer_reading_integrated() {
    // At rest the specific force is f = R_wbᵀ(−g), so Δv = f Δt and Δp = ½ f Δt², ΔR = I.
    let scene = sim::StaticScene::default();
    let (dr, dv, dp) = exact_deltas(&scene, 1_000_000_000, 3_500_000_000, G);
    let f = scene.r_wb.inverse() * (-G);
    assert!(dr.log().norm() < 1e-15);
    assert!((dv - f * 2.5).norm() < 1e-12);
    assert!((dp - f * (0.5 * 2.5 * 2.5)).norm() < 1e-12);
}

#[test]
fn exact_deltas_match_a_fine_gravity_free_integration_of_the_samples() {
    // With initial state (I, 0, 0) and zero gravity, dead reckoning of the body-frame samples
    // *is* preintegration, so a fine midpoint run must converge to exact_deltas.
    for name in ["seed-ellipse", "aggressive", "spin"] {
        let scene = scene_by_name(name).unwrap();
        let out = simulate(scene.as_ref(), 2000.0, 2.0, &SimConfig::noise_free(), 0).unwrap();
        let (i, j) = (500, 3500);
        let samples = &out.samples[i..=j];
        let traj = dead_reckon(
            samples,
            &NavState::identity(),
            &ImuBias::zero(),
            &Vector3::zeros(),
            Rule::Midpoint,
            Attitude::Matrix,
        );
        let last = traj.last().unwrap();
        let (dr, dv, dp) = exact_deltas(scene.as_ref(), samples[0].t_ns, samples[j - i].t_ns, G);
        let er = (dr.inverse() * last.r).log().norm();
        let (ev, ep) = ((dv - last.v).norm(), (dp - last.p).norm());
        println!(
            "{name}: |ΔR err| {er:.2e}, |Δv err| {ev:.2e}, |Δp err| {ep:.2e} (|Δv| {:.2})",
            dv.norm()
        );
        assert!(
            er < 1e-5 && ev < 1e-4 && ep < 1e-4,
            "{name}: {er} {ev} {ep}"
        );
        // Δv includes −R_iᵀ g Δt (≈ 9.81 · 1.5 s) — a sign slip would be off by ~30 m/s.
        assert!(dv.norm() > 5.0);
    }
}
