//! The window's own discretisation error (`preint::truncation`): the estimate against the true
//! error on every scene and rate of `preint bench-steps`, and the χ² at the true states with the
//! estimate in the covariance.
//!
//! Setup (estimate). Every built-in scene, noise-free ideal samples from its analytic state at
//! 25…3 200 Hz (the rates of `bench-steps`), the window [1 s, 2 s], zero bias; the true error is
//! the scheme's deltas ⊖ `preint_sim::exact_deltas` (chart [δφ, δv, δp]), the estimate
//! `truncation::estimate`. Reported: the relative error of the estimate, `|ê − e| / |e|`, per
//! scheme, scene and rate; asserted where the true error is above round-off (`|e| > 1e-9`):
//! ≤ 0.02 for euler, midpoint and galilean (measured 2.1e-5, 3.0e-4 and 3.5e-5 at worst) and
//! ≤ 0.5 for hermite4
//! (Richardson on every other sample, 0.46 at worst, at 25 Hz, where its 12.5 Hz coarse grid is
//! far from asymptotic; ≤ 1.1e-2 from 50 Hz).
//!
//! Setup (χ²). Window [1 s, 2 s] of `seed-ellipse` at 20 Hz and `aggressive` at 40 and 20 Hz,
//! EuRoC densities, N = 32 000 realisations (`evidence::noisy_stream`), euler, midpoint and
//! galilean, `ImuFactor` at the true states with the measurement as is and weighted with its
//! estimate (`truncation::inflate`: the companion's covariance plus the estimate's outer product
//! in the chart of the Logmap (default) or the component-wise residual). Beside them, the mean
//! the estimate's own error predicts: `9 + dᵀΣ'⁻¹d`, `d = e − ê` on the noise-free window.
//! Measured (Logmap / component-wise / predicted):
//!
//! | scene, rate | euler | midpoint | galilean |
//! |---|---|---|---|
//! | seed-ellipse 20 Hz (as is 74 951 / 51.9 / 74 679) | 9.037 / 9.035 / 9.000 | 9.046 / 9.046 / 9.000 | 9.036 / 9.034 / 9.000 |
//! | aggressive 40 Hz (as is 52 068 / 201.1 / 32 742) | 9.033 / 9.031 / 9.000 | 9.049 / 9.049 / 9.000 | 9.028 / 9.025 / 9.000 |
//! | aggressive 20 Hz (as is 199 365 / 3 263 / 122 137) | 9.055 / 9.050 / 9.017 | 9.040 / 9.040 / 9.019 | 9.054 / 9.048 / 9.016 |
//!
//! Asserted: the inflated mean a hundred times closer to 9 than the plain one everywhere; the
//! component-wise mean within `4.42 √(18/N)` (±0.106) of the prediction; and both residuals
//! within ±0.106 of 9 everywhere, including `aggressive` at 20 Hz (components up to 3.1 Hz
//! sampled 6.5 times per period), where the companion on the samples upsampled by degree-11
//! polynomials leaves 0.13σ of its own error (`preint::truncation`). The +0.03–0.05 left is the
//! estimate's noise, which is correlated with the companion's.
//!
//! Output: `target/evidence/truncation.json`.

use evidence::{Gauss, mean, noisy_stream, true_state, write_json};
use nalgebra::Vector3;
use preint::truncation::{estimate, inflate};
use preint::{
    ImuBias, ImuFactor, ImuNoise, ImuSample, Level, PreintParams, ResidualMode, Scheme,
    preintegrate,
};
use preint_sim::{SCENE_NAMES, exact_deltas, scene_by_name, t_s};

const T_I: i64 = 1_000_000_000;
const T_J: i64 = 2_000_000_000;

fn g() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

fn ideal(name: &str, rate_hz: f64) -> Vec<ImuSample> {
    let scene = scene_by_name(name).unwrap();
    let period = (1e9 / rate_hz).round() as i64;
    (0..=(3_000_000_000 / period))
        .map(|k| {
            let t = k * period;
            scene.state(t_s(t)).ideal_sample(t, &g())
        })
        .collect()
}

#[test]
fn the_estimate_follows_the_true_error_on_every_scene_and_rate() {
    let rates = [25.0, 50.0, 100.0, 200.0, 400.0, 800.0, 1600.0, 3200.0];
    let b0 = ImuBias::zero();
    let mut out = serde_json::Map::new();
    let mut worst = [0.0f64; 4];
    for name in SCENE_NAMES {
        let scene = scene_by_name(name).unwrap();
        let (r, v, p) = exact_deltas(scene.as_ref(), T_I, T_J, g());
        for rate in rates {
            let s = ideal(name, rate);
            for (si, scheme) in Scheme::ALL.iter().enumerate() {
                let params = PreintParams::default()
                    .with_scheme(*scheme)
                    .with_level(Level::Deltas)
                    .with_gravity(g());
                let m = preintegrate(&params, &b0, &s, T_I, T_J).unwrap();
                let mut exact = m.clone();
                (exact.delta_r, exact.delta_v, exact.delta_p) = (r, v, p);
                let e = m.delta_error(&exact);
                let est = estimate(&params, &b0, &s, &m).unwrap();
                let rel = (est.error - e).norm() / e.norm();
                if e.norm() > 1e-9 {
                    worst[si] = worst[si].max(rel);
                    println!(
                        "{name:<18} {rate:>6} Hz {:<9} |e| {:.2e}, estimate {:.2e}, relative error {rel:.2e}",
                        scheme.name(),
                        e.norm(),
                        est.error.norm()
                    );
                }
                out.insert(
                    format!("{name}/{rate}/{}", scheme.name()),
                    serde_json::json!({"true": e.norm(), "estimate": est.error.norm(), "relative_error": rel}),
                );
            }
        }
    }
    println!(
        "worst relative error of the estimate: euler {:.2e}, midpoint {:.2e}, hermite4 {:.2e}, galilean {:.2e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    write_json("truncation", &serde_json::Value::Object(out));
    assert!(
        worst[0] <= 0.02 && worst[1] <= 0.02 && worst[3] <= 0.02,
        "{worst:?}"
    );
    assert!(worst[2] <= 0.5, "{worst:?}");
}

/// Mean χ² at the true states of `ImuFactor` over [1 s, 2 s] of `scene` at `rate` Hz with EuRoC
/// noise, for `scheme`: as is, inflated by the estimate for the Logmap (default) and the
/// component-wise residual, and the mean the estimate's own error predicts for the latter
/// (`9 + dᵀΣ'⁻¹d`, `d = e − ê` on the noise-free window, `e` its true error against
/// `exact_deltas`, `Σ' = Σ_c + ê êᵀ` its inflated weight).
fn chi2_at_truth(scene_name: &str, rate: f64, scheme: Scheme, n_real: usize) -> [f64; 4] {
    let noise = ImuNoise::euroc();
    let s = ideal(scene_name, rate);
    let dt = 1.0 / rate;
    let (sg, sa) = (noise.gyro_sample_std(dt), noise.acc_sample_std(dt));
    let scene = scene_by_name(scene_name).unwrap();
    let (xi, xj) = (
        true_state(scene.as_ref(), T_I),
        true_state(scene.as_ref(), T_J),
    );
    let b0 = ImuBias::zero();
    let params = PreintParams::from_noise(&noise)
        .with_scheme(scheme)
        .with_level(Level::Covariance)
        .with_gravity(g());
    let clean = preintegrate(&params, &b0, &s, T_I, T_J).unwrap();
    let mut exact = clean.clone();
    (exact.delta_r, exact.delta_v, exact.delta_p) = exact_deltas(scene.as_ref(), T_I, T_J, g());
    let e = clean.delta_error(&exact);
    let est = estimate(&params, &b0, &s, &clean).unwrap();
    let big = inflate(&clean, &est, ResidualMode::ComponentWise).cov;
    let w = big.cholesky().unwrap().inverse();
    let d = e - est.error;
    let predicted = 9.0 + d.dot(&(w * d));
    let (mut plain, mut logmap, mut component) = (vec![], vec![], vec![]);
    for r in 0..n_real {
        let mut rng = Gauss::new(0x7C00_0000 | r as u64);
        let (noisy, _) = noisy_stream(&s, &mut rng, (sg, sa), None);
        let m = preintegrate(&params, &b0, &noisy, T_I, T_J).unwrap();
        let est = estimate(&params, &b0, &noisy, &m).unwrap();
        plain.push(ImuFactor::new(m.clone()).unwrap().chi2(&xi, &xj, &b0));
        let big = inflate(&m, &est, ResidualMode::Logmap);
        logmap.push(ImuFactor::new(big).unwrap().chi2(&xi, &xj, &b0));
        let big = inflate(&m, &est, ResidualMode::ComponentWise);
        let cw = ImuFactor::with_mode(big, ResidualMode::ComponentWise).unwrap();
        component.push(cw.chi2(&xi, &xj, &b0));
    }
    [mean(&plain), mean(&logmap), mean(&component), predicted]
}

#[test]
fn inflated_covariance_puts_the_factor_chi2_at_the_truth_back_to_its_dof() {
    let n_real = 32_000;
    // 4.42σ of the mean of a χ²₉ (probability 1e-5 of a false failure): ±0.106.
    let band = 4.42 * (18.0 / n_real as f64).sqrt();
    let mut out = serde_json::Map::new();
    let mut failures = vec![];
    for (scene, rate) in [
        ("seed-ellipse", 20.0),
        ("aggressive", 40.0),
        ("aggressive", 20.0),
    ] {
        for scheme in [Scheme::Euler, Scheme::Midpoint, Scheme::Galilean] {
            let [mp, ml, mc, pred] = chi2_at_truth(scene, rate, scheme, n_real);
            println!(
                "{scene:<13} {rate:>3} Hz {:<9} N = {n_real}: mean χ² {mp:>9.1} as is; with the \
                 estimate {ml:.3} (Logmap), {mc:.3} (component-wise; {pred:.3} predicted by the \
                 true error)",
                scheme.name()
            );
            out.insert(
                format!("{scene}/{rate}/{}", scheme.name()),
                serde_json::json!({"plain": mp, "logmap": ml, "component": mc, "predicted": pred}),
            );
            let what = format!("{scene} {rate} Hz {}", scheme.name());
            if !(mp > 20.0 && (ml - 9.0).abs() < (mp - 9.0) / 100.0) {
                failures.push(format!(
                    "{what}: {mp} → {ml}, not a hundredfold closer to 9"
                ));
            }
            // The component-wise mean is what the estimate's own error predicts.
            if (mc - pred).abs() > band {
                failures.push(format!("{what}: component-wise {mc}, predicted {pred}"));
            }
            // Both residuals are back at their dof.
            for (name, m) in [("Logmap", ml), ("component-wise", mc)] {
                if (m - 9.0).abs() > band {
                    failures.push(format!("{what}: {name} mean χ² {m}"));
                }
            }
        }
    }
    write_json("truncation_chi2", &serde_json::Value::Object(out));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
