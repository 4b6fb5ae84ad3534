//! Earth rotation against GTSAM 4.3 (`omegaCoriolis`): prediction, `ImuFactor` and
//! `CombinedImuFactor` residuals and the residual covariance (GTSAM PR #2806's whitening).
//!
//! Fixtures `tests/fixtures/gtsam/earth_*.gtsam.json` (`generate_earth.py` there). The
//! [`PreintegratedImu`] is built from each fixture's ΔR, Δv, Δp and Forster-chart covariance
//! (reordered [φ, p, v] → [φ, v, p]) with `CoriolisMode::Exact`, so only prediction and the
//! factor are under test. GTSAM's ComponentWise error `e = [Log(R_jᵀR̂_j), R_jᵀ(p̂_j − p_j),
//! R_jᵀ(v̂_j − v_j)]` follows from our residual exactly (`preint::ImuFactor` docs, rotating frame),
//! with `A = Exp(−ωT)`, `M = R_jᵀ A R_i`, `N = R_jᵀ[ω]× A R_i`:
//!
//! ```text
//! e_rot = −r_φ,   e_pos = −M r_p,   e_vel = −M r_v + N r_p
//! ```
//!
//! The `N` block is the δp → δv term GTSAM PR #2806 adds to the whitening; the covariance of
//! `e` is `L cov Lᵀ` with `L` that linear map. For the combined factor, `L` is extended by
//! `−I` from our bias rows `[b_g,j − b_g,i, b_a,j − b_a,i]` to GTSAM's `[b_a,i − b_a,j,
//! b_g,i − b_g,j]`, and `cov15` is GTSAM's combined `preintMeasCov()` in our chart (tangent
//! backend: `φ = Jr(θ) dθ`, reordered).
//!
//! Logmap error mode (`earth_logmap_*.gtsam.json`, `generate_earth_logmap.py`): GTSAM's error is
//! `[w, Jl(w)⁻¹ e_pos, Jl(w)⁻¹ e_vel]` of its component-wise one, `w = −r_φ`; since
//! `M = Exp(−r_φ) ΔRᵀ`, this is exactly our [`ResidualMode::Logmap`] residual `r_L` mapped as
//! `e = −P r_L + [0, 0, Jl(w)⁻¹ N r_p]` (`P`: [φ, v, p] → [rot, pos, vel], `r_p` the
//! component-wise position row): the same `N` term as in the component-wise mode.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};
use preint::ResidualMode;
use preint::edges::EdgeNoise;
use preint::{
    BiasJacobians, CombinedImuFactor, CoriolisMode, Cov9, Cov15, ImuBias, ImuFactor, Level,
    NavState, PreintegratedImu, predict,
};
use preint_lie::{SO3, hat, jl_inv, jr};
use serde_json::Value;
use std::path::PathBuf;

fn fixture(name: &str) -> Value {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures/gtsam")
        .join(format!("earth_{name}.gtsam.json"));
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

fn v3(v: &Value) -> Vector3<f64> {
    Vector3::from_fn(|i, _| v[i].as_f64().unwrap())
}

fn mat<const N: usize>(v: &Value) -> SMatrix<f64, N, N> {
    SMatrix::<f64, N, N>::from_fn(|r, c| v[r][c].as_f64().unwrap())
}

fn state(v: &Value) -> NavState {
    NavState::new(
        SO3::from_matrix(&mat::<3>(&v["R"])),
        v3(&v["p"]),
        v3(&v["v"]),
    )
}

struct Case {
    pim: PreintegratedImu,
    omega: Vector3<f64>,
    xi: NavState,
    xj: NavState,
    f: Value,
}

fn case(name: &str) -> Case {
    let f = fixture(name);
    let perm = [0, 1, 2, 6, 7, 8, 3, 4, 5];
    let c = mat::<9>(&f["covariance"]);
    let omega = v3(&f["omega_coriolis"]);
    let delta_t = f["delta_t"].as_f64().unwrap();
    let mut cov15 = Cov15::identity() * 1e-6;
    cov15
        .fixed_view_mut::<9, 9>(0, 0)
        .copy_from(&Cov9::from_fn(|r, col| c[(perm[r], perm[col])]));
    let pim = PreintegratedImu {
        t_i_ns: 0,
        t_j_ns: (delta_t * 1e9).round() as i64,
        delta_t,
        delta_r: SO3::from_matrix(&mat::<3>(&f["delta_R"])),
        delta_v: v3(&f["delta_v"]),
        delta_p: v3(&f["delta_p"]),
        cov: Cov9::from_fn(|r, col| c[(perm[r], perm[col])]),
        cov15,
        jac: BiasJacobians::default(),
        jac_td: Default::default(),
        bias_hat: ImuBias::new(v3(&f["bias_hat"]["bg"]), v3(&f["bias_hat"]["ba"])),
        gravity: v3(&f["n_gravity"]),
        omega_coriolis: Some(omega),
        coriolis: CoriolisMode::Exact,
        level: Level::Combined,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    };
    Case {
        pim,
        omega,
        xi: state(&f["state_i"]),
        xj: state(&f["factor"]["state_j"]),
        f,
    }
}

/// `L` of the module docs (GTSAM order [rot, pos, vel] ← ours [φ, v, p]) at states (i, j).
fn to_gtsam(c: &Case, rj: &SO3) -> SMatrix<f64, 9, 9> {
    let a = SO3::exp(&(-c.omega * c.pim.delta_t));
    let ar = a.matrix() * c.xi.r.matrix();
    let m = rj.matrix().transpose() * ar;
    let n = rj.matrix().transpose() * hat(&c.omega) * ar;
    let mut l = SMatrix::<f64, 9, 9>::zeros();
    l.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-Matrix3::identity()));
    l.fixed_view_mut::<3, 3>(3, 6).copy_from(&(-m));
    l.fixed_view_mut::<3, 3>(6, 3).copy_from(&(-m));
    l.fixed_view_mut::<3, 3>(6, 6).copy_from(&n);
    l
}

/// Error of a [rot, pos, vel] residual relative to the size of what it is formed from: the
/// rotation block in rad, the position block over |p_j| [m], the velocity block over |v_j|
/// [m/s] (the residual is a difference of those; its own size, a few σ, is far below).
fn rel_to_state(e: &SVector<f64, 9>, g: &SVector<f64, 9>, xj: &NavState) -> f64 {
    let d = e - g;
    let b = |k: usize| d.fixed_rows::<3>(k).amax();
    b(0).max(b(3) / xj.p.amax().max(1.0))
        .max(b(6) / xj.v.amax().max(1.0))
}

fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

fn dm<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_column_slice(R, C, m.as_slice())
}

const CASES: [&str; 3] = ["lat48", "fast", "near"];

#[test]
fn exact_prediction_matches_gtsam() {
    for name in CASES {
        let c = case(name);
        let x = predict(&c.pim, &c.xi, &c.pim.bias_hat);
        let g = state(&c.f["predict"]);
        let e_r = x.r.minus(&g.r).norm();
        let e_p = (x.p - g.p).amax() / g.p.amax();
        let e_v = (x.v - g.v).amax() / g.v.amax();
        println!(
            "{name}: prediction vs GTSAM: rotation {e_r:.1e} rad, p {e_p:.1e}, v {e_v:.1e} (relative)"
        );
        assert!(
            e_r < 1e-14 && e_p < 1e-12 && e_v < 1e-12,
            "{name}: {e_r} {e_p} {e_v}"
        );
    }
}

#[test]
fn imu_factor_residual_matches_gtsam() {
    for name in CASES {
        let c = case(name);
        let r = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise)
            .unwrap()
            .residual(&c.xi, &c.xj, &c.pim.bias_hat);
        let e = to_gtsam(&c, &c.xj.r) * r;
        let g = SVector::<f64, 9>::from_fn(|i, _| c.f["factor"]["error"][i].as_f64().unwrap());
        let err = rel(&dm(&e), &dm(&g));
        let err_state = rel_to_state(&e, &g, &c.xj);
        println!(
            "{name}: ImuFactor error vs GTSAM: {err_state:.1e} relative to the states, \
             {err:.1e} relative to the residual (|e| = {:.1e})",
            g.amax()
        );
        assert!(err_state < 1e-14 && err < 1e-9, "{name}: {err}\n{e}\n{g}");
        // Near the origin the residual is not a small difference of large positions.
        assert!(name != "near" || err < 1e-12, "{name}: {err}");
    }
}

#[test]
fn combined_factor_residual_matches_gtsam() {
    for name in CASES {
        let c = case(name);
        let b = c.pim.bias_hat;
        let r = CombinedImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise)
            .unwrap()
            .residual(&c.xi, &c.xj, &b, &b);
        let e = to_gtsam(&c, &c.xj.r) * r.fixed_rows::<9>(0);
        let g = SVector::<f64, 15>::from_fn(|i, _| c.f["combined"]["error"][i].as_f64().unwrap());
        let g9 = g.fixed_rows::<9>(0).into_owned();
        let err = rel(&dm(&e), &dm(&g9));
        let err_state = rel_to_state(&e, &g9, &c.xj);
        println!(
            "{name}: CombinedImuFactor error vs GTSAM: {err_state:.1e} relative to the states, \
             {err:.1e} relative to the residual"
        );
        assert!(err_state < 1e-14 && err < 1e-9, "{name}: {err}");
        assert!(name != "near" || err < 1e-12, "{name}: {err}");
        assert!(g.fixed_rows::<6>(9).amax() == 0.0 && r.fixed_rows::<6>(9).amax() == 0.0);
    }
}

#[test]
fn residual_covariance_in_gtsam_chart_matches_residual_covariance_at_the_prediction() {
    for name in CASES {
        let c = case(name);
        let pred = predict(&c.pim, &c.xi, &c.pim.bias_hat);
        let l = to_gtsam(&c, &pred.r);
        let ours = l * c.pim.cov * l.transpose();
        let at = mat::<9>(&c.f["factor"]["residual_covariance_at_predicted"]);
        let plain = mat::<9>(&c.f["factor"]["residual_covariance"]);
        let err_at = rel(&dm(&ours), &dm(&at));
        let err_plain = rel(&dm(&ours), &dm(&plain));
        // Without the N block (no PR #2806 term), for scale.
        let mut l0 = l;
        l0.fixed_view_mut::<3, 3>(6, 6).fill(0.0);
        let without = l0 * c.pim.cov * l0.transpose();
        let err_without = rel(&dm(&without), &dm(&at));
        println!(
            "{name}: L cov Lᵀ vs residualCovarianceAt(R̂_j) {err_at:.1e}, vs residualCovariance() \
             {err_plain:.1e}; without the δp→δv block {err_without:.1e}"
        );
        assert!(err_at < 1e-9, "{name}: {err_at}");
    }
}

#[test]
fn combined_residual_covariance_in_gtsam_chart_matches_residual_covariance_at_the_prediction() {
    for name in CASES {
        let mut c = case(name);
        let cf = &c.f["combined"];
        // GTSAM's native [θ, p, v, b_a, b_g] → ours [φ, v, p, b_g, b_a], φ = Jr(θ) dθ.
        let native = mat::<15>(&cf["preint_meas_cov"]);
        let mut t = SMatrix::<f64, 15, 15>::identity();
        t.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&jr(&v3(&cf["delta_R_log"])));
        let forster = t * native * t.transpose();
        let perm = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11];
        c.pim.cov15 = Cov15::from_fn(|r, col| forster[(perm[r], perm[col])]);
        let pred = predict(&c.pim, &c.xi, &c.pim.bias_hat);
        let mut l = SMatrix::<f64, 15, 15>::zeros();
        l.fixed_view_mut::<9, 9>(0, 0)
            .copy_from(&to_gtsam(&c, &pred.r));
        l.fixed_view_mut::<3, 3>(9, 12)
            .copy_from(&(-Matrix3::identity()));
        l.fixed_view_mut::<3, 3>(12, 9)
            .copy_from(&(-Matrix3::identity()));
        let ours = l * c.pim.residual_cov15() * l.transpose();
        let at = mat::<15>(&cf["residual_covariance_at_predicted"]);
        let err = rel(&dm(&ours), &dm(&at));
        println!("{name}: combined L cov15 Lᵀ vs residualCovarianceAt(R̂_j): {err:.1e}");
        assert!(err < 1e-9, "{name}: {err}");
        // Our χ² (residual whitened by residual_cov15) against GTSAM's (its error whitened by
        // residualCovarianceAt(R̂_j)): equal to first order. They differ by the chart change
        // `L`, which GTSAM freezes at R̂_j while R_j is a few σ (~1e-4 rad) away from it.
        let b = c.pim.bias_hat;
        let f = CombinedImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let chi2_ours = f.chi2(&c.xi, &c.xj, &b, &b);
        let e = SVector::<f64, 15>::from_fn(|i, _| cf["error"][i].as_f64().unwrap());
        let chi2_gtsam = e.dot(&at.cholesky().unwrap().solve(&e));
        println!("{name}: combined χ² {chi2_ours:.9} vs GTSAM {chi2_gtsam:.9}");
        assert!((chi2_ours - chi2_gtsam).abs() < 1e-3 * chi2_gtsam);
    }
}

/// GTSAM's Logmap-mode error from our Logmap residual `r_l` and component-wise position row
/// `r_p` (module docs).
fn logmap_to_gtsam(c: &Case, r_l: &SVector<f64, 9>, r_p: &Vector3<f64>) -> SVector<f64, 9> {
    let a = SO3::exp(&(-c.omega * c.pim.delta_t));
    let n = c.xj.r.matrix().transpose() * hat(&c.omega) * a.matrix() * c.xi.r.matrix();
    let w: Vector3<f64> = -r_l.fixed_rows::<3>(0);
    let mut e = SVector::<f64, 9>::zeros();
    e.fixed_rows_mut::<3>(0).copy_from(&w);
    e.fixed_rows_mut::<3>(3)
        .copy_from(&(-r_l.fixed_rows::<3>(6)));
    e.fixed_rows_mut::<3>(6)
        .copy_from(&(-r_l.fixed_rows::<3>(3) + jl_inv(&w) * n * r_p));
    e
}

#[test]
fn logmap_residual_matches_gtsam_logmap_with_earth_rate() {
    for name in CASES {
        let c = case(name);
        let g = fixture(&format!("logmap_{name}"));
        let b = c.pim.bias_hat;
        let r_cw = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise)
            .unwrap()
            .residual(&c.xi, &c.xj, &b);
        let r_p = r_cw.fixed_rows::<3>(6).into_owned();
        let r_l = ImuFactor::with_mode(c.pim.clone(), ResidualMode::Logmap)
            .unwrap()
            .residual(&c.xi, &c.xj, &b);
        let rc_l = CombinedImuFactor::with_mode(c.pim.clone(), ResidualMode::Logmap)
            .unwrap()
            .residual(&c.xi, &c.xj, &b, &b);
        assert_eq!(rc_l.fixed_rows::<9>(0), r_l, "{name}: combined rows 0..9");
        let e = logmap_to_gtsam(&c, &r_l, &r_p);
        for (key, len) in [("error", 9), ("combined_error", 15)] {
            let gv = SVector::<f64, 9>::from_fn(|i, _| g[key][i].as_f64().unwrap());
            assert_eq!(g[key].as_array().unwrap().len(), len);
            let err = rel(&dm(&e), &dm(&gv));
            let err_state = rel_to_state(&e, &gv, &c.xj);
            println!(
                "{name}: {key} (Logmap) vs GTSAM: {err_state:.1e} relative to the states, \
                 {err:.1e} relative to the residual"
            );
            assert!(
                err_state < 1e-14 && err < 1e-9,
                "{name} {key}: {err}\n{e}\n{gv}"
            );
            assert!(name != "near" || err < 1e-12, "{name}: {err}");
        }
    }
}
