//! Factor-level consistency at the true states: is the χ² of `ImuFactor` and
//! `CombinedImuFactor`, evaluated at the scene's exact states and biases, distributed as the
//! covariance each factor weights with says?
//!
//! This checks the covariance where a user meets it — as the weight of the residual a back end
//! evaluates — rather than as the spread of the preintegrated deltas (`nees.rs`). The two differ
//! in sign conventions (the residual is true ⊖ measured for the deltas and `b_j − b_i` for the
//! biases), which is what this test exists to catch.
//!
//! Setup. Scenes `aggressive` and `seed-ellipse`, 200 Hz, windows of 1 s and 10 s starting at
//! `t_i = 1 s` (samples on the grid, no boundary interpolation), EuRoC densities. The samples are
//! the ideal readings of the scene plus the bias `b` (`b_g = (0.01, −0.02, 0.015)` rad/s,
//! `b_a = (0.1, −0.05, 0.2)` m/s²) plus, per realisation, white noise drawn by the suite's own
//! seeded generator (`evidence::Gauss`), the same stream for every scheme:
//!
//! - 9-dim: the bias stays `b`; `Level::Covariance`, integrated with `b̂ = b`; `ImuFactor` at
//!   the true states with `b_i = b`.
//! - 15-dim: the bias follows its random walk from `b` (`b_k = b_{k−1} + σ_b√Δt w_k`);
//!   `Level::Combined`, integrated with `b̂ = b = b_i`; `CombinedImuFactor` at the true states
//!   with `b_i = b` and `b_j` the walk's value at the last sample.
//!
//! Expected value. The residual at the truth is the discretisation error `d` (a property of
//! the scheme and rate, the same in every realisation) plus the noise's effect. If the weight
//! `Σ` is the noise's covariance, `χ² = (d + n)ᵀΣ⁻¹(d + n)` is non-central χ² with `k` degrees
//! of freedom (9 or 15) and non-centrality `λ = dᵀΣ⁻¹d`: mean `k + λ`, variance `2k + 4λ`. `λ`
//! is measured by evaluating the factor of the noise-free samples at the truth (the row's
//! "discretisation χ²"; it is why Euler's rows are high). The 95 % band of the mean of `N`
//! realisations is `k + λ ± 1.96 √((2k + 4λ)/N)` ([8.815, 9.187] and [14.76, 15.24] for `λ = 0`,
//! `N = 2 000`).
//!
//! Asserted, per row: the mean χ² is within `k + λ ± 4.42 √((2k + 4λ)/N)`, the band that a
//! correct covariance misses with probability 1e-5, so that the whole table (28 rows) passes
//! with probability > 0.999 without tuning a seed; and, over the table, at most 5 rows
//! outside their 95 % band (for 28 independent rows `P(more than 5) ≈ 0.006`), so that a
//! covariance off by a few percent everywhere fails. With the delta–bias blocks of the
//! combined covariance taken with the error state's sign (weighting by `cov15` itself), the
//! 15-dim means are ≈ 22 on 1 s windows and > 80 on 10 s windows: far outside.
//!
//! Also a merged row: ten consecutive 1 s windows of one stream (`preint::preintegrate`),
//! merged (`preint::merge`) into the 10 s window, weighted by the combined factor: the merge
//! composes the error state's covariance and the factor turns it into the residual's.
//!
//! Size: N = 2 000 realisations per row (≈ 25 s in the test profile on 2 cores);
//! `PREINT_FULL=1` runs N = 20 000. Output: `target/evidence/factor_consistency.json`.

use evidence::monte_carlo::{Chi2Draws, MonteCarlo, SampleNoise, on_two_threads};
use evidence::{SceneWindow, full_run, gravity, integrate_all, scene_bias, write_json};
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, ImuSample, Level, PreintParams,
    PreintegratedImu, Scheme, merge, preintegrate,
};
use preint_sim::scene_by_name;

const T_I: i64 = 1_000_000_000;
const PERIOD: i64 = 5_000_000;
const SCHEMES: [(Scheme, &str); 3] = [
    (Scheme::Euler, "euler"),
    (Scheme::Midpoint, "midpoint"),
    (Scheme::Hermite4, "hermite4"),
];

fn realisations() -> usize {
    if full_run() { 20_000 } else { 2_000 }
}

fn run(params: &PreintParams, samples: &[ImuSample]) -> PreintegratedImu {
    integrate_all(params, &scene_bias(), samples)
}

/// Ten 1 s windows of the stream, preintegrated on their own and merged.
fn run_merged(params: &PreintParams, samples: &[ImuSample]) -> PreintegratedImu {
    let t_j = samples[samples.len() - 1].t_ns;
    let mut m: Option<PreintegratedImu> = None;
    let mut t = samples[0].t_ns;
    while t < t_j {
        let w = preintegrate(params, &scene_bias(), samples, t, t + 1_000_000_000).unwrap();
        m = Some(match m {
            None => w,
            Some(a) => merge(&a, &w).unwrap(),
        });
        t += 1_000_000_000;
    }
    m.unwrap()
}

/// One row of the table: a factor of one scheme on one scene and window, its χ² draws and
/// their expected mean (`λ` the noise-free discretisation χ²).
#[derive(Clone, Debug)]
struct Row {
    scene: &'static str,
    window_s: i64,
    scheme: &'static str,
    chi2: Chi2Draws,
}

/// The rows of one scene and window: 9- and 15-dim for every scheme, and the merged 15-dim
/// rows (10 s windows only).
fn rows_of(scene_name: &'static str, window_s: i64, n_real: usize, seed: u64) -> Vec<Row> {
    let scene = scene_by_name(scene_name).unwrap();
    let b = scene_bias();
    let t_j = T_I + window_s * 1_000_000_000;
    let w = SceneWindow::new(scene.as_ref(), (T_I, t_j), PERIOD, &b);
    let (xi, xj, clean) = (w.state_i, w.state_j, w.clean);
    let noise = ImuNoise::euroc();
    let mc = MonteCarlo {
        clean: &clean,
        noise: SampleNoise::at(&noise, PERIOD as f64 * 1e-9),
        n: n_real,
    };
    let merged_schemes: &[usize] = if window_s == 10 { &[1, 2] } else { &[] };

    let p9: Vec<PreintParams> = SCHEMES
        .iter()
        .map(|(s, _)| {
            PreintParams::from_noise(&noise)
                .with_scheme(*s)
                .with_level(Level::Covariance)
                .with_gravity(gravity())
        })
        .collect();
    let p15: Vec<PreintParams> = p9
        .iter()
        .map(|p| p.clone().with_level(Level::Combined))
        .collect();
    let chi2_9 = |m: PreintegratedImu| ImuFactor::new(m).unwrap().chi2(&xi, &xj, &b);
    let chi2_15 = |m: PreintegratedImu, bj: &ImuBias| {
        CombinedImuFactor::new(m).unwrap().chi2(&xi, &xj, &b, bj)
    };
    // Per scheme, then the merged windows.
    let pims15 = |s: &[ImuSample]| {
        let merged = merged_schemes.iter().map(|&k| run_merged(&p15[k], s));
        p15.iter()
            .map(|p| run(p, s))
            .chain(merged)
            .collect::<Vec<_>>()
    };
    let f9 = mc.white(seed << 40, |s| {
        p9.iter().map(|p| chi2_9(run(p, s))).collect::<Vec<_>>()
    });
    let f15 = mc.walk((seed << 40) | (1 << 39), |s, walk| {
        let bj = ImuBias::new(b.gyro + walk.gyro, b.acc + walk.acc);
        pims15(s)
            .into_iter()
            .map(|m| chi2_15(m, &bj))
            .collect::<Vec<_>>()
    });
    let row = |scheme: &'static str, dof: usize, lambda: f64, draws: &[f64]| Row {
        scene: scene_name,
        window_s,
        scheme,
        chi2: Chi2Draws {
            dof,
            lambda,
            draws: draws.to_vec(),
        },
    };
    let clean15 = pims15(&clean);
    let mut rows: Vec<Row> = Vec::new();
    for (s, (_, name)) in SCHEMES.iter().enumerate() {
        rows.push(row(name, 9, chi2_9(run(&p9[s], &clean)), &f9[s]));
        rows.push(row(name, 15, chi2_15(clean15[s].clone(), &b), &f15[s]));
    }
    for (k, &s) in merged_schemes.iter().enumerate() {
        let name = match s {
            1 => "midpoint, 10 merged 1 s windows",
            _ => "hermite4, 10 merged 1 s windows",
        };
        let i = SCHEMES.len() + k;
        rows.push(row(name, 15, chi2_15(clean15[i].clone(), &b), &f15[i]));
    }
    rows
}

#[test]
fn both_factors_are_chi2_consistent_at_the_true_states() {
    let n_real = realisations();
    let setups: [(&'static str, i64); 4] = [
        ("aggressive", 10),
        ("seed-ellipse", 10),
        ("aggressive", 1),
        ("seed-ellipse", 1),
    ];
    // Two threads (the CI machine has two cores), each taking every other setup.
    let rows = on_two_threads(&setups, |i, (scene, w)| {
        rows_of(scene, *w, n_real, i as u64 + 1)
    });

    let mut failures = vec![];
    let mut outside95 = 0;
    let mut records = vec![];
    println!(
        "{:<13} {:>4} {:<33} {:>3} {:>12} {:>10} {:>10}  {:<20} {:>6}",
        "scene", "T[s]", "scheme", "dim", "disc. χ²", "expected", "mean χ²", "95 % band", "z"
    );
    for r in &rows {
        let c = &r.chi2;
        let (m, e, sd, z) = (c.mean(), c.expected(), c.std_of_mean(), c.z());
        let band = c.band(1.96);
        let inside = z.abs() <= 1.96;
        if !inside {
            outside95 += 1;
        }
        println!(
            "{:<13} {:>4} {:<33} {:>3} {:>12.4} {:>10.3} {:>10.3}  [{:.3}, {:.3}]{} {:>6.2}",
            r.scene,
            r.window_s,
            r.scheme,
            c.dof,
            c.lambda,
            e,
            m,
            band.0,
            band.1,
            if inside { " " } else { "*" },
            z
        );
        if z.abs() > 4.42 {
            failures.push(format!(
                "{} {} s {} {}-dim: mean χ² {m:.3}, expected {e:.3} ± {sd:.3} (z = {z:.2})",
                r.scene, r.window_s, r.scheme, c.dof
            ));
        }
        records.push(serde_json::json!({
            "scene": r.scene, "window_s": r.window_s, "scheme": r.scheme, "dim": c.dof,
            "discretisation_chi2": c.lambda, "expected_mean": e, "mean_chi2": m,
            "band95": [band.0, band.1], "z": z,
        }));
    }
    println!(
        "N = {n_real}; rows outside their 95 % band: {outside95} of {}",
        rows.len()
    );
    write_json(
        "factor_consistency.json",
        &serde_json::json!({
            "description": "mean chi2 of ImuFactor (9) and CombinedImuFactor (15) at the true \
                            states, 200 Hz, EuRoC densities; expected = dim + discretisation chi2",
            "realisations": n_real,
            "residual_order": "[r_phi, r_v, r_p] (9), [r_phi, r_v, r_p, r_bg, r_ba] (15)",
            "rows": records,
        }),
    );
    assert_eq!(rows.len(), 28);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        outside95 <= 5,
        "{outside95} of {} rows outside their 95 % band",
        rows.len()
    );
}
