//! The combined (15-dim) covariance and `CombinedImuFactor` against GTSAM 4.3.
//!
//! Fixtures `tests/fixtures/gtsam/combined_*.gtsam.json`, made by `generate_combined.py` there
//! with GTSAM 4.3.0's `PreintegratedCombinedMeasurementsManifold` (the Euler scheme), EuRoC
//! densities with bias random walk, on three inputs of that folder (200 Hz, 2 s, 50° of
//! rotation; 1 kHz with a bias estimate; 10 rad/s spin).
//!
//! Mapping. GTSAM orders the tangent [rot, pos, vel] and the bias [acc, gyro], and expresses the
//! pos and vel errors of the delta in its `NavState` chart (rotated by `ΔRᵀ` with respect to
//! ours, frame i). With `P` our [δφ, δv, δp, δb_g, δb_a] → GTSAM's order and
//! `T = diag(I, ΔRᵀ, ΔRᵀ, I, I)`:
//!
//! - `preintMeasCov() = T P cov15 Pᵀ Tᵀ` — the error state's covariance (measured ⊖ true,
//!   `b_j − b_i`);
//! - `residualCovariance() = T P residual_cov15 Pᵀ Tᵀ` — the covariance of the combined
//!   factor's residual, whose delta–bias blocks have the opposite sign;
//! - at states with `R_j = R_i ΔR` (so that GTSAM's frame change of the residual is `T` itself)
//!   GTSAM's χ² equals ours.
//!
//! Each of the three is asserted; the χ² test also checks that weighting with `cov15` itself
//! would miss GTSAM's χ² (so the test tells the two signs apart).

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use preint::ResidualMode;
use preint::{
    CombinedImuFactor, ImuBias, ImuNoise, Level, NavState, PreintParams, PreintegratedImu, Scheme,
    preintegrate, sqrt_information,
};
use preint_io::read_euroc_imu;
use preint_lie::SO3;
use serde_json::Value;
use std::path::PathBuf;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/gtsam")
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn vec3(v: &Value) -> Vector3<f64> {
    let a = v.as_array().expect("array");
    Vector3::new(num(&a[0]), num(&a[1]), num(&a[2]))
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows = v.as_array().expect("rows");
    let n = rows.len();
    let m = rows[0].as_array().unwrap().len();
    DMatrix::from_fn(n, m, |r, c| num(&rows[r].as_array().unwrap()[c]))
}

fn state(s: &Value) -> NavState {
    let r = mat(&s["R"]);
    NavState::new(
        SO3::from_matrix(&Matrix3::from_fn(|i, j| r[(i, j)])),
        vec3(&s["p"]),
        vec3(&s["v"]),
    )
}

fn bias(b: &Value) -> ImuBias {
    ImuBias::new(vec3(&b["bg"]), vec3(&b["ba"]))
}

struct Case {
    name: String,
    out: Value,
    pim: PreintegratedImu,
}

fn cases() -> Vec<Case> {
    let mut names: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("combined_") && n.ends_with(".gtsam.json"))
        .filter(|n| !n.starts_with("combined_modes_"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 3, "combined fixtures: {names:?}");
    names
        .into_iter()
        .map(|n| {
            let out: Value =
                serde_json::from_str(&std::fs::read_to_string(dir().join(&n)).unwrap()).unwrap();
            let p = &out["params"];
            let noise = ImuNoise {
                gyro_noise_density: num(&p["gyro_noise_density"]),
                gyro_random_walk: num(&p["gyro_random_walk"]),
                acc_noise_density: num(&p["accel_noise_density"]),
                acc_random_walk: num(&p["accel_random_walk"]),
                update_rate_hz: 200.0,
            };
            let samples = read_euroc_imu(&dir().join(out["csv"].as_str().unwrap())).unwrap();
            let params = PreintParams::from_noise(&noise)
                .with_scheme(Scheme::Euler)
                .with_level(Level::Combined)
                .with_gravity(Vector3::new(0.0, 0.0, -num(&p["gravity"])));
            let b = ImuBias::new(vec3(&p["bg"]), vec3(&p["ba"]));
            let (t0, t1) = (samples[0].t_ns, samples[samples.len() - 1].t_ns);
            let pim = preintegrate(&params, &b, &samples, t0, t1).unwrap();
            Case { name: n, out, pim }
        })
        .collect()
}

/// Our [δφ, δv, δp, δb_g, δb_a] index of GTSAM's [rot, pos, vel, b_a, b_g] index.
const PERM: [usize; 15] = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11];

/// `T P c Pᵀ Tᵀ` (module docs).
fn to_gtsam(c: &SMatrix<f64, 15, 15>, delta_r: &SO3) -> DMatrix<f64> {
    let p = DMatrix::from_fn(15, 15, |r, k| c[(PERM[r], PERM[k])]);
    let mut t = DMatrix::<f64>::identity(15, 15);
    let rt = delta_r.matrix().transpose();
    for o in [3, 6] {
        t.view_mut((o, o), (3, 3)).copy_from(&rt);
    }
    &t * p * t.transpose()
}

/// Largest `|a − b| / √(b_ii b_jj)` (entries relative to their correlation scale).
fn worst_rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    let mut w = 0.0f64;
    for r in 0..15 {
        for c in 0..15 {
            let s = (b[(r, r)] * b[(c, c)]).sqrt();
            w = w.max((a[(r, c)] - b[(r, c)]).abs() / s);
        }
    }
    w
}

#[test]
fn cov15_is_gtsams_preint_meas_cov() {
    for c in cases() {
        assert!(
            (c.pim.delta_r.matrix() - Matrix3::from_fn(|i, j| mat(&c.out["delta_R"])[(i, j)]))
                .amax()
                < 1e-12,
            "{}: ΔR",
            c.name
        );
        let theirs = mat(&c.out["preint_meas_cov"]);
        let w = worst_rel(&to_gtsam(&c.pim.cov15, &c.pim.delta_r), &theirs);
        println!("{}: cov15 vs preintMeasCov, worst {w:.2e}", c.name);
        assert!(w < 1e-12, "{}: {w:e}", c.name);
        // The delta–bias blocks are not negligible, so the sign is tested.
        let cross = worst_rel(
            &theirs,
            &DMatrix::from_fn(15, 15, |r, k| {
                if (r < 9) != (k < 9) {
                    0.0
                } else {
                    theirs[(r, k)]
                }
            }),
        );
        assert!(cross > 0.05, "{}: cross correlation {cross}", c.name);
    }
}

#[test]
fn residual_cov15_is_gtsams_residual_covariance() {
    for c in cases() {
        let theirs = mat(&c.out["residual_covariance"]);
        let w = worst_rel(&to_gtsam(&c.pim.residual_cov15(), &c.pim.delta_r), &theirs);
        println!(
            "{}: residual_cov15 vs residualCovariance, worst {w:.2e}",
            c.name
        );
        assert!(w < 1e-12, "{}: {w:e}", c.name);
    }
}

#[test]
fn combined_factor_chi2_and_residual_are_gtsams() {
    for c in cases() {
        let f = &c.out["factor"];
        let (xi, xj) = (state(&f["state_i"]), state(&f["state_j"]));
        let (bi, bj) = (bias(&f["bias_i"]), bias(&f["bias_j"]));
        let fac = CombinedImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let r = fac.residual(&xi, &xj, &bi, &bj);
        // e = [−r_φ, −M r_p, −M r_v, −r_ba, −r_bg], M = R_jᵀ R_i.
        let m = xj.r.inverse().compose(&xi.r);
        let seg = |o: usize| Vector3::new(r[o], r[o + 1], r[o + 2]);
        let mapped: Vec<f64> = [-seg(0), -m.act(&seg(6)), -m.act(&seg(3)), -seg(12), -seg(9)]
            .iter()
            .flat_map(|v| v.iter().copied().collect::<Vec<_>>())
            .collect();
        let e: Vec<f64> = f["residual"].as_array().unwrap().iter().map(num).collect();
        for k in 0..15 {
            assert!(
                (mapped[k] - e[k]).abs() <= 1e-9 * (1.0 + e[k].abs()),
                "{}: e[{k}] ours {:e} gtsam {:e}",
                c.name,
                mapped[k],
                e[k]
            );
        }
        let chi2_g = num(&f["chi2"]);
        let ours = fac.chi2(&xi, &xj, &bi, &bj);
        let with_cov15 = (sqrt_information(&c.pim.cov15).unwrap() * r).norm_squared();
        println!(
            "{}: χ² ours {ours:.9e}, GTSAM {chi2_g:.9e}; weighted with cov15 {with_cov15:.6e}",
            c.name
        );
        assert!(
            (ours - chi2_g).abs() <= 1e-8 * chi2_g,
            "{}: {ours} vs {chi2_g}",
            c.name
        );
        assert!(
            (with_cov15 - chi2_g).abs() > 1e-2 * chi2_g,
            "{}: the fixture does not tell the two signs apart",
            c.name
        );
    }
}
