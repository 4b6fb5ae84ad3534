//! The calibration file's `preint_scheme` key and its plausibility limits: intrinsics far from
//! the identity are refused naming the file, line and key, unless the file says the sensor is
//! unusual.

use preint::Scheme;
use preint::intrinsics::{ImuIntrinsics, IntrinsicsModel};
use preint_io::intrinsics::{
    ImuCalibration, openvins_imu_chain_string, parse_kalibr_imu, parse_openvins_imu_chain,
};

fn file(scheme: Option<Scheme>) -> ImuCalibration {
    ImuCalibration {
        intrinsics: ImuIntrinsics::example(IntrinsicsModel::Kalibr),
        noise: None,
        time_offset_s: Some(4.04e-3),
        rostopic: None,
        scheme,
        body_p_sensor: None,
    }
}

/// `preint_body_p_sensor` is written and read back exactly; a quaternion that is not unit or a
/// list of the wrong length is refused naming the file, line and key.
#[test]
fn the_imu_pose_round_trips_and_malformed_ones_are_refused() {
    use preint::SensorPose;
    use preint_lie::SO3;
    let x = SensorPose::new(
        SO3::exp(&preint::nalgebra::Vector3::new(0.3, -1.2, 0.7)),
        preint::nalgebra::Vector3::new(0.12, -0.05, 0.3),
    );
    let cal = ImuCalibration {
        body_p_sensor: Some(x),
        ..file(None)
    };
    let text = preint_io::openvins_imu_chain_string(&cal);
    let back = preint_io::parse_openvins_imu_chain(&text, "cal.yaml").unwrap();
    let y = back.body_p_sensor.unwrap();
    assert_eq!(y.translation, x.translation);
    assert!((y.rotation.matrix() - x.rotation.matrix()).amax() < 1e-15);
    for (bad, needle) in [
        (
            "imu0:\n  preint_body_p_sensor: [ 0, 0, 0, 1, 0, 0, 0.1 ]\n",
            "norm 1.004987562",
        ),
        (
            "imu0:\n  preint_body_p_sensor: [ 0, 0, 0, 1, 0, 0 ]\n",
            "expected 7 numbers",
        ),
        (
            "imu0:\n  preint_body_p_sensor: [ 0, 0, x, 1, 0, 0, 0 ]\n",
            "preint_body_p_sensor[2]",
        ),
    ] {
        let e = preint_io::parse_openvins_imu_chain(bad, "cal.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("cal.yaml:2") && e.contains(needle), "{e}");
    }
}

#[test]
fn the_scheme_round_trips_and_an_unknown_one_is_named() {
    for s in Scheme::ALL {
        let text = openvins_imu_chain_string(&file(Some(*s)));
        assert!(
            text.contains(&format!("preint_scheme: \"{}\"", s.name())),
            "{text}"
        );
        assert_eq!(
            parse_openvins_imu_chain(&text, "f").unwrap().scheme,
            Some(*s)
        );
    }
    let text = openvins_imu_chain_string(&file(None));
    assert!(!text.contains("preint_scheme"));
    assert_eq!(parse_openvins_imu_chain(&text, "f").unwrap().scheme, None);
    let bad = "imu0:\n  time_offset: 0.004\n  preint_scheme: trapezoid\n";
    let e = parse_openvins_imu_chain(bad, "calib.yaml")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("calib.yaml:3:"), "{e}");
    assert!(e.contains("`imu0.preint_scheme`: `trapezoid`"), "{e}");
}

/// One entry changed in an otherwise plausible OpenVINS file: its line (the matrix's first
/// row) and key are named, and `preint_unusual_intrinsics: true` accepts it.
#[test]
fn implausible_intrinsics_are_refused_by_key_and_line() {
    let base = "%YAML:1.0\nimu0:\n  model: \"kalibr\"\n  Tw:\n    - [ 1.0, 0.0, 0.0 ]\n    \
                - [ 0.0, 1.0, 0.0 ]\n    - [ 0.0, 0.0, 1.0 ]\n  Tg:\n    - [ 0.0, 0.0, 0.0 ]\n    \
                - [ 0.0, 0.0, 0.0 ]\n    - [ 0.0, 0.0, 0.0 ]\n";
    assert!(parse_openvins_imu_chain(base, "c.yaml").is_ok());
    let cases = [
        // A scale of 1.3 (30 %), a misalignment of 14°, 0.03 (rad/s)/(m/s²) of g-sensitivity.
        (
            "- [ 0.0, 0.0, 1.0 ]",
            "- [ 0.0, 0.0, 1.3 ]",
            "`imu0.Tw`",
            "c.yaml:5:",
            "scale",
        ),
        (
            "- [ 0.0, 1.0, 0.0 ]",
            "- [ 0.25, 1.0, 0.0 ]",
            "`imu0.Tw`",
            "c.yaml:5:",
            "14.0°",
        ),
        (
            "- [ 0.0, 0.0, 0.0 ]\n    - [ 0.0, 0.0, 0.0 ]\n",
            "- [ 0.0, 0.03, 0.0 ]\n    - [ 0.0, 0.0, 0.0 ]\n",
            "`imu0.Tg`",
            "c.yaml:9:",
            "°/s/g",
        ),
    ];
    for (from, to, key, line, what) in cases {
        let text = base.replacen(from, to, 1);
        let e = parse_openvins_imu_chain(&text, "c.yaml")
            .unwrap_err()
            .to_string();
        for needle in [key, line, what, "preint_unusual_intrinsics: true"] {
            assert!(e.contains(needle), "{needle:?} not in {e}");
        }
        let accepted = text.replacen("imu0:\n", "imu0:\n  preint_unusual_intrinsics: true\n", 1);
        assert!(
            parse_openvins_imu_chain(&accepted, "c.yaml").is_ok(),
            "{accepted}"
        );
    }
    // A gyro rotated by 90° about z.
    let r = "  R_IMUtoGYRO:\n    - [ 0.0, -1.0, 0.0 ]\n    - [ 1.0, 0.0, 0.0 ]\n    \
             - [ 0.0, 0.0, 1.0 ]\n";
    let text = format!("{base}{r}");
    let e = parse_openvins_imu_chain(&text, "c.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("c.yaml:13:") && e.contains("`imu0.R_IMUtoGYRO`"),
        "{e}"
    );
    assert!(e.contains("90.0°"), "{e}");
}

/// Kalibr's layout names its own keys.
#[test]
fn kalibr_keys_are_named() {
    let text = "imu0:\n  model: scale-misalignment\n  gyroscopes:\n    A:\n      \
                - [0, 0, 0]\n      - [0, 0, 0]\n      - [0, 0, 0]\n    C_gyro_i:\n      \
                - [1, 0, 0]\n      - [0, 1, 0]\n      - [0, 0, 1]\n    M:\n      \
                - [1, 0, 0]\n      - [0, 1, 0]\n      - [0, 0, 1]\n  accelerometers:\n    M:\n      \
                - [0.5, 0, 0]\n      - [0, 1, 0]\n      - [0, 0, 1]\n";
    let e = parse_kalibr_imu(text, "imu.yaml").unwrap_err().to_string();
    assert!(
        e.starts_with("imu.yaml:18:") && e.contains("`imu0.accelerometers.M`"),
        "{e}"
    );
    assert!(e.contains("is 0.5"), "{e}");
}
