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

use evidence::{Gauss, full_run, integrate_all, mean, noisy_stream, true_state, write_json};
use nalgebra::Vector3;
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, ImuSample, Level, PreintParams,
    PreintegratedImu, Scheme, merge, preintegrate,
};
use preint_sim::{scene_by_name, t_s};

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

fn bias() -> ImuBias {
    ImuBias::new(
        Vector3::new(0.01, -0.02, 0.015),
        Vector3::new(0.1, -0.05, 0.2),
    )
}

fn gravity() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

fn run(params: &PreintParams, samples: &[ImuSample]) -> PreintegratedImu {
    integrate_all(params, &bias(), samples)
}

/// Ten 1 s windows of the stream, preintegrated on their own and merged.
fn run_merged(params: &PreintParams, samples: &[ImuSample]) -> PreintegratedImu {
    let t_j = samples[samples.len() - 1].t_ns;
    let mut m: Option<PreintegratedImu> = None;
    let mut t = samples[0].t_ns;
    while t < t_j {
        let w = preintegrate(params, &bias(), samples, t, t + 1_000_000_000).unwrap();
        m = Some(match m {
            None => w,
            Some(a) => merge(&a, &w).unwrap(),
        });
        t += 1_000_000_000;
    }
    m.unwrap()
}

/// One row of the table: a factor of one scheme on one scene and window.
#[derive(Clone, Debug)]
struct Row {
    scene: &'static str,
    window_s: i64,
    scheme: &'static str,
    dim: usize,
    /// Noise-free discretisation χ² `λ`.
    disc_chi2: f64,
    chi2: Vec<f64>,
}

impl Row {
    fn expected(&self) -> f64 {
        self.dim as f64 + self.disc_chi2
    }

    /// Std of the mean of the χ² draws if the weight is right.
    fn std_of_mean(&self) -> f64 {
        ((2.0 * self.dim as f64 + 4.0 * self.disc_chi2) / self.chi2.len() as f64).sqrt()
    }

    fn z(&self) -> f64 {
        (mean(&self.chi2) - self.expected()) / self.std_of_mean()
    }
}

/// The rows of one scene and window: 9- and 15-dim for every scheme, and the merged 15-dim
/// rows (10 s windows only).
fn rows_of(scene_name: &'static str, window_s: i64, n_real: usize, seed: u64) -> Vec<Row> {
    let scene = scene_by_name(scene_name).unwrap();
    let n = (window_s * 1_000_000_000 / PERIOD) as usize + 1;
    let t_j = T_I + window_s * 1_000_000_000;
    let (xi, xj) = (
        true_state(scene.as_ref(), T_I),
        true_state(scene.as_ref(), t_j),
    );
    let b = bias();
    let clean: Vec<ImuSample> = (0..n as i64)
        .map(|k| {
            let t = T_I + k * PERIOD;
            let s = scene.state(t_s(t)).ideal_sample(t, &gravity());
            ImuSample::new(t, s.gyro + b.gyro, s.acc + b.acc)
        })
        .collect();
    let noise = ImuNoise::euroc();
    let dt = PERIOD as f64 * 1e-9;
    let (sg, sa) = (noise.gyro_sample_std(dt), noise.acc_sample_std(dt));
    let (sbg, sba) = (noise.gyro_bias_step_std(dt), noise.acc_bias_step_std(dt));
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
    let mut rows: Vec<Row> = Vec::new();
    let mut row = |scheme: &'static str, dim: usize, disc_chi2: f64| {
        rows.push(Row {
            scene: scene_name,
            window_s,
            scheme,
            dim,
            disc_chi2,
            chi2: Vec::with_capacity(n_real),
        });
        rows.len() - 1
    };
    let mut idx9 = vec![];
    let mut idx15 = vec![];
    let mut idx_merged = vec![];
    for (s, (_, name)) in SCHEMES.iter().enumerate() {
        let f9 = ImuFactor::new(run(&p9[s], &clean)).unwrap();
        idx9.push(row(name, 9, f9.chi2(&xi, &xj, &b)));
        let f15 = CombinedImuFactor::new(run(&p15[s], &clean)).unwrap();
        idx15.push(row(name, 15, f15.chi2(&xi, &xj, &b, &b)));
    }
    for &s in merged_schemes {
        let f = CombinedImuFactor::new(run_merged(&p15[s], &clean)).unwrap();
        let name = match s {
            1 => "midpoint, 10 merged 1 s windows",
            _ => "hermite4, 10 merged 1 s windows",
        };
        idx_merged.push((s, row(name, 15, f.chi2(&xi, &xj, &b, &b))));
    }

    for r in 0..n_real {
        let mut rng = Gauss::new((seed << 40) | (r as u64));
        let (noisy, _) = noisy_stream(&clean, &mut rng, (sg, sa), None);
        for (s, &i) in idx9.iter().enumerate() {
            let f = ImuFactor::new(run(&p9[s], &noisy)).unwrap();
            rows[i].chi2.push(f.chi2(&xi, &xj, &b));
        }
        let mut rng = Gauss::new((seed << 40) | (1 << 39) | (r as u64));
        let (noisy, walk) = noisy_stream(&clean, &mut rng, (sg, sa), Some((sbg, sba)));
        let bj = ImuBias::new(b.gyro + walk.gyro, b.acc + walk.acc);
        for (s, &i) in idx15.iter().enumerate() {
            let f = CombinedImuFactor::new(run(&p15[s], &noisy)).unwrap();
            rows[i].chi2.push(f.chi2(&xi, &xj, &b, &bj));
        }
        for &(s, i) in &idx_merged {
            let f = CombinedImuFactor::new(run_merged(&p15[s], &noisy)).unwrap();
            rows[i].chi2.push(f.chi2(&xi, &xj, &b, &bj));
        }
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
    let rows: Vec<Row> = std::thread::scope(|sc| {
        let handles: Vec<_> = (0..2)
            .map(|t| {
                sc.spawn(move || {
                    setups
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| i % 2 == t)
                        .flat_map(|(i, (scene, w))| rows_of(scene, *w, n_real, i as u64 + 1))
                        .collect::<Vec<Row>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });

    let mut failures = vec![];
    let mut outside95 = 0;
    let mut records = vec![];
    println!(
        "{:<13} {:>4} {:<33} {:>3} {:>12} {:>10} {:>10}  {:<20} {:>6}",
        "scene", "T[s]", "scheme", "dim", "disc. χ²", "expected", "mean χ²", "95 % band", "z"
    );
    for r in &rows {
        let (m, e, sd, z) = (mean(&r.chi2), r.expected(), r.std_of_mean(), r.z());
        let band = (e - 1.96 * sd, e + 1.96 * sd);
        let inside = z.abs() <= 1.96;
        if !inside {
            outside95 += 1;
        }
        println!(
            "{:<13} {:>4} {:<33} {:>3} {:>12.4} {:>10.3} {:>10.3}  [{:.3}, {:.3}]{} {:>6.2}",
            r.scene,
            r.window_s,
            r.scheme,
            r.dim,
            r.disc_chi2,
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
                r.scene, r.window_s, r.scheme, r.dim
            ));
        }
        records.push(serde_json::json!({
            "scene": r.scene, "window_s": r.window_s, "scheme": r.scheme, "dim": r.dim,
            "discretisation_chi2": r.disc_chi2, "expected_mean": e, "mean_chi2": m,
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
