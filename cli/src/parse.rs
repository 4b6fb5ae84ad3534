//! Value parsers for flags: comma-separated vectors (negative numbers allowed in both
//! `--flag -1,2,3` and `--flag=-1,2,3` forms) and positive numbers (lists of rates use clap's
//! `value_delimiter`).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint::SensorPose;
use preint::lie::SO3;

/// Parses exactly `N` comma-separated finite numbers; `expected` names them in the error
/// (e.g. "three comma-separated numbers x,y,z").
pub fn numbers<const N: usize>(s: &str, expected: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!("expected {expected}, got {} in `{s}`", parts.len()));
    }
    let mut v = [0.0; N];
    for (x, p) in v.iter_mut().zip(&parts) {
        *x = p
            .parse::<f64>()
            .map_err(|_| format!("`{p}` is not a number (in `{s}`)"))?;
        if !x.is_finite() {
            return Err(format!("`{p}` is not finite (in `{s}`)"));
        }
    }
    Ok(v)
}

/// Parses `x,y,z` into a vector; every component must be a finite number.
pub fn vec3(s: &str) -> Result<Vector3<f64>, String> {
    let [x, y, z] = numbers::<3>(s, "three comma-separated numbers x,y,z")?;
    Ok(Vector3::new(x, y, z))
}

/// Largest accepted `| |q| − 1 |` of a quaternion given on the command line: closer ones are
/// normalised (a quaternion printed with a few decimals), farther ones refused (a typo).
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// The rotation of the quaternion `[qw, qx, qy, qz]` (Hamilton, scalar first), normalised
/// when its norm is within [`QUATERNION_NORM_TOLERANCE`] of 1, refused otherwise.
pub fn unit_quaternion([w, x, y, z]: [f64; 4]) -> Result<SO3, String> {
    let q = Quaternion::new(w, x, y, z);
    let n = q.norm();
    if (n - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(format!(
            "the quaternion qw,qx,qy,qz = {w},{x},{y},{z} has norm {n}, not a unit norm \
             (1 ± {QUATERNION_NORM_TOLERANCE})"
        ));
    }
    let r = UnitQuaternion::from_quaternion(q).to_rotation_matrix();
    Ok(SO3::from_matrix(r.matrix()))
}

/// Parses `x,y,z,qw,qx,qy,qz` (GTSAM's `body_P_sensor`: the sensor origin in the body frame
/// \[m\] and the unit quaternion rotating sensor vectors into the body frame).
pub fn sensor_pose(s: &str) -> Result<SensorPose, String> {
    let v = numbers::<7>(
        s,
        "seven comma-separated numbers x,y,z,qw,qx,qy,qz (metres; quaternion rotating sensor \
         vectors into the body frame)",
    )?;
    let rotation = unit_quaternion([v[3], v[4], v[5], v[6]])?;
    Ok(SensorPose::new(rotation, Vector3::new(v[0], v[1], v[2])))
}

/// Parses one positive finite number (e.g. a rate in Hz).
pub fn positive(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a positive number")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_and_lists() {
        assert_eq!(
            vec3("-0.01,0.002,0").unwrap(),
            Vector3::new(-0.01, 0.002, 0.0)
        );
        assert_eq!(vec3(" 1, 2 ,3").unwrap(), Vector3::new(1.0, 2.0, 3.0));
        assert!(vec3("1,2").unwrap_err().contains("three"));
        assert!(vec3("1,x,3").unwrap_err().contains("`x`"));
        assert!(vec3("1,inf,3").is_err());
        assert_eq!(positive("50.5").unwrap(), 50.5);
        assert!(positive("-50").is_err());
        assert!(positive("0").is_err());
        assert!(positive("nan").is_err());
    }
}
