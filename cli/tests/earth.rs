//! Earth rotation on the command line: `simulate --earth-rate/--latitude`, `integrate
//! --omega-coriolis/--coriolis/--initial-state` (the predicted state against the simulator's
//! ground truth), and the refusals.

mod common;

use common::{json, matrix, run, simulate, tmp, truth, vec3};

fn state_flag(p: [f64; 3], q: [f64; 4], v: [f64; 3]) -> String {
    let all: Vec<String> = p
        .iter()
        .chain(&v)
        .chain(&q)
        .map(|x| format!("{x:e}"))
        .collect();
    format!("--initial-state={}", all.join(","))
}

fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

#[test]
fn prediction_in_a_rotating_frame_lands_on_the_simulated_truth() {
    let d = tmp("earth-predict");
    let rate = "0.01,-0.02,0.03";
    let sim = simulate(
        &d,
        &[
            "--scene",
            "seed-ellipse",
            "--noise",
            "none",
            "--duration",
            "3",
            "--earth-rate",
            rate,
        ],
    );
    assert_eq!(vec3(&sim["earth_rate"]), [0.01, -0.02, 0.03]);
    let (p1, q1, v1) = truth(&d, 1_000_000_000);
    let (p2, _, v2) = truth(&d, 2_000_000_000);
    let imu = d.join("imu.csv");
    let base = [
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--scheme",
        "hermite4",
        "--from",
        "1000000000",
        "--to",
        "2000000000",
    ];
    let initial = state_flag(p1, q1, v1);
    let mut with_rate = base.to_vec();
    with_rate.extend_from_slice(&["--omega-coriolis", rate, &initial]);
    let out = json(&with_rate);
    assert_eq!(out["coriolis"], "exact");
    let pred = &out["predicted"];
    let (ep, ev) = (
        max_diff(vec3(&pred["position"]), p2),
        max_diff(vec3(&pred["velocity"]), v2),
    );
    assert!(ep < 1e-6 && ev < 1e-6, "exact: {ep} m, {ev} m/s");
    assert_eq!(matrix(&pred["rotation"]).len(), 3);
    // The same window predicted as if the frame did not rotate misses by far more.
    let mut without = base.to_vec();
    without.push(&initial);
    let out = json(&without);
    assert!(out["omega_coriolis"].is_null());
    let ep0 = max_diff(vec3(&out["predicted"]["position"]), p2);
    assert!(ep0 > 1e-3, "non-rotating prediction off by only {ep0} m");
    // First order: between the two.
    let mut first = with_rate.clone();
    first.extend_from_slice(&["--coriolis", "first"]);
    let out = json(&first);
    assert_eq!(out["coriolis"], "first");
    let ep1 = max_diff(vec3(&out["predicted"]["position"]), p2);
    assert!(ep1 > ep && ep1 < ep0, "first order {ep1} m");
    // The text form prints the prediction too.
    let o = run(&with_rate);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("predicted at t_j") && text.contains("Coriolis mode exact"),
        "{text}"
    );
}

#[test]
fn latitude_gives_the_enu_earth_rate() {
    let d = tmp("earth-lat");
    let sim = simulate(
        &d,
        &[
            "--scene",
            "static",
            "--noise",
            "none",
            "--duration",
            "1",
            "--latitude",
            "-30",
        ],
    );
    let w = vec3(&sim["earth_rate"]);
    assert_eq!(w[0], 0.0);
    assert!((w[1] - 7.292115e-5 * 3f64.sqrt() / 2.0).abs() < 1e-18);
    assert!((w[2] + 7.292115e-5 * 0.5).abs() < 1e-18);
}

#[test]
fn bad_earth_flags_are_refused_with_a_reason() {
    let d = tmp("earth-bad");
    simulate(
        &d,
        &["--scene", "static", "--noise", "none", "--duration", "1"],
    );
    let imu = d.join("imu.csv");
    let imu = imu.to_str().unwrap();
    let cases: [(&[&str], &str); 5] = [
        (
            &["integrate", "--imu", imu, "--coriolis", "exact"],
            "--omega-coriolis",
        ),
        (
            &[
                "integrate",
                "--imu",
                imu,
                "--coriolis",
                "third",
                "--omega-coriolis",
                "0,0,1e-4",
            ],
            "first, second or exact",
        ),
        (
            &[
                "integrate",
                "--imu",
                imu,
                "--initial-state=0,0,0,0,0,0,2,0,0,0",
            ],
            "norm",
        ),
        (
            &[
                "integrate",
                "--imu",
                imu,
                "--initial-state=0,0,0,0,0,0,1,0,0",
            ],
            "ten",
        ),
        (
            &[
                "simulate",
                "--out",
                d.to_str().unwrap(),
                "--latitude",
                "45",
                "--earth-rate",
                "0,0,1",
            ],
            "cannot be used with",
        ),
    ];
    for (args, msg) in cases {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}

#[test]
fn calibrate_with_latitude_does_not_take_the_earth_rate_for_gyro_bias() {
    // A tactical-grade gyro at rest at 45° N (static scene: yaw 0.8 rad from east), zero bias.
    let d = tmp("earth-calib");
    let noise = common::write_noise_yaml(&d, "imu.yaml", [5e-6, 0.0, 2e-4, 0.0], 100.0);
    simulate(
        &d,
        &[
            "--scene",
            "static",
            "--rate",
            "100",
            "--duration",
            "60",
            "--latitude",
            "45",
            "--noise",
            noise.to_str().unwrap(),
        ],
    );
    let imu = d.join("imu.csv");
    let base = [
        "calibrate",
        "--imu",
        imu.to_str().unwrap(),
        "--noise",
        noise.to_str().unwrap(),
    ];
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let plain = json(&base);
    assert!(
        (norm(vec3(&plain["gyro_bias"])) - 7.292115e-5).abs() < 5e-6,
        "{plain}"
    );
    assert!(plain["earth_rate"].is_null());

    let mut lat = base.to_vec();
    lat.extend_from_slice(&["--latitude", "45"]);
    let out = json(&lat);
    let (b, s) = (vec3(&out["gyro_bias"]), vec3(&out["gyro_bias_std"]));
    let horizontal = 7.292115e-5 * 45f64.to_radians().cos();
    assert!((norm(b) - horizontal).abs() < 5e-6, "{b:?}");
    for k in 0..3 {
        assert!(b[k].abs() <= 3.0 * s[k], "axis {k}: {b:?} ± {s:?}");
    }
    assert!(
        out["earth_rate"]["note"]
            .as_str()
            .unwrap()
            .contains("not separable")
    );

    let mut head = lat.clone();
    let heading = format!("{}", 90.0 - 0.8f64.to_degrees());
    head.extend_from_slice(&["--heading", &heading]);
    let out = json(&head);
    let (b, s) = (vec3(&out["gyro_bias"]), vec3(&out["gyro_bias_std"]));
    assert!(s[0] < 1e-6 && norm(b) < 4.0 * s[0], "{b:?} ± {s:?}");
}
