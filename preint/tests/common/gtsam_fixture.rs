//! Reading the GTSAM fixtures of `tests/fixtures/gtsam/` (JSON written by the generators
//! there): the folder, a file, matrices and vectors stored as nested arrays, and the parameters
//! of a `NAME.params.json`.

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use preint::{ImuBias, Level, PreintParams, Scheme};
use serde_json::Value;
use std::path::PathBuf;

/// `tests/fixtures/gtsam/`.
pub fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/gtsam")
}

/// The JSON file `name` of the fixture folder.
pub fn json(name: &str) -> Value {
    let path = dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// A matrix stored as an array of rows.
pub fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

/// A 3×3 matrix stored as an array of rows.
pub fn m3(v: &Value) -> Matrix3<f64> {
    let m = mat(v);
    Matrix3::from_fn(|i, j| m[(i, j)])
}

/// A 3-vector stored as an array.
pub fn v3(v: &Value) -> Vector3<f64> {
    let a: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    Vector3::new(a[0], a[1], a[2])
}

/// Scalar `s` → `s I`, else the 3×3 matrix.
pub fn cov3(v: &Value) -> Matrix3<f64> {
    match v.as_f64() {
        Some(s) => Matrix3::identity() * s,
        None => m3(v),
    }
}

/// The parameters (scheme `scheme`, level covariance) and bias estimate of a
/// `NAME.params.json`, as the generators' `gtsam_preint.py` reads them.
pub fn params_of(cfg: &Value, scheme: Scheme) -> (PreintParams, ImuBias) {
    let mut p = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Covariance);
    p.gravity = match cfg.get("n_gravity") {
        Some(g) => v3(g),
        None => Vector3::new(0.0, 0.0, -cfg["gravity"].as_f64().unwrap_or(9.81)),
    };
    p.gyro_cov = match cfg.get("gyro_covariance") {
        Some(c) => cov3(c),
        None => Matrix3::identity() * cfg["gyro_noise_density"].as_f64().unwrap().powi(2),
    };
    p.acc_cov = match cfg.get("accel_covariance") {
        Some(c) => cov3(c),
        None => Matrix3::identity() * cfg["accel_noise_density"].as_f64().unwrap().powi(2),
    };
    p.integration_cov = cfg.get("integration_covariance").map(cov3);
    (p, ImuBias::new(v3(&cfg["bg"]), v3(&cfg["ba"])))
}

/// `‖ours − theirs‖_F / ‖theirs‖_F`.
pub fn rel(ours: &DMatrix<f64>, theirs: &DMatrix<f64>) -> f64 {
    (ours - theirs).norm() / theirs.norm()
}

/// A fixed-size matrix as a dynamic one.
pub fn dm<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_fn(R, C, |i, j| m[(i, j)])
}
