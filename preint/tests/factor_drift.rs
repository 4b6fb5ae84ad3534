//! `ImuFactor::with_in_window_drift` at the point of use: the 9-dim factor's χ² at the true
//! states, while the true bias drifts as a random walk within the window, is χ²₉ with the
//! drift in the weight and too large without it (a Monte Carlo of seeded draws); the
//! constructor needs the combined level and weights by `cov15`'s [δφ, δv, δp] block.

use nalgebra::{Matrix3, Vector3};
use preint::{
    FactorError, ImuBias, ImuFactor, ImuNoise, ImuSample, Level, NavState, PreintParams,
    ResidualMode, Scheme, predict, preintegrate,
};

mod common;
use common::factor_vars::Rng;

const RATE_HZ: f64 = 100.0;
const WINDOW_S: f64 = 2.0;
const NOISE: ImuNoise = ImuNoise {
    gyro_noise_density: 1e-3,
    acc_noise_density: 1e-2,
    gyro_random_walk: 1e-3,
    acc_random_walk: 5e-2,
    update_rate_hz: RATE_HZ,
};

fn normal(rng: &mut Rng) -> f64 {
    let (u, v) = (rng.u().max(1e-300), rng.u());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

fn n3(rng: &mut Rng) -> Vector3<f64> {
    Vector3::new(normal(rng), normal(rng), normal(rng))
}

/// The true signal at sample `k`: a turning, accelerating body.
fn truth(k: usize) -> (Vector3<f64>, Vector3<f64>) {
    let t = k as f64 / RATE_HZ;
    (
        Vector3::new(0.3 * t.sin(), -0.2, 0.5 * t.cos()),
        Vector3::new(0.5 * t.cos(), 0.2, 9.81 + 0.3 * t.sin()),
    )
}

fn samples(rng: Option<&mut Rng>) -> Vec<ImuSample> {
    let n = (RATE_HZ * WINDOW_S) as usize;
    let dt = 1.0 / RATE_HZ;
    let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
    let mut rng = rng;
    (0..=n)
        .map(|k| {
            let (w, a) = truth(k);
            let t_ns = (k as f64 * 1e9 / RATE_HZ).round() as i64;
            let Some(r) = rng.as_deref_mut() else {
                return ImuSample::new(t_ns, w, a);
            };
            let s = ImuSample::new(
                t_ns,
                w + bg + n3(r) * (NOISE.gyro_noise_density / dt.sqrt()),
                a + ba + n3(r) * (NOISE.acc_noise_density / dt.sqrt()),
            );
            bg += n3(r) * (NOISE.gyro_random_walk * dt.sqrt());
            ba += n3(r) * (NOISE.acc_random_walk * dt.sqrt());
            s
        })
        .collect()
}

fn params() -> PreintParams {
    PreintParams::from_noise(&NOISE)
        .with_scheme(Scheme::Euler)
        .with_level(Level::Combined)
}

/// Over 400 draws (bias zero at i, drifting after), the mean χ² of the drift-weighted factor
/// is within 4σ of 9 (σ = √(18/400)) and the white-noise-weighted one is far above it.
#[test]
fn drift_weighted_chi2_is_chi2_9_where_the_plain_weight_is_optimistic() {
    let p = params();
    let t_j = (WINDOW_S * 1e9) as i64;
    let clean = preintegrate(&p, &ImuBias::zero(), &samples(None), 0, t_j).unwrap();
    let xi = NavState::new(
        preint::lie::SO3::exp(&Vector3::new(0.1, -0.2, 0.3)),
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(0.5, -0.3, 0.1),
    );
    let xj = predict(&clean, &xi, &ImuBias::zero());
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let draws = 400;
    let (mut drift, mut plain) = (0.0, 0.0);
    for _ in 0..draws {
        let pim = preintegrate(&p, &ImuBias::zero(), &samples(Some(&mut rng)), 0, t_j).unwrap();
        let mode = ResidualMode::ComponentWise;
        let fd = ImuFactor::with_in_window_drift(pim.clone(), mode).unwrap();
        let f = ImuFactor::with_mode(pim, mode).unwrap();
        drift += fd.chi2(&xi, &xj, &ImuBias::zero()) / draws as f64;
        plain += f.chi2(&xi, &xj, &ImuBias::zero()) / draws as f64;
    }
    eprintln!("mean χ²: drift-weighted {drift:.3}, white-noise weight {plain:.3}");
    let tol = 4.0 * (18.0 / draws as f64).sqrt();
    assert!((drift - 9.0).abs() < tol, "drift-weighted mean χ² {drift}");
    assert!(plain > 9.0 * 3.0, "plain mean χ² {plain}");
}

/// The weight is `cov15`'s top-left block (in both residual modes' component-wise form), which
/// exceeds `cov` by a positive semi-definite drift term; a `Level::Covariance` measurement,
/// whose `cov15` has no drift in its deltas, is refused.
#[test]
fn the_weight_is_the_combined_block_and_needs_the_combined_level() {
    let s = samples(None);
    let t_j = (WINDOW_S * 1e9) as i64;
    let pim = preintegrate(&params(), &ImuBias::zero(), &s, 0, t_j).unwrap();
    let f = ImuFactor::with_in_window_drift(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let block = pim.cov15.fixed_view::<9, 9>(0, 0).into_owned();
    assert_eq!(*f.residual_covariance(), block);
    let extra = block - pim.cov;
    let v: Matrix3<f64> = extra.fixed_view::<3, 3>(3, 3).into_owned();
    assert!(v.trace() > 10.0 * pim.cov.fixed_view::<3, 3>(3, 3).trace());
    assert!(extra.symmetric_eigenvalues().min() > -1e-12 * extra.amax());
    let low = preintegrate(
        &params().with_level(Level::Covariance),
        &ImuBias::zero(),
        &s,
        0,
        t_j,
    )
    .unwrap();
    assert_eq!(
        ImuFactor::with_in_window_drift(low, ResidualMode::Logmap),
        Err(FactorError::LevelTooLow {
            needed: Level::Combined,
            got: Level::Covariance
        })
    );
}
