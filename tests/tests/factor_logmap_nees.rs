//! Which residual is consistent over long windows? The mean χ² (NEES) of both factors at the
//! true states in each [`ResidualMode`]: the component-wise residual `[r_φ, r_v, r_p]` and the
//! SE₂(3) Logmap residual `Log(D(b)⁻¹ Y)` (`preint::factor::logmap`), each weighted by the
//! covariance of its chart.
//!
//! Setup (GTSAM's `Logmap_IMU_NEES` experiment on our scenes): scenes `aggressive` and
//! `seed-ellipse`, 10 s windows from `t_i = 1 s`, 200 Hz, the 4th-order scheme (`hermite4`,
//! whose discretisation χ² here is below 1e-3), fixed bias `b` integrated with `b̂ = b`
//! (9-dim) or a bias random walk from `b` (15-dim, `Level::Combined`, `b_j` the walk's value),
//! white noise of three density pairs drawn by the suite's seeded generator:
//!
//! - `euroc`: σ_g = 1.6968e-4 rad/s/√Hz, σ_a = 2.0e-3 m/s²/√Hz (EuRoC / ADIS16448);
//! - `seed`: σ_g = 0.015, σ_a = 0.019 (the seed course's);
//! - `high`: σ_g = 0.05, σ_a = 0.1 (`PREINT_FULL=1` only);
//!
//! with the EuRoC random walk. Both modes read the same preintegration of the same stream in
//! each realisation, so their difference is the residual's chart alone. The expected mean is
//! `k + λ` (`k` = 9 or 15, `λ` the noise-free discretisation χ² of the mode), its 95 % band
//! `k + λ ± 1.96 √((2k + 4λ)/N)`.
//!
//! Asserted: (1) at EuRoC densities both modes are inside `k + λ ± 4.42 √((2k + 4λ)/N)` (the
//! band a correct weight misses with probability 1e-5); (2) at the seed densities the
//! component-wise mean is above that band (over-confident: linearisation error of the
//! rotation error's coupling into velocity and position) and the Logmap mean is closer to
//! `k + λ` than the component-wise one, in every scene and dimension.
//!
//! Size: N = 1 000 realisations per setup (CI, ≈ 10 s in the test profile); `PREINT_FULL=1`: N = 4 000 and the `high` rows.
//! Output: `target/evidence/factor_logmap_nees.json`.

use evidence::{Gauss, full_run, integrate_all, mean, noisy_stream, true_state, write_json};
use nalgebra::Vector3;
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, ImuSample, Level, PreintParams,
    PreintegratedImu, ResidualMode, Scheme,
};
use preint_sim::{scene_by_name, t_s};

const T_I: i64 = 1_000_000_000;
const PERIOD: i64 = 5_000_000;
const WINDOW_S: i64 = 10;
const MODES: [ResidualMode; 2] = [ResidualMode::ComponentWise, ResidualMode::Logmap];

fn realisations() -> usize {
    if full_run() { 4_000 } else { 1_000 }
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

fn noise(name: &str) -> ImuNoise {
    let (g, a) = match name {
        "euroc" => (1.6968e-4, 2.0e-3),
        "seed" => (0.015, 0.019),
        _ => (0.05, 0.1),
    };
    ImuNoise {
        gyro_noise_density: g,
        acc_noise_density: a,
        ..ImuNoise::euroc()
    }
}

#[derive(Clone, Debug)]
struct Row {
    scene: &'static str,
    noise: &'static str,
    dim: usize,
    mode: ResidualMode,
    disc_chi2: f64,
    chi2: Vec<f64>,
}

impl Row {
    fn expected(&self) -> f64 {
        self.dim as f64 + self.disc_chi2
    }
    fn std_of_mean(&self) -> f64 {
        ((2.0 * self.dim as f64 + 4.0 * self.disc_chi2) / self.chi2.len() as f64).sqrt()
    }
    fn z(&self) -> f64 {
        (mean(&self.chi2) - self.expected()) / self.std_of_mean()
    }
}

/// Rows [9-dim component, 9-dim Logmap, 15-dim component, 15-dim Logmap] of one setup.
fn rows_of(
    scene_name: &'static str,
    noise_name: &'static str,
    n_real: usize,
    seed: u64,
) -> Vec<Row> {
    let scene = scene_by_name(scene_name).unwrap();
    let n = (WINDOW_S * 1_000_000_000 / PERIOD) as usize + 1;
    let t_j = T_I + WINDOW_S * 1_000_000_000;
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
    let nz = noise(noise_name);
    let dt = PERIOD as f64 * 1e-9;
    let (sg, sa) = (nz.gyro_sample_std(dt), nz.acc_sample_std(dt));
    let (sbg, sba) = (nz.gyro_bias_step_std(dt), nz.acc_bias_step_std(dt));
    let p9 = PreintParams::from_noise(&nz)
        .with_scheme(Scheme::Hermite4)
        .with_level(Level::Covariance)
        .with_gravity(gravity());
    let p15 = p9.clone().with_level(Level::Combined);
    let (c9, c15) = (run(&p9, &clean), run(&p15, &clean));
    let mut rows: Vec<Row> = Vec::new();
    for (dim, pim) in [(9, &c9), (15, &c15)] {
        for mode in MODES {
            let disc_chi2 = if dim == 9 {
                ImuFactor::with_mode(pim.clone(), mode)
                    .unwrap()
                    .chi2(&xi, &xj, &b)
            } else {
                CombinedImuFactor::with_mode(pim.clone(), mode)
                    .unwrap()
                    .chi2(&xi, &xj, &b, &b)
            };
            rows.push(Row {
                scene: scene_name,
                noise: noise_name,
                dim,
                mode,
                disc_chi2,
                chi2: Vec::with_capacity(n_real),
            });
        }
    }
    for r in 0..n_real {
        let mut rng = Gauss::new((seed << 40) | (r as u64));
        let (noisy, _) = noisy_stream(&clean, &mut rng, (sg, sa), None);
        let pim = run(&p9, &noisy);
        for (k, mode) in MODES.into_iter().enumerate() {
            let f = ImuFactor::with_mode(pim.clone(), mode).unwrap();
            rows[k].chi2.push(f.chi2(&xi, &xj, &b));
        }
        let mut rng = Gauss::new((seed << 40) | (1 << 39) | (r as u64));
        let (noisy, walk) = noisy_stream(&clean, &mut rng, (sg, sa), Some((sbg, sba)));
        let bj = ImuBias::new(b.gyro + walk.gyro, b.acc + walk.acc);
        let pim = run(&p15, &noisy);
        for (k, mode) in MODES.into_iter().enumerate() {
            let f = CombinedImuFactor::with_mode(pim.clone(), mode).unwrap();
            rows[2 + k].chi2.push(f.chi2(&xi, &xj, &b, &bj));
        }
    }
    rows
}

#[test]
fn logmap_residual_is_closer_to_its_chi2_than_the_component_wise_one() {
    let n_real = realisations();
    let mut setups: Vec<(&'static str, &'static str)> = vec![
        ("aggressive", "euroc"),
        ("seed-ellipse", "euroc"),
        ("aggressive", "seed"),
        ("seed-ellipse", "seed"),
    ];
    if full_run() {
        setups.extend([("aggressive", "high"), ("seed-ellipse", "high")]);
    }
    let rows: Vec<Row> = std::thread::scope(|sc| {
        let handles: Vec<_> = (0..2)
            .map(|t| {
                let setups = &setups;
                sc.spawn(move || {
                    setups
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| i % 2 == t)
                        .flat_map(|(i, (s, nz))| rows_of(s, nz, n_real, i as u64 + 101))
                        .collect::<Vec<Row>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });

    println!(
        "{:<13} {:<6} {:>3} {:<9} {:>10} {:>9} {:>9}  {:<18} {:>7}",
        "scene", "noise", "dim", "residual", "disc. χ²", "expected", "mean χ²", "95 % band", "z"
    );
    let mut records = vec![];
    for r in &rows {
        let (m, e, sd, z) = (mean(&r.chi2), r.expected(), r.std_of_mean(), r.z());
        println!(
            "{:<13} {:<6} {:>3} {:<9} {:>10.2e} {:>9.3} {:>9.3}  [{:.3}, {:.3}] {:>7.2}",
            r.scene,
            r.noise,
            r.dim,
            r.mode.name(),
            r.disc_chi2,
            e,
            m,
            e - 1.96 * sd,
            e + 1.96 * sd,
            z
        );
        records.push(serde_json::json!({
            "scene": r.scene, "noise": r.noise, "dim": r.dim, "residual": r.mode.name(),
            "discretisation_chi2": r.disc_chi2, "expected_mean": e, "mean_chi2": m,
            "band95": [e - 1.96 * sd, e + 1.96 * sd], "z": z,
        }));
    }
    println!("N = {n_real} realisations per row");
    write_json(
        "factor_logmap_nees.json",
        &serde_json::json!({
            "description": "mean chi2 at the true states of ImuFactor (9) and CombinedImuFactor \
                            (15) in both residual modes; hermite4, 200 Hz, 10 s windows",
            "realisations": n_real,
            "rows": records,
        }),
    );

    let mut failures = vec![];
    for pair in rows.chunks(2) {
        let (cw, lm) = (&pair[0], &pair[1]);
        let what = format!("{} {} {}-dim", cw.scene, cw.noise, cw.dim);
        match cw.noise {
            "euroc" => {
                for r in pair {
                    if r.z().abs() > 4.42 {
                        failures.push(format!("{what} {}: z = {:.2}", r.mode.name(), r.z()));
                    }
                }
            }
            "seed" => {
                if cw.z() <= 4.42 {
                    failures.push(format!(
                        "{what}: component-wise z = {:.2}, not over-confident",
                        cw.z()
                    ));
                }
                if lm.z() >= cw.z() || lm.z().abs() >= cw.z().abs() {
                    failures.push(format!(
                        "{what}: Logmap z = {:.2} not closer than component-wise z = {:.2}",
                        lm.z(),
                        cw.z()
                    ));
                }
            }
            _ => {}
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
