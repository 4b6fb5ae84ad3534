//! Convergence order and accuracy of the three schemes on noise-free analytic motion.
//!
//! Setup. Scenes `seed-ellipse` and `aggressive` (`sim`, analytic states). Window
//! `[1 s, 2 s]` (starting at 1 s so the hermite4 boundary stencils have stream neighbours); rates
//! 25·2^k Hz up to 3200 Hz. Samples are the ideal IMU readings computed here from the scene's
//! analytic state (`ω_m = ω_b`, `a_m = R_wbᵀ(a − g)`, g = (0, 0, −9.81)) on a grid that extends
//! 3 samples beyond each end of the window; `preint::preintegrate` cuts the window. Errors
//! against `preint_sim::exact_deltas` (which uses only the scene's states at 1 s and 2 s): rotation
//! `|Log(ΔR*ᵀΔR)|` [rad], `|Δv − Δv*|` [m/s], `|Δp − Δp*|` [m]. Nothing asserted here is
//! computed by the code under test.
//!
//! Asserted: the least-squares log-log slope of error vs step `h = 1/rate` over the asymptotic
//! range is in [0.9, 1.1] for Euler, [1.85, 2.15] for midpoint and ≥ 3.7 for hermite4, for each of
//! the three errors and both scenes. The asymptotic range is the rates at which
//! - the step resolves the motion: `rate ≥ 100 Hz` on `aggressive` (components up to 3.1 Hz,
//!   body rates ≈ 4 rad/s: at 25–50 Hz a step turns the body by up to 0.16 rad and the leading
//!   error term does not dominate yet; measured slopes there are 0.85 for Euler, 4.5 for hermite4),
//!   every rate on `seed-ellipse` (≤ 0.5 Hz content, ≤ 0.35 rad/s);
//! - the error is above the round-off floor: ≥ 1e-13 rad for the rotation (ΔR is of size 1 and
//!   ≤ 3 200 steps of ≈ 1e-16 accumulate to ≈ 1e-15–1e-14), ≥ 1e-11 m/s and m for Δv, Δp
//!   (sizes up to ≈ 10, so ≈ 10× higher floor, reached by hermite4 at 1600–3200 Hz).
//!
//! At least three rates must remain in every fit (asserted), so a slope is never a two-point
//! artefact. The widths of the intervals (±0.1, ±0.15) absorb the sub-leading terms that
//! remain at 100 Hz; a scheme of the wrong order misses them by ≥ 0.8.
//!
//! A second test checks that these ideal readings equal `preint_sim::simulate`'s noise-free output
//! (≤ 1e-12), so the numbers also describe simulated datasets.
//!
//! Output: a table of the errors at 200 Hz on stdout (`--nocapture`) and in
//! `target/evidence/accuracy_200hz.json` (for the README), plus every slope.

use evidence::{loglog_slope, rot_angle, write_json};
use nalgebra::Vector3;
use preint::{ImuBias, ImuSample, Level, PreintParams, Scheme, preintegrate};
use preint_sim::{Scene, exact_deltas, scene_by_name, t_s};

const T_I: i64 = 1_000_000_000;
const T_J: i64 = 2_000_000_000;
const RATES: [i64; 8] = [25, 50, 100, 200, 400, 800, 1600, 3200];
/// Round-off floors [rad, m/s, m] (see the header).
const FLOOR: [f64; 3] = [1e-13, 1e-11, 1e-11];

/// Lowest rate of the asymptotic range of a scene (see the header).
fn fit_min_rate(scene: &str) -> i64 {
    if scene == "aggressive" { 100 } else { 25 }
}

fn ideal(scene: &dyn Scene, t_ns: i64, g: &Vector3<f64>) -> ImuSample {
    scene.state(t_s(t_ns)).ideal_sample(t_ns, g)
}

/// `[rot, vel, pos]` errors of `scheme` at `rate` on `[T_I, T_J]`.
fn errors(scene: &dyn Scene, scheme: Scheme, rate: i64) -> [f64; 3] {
    let g = Vector3::new(0.0, 0.0, -9.81);
    let period = 1_000_000_000 / rate;
    assert_eq!(period * rate, 1_000_000_000, "rate {rate} must divide 1 s");
    let samples: Vec<ImuSample> = (-3..=rate + 3)
        .map(|k| ideal(scene, T_I + k * period, &g))
        .collect();
    let params = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Deltas)
        .with_gravity(g);
    let m = preintegrate(&params, &ImuBias::zero(), &samples, T_I, T_J).expect("preintegrate");
    let (dr, dv, dp) = exact_deltas(scene, T_I, T_J, g);
    [
        rot_angle(&dr, &m.delta_r),
        (m.delta_v - dv).norm(),
        (m.delta_p - dp).norm(),
    ]
}

#[test]
fn convergence_orders_and_accuracy_at_200_hz() {
    let schemes = [
        (Scheme::Euler, "euler", 0.9, 1.1),
        (Scheme::Midpoint, "midpoint", 1.85, 2.15),
        (Scheme::Hermite4, "hermite4", 3.7, f64::INFINITY),
    ];
    let what = ["rot_rad", "vel_mps", "pos_m"];
    let mut at200 = serde_json::Map::new();
    let mut slopes_json = serde_json::Map::new();
    let mut failures = vec![];
    println!("errors at 200 Hz, window [1 s, 2 s], noise-free:");
    println!(
        "{:<14} {:<9} {:>12} {:>12} {:>12}",
        "scene", "scheme", "rot [rad]", "vel [m/s]", "pos [m]"
    );
    for name in ["seed-ellipse", "aggressive"] {
        let scene = scene_by_name(name).expect("scene");
        let mut scene_json = serde_json::Map::new();
        for &(scheme, sname, lo, hi) in &schemes {
            let errs: Vec<[f64; 3]> = RATES
                .iter()
                .map(|&r| errors(scene.as_ref(), scheme, r))
                .collect();
            let e200 = errs[RATES.iter().position(|&r| r == 200).unwrap()];
            println!(
                "{name:<14} {sname:<9} {:>12.3e} {:>12.3e} {:>12.3e}",
                e200[0], e200[1], e200[2]
            );
            scene_json.insert(
                sname.into(),
                serde_json::json!({"rot_rad": e200[0], "vel_mps": e200[1], "pos_m": e200[2]}),
            );
            for (c, w) in what.iter().enumerate() {
                let (h, e): (Vec<f64>, Vec<f64>) = RATES
                    .iter()
                    .zip(&errs)
                    .filter(|(r, e)| **r >= fit_min_rate(name) && e[c] >= FLOOR[c])
                    .map(|(r, e)| (1.0 / *r as f64, e[c]))
                    .unzip();
                let all: Vec<String> = errs.iter().map(|e| format!("{:.2e}", e[c])).collect();
                assert!(
                    h.len() >= 3,
                    "{name} {sname} {w}: only {} rates in the asymptotic range: {all:?}",
                    h.len()
                );
                let slope = loglog_slope(&h, &e);
                println!(
                    "  slope {name} {sname} {w}: {slope:.3} over {} rates; errors {all:?}",
                    h.len()
                );
                slopes_json.insert(format!("{name}/{sname}/{w}"), slope.into());
                if !(lo..=hi).contains(&slope) {
                    failures.push(format!(
                        "{name} {sname} {w}: slope {slope:.3} ∉ [{lo}, {hi}]"
                    ));
                }
            }
        }
        at200.insert(name.into(), scene_json.into());
    }
    write_json(
        "accuracy_200hz.json",
        &serde_json::json!({
            "description": "noise-free preintegration error vs the scene's exact deltas, 200 Hz, window [1 s, 2 s]",
            "errors": at200,
            "loglog_slopes_vs_step": slopes_json,
        }),
    );
    assert!(
        failures.is_empty(),
        "convergence orders:\n{}",
        failures.join("\n")
    );
}

/// The ideal readings used above (computed here from the scene's analytic state) are the same
/// as `preint_sim::simulate`'s noise-free output, so these results hold for simulated datasets too.
#[test]
fn ideal_readings_match_the_simulator() {
    let g = Vector3::new(0.0, 0.0, -9.81);
    for name in ["seed-ellipse", "aggressive"] {
        let scene = scene_by_name(name).unwrap();
        let out = preint_sim::simulate(
            scene.as_ref(),
            200.0,
            2.0,
            &preint_sim::SimConfig::noise_free(),
            1,
        )
        .expect("simulate");
        assert_eq!(out.samples.len(), 401);
        for s in &out.samples {
            let mine = ideal(scene.as_ref(), s.t_ns, &g);
            let d = (s.gyro - mine.gyro).amax().max((s.acc - mine.acc).amax());
            assert!(d <= 1e-12, "{name} at {} ns: sim differs by {d:e}", s.t_ns);
        }
    }
}
