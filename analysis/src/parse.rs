//! Value parsers for flags (the command line's value parsers, and the checks of the same values
//! given by other callers): comma-separated vectors (negative numbers allowed in both
//! `--flag -1,2,3` and `--flag=-1,2,3` forms) and positive numbers, and the physical ranges of
//! the quantities they carry (a value outside its range is refused, naming the flag):
//! - gravity magnitude ([`gravity`]): [0, [`MAX_GRAVITY_M_S2`] = 100] m/s²; a gravity vector
//!   ([`gravity_vector`]): its norm in the same range;
//! - rate of a rotating navigation frame ([`frame_rate`]): |ω| ≤ [`MAX_FRAME_RATE_RAD_S`] =
//!   100 rad/s;
//! - lever arm of `--body-p-sensor` ([`sensor_pose`]): |r| ≤ [`MAX_LEVER_ARM_M`] = 1000 m;
//! - a state's position and velocity (`--initial-state`): |p| ≤ [`MAX_POSITION_M`] = 10¹² m,
//!   |v| below the speed of light;
//! - a latitude ([`latitude`]): [−90, 90] degrees.

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
    let r = Vector3::new(v[0], v[1], v[2]);
    if r.norm() > MAX_LEVER_ARM_M {
        return Err(format!(
            "a lever arm of {},{},{} m is longer than any rigid mount (norm at most \
             {MAX_LEVER_ARM_M} m): is it in mm?",
            v[0], v[1], v[2]
        ));
    }
    Ok(SensorPose::new(rotation, r))
}

/// Largest gravity magnitude accepted \[m/s²\]: 100. Zero is accepted (GTSAM's tests
/// preintegrate with g = 0; free fall, orbit), and so is any body a vehicle stands on: the
/// Moon 1.62, Mars 3.72, the Earth 9.78–9.83, Jupiter 24.8 m/s² (the largest planetary surface
/// gravity of the solar system), with a fourfold margin. Beyond it lie typos and absurd values
/// (1e308 overflows the prediction ½ g Δt² to infinity).
pub const MAX_GRAVITY_M_S2: f64 = 100.0;

/// Parses a gravity magnitude \[m/s²\]: finite, in [0, [`MAX_GRAVITY_M_S2`]].
pub fn gravity(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(g) if (0.0..=MAX_GRAVITY_M_S2).contains(&g) => Ok(g),
        _ => Err(format!(
            "`{s}` is not a gravity magnitude in [0, {MAX_GRAVITY_M_S2}] m/s^2 (0 for no \
             gravity; the Earth's is 9.81, Jupiter's 24.8)"
        )),
    }
}

/// Parses a world-frame gravity vector `x,y,z` \[m/s²\] (e.g. the `gravity.vector` of
/// `calibrate --estimate noise`): finite, with norm at most [`MAX_GRAVITY_M_S2`].
pub fn gravity_vector(s: &str) -> Result<Vector3<f64>, String> {
    let g = vec3(s)?;
    if g.norm() > MAX_GRAVITY_M_S2 {
        return Err(format!(
            "a gravity vector of {s} m/s^2 has norm {:.4e}, above any planet's {MAX_GRAVITY_M_S2} \
             m/s^2 (the Earth's is 9.81): is it in another unit?",
            g.norm()
        ));
    }
    Ok(g)
}

/// Largest rotation rate of a rotating navigation frame \[rad/s\]: 100 (955 rpm). The Earth
/// turns at 7.29e-5 rad/s; turntables, centrifuges and GTSAM's fast-rotating test frames at
/// up to a few rad/s. A frame turning faster is a typo (a rate in deg/s, or rpm).
pub const MAX_FRAME_RATE_RAD_S: f64 = 100.0;

/// Parses `x,y,z` \[rad/s\], the rate of a rotating navigation frame: finite, with norm at
/// most [`MAX_FRAME_RATE_RAD_S`].
pub fn frame_rate(s: &str) -> Result<Vector3<f64>, String> {
    let w = vec3(s)?;
    if w.norm() > MAX_FRAME_RATE_RAD_S {
        return Err(format!(
            "a navigation frame turning at {s} rad/s is beyond any rotating frame (norm at most \
             {MAX_FRAME_RATE_RAD_S} rad/s; the Earth's is 7.292115e-5 rad/s): is it in deg/s or \
             rpm?"
        ));
    }
    Ok(w)
}

/// Largest lever arm of `--body-p-sensor` \[m\]: 1000. The largest rigid bodies an IMU is
/// mounted on (ships, aircraft) put it tens to a few hundred metres from their reference
/// point; a kilometre is a unit slip (mm given as m).
pub const MAX_LEVER_ARM_M: f64 = 1000.0;

/// Largest position of `--initial-state` \[m\]: 10¹² (6.7 au). Beyond it a double's spacing
/// exceeds 0.1 mm, coarser than the position change over one IMU sample, and no navigation
/// frame puts a vehicle that far from its origin.
pub const MAX_POSITION_M: f64 = 1e12;

/// The speed of light \[m/s\]: no velocity of `--initial-state` reaches it.
pub const SPEED_OF_LIGHT_M_S: f64 = 299_792_458.0;

/// Parses a latitude in degrees: finite and within [−90, 90].
pub fn latitude(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && (-90.0..=90.0).contains(&x) => Ok(x),
        _ => Err(format!(
            "`{s}` is not a latitude in degrees within [-90, 90]"
        )),
    }
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

    #[test]
    fn physical_ranges() {
        assert_eq!(gravity("0"), Ok(0.0));
        assert_eq!(gravity("24.8"), Ok(24.8));
        for bad in ["-1", "100.5", "1e308", "inf", "nan", "g"] {
            assert!(gravity(bad).unwrap_err().contains("[0, 100]"), "{bad}");
        }
        assert_eq!(
            gravity_vector("0.0375,-0.0012,-9.8099"),
            Ok(Vector3::new(0.0375, -0.0012, -9.8099))
        );
        assert!(
            gravity_vector("0,0,-100.1")
                .unwrap_err()
                .contains("another unit")
        );
        assert!(gravity_vector("0,nan,-9.81").is_err());
        assert!(gravity_vector("0,-9.81").unwrap_err().contains("three"));
        assert!(frame_rate("0,0,7.292115e-5").is_ok());
        assert!(frame_rate("0,60,80").is_ok());
        let e = frame_rate("1e10,0,0").unwrap_err();
        assert!(
            e.contains("1e10,0,0 rad/s") && e.contains("deg/s or rpm"),
            "{e}"
        );
        assert!(frame_rate("1e300,1e300,0").is_err());
        assert!(frame_rate("0,60,80.1").is_err());
        assert!(sensor_pose("100,0,0,1,0,0,0").is_ok());
        assert!(
            sensor_pose("0,0,1001,1,0,0,0")
                .unwrap_err()
                .contains("in mm")
        );
    }
}
