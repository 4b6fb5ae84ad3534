//! Monte Carlo consistency of the preintegration covariance (9-dim and combined 15-dim).
//!
//! Setup. Scenes `seed-ellipse` and `aggressive`; 200 Hz; window `[1 s, 2 s]` (201 samples on
//! the grid, so no boundary interpolation). Noise-free samples are the ideal readings from the
//! scene's analytic state (`ω_m = ω_b`, `a_m = R_wbᵀ(a − g)`). Each realisation adds white
//! noise with the EuRoC densities (`ImuNoise::euroc()`): per-sample std `σ/√Δt`, drawn by the
//! suite's own seeded generator (`evidence::Gauss`, xoshiro256** + Box–Muller), so the test is
//! deterministic and independent of the code under test. Realisation `r` of scene `s` uses the
//! same seed for every scheme.
//!
//! 9-dim (fixed bias `b̂ = (0.01, −0.02, 0.015) rad/s, (0.1, −0.05, 0.2) m/s²` in the samples and
//! the estimate, `Level::Covariance`): `e = [Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀]` against the
//! noise-free run of the same scheme, NEES `eᵀΣ⁻¹e` with the realisation's own `cov`.
//! Asserted: mean NEES ∈ [8.6, 9.4] per scheme and scene. If Σ is right, NEES ~ χ²₉ and the
//! mean of N draws has std `√(18/N)`: 0.134 at N = 1 000, 0.095 at the CI default N = 2 000
//! (the interval is then ±4.2σ; ≈ 7 s), 0.03 with `PREINT_FULL=1` (N = 20 000; ≈ 85 s, all
//! twelve means measured within 8.98–9.00 and 14.92–15.04). A covariance off by
//! 5 % in scale moves the mean by 0.45 and fails.
//!
//! 15-dim (`Level::Combined`, bias random walk with the EuRoC densities: the samples' biases
//! follow `b_k = b_{k−1} + σ_b √Δt w_k` from `b_0 = b̂`, the estimate stays `b̂`):
//! `e15 = [e, b_j − b_i]` (order [δφ, δv, δp, δb_g, δb_a]) with `cov15`; the noise-free
//! reference is the constant-bias run. Mean of N χ²₁₅ has std `√(30/N)`; asserted
//! `|mean − 15| ≤ 4√(30/N)` (0.49 at N = 2 000; 0.155 at N = 20 000): a 4σ bound, so a
//! correct covariance fails with probability ≈ 6e-5, and the run is seeded.
//!
//! Also asserted, so that a pass cannot be vacuous (e.g. noise that never reaches the deltas):
//! the mean rotation error `mean |e_φ|` exceeds `0.5·√tr Σ_φφ` (for a correct Σ it is
//! ≈ 0.92·√tr Σ_φφ, the mean of a χ₃ scaled to the trace).
//!
//! Output: per scheme and scene mean NEES (9 and 15) in `target/evidence/nees.json`.

use evidence::monte_carlo::{Chi2Draws, MonteCarlo, SampleNoise, combined_error, nees};
use evidence::{SceneWindow, full_run, gravity, integrate_all, mean, scene_bias, write_json};
use preint::{ImuNoise, Level, PreintParams, PreintegratedImu, Scheme};
use preint_sim::scene_by_name;

const T_I: i64 = 1_000_000_000;
const PERIOD: i64 = 5_000_000;
const T_J: i64 = 2_000_000_000;

fn realisations() -> usize {
    if full_run() { 20_000 } else { 2_000 }
}

fn run(params: &PreintParams, samples: &[preint::ImuSample]) -> PreintegratedImu {
    integrate_all(params, &scene_bias(), samples)
}

#[test]
fn mean_nees_is_chi2_consistent() {
    let n_real = realisations();
    let noise = ImuNoise::euroc();
    let g = gravity();
    let mut out = serde_json::Map::new();
    let mut failures = vec![];
    for (si, name) in ["seed-ellipse", "aggressive"].iter().enumerate() {
        let scene = scene_by_name(name).unwrap();
        let clean = SceneWindow::new(scene.as_ref(), (T_I, T_J), PERIOD, &scene_bias()).clean;
        let mc = MonteCarlo {
            clean: &clean,
            noise: SampleNoise::at(&noise, PERIOD as f64 * 1e-9),
            n: n_real,
        };
        let mut scene_json = serde_json::Map::new();
        for (scheme, sname) in [
            (Scheme::Euler, "euler"),
            (Scheme::Midpoint, "midpoint"),
            (Scheme::Hermite4, "hermite4"),
        ] {
            let p9 = PreintParams::from_noise(&noise)
                .with_scheme(scheme)
                .with_level(Level::Covariance)
                .with_gravity(g);
            let p15 = p9.clone().with_level(Level::Combined);
            let (m0, m0_15) = (run(&p9, &clean), run(&p15, &clean));
            // White noise only: NEES and the rotation error's norm.
            let f9 = mc.white((si as u64) << 32, |noisy| {
                let m = run(&p9, noisy);
                let e = m.delta_error(&m0);
                [nees(&e, &m.cov), e.fixed_rows::<3>(0).norm()]
            });
            // White noise plus bias random walk.
            let f15 = mc.walk(((si as u64) << 32) | (1 << 31), |noisy, walk| {
                let m = run(&p15, noisy);
                [nees(
                    &combined_error(&m.delta_error(&m0_15), walk),
                    &m.cov15,
                )]
            });
            let n9 = Chi2Draws {
                dof: 9,
                lambda: 0.0,
                draws: f9[0].clone(),
            };
            let n15 = Chi2Draws {
                dof: 15,
                lambda: 0.0,
                draws: f15[0].clone(),
            };
            let (mean9, mean15) = (n9.mean(), n15.mean());
            let bound15 = 4.0 * n15.std_of_mean();
            let phi_sigma = (m0.cov[(0, 0)] + m0.cov[(1, 1)] + m0.cov[(2, 2)]).sqrt();
            let mean_ephi = mean(&f9[1]);
            println!(
                "{name:<13} {sname:<9} N = {n_real}: mean NEES9 {mean9:.3} (std of mean {:.3}), \
                 mean NEES15 {mean15:.3} (bound ±{bound15:.3}); mean |e_φ| {mean_ephi:.2e} rad, \
                 √tr Σ_φφ {phi_sigma:.2e}",
                n9.std_of_mean()
            );
            scene_json.insert(
                sname.into(),
                serde_json::json!({"mean_nees_9": mean9, "mean_nees_15": mean15}),
            );
            if !(8.6..=9.4).contains(&mean9) {
                failures.push(format!(
                    "{name} {sname}: mean NEES9 {mean9:.3} ∉ [8.6, 9.4]"
                ));
            }
            if (mean15 - 15.0).abs() > bound15 {
                failures.push(format!(
                    "{name} {sname}: mean NEES15 {mean15:.3} ∉ 15 ± {bound15:.3}"
                ));
            }
            if mean_ephi < 0.5 * phi_sigma {
                failures.push(format!("{name} {sname}: the noise does not move ΔR"));
            }
        }
        out.insert((*name).into(), scene_json.into());
    }
    write_json(
        "nees.json",
        &serde_json::json!({
            "description": "mean NEES of noisy vs noise-free preintegration, 200 Hz, 1 s, EuRoC densities",
            "realisations": n_real,
            "tangent_order": "[dphi, dv, dp] (9), [dphi, dv, dp, dbg, dba] (15)",
            "expected": {"nees_9": 9.0, "nees_15": 15.0},
            "results": out,
        }),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
