//! Held-input exactness is not smooth-input exactness: the Galilean scheme (exact when the input
//! is held constant over each interval, `galilean_stress.rs`, `preint/tests/galilean.rs`) on a
//! smooth motion, against the 4th-order scheme and the others, at the rates of GTSAM's advice
//! for it (low IMU rates).
//!
//! Setup. Scene `aggressive` (`preint_sim`, analytic states, sums of sinusoids up to 3.1 Hz,
//! |ω_b| up to 4.3 rad/s), noise-free ideal samples computed here from the analytic state
//! (`ω_m = ω_b`, `a_m = R_wbᵀ(a − g)`, g = (0, 0, −9.81)) on a grid over [0 s, 12 s] at 25, 50,
//! 100, 200 and 400 Hz; ten 1 s windows [k s, k+1 s], k = 1…10, cut by `preint::preintegrate`
//! (the grid has samples beyond both ends, so hermite4's stencils have neighbours), zero bias.
//! Errors against `preint_sim::exact_deltas` (the scene's states at the window's ends only):
//! rotation `|Log(ΔR*ᵀΔR)|` [rad], `|Δv − Δv*|` [m/s], `|Δp − Δp*|` [m]; per scheme and rate the
//! RMS over the ten windows (and the worst window, printed).
//!
//! Asserted (nothing computed by the code under test):
//! - hermite4's velocity and position errors at least ten times below galilean's at every rate,
//!   in RMS over the windows and in every single window;
//! - galilean is of order 1 on smooth input: the least-squares log-log slope of its RMS
//!   rotation, velocity and position errors against the step over 25–400 Hz is in [0.9, 1.1].
//!
//! Output: `target/evidence/galilean_smooth.json`.

use evidence::{loglog_slope, rot_angle, write_json};
use nalgebra::Vector3;
use preint::{ImuBias, ImuSample, Level, PreintParams, Scheme, preintegrate};
use preint_sim::{exact_deltas, scene_by_name, t_s};

const RATES: [i64; 5] = [25, 50, 100, 200, 400];
const WINDOWS: std::ops::RangeInclusive<i64> = 1..=10;
const SEC: i64 = 1_000_000_000;

fn g() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

/// Ideal samples of `aggressive` over [0 s, 12 s] at `rate` Hz.
fn ideal(rate: i64) -> Vec<ImuSample> {
    let scene = scene_by_name("aggressive").unwrap();
    let period = SEC / rate;
    assert_eq!(period * rate, SEC, "rate {rate} must divide 1 s");
    (0..=12 * rate)
        .map(|k| {
            let t = k * period;
            scene.state(t_s(t)).ideal_sample(t, &g())
        })
        .collect()
}

/// `[rotation, velocity, position]` errors of `scheme` on every window, from `samples`.
fn window_errors(scheme: Scheme, samples: &[ImuSample]) -> Vec<[f64; 3]> {
    let scene = scene_by_name("aggressive").unwrap();
    let params = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Deltas)
        .with_gravity(g());
    WINDOWS
        .map(|k| {
            let (ti, tj) = (k * SEC, (k + 1) * SEC);
            let m = preintegrate(&params, &ImuBias::zero(), samples, ti, tj).unwrap();
            let (r, v, p) = exact_deltas(scene.as_ref(), ti, tj, g());
            [
                rot_angle(&r, &m.delta_r),
                (m.delta_v - v).norm(),
                (m.delta_p - p).norm(),
            ]
        })
        .collect()
}

fn rms(e: &[[f64; 3]], c: usize) -> f64 {
    (e.iter().map(|x| x[c] * x[c]).sum::<f64>() / e.len() as f64).sqrt()
}

fn worst(e: &[[f64; 3]], c: usize) -> f64 {
    e.iter().map(|x| x[c]).fold(0.0, f64::max)
}

#[test]
fn hermite4_beats_galilean_tenfold_on_smooth_motion_and_galilean_is_first_order() {
    // errors[scheme][rate] = per-window errors.
    let schemes = Scheme::ALL;
    let mut errors: Vec<Vec<Vec<[f64; 3]>>> = vec![vec![]; schemes.len()];
    for rate in RATES {
        let s = ideal(rate);
        for (k, scheme) in schemes.iter().enumerate() {
            errors[k].push(window_errors(*scheme, &s));
        }
    }

    println!(
        "aggressive, noise-free, ten 1 s windows: RMS over the windows (worst window in brackets)"
    );
    println!(
        "{:<9} {:>5}  {:>20}  {:>20}  {:>20}",
        "scheme", "Hz", "rotation [rad]", "velocity [m/s]", "position [m]"
    );
    let mut rows = vec![];
    for (k, scheme) in schemes.iter().enumerate() {
        for (ri, rate) in RATES.iter().enumerate() {
            let e = &errors[k][ri];
            let cell = |c| format!("{:.2e} ({:.2e})", rms(e, c), worst(e, c));
            println!(
                "{:<9} {:>5}  {:>20}  {:>20}  {:>20}",
                scheme.name(),
                rate,
                cell(0),
                cell(1),
                cell(2)
            );
            rows.push(serde_json::json!({
                "scheme": scheme.name(), "rate_hz": rate,
                "rms": {"rotation_rad": rms(e, 0), "velocity_m_s": rms(e, 1), "position_m": rms(e, 2)},
                "worst": {"rotation_rad": worst(e, 0), "velocity_m_s": worst(e, 1), "position_m": worst(e, 2)},
            }));
        }
    }

    let gi = schemes.iter().position(|s| *s == Scheme::Galilean).unwrap();
    let hi = schemes.iter().position(|s| *s == Scheme::Hermite4).unwrap();
    let mut failures = vec![];
    let mut ratios = vec![];
    for (ri, rate) in RATES.iter().enumerate() {
        let (ge, he) = (&errors[gi][ri], &errors[hi][ri]);
        let r = [rms(ge, 1) / rms(he, 1), rms(ge, 2) / rms(he, 2)];
        let min_window = (0..ge.len())
            .flat_map(|w| [ge[w][1] / he[w][1], ge[w][2] / he[w][2]])
            .fold(f64::INFINITY, f64::min);
        println!(
            "{rate:>4} Hz: galilean / hermite4 RMS error: velocity {:.0}×, position {:.0}×; \
             smallest ratio over the windows {min_window:.0}×",
            r[0], r[1]
        );
        ratios.push(
            serde_json::json!({"rate_hz": rate, "velocity": r[0], "position": r[1],
                                       "smallest_window_ratio": min_window}),
        );
        if r[0] < 10.0 || r[1] < 10.0 || min_window < 10.0 {
            failures.push(format!(
                "{rate} Hz: ratios {r:?}, smallest window {min_window}"
            ));
        }
    }
    let h: Vec<f64> = RATES.iter().map(|r| 1.0 / *r as f64).collect();
    let slopes: Vec<f64> = (0..3)
        .map(|c| {
            let y: Vec<f64> = errors[gi].iter().map(|e| rms(e, c)).collect();
            loglog_slope(&h, &y)
        })
        .collect();
    println!(
        "galilean order (log-log slope over 25–400 Hz): rotation {:.3}, velocity {:.3}, position {:.3}",
        slopes[0], slopes[1], slopes[2]
    );
    for (c, s) in ["rotation", "velocity", "position"].iter().zip(&slopes) {
        if !(0.9..=1.1).contains(s) {
            failures.push(format!("galilean {c} slope {s}"));
        }
    }
    write_json(
        "galilean_smooth.json",
        &serde_json::json!({
            "description": "aggressive, noise-free, ten 1 s windows [k, k+1] s: deltas errors \
                            against exact_deltas per scheme and rate",
            "rows": rows, "galilean_over_hermite4": ratios,
            "galilean_slopes": {"rotation": slopes[0], "velocity": slopes[1], "position": slopes[2]},
        }),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
