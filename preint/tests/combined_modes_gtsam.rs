//! `CombinedImuFactor` in both residual modes against GTSAM 4.3's `CombinedImuFactor` in both
//! `ImuFactorErrorMode`s: residual, every Jacobian block and (Logmap) χ², ≤ 1e-9 relative.
//!
//! Fixtures `tests/fixtures/gtsam/combined_modes_*.gtsam.json` (`generate_combined_modes.py`
//! there): GTSAM's manifold preintegration of `example.csv` and `fastspin.csv`, states off the
//! prediction (0.03 rad, 5 cm, 5 cm/s), a bias at i off the estimate and a bias at j off the
//! bias at i. Our factor reads GTSAM's own deltas, bias Jacobians and covariance, so only the
//! factor is under test.
//!
//! Mapping, with `Q` the row permutation our [φ, v, p, b_g, b_a] → GTSAM's [rot, pos, vel, b_a,
//! b_g] and `M = R_jᵀR_i`:
//!
//! - Logmap: `e = −Q r_L` and `∂e/∂x = −Q ∂r_L/∂x` exactly (`preint::ResidualMode` docs);
//!   GTSAM weights with `residualCovariance() = T Q residual_cov15 Qᵀ Tᵀ`, `T = diag(I, ΔRᵀ,
//!   ΔRᵀ, I, I)`, which is our Logmap weight reordered, so the χ² are equal.
//! - ComponentWise: rows `[−r_φ, −M r_p, −M r_v, −r_ba, −r_bg]`, the Jacobians likewise plus
//!   `M[r_{p,v}]×` in the `δφ_i` columns and `−[M r_{p,v}]×` in the `δφ_j` columns
//!   (`preint::ImuFactor` docs).
//!
//! Columns: GTSAM's pose `[dw, dt]` = our [δφ, δp] to first order, world velocity = δv, bias
//! columns [acc, gyro].

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use preint::edges::EdgeNoise;
use preint::{
    BiasJacobians, CombinedImuFactor, CombinedImuFactorJacobians, Cov9, Cov15, ImuBias, Level,
    NavState, PreintegratedImu, ResidualMode,
};
use preint_lie::{SO3, hat};
use serde_json::Value;
mod common;
use common::gtsam_fixture::{json, m3, mat, v3};

/// Our index of GTSAM's index g (both 15-dim).
const PERM: [usize; 15] = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11];
const CASES: [&str; 2] = ["example", "fastspin"];

fn state(s: &Value) -> NavState {
    NavState::new(SO3::from_matrix(&m3(&s["R"])), v3(&s["p"]), v3(&s["v"]))
}

fn bias(b: &Value) -> ImuBias {
    ImuBias::new(v3(&b["bg"]), v3(&b["ba"]))
}

/// The measurement from GTSAM's deltas, bias Jacobians and `preintMeasCov` (mapped back:
/// `cov15 = Qᵀ T⁻¹ preintMeasCov T⁻ᵀ Q`).
fn pim(out: &Value) -> PreintegratedImu {
    let dr = SO3::from_matrix(&m3(&out["delta_R"]));
    let g = mat(&out["preint_meas_cov"]);
    let mut t = DMatrix::<f64>::identity(15, 15);
    for o in [3, 6] {
        t.view_mut((o, o), (3, 3)).copy_from(dr.matrix());
    }
    let gt = &t * g * t.transpose(); // T⁻¹ = diag(I, ΔR, ΔR, I, I)
    let mut cov15 = Cov15::zeros();
    for r in 0..15 {
        for c in 0..15 {
            cov15[(PERM[r], PERM[c])] = gt[(r, c)];
        }
    }
    let bj = &out["bias_jacobians"];
    let p = &out["params"];
    let delta_t = out["delta_t"].as_f64().unwrap();
    PreintegratedImu {
        t_i_ns: 0,
        t_j_ns: (delta_t * 1e9).round() as i64,
        delta_t,
        delta_r: dr,
        delta_v: v3(&out["delta_v"]),
        delta_p: v3(&out["delta_p"]),
        cov: Cov9::from_fn(|r, c| cov15[(r, c)]),
        cov15,
        jac: BiasJacobians {
            d_r_d_bg: m3(&bj["dR_dbg"]),
            d_v_d_bg: m3(&bj["dv_dbg"]),
            d_v_d_ba: m3(&bj["dv_dba"]),
            d_p_d_bg: m3(&bj["dp_dbg"]),
            d_p_d_ba: m3(&bj["dp_dba"]),
        },
        jac_td: Default::default(),
        bias_hat: ImuBias::new(v3(&p["bg"]), v3(&p["ba"])),
        gravity: Vector3::new(0.0, 0.0, -p["gravity"].as_f64().unwrap()),
        omega_coriolis: None,
        coriolis: preint::CoriolisMode::Exact,
        level: Level::Combined,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    }
}

type Blk = SMatrix<f64, 15, 3>;

/// Our block in GTSAM's rows: `−Q b`, plus for ComponentWise the `M` rotation of the pos and
/// vel rows (the `δφ` corrections are added by the caller).
fn rows(b: &Blk, m: Option<&Matrix3<f64>>) -> Blk {
    let mut o = Blk::from_fn(|g, c| -b[(PERM[g], c)]);
    if let Some(m) = m {
        for g in [3, 6] {
            let v: Matrix3<f64> = o.fixed_view::<3, 3>(g, 0).into();
            o.fixed_view_mut::<3, 3>(g, 0).copy_from(&(m * v));
        }
    }
    o
}

fn blocks(
    j: &CombinedImuFactorJacobians,
    r: &SMatrix<f64, 15, 1>,
    cw: Option<&Matrix3<f64>>,
) -> [(&'static str, Blk, &'static str, usize); 10] {
    let mut phi_i = rows(&j.phi_i, cw);
    let mut phi_j = rows(&j.phi_j, cw);
    if let Some(m) = cw {
        // GTSAM rows pos (3) and vel (6) ↔ our r_p (6) and r_v (3).
        for (g, o) in [(3, 6), (6, 3)] {
            let ro = Vector3::new(r[o], r[o + 1], r[o + 2]);
            let mut a = phi_i.fixed_view_mut::<3, 3>(g, 0);
            a += m * hat(&ro);
            let mut b = phi_j.fixed_view_mut::<3, 3>(g, 0);
            b -= hat(&(m * ro));
        }
    }
    [
        ("phi_i", phi_i, "H_pose_i", 0),
        ("p_i", rows(&j.p_i, cw), "H_pose_i", 3),
        ("v_i", rows(&j.v_i, cw), "H_vel_i", 0),
        ("phi_j", phi_j, "H_pose_j", 0),
        ("p_j", rows(&j.p_j, cw), "H_pose_j", 3),
        ("v_j", rows(&j.v_j, cw), "H_vel_j", 0),
        ("ba_i", rows(&j.ba_i, cw), "H_bias_i", 0),
        ("bg_i", rows(&j.bg_i, cw), "H_bias_i", 3),
        ("ba_j", rows(&j.ba_j, cw), "H_bias_j", 0),
        ("bg_j", rows(&j.bg_j, cw), "H_bias_j", 3),
    ]
}

#[test]
fn combined_factor_matches_gtsam_in_both_error_modes() {
    for name in CASES {
        let out = json(&format!("combined_modes_{name}.gtsam.json"));
        let pim = pim(&out);
        let f = &out["factor"];
        let (xi, xj) = (state(&f["state_i"]), state(&f["state_j"]));
        let (bi, bj) = (bias(&f["bias_i"]), bias(&f["bias_j"]));
        let m = *xj.r.inverse().compose(&xi.r).matrix();
        for (mode, key) in [
            (ResidualMode::ComponentWise, "ComponentWise"),
            (ResidualMode::Logmap, "Logmap"),
        ] {
            let g = &f["modes"][key];
            let fac = CombinedImuFactor::with_mode(pim.clone(), mode).unwrap();
            let (r, j) = fac.evaluate(&xi, &xj, &bi, &bj);
            let cw = (mode == ResidualMode::ComponentWise).then_some(&m);
            let e: Vec<f64> = g["residual"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let mut worst = 0.0f64;
            let mapped = rows(&Blk::from_fn(|k, c| if c == 0 { r[k] } else { 0.0 }), cw);
            for k in 0..15 {
                let d = (mapped[(k, 0)] - e[k]).abs() / (1.0 + e[k].abs());
                assert!(
                    d < 1e-9,
                    "{name} {key}: e[{k}] {} vs {}",
                    mapped[(k, 0)],
                    e[k]
                );
                worst = worst.max(d);
            }
            let mut worst_j = 0.0f64;
            for (blk, ours, hkey, col) in blocks(&j, &r, cw) {
                let h = mat(&g[hkey]);
                let theirs = Blk::from_fn(|k, c| h[(k, col + c)]);
                let d = (ours - theirs).amax() / (1.0 + theirs.amax());
                assert!(d < 1e-9, "{name} {key} {blk}: ours {ours} gtsam {theirs}");
                worst_j = worst_j.max(d);
            }
            let chi2_g = g["chi2"].as_f64().unwrap();
            let chi2 = if mode == ResidualMode::Logmap {
                fac.chi2(&xi, &xj, &bi, &bj)
            } else {
                // GTSAM's chart: pos and vel rows rotated by ΔR M (its covariance's frame).
                let t = pim.delta_r.matrix() * m;
                let mut r2 = r;
                for o in [3, 6] {
                    let v = t * Vector3::new(r[o], r[o + 1], r[o + 2]);
                    r2.fixed_rows_mut::<3>(o).copy_from(&v);
                }
                (fac.sqrt_information() * r2).norm_squared()
            };
            assert!(
                (chi2 - chi2_g).abs() <= 1e-8 * chi2_g,
                "{name} {key}: χ² {chi2} vs {chi2_g}"
            );
            println!(
                "{name} {key}: residual worst {worst:.1e}, Jacobians worst {worst_j:.1e}, χ² {chi2:.9e} vs {chi2_g:.9e}"
            );
            assert!(r.fixed_rows::<3>(0).norm() > 0.01, "a rotation residual");
        }
    }
}
