//! Value parsers for flags: comma-separated vectors (negative numbers allowed in both
//! `--flag -1,2,3` and `--flag=-1,2,3` forms) and positive numbers (lists of rates use clap's
//! `value_delimiter`).

use nalgebra::Vector3;

/// Parses `x,y,z` into a vector; every component must be a finite number.
pub fn vec3(s: &str) -> Result<Vector3<f64>, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers x,y,z, got `{s}`"
        ));
    }
    let mut v = [0.0; 3];
    for (i, p) in parts.iter().enumerate() {
        let x: f64 = p
            .parse()
            .map_err(|_| format!("`{p}` is not a number (in `{s}`)"))?;
        if !x.is_finite() {
            return Err(format!("`{p}` is not finite (in `{s}`)"));
        }
        v[i] = x;
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// Parses `x,y,z,qw,qx,qy,qz` (GTSAM's `body_P_sensor`: the sensor origin in the body frame
/// \[m\] and the unit quaternion rotating sensor vectors into the body frame).
pub fn sensor_pose(s: &str) -> Result<preint::SensorPose, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 7 {
        return Err(format!(
            "expected seven comma-separated numbers x,y,z,qw,qx,qy,qz (metres; quaternion \
             rotating sensor vectors into the body frame), got `{s}`"
        ));
    }
    let mut v = [0.0; 7];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p
            .parse()
            .map_err(|_| format!("`{p}` is not a number (in `{s}`)"))?;
    }
    preint::SensorPose::from_xyz_wxyz(v).ok_or_else(|| {
        format!("`{s}`: values must be finite and the quaternion of unit norm (±1e-3)")
    })
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
