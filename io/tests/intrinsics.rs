//! IMU intrinsics files: OpenVINS' own `kalibr_imu_chain.yaml` (rs_d455, `tests/data/openvins`),
//! Kalibr's `scale-misalignment` result layout, exact round trips, and typed errors naming the
//! file, line and field.

use preint::ImuSample;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint::nalgebra::{Matrix3, Vector3};
use preint_io::intrinsics::{
    ImuCalibration, kalibr_imu_string, openvins_imu_chain_string, parse_kalibr_imu,
    parse_openvins_imu_chain, read_openvins_imu_chain,
};
use preint_io::{IoError, Location};
use preint_lie::SO3;
use std::path::Path;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/openvins")
        .join(name)
}

#[test]
fn reads_openvins_own_rs_d455_file() {
    let cal = read_openvins_imu_chain(&data("rs_d455_kalibr_imu_chain.yaml")).unwrap();
    let x = &cal.intrinsics;
    assert_eq!(x.model, IntrinsicsModel::Kalibr);
    assert_eq!((x.t_w, x.t_a), (Matrix3::identity(), Matrix3::identity()));
    assert_eq!(x.r_imu_to_gyro, Matrix3::identity());
    assert_eq!(x.r_imu_to_acc, Matrix3::identity());
    assert_eq!(x.t_g, Matrix3::zeros());
    // The inflated densities, not the commented-out Allan values above them.
    let n = cal.noise.unwrap();
    assert_eq!(n.acc_noise_density, 0.00207649074);
    assert_eq!(n.acc_random_walk, 0.00041327852);
    assert_eq!(n.gyro_noise_density, 0.00020544166);
    assert_eq!(n.gyro_random_walk, 0.00001110622);
    assert_eq!(n.update_rate_hz, 400.0);
    assert_eq!(cal.rostopic.as_deref(), Some("/d455/imu"));
    assert_eq!(cal.time_offset_s, Some(0.0));
}

/// The library's example intrinsics with `R_IMUtoACC = I` (Kalibr's `imu.yaml` has no
/// accelerometer rotation).
fn realistic(model: IntrinsicsModel) -> ImuIntrinsics {
    ImuIntrinsics {
        r_imu_to_acc: Matrix3::identity(),
        ..ImuIntrinsics::example(model)
    }
}

fn calibration(x: ImuIntrinsics) -> ImuCalibration {
    ImuCalibration {
        intrinsics: x,
        noise: Some(preint::ImuNoise::euroc()),
        time_offset_s: Some(-0.0045123456789),
        rostopic: Some("/imu0".into()),
        scheme: None,
        body_p_sensor: None,
    }
}

#[test]
fn openvins_files_round_trip_exactly() {
    for model in [IntrinsicsModel::Kalibr, IntrinsicsModel::Rpng] {
        let mut x = realistic(model);
        x.r_imu_to_acc = *SO3::exp(&Vector3::new(-0.001, 0.002, 0.002)).matrix();
        let cal = calibration(x);
        let text = openvins_imu_chain_string(&cal);
        assert!(text.starts_with("%YAML:1.0"));
        assert_eq!(
            parse_openvins_imu_chain(&text, "mem").unwrap(),
            cal,
            "{text}"
        );
    }
    // No noise, offset or topic: none is invented.
    let bare = ImuCalibration {
        intrinsics: realistic(IntrinsicsModel::Rpng),
        noise: None,
        time_offset_s: None,
        rostopic: None,
        scheme: None,
        body_p_sensor: None,
    };
    let text = openvins_imu_chain_string(&bare);
    assert_eq!(parse_openvins_imu_chain(&text, "mem").unwrap(), bare);
}

/// Kalibr's result file as its `yaml.dump` writes it (keys sorted, lists at the key's
/// indentation).
const KALIBR: &str = "imu0:
  T_i_b:
  - [1.0, 0.0, 0.0, 0.0]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  accelerometer_noise_density: 0.01
  accelerometer_random_walk: 0.0002
  accelerometers:
    M:
    - [1.01, 0.0, 0.0]
    - [0.002, 0.99, 0.0]
    - [-0.001, 0.003, 1.0]
  gyroscope_noise_density: 0.005
  gyroscope_random_walk: 4.0e-06
  gyroscopes:
    A:
    - [0.001, -0.002, 0.0005]
    - [0.0, 0.0015, -0.001]
    - [0.002, 0.0, 0.001]
    C_gyro_i:
    - [0.9999980000006666, -0.0019999986666669333, 0.0]
    - [0.0019999986666669333, 0.9999980000006666, 0.0]
    - [0.0, 0.0, 1.0]
    M:
    - [0.995, 0.0, 0.0]
    - [0.001, 1.004, 0.0]
    - [0.002, -0.001, 1.0]
  model: scale-misalignment
  rostopic: /imu0
  time_offset: 0.0
  update_rate: 200.0
";

#[test]
fn reads_kalibr_scale_misalignment_and_inverts_its_sensor_model() {
    let cal = parse_kalibr_imu(KALIBR, "imu.yaml").unwrap();
    let x = &cal.intrinsics;
    let m_w = Matrix3::new(0.995, 0.0, 0.0, 0.001, 1.004, 0.0, 0.002, -0.001, 1.0);
    let m_a = Matrix3::new(1.01, 0.0, 0.0, 0.002, 0.99, 0.0, -0.001, 0.003, 1.0);
    let a = Matrix3::new(
        0.001, -0.002, 0.0005, 0.0, 0.0015, -0.001, 0.002, 0.0, 0.001,
    );
    let c = Matrix3::new(
        0.9999980000006666,
        -0.0019999986666669333,
        0.0,
        0.0019999986666669333,
        0.9999980000006666,
        0.0,
        0.0,
        0.0,
        1.0,
    );
    assert_eq!((x.t_w, x.t_a, x.r_imu_to_gyro), (m_w, m_a, c));
    assert_eq!(x.r_imu_to_acc, Matrix3::identity());
    assert_eq!(x.t_g, a * c);
    assert_eq!(cal.noise.unwrap().gyro_random_walk, 4.0e-6);
    // Kalibr's forward model (IccSensors.py): ω_m = M C ω + A C a, a_m = M_a a (no bias);
    // the correction returns the true rate and specific force.
    let (w, f) = (Vector3::new(0.3, -1.2, 0.7), Vector3::new(0.4, -0.2, 9.7));
    let raw = ImuSample::new(0, m_w * c * w + a * c * f, m_a * f);
    let back = x.apply(&raw);
    // Round-off only: a wrong convention (A on frame-I force, C transposed) is off by ≥ 1e-5.
    assert!((back.gyro - w).amax() < 1e-13 && (back.acc - f).amax() < 1e-13);
    // Written back as Kalibr: the same matrices (A through C_gyro_i and back, to round-off).
    let again = parse_kalibr_imu(&kalibr_imu_string(&cal, "out.yaml").unwrap(), "out").unwrap();
    let y = &again.intrinsics;
    assert_eq!(
        (y.t_w, y.t_a, y.r_imu_to_gyro),
        (x.t_w, x.t_a, x.r_imu_to_gyro)
    );
    assert!((y.t_g - x.t_g).amax() < 1e-18);
    // With C_gyro_i = I the round trip is exact.
    let mut z = cal.clone();
    z.intrinsics.r_imu_to_gyro = Matrix3::identity();
    let text = kalibr_imu_string(&z, "out.yaml").unwrap();
    assert_eq!(parse_kalibr_imu(&text, "out").unwrap(), z);
}

#[test]
fn kalibr_writer_refuses_intrinsics_outside_its_model() {
    let cal = calibration(realistic(IntrinsicsModel::Rpng));
    assert!(matches!(
        kalibr_imu_string(&cal, "out.yaml"),
        Err(IoError::Format { source_name, .. }) if source_name == "out.yaml"
    ));
    let calibrated = "imu0:\n  model: calibrated\n  rostopic: /imu0\n";
    let cal = parse_kalibr_imu(calibrated, "c").unwrap();
    assert!(cal.intrinsics.is_identity() && cal.noise.is_none());
}

fn parse_error(text: &str) -> (Location, String) {
    match parse_openvins_imu_chain(text, "chain.yaml") {
        Err(IoError::Parse {
            source_name,
            at,
            msg,
        }) => {
            assert_eq!(source_name, "chain.yaml");
            (at, msg)
        }
        other => panic!("{text}: {other:?}"),
    }
}

#[test]
fn malformed_files_name_the_file_line_and_field() {
    let head = "%YAML:1.0\nimu0:\n  model: kalibr\n";
    let (at, msg) = parse_error(&format!(
        "{head}  Tw:\n    - [ 1.0, 0.0, 0.0 ]\n    - [ 0.0, 1.0, x ]\n    - [ 0.0, 0.0, 1.0 ]\n"
    ));
    assert_eq!(at, Location::Line(6));
    assert!(msg.contains("imu0.Tw[1][2]"), "{msg}");
    let (at, msg) = parse_error(&format!(
        "{head}  Ta:\n    - [ 1.0, 0.0, 0.0 ]\n    - [ 0.0, 1.0, 0.0 ]\n"
    ));
    assert_eq!(at, Location::Line(5));
    assert!(
        msg.contains("imu0.Ta") && msg.contains("3 rows of 3"),
        "{msg}"
    );
    let (_, msg) = parse_error("imu0:\n  model: \"imu\"\n");
    assert!(msg.contains("imu0.model"), "{msg}");
    let (_, msg) = parse_error(&format!(
        "{head}  Tw:\n    - [ 1.0, 0.1, 0.0 ]\n    - [ 0.0, 1.0, 0.0 ]\n    - [ 0.0, 0.0, 1.0 ]\n"
    ));
    assert!(
        msg.contains("imu0.Tw") && msg.contains("lower triangular"),
        "{msg}"
    );
    let (_, msg) = parse_error(&format!(
        "{head}  Ta:\n    - [ 1.0, 0.0, 0.0 ]\n    - [ 0.0, 0.0, 0.0 ]\n    - [ 0.0, 0.0, 1.0 ]\n"
    ));
    assert!(msg.contains("not invertible"), "{msg}");
    let (at, _) = parse_error("imu0:\n  Tw:\n    - [ 1.0, 0.0, 0.0\n");
    assert_eq!(at, Location::Line(3));
    match parse_openvins_imu_chain("imu0:\n  gyroscope_noise_density: 0.001\n", "chain.yaml") {
        Err(IoError::MissingKey { source_name, key }) => {
            assert_eq!(
                (source_name.as_str(), key),
                ("chain.yaml", "gyroscope_random_walk")
            );
        }
        other => panic!("{other:?}"),
    }
    match read_openvins_imu_chain(Path::new("/nonexistent/chain.yaml")) {
        Err(IoError::File { path, .. }) => assert_eq!(path, "/nonexistent/chain.yaml"),
        other => panic!("{other:?}"),
    }
}
