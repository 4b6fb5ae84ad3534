//! Matrices and vectors as JSON and as text.

use nalgebra::{Dim, Matrix, RawStorage, Vector3};
use serde_json::{Value, json};
use std::fmt::Write as _;

/// The six IMU channels as printed, in sample order (gyro first).
pub const IMU_AXES: [&str; 6] = ["gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"];

/// A matrix as a JSON list of rows.
pub fn rows<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(m: &Matrix<f64, R, C, S>) -> Value {
    Value::Array(
        (0..m.nrows())
            .map(|i| json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// A 3-vector as a JSON list `[x, y, z]`.
pub fn list(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

/// An optional 3-vector as a JSON list, or `null`.
pub fn opt_list(v: Option<Vector3<f64>>) -> Value {
    v.map_or(Value::Null, |v| list(&v))
}

/// A matrix for the human summary, one row per line after `margin`, each entry `{:>13.5e}`.
pub fn text_matrix<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
    m: &Matrix<f64, R, C, S>,
    margin: &str,
) -> String {
    let mut s = String::new();
    for i in 0..m.nrows() {
        s.push_str(margin);
        for j in 0..m.ncols() {
            let _ = write!(s, "{:>13.5e}", m[(i, j)]);
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2x3;

    #[test]
    fn matrices_as_rows_and_text() {
        let m = Matrix2x3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        assert_eq!(rows(&m), json!([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]));
        assert_eq!(opt_list(None), Value::Null);
        let t = text_matrix(&m, "  ");
        assert_eq!(
            t,
            "      1.00000e0    2.00000e0    3.00000e0\n      4.00000e0    5.00000e0    6.00000e0\n"
        );
    }
}
