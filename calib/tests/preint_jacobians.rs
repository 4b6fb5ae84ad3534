//! Re-check of every analytic Jacobian in `preint` with this crate's Ridders-based checker
//! ([`preint_calib::check_jacobian`], relative error ≤ 1e-8), on the manifold:
//!
//! - the five bias Jacobians `∂ΔR/∂b_g, ∂Δv/∂b_g, ∂Δv/∂b_a, ∂Δp/∂b_g, ∂Δp/∂b_a` of
//!   [`preint::preintegrate`] against **re-integration** of the samples at the perturbed bias
//!   (output `(ΔR, Δv, Δp)` differenced as `[Log(ΔR₀ᵀΔR), Δv − Δv₀, Δp − Δp₀]`, i.e. the right
//!   perturbation of ΔR that the Jacobians are defined for), for all three schemes;
//! - every block of [`ImuFactor`] (`NavState` i and j with the tangent `[δφ, δp, δv]`, b_g, b_a)
//!   and of [`CombinedImuFactor`] (plus the bias at j).
//!
//! States: a generic window of the `aggressive` scene; a window of the `spin` scene whose ΔR is
//! `π − 10⁻³` (Log and Jr⁻¹ next to their cut); a static window (ΔR ≈ I, the small-angle series);
//! factor states with `R_i` at `π − 10⁻⁴` and with a residual rotation `r_φ` at `π − 10⁻³`.
//! Next to the cut the Ridders base step is lowered to 1e-5 (its default first step, 0.32,
//! would cross it; see the [`preint_calib::numdiff`] docs). `preint::predict` has no Jacobians (it is the factor's
//! prediction; its derivative is covered through the factor).
//!
//! Data come from `sim` (noise-free, so that the windows are exactly the scenes' motions).

use nalgebra::{DMatrix, DVector, Vector3};
use preint::{
    CombinedImuFactor, ImuBias, ImuFactor, ImuNoise, ImuSample, NavState, PreintParams,
    PreintegratedImu, Scheme, preintegrate,
};
use preint_calib::{CheckOptions, NumDiffOptions, check_jacobian, to_dmatrix};
use preint_lie::{Manifold, SO3};
use preint_sim::{EulerScene, Scene, SimConfig, SpinScene, StaticScene, simulate};

const SCHEMES: [Scheme; 3] = [Scheme::Euler, Scheme::Midpoint, Scheme::Hermite4];

struct Window {
    name: &'static str,
    samples: Vec<ImuSample>,
    t_i: i64,
    t_j: i64,
    /// Ridders base step [tangent units] (1e-5 next to the Log cut).
    step: Option<f64>,
}

fn window(name: &'static str, scene: &dyn Scene, t_i: f64, t_j: f64, step: Option<f64>) -> Window {
    // The samples carry the integration bias, so that ΔR(bias_hat) is the scene's rotation.
    let cfg = SimConfig {
        initial_bias: bias_hat(),
        ..SimConfig::default()
    };
    let out = simulate(scene, 200.0, t_j + 0.5, &cfg, 0).unwrap();
    Window {
        name,
        samples: out.samples,
        t_i: (t_i * 1e9) as i64,
        t_j: (t_j * 1e9) as i64,
        step,
    }
}

fn windows() -> Vec<Window> {
    // 0.5 s at (π − 1e-3)/0.5 rad/s: ΔR = Exp((π − 1e-3)·n).
    let spin = SpinScene::new(
        SO3::exp(&Vector3::new(0.3, -0.2, 0.5)),
        Vector3::new(1.0, -0.5, 2.0),
        (std::f64::consts::PI - 1e-3) / 0.5,
        Vector3::zeros(),
    );
    vec![
        window("aggressive", &EulerScene::aggressive(), 0.5, 1.5, None),
        window("spin, ΔR at π − 1e-3", &spin, 1.0, 1.5, Some(1e-5)),
        window("static", &StaticScene::default(), 0.5, 1.5, None),
    ]
}

fn opts(step: Option<f64>) -> CheckOptions {
    CheckOptions {
        numdiff: step.map_or_else(NumDiffOptions::default, NumDiffOptions::with_ridders_step),
        ..CheckOptions::default()
    }
}

/// A bias estimate (integration bias, `bias_hat`), not zero so that nothing cancels.
fn bias_hat() -> ImuBias {
    ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.08),
    )
}

fn pim(params: &PreintParams, w: &Window, b: &ImuBias) -> PreintegratedImu {
    preintegrate(params, b, &w.samples, w.t_i, w.t_j).unwrap()
}

#[test]
fn bias_jacobians_match_reintegration_all_schemes() {
    let noise = ImuNoise::euroc();
    for w in windows() {
        for scheme in SCHEMES {
            let params = PreintParams::from_noise(&noise).with_scheme(scheme);
            let b0 = bias_hat();
            let p = pim(&params, &w, &b0);
            let angle = p.delta_r.log().norm();
            let f = |x: &(Vector3<f64>, Vector3<f64>)| {
                let q = pim(&params, &w, &ImuBias::new(x.0, x.1));
                (q.delta_r, q.delta_v, q.delta_p)
            };
            let j = &p.jac;
            let mut jg = DMatrix::zeros(9, 3);
            jg.view_mut((0, 0), (3, 3)).copy_from(&j.d_r_d_bg);
            jg.view_mut((3, 0), (3, 3)).copy_from(&j.d_v_d_bg);
            jg.view_mut((6, 0), (3, 3)).copy_from(&j.d_p_d_bg);
            let mut ja = DMatrix::zeros(9, 3);
            ja.view_mut((3, 0), (3, 3)).copy_from(&j.d_v_d_ba);
            ja.view_mut((6, 0), (3, 3)).copy_from(&j.d_p_d_ba);
            let rep = check_jacobian(f, &(b0.gyro, b0.acc), &[jg, ja], &opts(w.step))
                .unwrap_or_else(|e| panic!("{} {scheme:?}: {e}", w.name));
            println!(
                "bias Jacobians, {} (|ΔR| = {angle:.4} rad), {scheme:?}: {:.2e}",
                w.name, rep.worst_rel_error
            );
        }
    }
}

/// Factor states: x_j near the prediction, perturbed so that every residual block is non-zero,
/// or with a given residual rotation.
fn states(
    p: &PreintegratedImu,
    b: &ImuBias,
) -> Vec<(&'static str, NavState, NavState, Option<f64>)> {
    let xi = NavState::new(
        SO3::exp(&Vector3::new(0.3, -0.2, 0.6)),
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(0.5, -0.3, 0.1),
    );
    let pert = [0.02, -0.01, 0.03, 0.1, -0.05, 0.02, 0.03, 0.01, -0.02];
    let generic_j = Manifold::retract(&preint::predict(p, &xi, b), &pert);
    // R_i at angle π − 1e-4.
    let axis = Vector3::new(0.2, -0.9, 0.4).normalize();
    let xi_pi = NavState::new(
        SO3::exp(&(axis * (std::f64::consts::PI - 1e-4))),
        xi.p,
        xi.v,
    );
    let xj_pi = Manifold::retract(&preint::predict(p, &xi_pi, b), &pert);
    // Residual rotation r_φ = (π − 1e-3)·n: R_j = R_i ΔR(b) Exp(r_φ).
    let mut big = Manifold::retract(&preint::predict(p, &xi, b), &pert);
    let (dr, _, _) = p.corrected(b);
    big.r = xi.r.compose(&dr).compose(&SO3::exp(
        &(Vector3::new(1.0, 2.0, -0.5).normalize() * (std::f64::consts::PI - 1e-3)),
    ));
    vec![
        ("generic", xi, generic_j, None),
        ("R_i at π − 1e-4", xi_pi, xj_pi, None),
        ("r_φ at π − 1e-3", xi, big, Some(1e-5)),
    ]
}

#[test]
fn imu_factor_and_combined_factor_jacobians_all_blocks() {
    let noise = ImuNoise::euroc();
    for w in windows() {
        for scheme in SCHEMES {
            let params = PreintParams::from_noise(&noise).with_scheme(scheme);
            let p = pim(&params, &w, &bias_hat());
            // Bias at i off the integration bias (the first-order correction is exercised).
            let bi = ImuBias::new(
                p.bias_hat.gyro + Vector3::new(0.002, -0.001, 0.003),
                p.bias_hat.acc + Vector3::new(0.02, 0.01, -0.03),
            );
            let bj = ImuBias::new(
                bi.gyro + Vector3::new(1e-3, 0.0, -1e-3),
                bi.acc + Vector3::new(0.0, 1e-2, 0.0),
            );
            let fac = ImuFactor::new(p.clone()).unwrap();
            let comb = CombinedImuFactor::new(p.clone()).unwrap();
            for (what, xi, xj, step) in states(&p, &bi) {
                let step = step.or(w.step);
                let (_, jf) = fac.evaluate(&xi, &xj, &bi);
                let g = |x: &(NavState, NavState, Vector3<f64>, Vector3<f64>)| {
                    DVector::from_column_slice(
                        fac.residual(&x.0, &x.1, &ImuBias::new(x.2, x.3)).as_slice(),
                    )
                };
                let blocks = [
                    to_dmatrix(&jf.state_i()),
                    to_dmatrix(&jf.state_j()),
                    to_dmatrix(&jf.bg_i),
                    to_dmatrix(&jf.ba_i),
                ];
                let rep = check_jacobian(g, &(xi, xj, bi.gyro, bi.acc), &blocks, &opts(step))
                    .unwrap_or_else(|e| panic!("ImuFactor {} {scheme:?} {what}: {e}", w.name));
                let (_, jc) = comb.evaluate(&xi, &xj, &bi, &bj);
                let bv = |b: &ImuBias| {
                    DVector::from_iterator(6, b.gyro.iter().chain(b.acc.iter()).copied())
                };
                let h = |x: &(NavState, NavState, DVector<f64>, DVector<f64>)| {
                    let b = |v: &DVector<f64>| {
                        ImuBias::new(
                            Vector3::new(v[0], v[1], v[2]),
                            Vector3::new(v[3], v[4], v[5]),
                        )
                    };
                    DVector::from_column_slice(
                        comb.residual(&x.0, &x.1, &b(&x.2), &b(&x.3)).as_slice(),
                    )
                };
                let blocks = [
                    to_dmatrix(&jc.state_i()),
                    to_dmatrix(&jc.state_j()),
                    to_dmatrix(&jc.bias_i()),
                    to_dmatrix(&jc.bias_j()),
                ];
                let rep_c = check_jacobian(h, &(xi, xj, bv(&bi), bv(&bj)), &blocks, &opts(step))
                    .unwrap_or_else(|e| {
                        panic!("CombinedImuFactor {} {scheme:?} {what}: {e}", w.name)
                    });
                println!(
                    "factor, {} {scheme:?} {what}: ImuFactor {:.2e}, CombinedImuFactor {:.2e}",
                    w.name, rep.worst_rel_error, rep_c.worst_rel_error
                );
            }
        }
    }
}

/// The checker is not vacuous here: a sign error in one block of the factor's Jacobian
/// (∂r_v/∂δφ_i flipped) is caught and located.
#[test]
fn checker_catches_a_flipped_factor_block() {
    let w = &windows()[0];
    let params = PreintParams::from_noise(&ImuNoise::euroc());
    let p = pim(&params, w, &bias_hat());
    let fac = ImuFactor::new(p.clone()).unwrap();
    let b = p.bias_hat;
    let (_, xi, xj, _) = states(&p, &b)[0];
    let (_, jf) = fac.evaluate(&xi, &xj, &b);
    let mut si = to_dmatrix(&jf.state_i());
    let flipped = -si.view((3, 0), (3, 3)).into_owned();
    si.view_mut((3, 0), (3, 3)).copy_from(&flipped);
    let g = |x: &(NavState, NavState)| {
        DVector::from_column_slice(fac.residual(&x.0, &x.1, &b).as_slice())
    };
    let err = check_jacobian(
        g,
        &(xi, xj),
        &[si, to_dmatrix(&jf.state_j())],
        &CheckOptions::default(),
    )
    .unwrap_err();
    match err {
        preint_calib::CheckError::Mismatch { report, .. } => {
            assert_eq!(report.block, 0);
            assert!((3..6).contains(&report.row) && report.col < 3, "{report}");
        }
        e => panic!("{e}"),
    }
}
