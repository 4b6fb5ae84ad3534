//! Readers and writers: lossless round trips, and typed errors that name the line and problem.
#![allow(clippy::excessive_precision)] // literals copied verbatim from the EuRoC file

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use preint::{ImuBias, ImuNoise, ImuSample};
use preint_io::*;
use proptest::prelude::*;

const HEADER: &str = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";

fn parse_err(text: &str) -> (u64, String) {
    match parse_euroc_imu(text, "imu.csv") {
        Err(IoError::Parse {
            at: Location::Line(line),
            msg,
            source_name,
        }) => {
            assert_eq!(source_name, "imu.csv");
            (line, msg)
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn reads_euroc_rows_exactly() {
    let text = format!(
        "{HEADER}1403715273262142976,-0.099134701513277898,0.14730578886832138,0.02722713633111154,8.1476917083333333,-0.37592158333333331,-2.4026292499999999\n1403715273267142912,1e-3,2,3,4,5,6\n"
    );
    let s = parse_euroc_imu(&text, "x").unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0].t_ns, 1403715273262142976);
    assert_eq!(s[0].gyro.x, -0.099134701513277898);
    assert_eq!(s[0].acc.z, -2.4026292499999999);
    assert_eq!(s[1].t_ns - s[0].t_ns, 4_999_936);
    assert_eq!(s[1].gyro, Vector3::new(1e-3, 2.0, 3.0));
}

#[test]
fn malformed_rows_name_line_and_problem() {
    let ok = "1000,0,0,0,0,0,9.81\n";
    let (line, msg) = parse_err(&format!("{HEADER}{ok}2000,0,0,0,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(
        msg.contains("expected 7 columns (comma-separated") && msg.contains("found 6"),
        "{msg}"
    );

    let (line, msg) = parse_err(&format!("{HEADER}{ok}2000,0,abc,0,0,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(msg.contains("column 3") && msg.contains("abc"), "{msg}");

    let (line, msg) = parse_err(&format!("{HEADER}{ok}2000,0,NaN,0,0,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(msg.contains("not finite"), "{msg}");

    let (line, msg) = parse_err(&format!("{HEADER}{ok}2000,0,0,0,inf,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(msg.contains("column 5"), "{msg}");

    let (line, msg) = parse_err(&format!("{HEADER}{ok}1000,0,0,0,0,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(msg.contains("duplicate timestamp"), "{msg}");

    let (line, msg) = parse_err(&format!("{HEADER}{ok}999,0,0,0,0,0,9.81\n"));
    assert_eq!(line, 3);
    assert!(msg.contains("decreases"), "{msg}");

    let (line, msg) = parse_err(&format!("{HEADER}1403715273.262,0,0,0,0,0,9.81\n"));
    assert_eq!(line, 2);
    assert!(
        msg.contains("fraction of a nanosecond") && msg.contains("--time-unit"),
        "{msg}"
    );

    assert!(matches!(
        parse_euroc_imu(HEADER, "e.csv"),
        Err(IoError::Empty { .. })
    ));
    let err = read_euroc_imu(std::path::Path::new("/nonexistent/imu.csv")).unwrap_err();
    assert!(err.to_string().contains("/nonexistent/imu.csv"));
}

#[test]
fn unit_check_flags_g_and_deg_per_s() {
    let mk = |w: f64, a: f64| -> Vec<ImuSample> {
        (0..10)
            .map(|k| {
                ImuSample::new(
                    k * 5_000_000,
                    Vector3::new(w, 0.0, 0.0),
                    Vector3::new(0.0, 0.0, a),
                )
            })
            .collect()
    };
    assert!(check_si_units(&mk(0.1, 9.81), "ok").is_ok());
    let e = check_si_units(&mk(0.1, 1.0), "g.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("--accel-unit g") && e.contains("g.csv"), "{e}");
    let e = check_si_units(&mk(57.0, 9.81), "deg.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("deg/s"), "{e}");
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3f64,
        any::<f64>().prop_filter("finite", |x| x.is_finite())
    ]
}

proptest! {
    #[test]
    fn imu_round_trip_is_bit_exact(
        t0 in -1_000_000_000_000i64..2_000_000_000_000_000_000,
        steps in prop::collection::vec((1i64..50_000_000, [finite(), finite(), finite(), finite(), finite(), finite()]), 1..40)
    ) {
        let mut t = t0;
        let samples: Vec<ImuSample> = steps.iter().map(|(dt, v)| {
            t += dt;
            ImuSample::new(t, Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]))
        }).collect();
        let back = parse_euroc_imu(&euroc_imu_string(&samples), "rt").unwrap();
        prop_assert_eq!(back, samples);
    }

    #[test]
    fn groundtruth_round_trip_is_bit_exact(q in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
                                           x in [finite(), finite(), finite(), finite(), finite(), finite(), finite(), finite(), finite(), finite(), finite(), finite()]) {
        let qq = Quaternion::new(q[0], q[1], q[2], q[3]);
        prop_assume!(qq.norm() > 0.1);
        let s = GroundTruthState {
            t_ns: 1403715273262142976,
            p: Vector3::new(x[0], x[1], x[2]),
            q: UnitQuaternion::new_normalize(qq),
            v: Vector3::new(x[3], x[4], x[5]),
            bias: ImuBias::new(Vector3::new(x[6], x[7], x[8]), Vector3::new(x[9], x[10], x[11])),
        };
        let back = parse_euroc_groundtruth(&euroc_groundtruth_string(&[s]), "rt").unwrap();
        prop_assert_eq!(back, vec![s]);
    }
}

#[test]
fn groundtruth_errors() {
    let row = "1000,1,2,3,1,0,0,0,0.1,0.2,0.3,0.01,0.02,0.03,0.1,0.2,0.3\n";
    let gt = parse_euroc_groundtruth(&format!("#header\n{row}"), "gt.csv").unwrap();
    assert_eq!(gt[0].rotation().matrix(), &nalgebra::Matrix3::identity());
    assert_eq!(gt[0].bias.acc, Vector3::new(0.1, 0.2, 0.3));
    let bad_q = "1000,1,2,3,2,0,0,0,0.1,0.2,0.3,0.01,0.02,0.03,0.1,0.2,0.3\n";
    let e = parse_euroc_groundtruth(&format!("#h\n{bad_q}"), "gt.csv")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("gt.csv:2:") && e.contains("norm 2"), "{e}");
    let e = parse_euroc_groundtruth("1000,1,2\n", "gt.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("expected 17 columns"), "{e}");
}

#[test]
fn kalibr_yaml_round_trip_and_errors() {
    let n = ImuNoise::euroc();
    assert_eq!(
        parse_kalibr_yaml(&kalibr_yaml_string(&n), "imu.yaml").unwrap(),
        n
    );
    // The EuRoC sensor.yaml style, with comments and extra keys.
    let text = "#Accelerometers\naccelerometer_noise_density: 2.0000e-3   # [ m / s^2 / sqrt(Hz) ]\naccelerometer_random_walk: 3.0000e-3\n\
                gyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\nrostopic: /imu0\nupdate_rate: 200.0\n";
    assert_eq!(parse_kalibr_yaml(text, "s.yaml").unwrap(), n);
    let missing = text.replace("update_rate: 200.0\n", "");
    assert!(matches!(
        parse_kalibr_yaml(&missing, "s.yaml"),
        Err(IoError::MissingKey {
            key: "update_rate",
            ..
        })
    ));
    let negative = text.replace("1.6968e-04", "-1.6968e-04");
    let e = parse_kalibr_yaml(&negative, "s.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("s.yaml:4:") && e.contains("gyroscope_noise_density"),
        "{e}"
    );
}
