//! Reading the GTSAM fixtures of `tests/fixtures/gtsam/` (JSON written by the generators
//! there): the folder, a file, and matrices and vectors stored as nested arrays.

use nalgebra::{DMatrix, Matrix3, Vector3};
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
