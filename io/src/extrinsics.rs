//! The IMU's pose in another sensor's frame in calibration files: the key
//! `preint_body_p_sensor` of this crate's calibration file (the OpenVINS `kalibr_imu_chain.yaml`
//! that [`crate::intrinsics`] reads and writes), and Kalibr's `camchain-imucam.yaml`.
//!
//! `preint_body_p_sensor: [ x, y, z, qw, qx, qy, qz ]` under `imu0` is the pose of the IMU (the
//! sensor s) in the frame of the poses (the body b: a camera, a lidar, a motion-capture body):
//! `p_bs` \[m\] and the Hamilton quaternion of `R_bs` (IMU → body), the transform `preint
//! --body-p-sensor` takes and GTSAM's `body_P_sensor`. A quaternion whose norm is not within
//! 1e-6 of 1 is refused, naming the file and line.
//!
//! Kalibr's `camchain-imucam.yaml` (`kalibr_calibrate_imu_camera`'s output, read by OpenVINS'
//! `kalibr_imucam_chain.yaml` and VINS-Fusion) holds, under `cam0`, `T_cam_imu` (the 4×4
//! transform taking IMU-frame points to the camera frame, `x_c = R_ci x_i + t_ci`: with the
//! camera as the body, `R_ci = R_bs` and `t_ci = p_bs`) and `timeshift_cam_imu` \[s\]
//! (`t_imu = t_cam + shift`, the sign of this crate's `time_offset`).

use crate::error::{IoError, Location, write_text};
use crate::number::parse_finite;
use crate::yaml::Node;
use preint::SensorPose;
use preint::nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint_lie::SO3;
use std::path::Path;

/// The key of the IMU's pose in this crate's calibration file (module docs).
pub const BODY_P_SENSOR_KEY: &str = "preint_body_p_sensor";

/// Reads `preint_body_p_sensor` from `map` (`path` its key prefix), if present.
pub(crate) fn read_body_p_sensor(
    map: &Node,
    path: &str,
    source: &str,
) -> Result<Option<SensorPose>, IoError> {
    let Some(node) = map.get(BODY_P_SENSOR_KEY) else {
        return Ok(None);
    };
    let field = format!("{path}{BODY_P_SENSOR_KEY}");
    let err = |line: u64, msg: String| IoError::parse(source, Location::Line(line), msg);
    let Node::Seq(xs, line) = node else {
        return Err(err(
            node.line(),
            format!("`{field}`: expected [ x, y, z, qw, qx, qy, qz ]"),
        ));
    };
    if xs.len() != 7 {
        return Err(err(
            *line,
            format!(
                "`{field}`: expected 7 numbers [ x, y, z, qw, qx, qy, qz ], found {}",
                xs.len()
            ),
        ));
    }
    let mut v = [0.0; 7];
    for (k, x) in xs.iter().enumerate() {
        v[k] = match x {
            Node::Scalar(s, l) => {
                parse_finite(s).map_err(|m| err(*l, format!("`{field}[{k}]`: {m}")))?
            }
            other => {
                return Err(err(
                    other.line(),
                    format!("`{field}[{k}]`: expected a number"),
                ));
            }
        };
    }
    let q = Quaternion::new(v[3], v[4], v[5], v[6]);
    if (q.norm() - 1.0).abs() > 1e-6 {
        return Err(err(
            *line,
            format!(
                "`{field}`: the quaternion (qw, qx, qy, qz) has norm {:.9}, not 1",
                q.norm()
            ),
        ));
    }
    // As `--body-p-sensor` is read, so that the two give the same rotation to the last bit.
    let r = SO3::from_matrix(
        UnitQuaternion::from_quaternion(q)
            .to_rotation_matrix()
            .matrix(),
    );
    Ok(Some(SensorPose::new(r, Vector3::new(v[0], v[1], v[2]))))
}

/// `[x, y, z, qw, qx, qy, qz]` of a pose, the quaternion with `qw ≥ 0`.
pub fn pose_vector(x: &SensorPose) -> [f64; 7] {
    let q = UnitQuaternion::from_rotation_matrix(
        &preint::nalgebra::Rotation3::from_matrix_unchecked(*x.rotation.matrix()),
    );
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    let t = x.translation;
    [t.x, t.y, t.z, s * q.w, s * q.i, s * q.j, s * q.k]
}

/// `x,y,z,qw,qx,qy,qz` as `--body-p-sensor` takes it (µm and 1e-8 of the quaternion).
pub fn body_p_sensor_flag(x: &SensorPose) -> String {
    let v = pose_vector(x);
    format!(
        "{:.6},{:.6},{:.6},{:.8},{:.8},{:.8},{:.8}",
        v[0], v[1], v[2], v[3], v[4], v[5], v[6]
    )
}

/// The calibration file's line of the key (module docs), indented under `imu0`.
pub(crate) fn body_p_sensor_line(x: &SensorPose) -> String {
    let v = pose_vector(x);
    format!(
        "  {BODY_P_SENSOR_KEY}: [ {:?}, {:?}, {:?}, {:?}, {:?}, {:?}, {:?} ]  # IMU in the \
         poses' frame: p_bs [ m ], R_bs as qw, qx, qy, qz\n",
        v[0], v[1], v[2], v[3], v[4], v[5], v[6]
    )
}

/// Kalibr's `camchain-imucam.yaml` text for the IMU at `x` in the camera frame and the time
/// offset `timeshift_s` (module docs).
pub fn kalibr_camchain_string(x: &SensorPose, timeshift_s: f64) -> String {
    let (r, t) = (x.rotation.matrix(), x.translation);
    let mut out = String::from("cam0:\n  T_cam_imu:\n");
    for i in 0..3 {
        out.push_str(&format!(
            "  - [{:?}, {:?}, {:?}, {:?}]\n",
            r[(i, 0)],
            r[(i, 1)],
            r[(i, 2)],
            t[i]
        ));
    }
    out.push_str("  - [0.0, 0.0, 0.0, 1.0]\n");
    out.push_str(&format!("  timeshift_cam_imu: {timeshift_s:?}\n"));
    out
}

/// Writes [`kalibr_camchain_string`] to `path`.
pub fn write_kalibr_camchain(path: &Path, x: &SensorPose, timeshift_s: f64) -> Result<(), IoError> {
    write_text(path, &kalibr_camchain_string(x, timeshift_s))
}
