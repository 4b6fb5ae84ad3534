//! `ImuFactor::evaluate_with_time_offset` and `CombinedImuFactor::evaluate_with_time_offset`:
//! the column `∂r/∂δt_d` against central differences of the residual in `δt_d` (step 1e-6 s),
//! and every other Jacobian block at `δt_d ≠ 0` against central differences on the manifold
//! (step 1e-5), both residual modes, both bias corrections, with and without an Earth rate;
//! at `δt_d = 0` the residual and blocks are `evaluate`'s.
//!
//! Measurement: a real window (`preintegrate`, midpoint, 200 Hz, 1 s of a smooth motion with
//! rates up to 1.7 rad/s), so that `jac_td` is a true column; states near the prediction, bias
//! off the integration bias. Tolerance: `|a − n| ≤ 2e-7 (1 + |a|)`, as `preint/tests/factor.rs`
//! (central differences of smooth functions with these steps are accurate to ~1e-9).

use nalgebra::{DMatrix, SVector, Vector3};
use preint::{
    BiasCorrection, CombinedImuFactor, ImuBias, ImuFactor, ImuSample, NavState, PreintParams,
    PreintegratedImu, ResidualMode, Scheme, predict, preintegrate,
};

mod common;
use common::factor_vars::{Rng, Vars, analytic, numeric};

fn measurement(correction: BiasCorrection, omega: Option<Vector3<f64>>) -> PreintegratedImu {
    let s: Vec<ImuSample> = (0..=800i64)
        .map(|k| {
            let t = k as f64 * 5e-3;
            let w = Vector3::new(
                0.8 * (2.0 * t).sin() + 0.3,
                0.5 * (3.0 * t).cos(),
                1.2 * (t + 0.4).sin(),
            );
            let a = Vector3::new(
                0.5 * (2.0 * t).cos() + 0.2,
                0.3 * (1.5 * t).sin(),
                9.81 + 0.4 * (3.0 * t).sin(),
            );
            ImuSample::new(k * 5_000_000, w, a)
        })
        .collect();
    let mut p = PreintParams::default()
        .with_scheme(Scheme::Midpoint)
        .with_bias_correction(Some(correction));
    if let Some(w) = omega {
        p = p.with_omega_coriolis(w);
    }
    let b = ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.08),
    );
    preintegrate(&p, &b, &s, 1_000_000_000, 2_000_000_000).unwrap()
}

fn vars(rng: &mut Rng, pim: &PreintegratedImu) -> Vars {
    let xi = NavState::new(rng.rot(), rng.v3(5.0), rng.v3(2.0));
    let b_i = ImuBias::new(
        pim.bias_hat.gyro + rng.v3(0.01),
        pim.bias_hat.acc + rng.v3(0.1),
    );
    let xj = predict(pim, &xi, &b_i).retract(&SVector::<f64, 9>::from_fn(|_, _| 0.01 * rng.s()));
    let b_j = ImuBias::new(b_i.gyro + rng.v3(0.001), b_i.acc + rng.v3(0.01));
    (xi, xj, b_i, b_j)
}

fn close(a: f64, n: f64) -> bool {
    (a - n).abs() <= 2e-7 * (1.0 + a.abs())
}

fn assert_cols<const R: usize>(ana: &SVector<f64, R>, num: &SVector<f64, R>, what: &str) {
    for r in 0..R {
        assert!(
            close(ana[r], num[r]),
            "{what}: row {r}: analytic {:e} numeric {:e}",
            ana[r],
            num[r]
        );
    }
}

fn assert_blocks(ana: &DMatrix<f64>, num: &DMatrix<f64>, what: &str) {
    for c in 0..ana.ncols() {
        for r in 0..ana.nrows() {
            assert!(
                close(ana[(r, c)], num[(r, c)]),
                "{what}: ({r}, {c}): {:e} vs {:e}",
                ana[(r, c)],
                num[(r, c)]
            );
        }
    }
}

#[test]
fn time_offset_column_and_blocks_match_central_differences() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let earth = Vector3::new(0.0, 4.2e-5, 5.9e-5);
    let h = 1e-6;
    for correction in BiasCorrection::ALL {
        for omega in [None, Some(earth)] {
            let pim = measurement(correction, omega);
            assert!(pim.jac_td.norm() > 1.0);
            for mode in [ResidualMode::ComponentWise, ResidualMode::Logmap] {
                let what = format!("{correction:?} {mode:?} earth {}", omega.is_some());
                let v = vars(&mut rng, &pim);
                let f9 = ImuFactor::with_mode(pim.clone(), mode).unwrap();
                let f15 = CombinedImuFactor::with_mode(pim.clone(), mode).unwrap();
                // At δt_d = 0: evaluate's residual and blocks.
                let (r0, j0, _) = f9.evaluate_with_time_offset(&v.0, &v.1, &v.2, 0.0);
                let (re, je) = f9.evaluate(&v.0, &v.1, &v.2);
                assert!(
                    (r0 - re).amax() <= 1e-12 && (analytic(&j0) - analytic(&je)).amax() <= 1e-12,
                    "{what}"
                );
                for dtd in [0.0, 2.5e-3, -4e-3] {
                    let (_, j9, c9) = f9.evaluate_with_time_offset(&v.0, &v.1, &v.2, dtd);
                    let res9 = |d: f64| f9.evaluate_with_time_offset(&v.0, &v.1, &v.2, d).0;
                    let n9 = (res9(dtd + h) - res9(dtd - h)) / (2.0 * h);
                    assert_cols(&c9, &n9, &format!("{what} δt_d {dtd} (9)"));
                    let num = numeric(
                        &v,
                        |x| f9.evaluate_with_time_offset(&x.0, &x.1, &x.2, dtd).0,
                        1e-5,
                    );
                    assert_blocks(
                        &analytic(&j9),
                        &num,
                        &format!("{what} δt_d {dtd} blocks (9)"),
                    );

                    let (_, j15, c15) = f15.evaluate_with_time_offset(&v.0, &v.1, &v.2, &v.3, dtd);
                    let res15 = |d: f64| f15.evaluate_with_time_offset(&v.0, &v.1, &v.2, &v.3, d).0;
                    let n15 = (res15(dtd + h) - res15(dtd - h)) / (2.0 * h);
                    assert_cols(&c15, &n15, &format!("{what} δt_d {dtd} (15)"));
                    let num = numeric(
                        &v,
                        |x| f15.evaluate_with_time_offset(&x.0, &x.1, &x.2, &x.3, dtd).0,
                        1e-5,
                    );
                    assert_blocks(
                        &analytic(&j15),
                        &num,
                        &format!("{what} δt_d {dtd} blocks (15)"),
                    );
                }
            }
        }
    }
}

/// The column moves the residual the way the time offset moves the deltas: a window
/// preintegrated with the offset `t̂_d + δ` has, at the states predicted by the window with
/// `t̂_d`, the residual `≈ r(δ)` of the first-order correction (to second order in δ = 0.5 ms).
#[test]
fn column_predicts_reintegrated_residual() {
    let pim = measurement(BiasCorrection::Additive, None);
    let f = ImuFactor::with_mode(pim.clone(), ResidualMode::ComponentWise).unwrap();
    let xi = NavState::identity();
    let xj = predict(&pim, &xi, &pim.bias_hat);
    let (r, _, col) = f.evaluate_with_time_offset(&xi, &xj, &pim.bias_hat, 5e-4);
    // r(δ) ≈ col δ at the predicted state (r(0) = 0).
    assert!(
        (r - col * 5e-4).norm() <= 1e-3 * r.norm(),
        "{r} vs {}",
        col * 5e-4
    );
}
