//! `preint integrate --at`: the deltas and predicted states inside the window, against the
//! window ending there and the simulator's ground truth; the refusals.

mod common;

use common::{json, run, simulate, tmp, truth, vec3};

fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

#[test]
fn integrate_at_prints_the_window_ending_there_and_the_true_states() {
    let d = tmp("deskew-at");
    simulate(
        &d,
        &[
            "--scene",
            "seed-ellipse",
            "--noise",
            "none",
            "--duration",
            "3",
        ],
    );
    let imu = d.join("imu.csv");
    let (p1, q1, v1) = truth(&d, 1_000_000_000);
    let state: Vec<String> = p1
        .iter()
        .chain(&v1)
        .chain(&q1)
        .map(|x| format!("{x:e}"))
        .collect();
    let initial = format!("--initial-state={}", state.join(","));
    let base = [
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--scheme",
        "hermite4",
    ];
    let window = |to: &'static str| {
        let mut a = base.to_vec();
        a.extend_from_slice(&["--from", "1000000000", "--to", to]);
        a
    };
    let mut args = window("2000000000");
    args.extend_from_slice(&[
        "--at",
        "1000000000,1250000000,1502345678,2000000000",
        &initial,
    ]);
    let out = json(&args);
    let at = out["at"].as_array().expect("at array");
    assert_eq!(at.len(), 4);
    assert_eq!(at[0]["delta_t"], 0.0);
    // The window's end is the last query; a query between samples is the window ending there.
    for key in ["delta_R", "delta_v", "delta_p"] {
        assert_eq!(at[3][key], out[key], "{key}");
    }
    let mid = json(&window("1502345678"));
    for key in ["delta_t", "delta_R", "delta_v", "delta_p"] {
        assert_eq!(at[2][key], mid[key], "{key}");
    }
    // The predicted state at a sample time lands on the simulator's truth.
    let (p, _, v) = truth(&d, 1_250_000_000);
    let pred = &at[1]["predicted"];
    let (ep, ev) = (
        max_diff(vec3(&pred["position"]), p),
        max_diff(vec3(&pred["velocity"]), v),
    );
    assert!(ep < 1e-6 && ev < 1e-6, "{ep} m, {ev} m/s");
    // The text form lists every query.
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(text.matches("\nat ").count(), 4, "{text}");
    // Without --from/--to the window is the whole recording.
    let whole = json(&[&base[..], &["--at", "500000000"]].concat());
    assert_eq!(whole["at"][0]["t_ns"], 500_000_000);
}

#[test]
fn integrate_at_refuses_times_outside_the_window_or_out_of_order() {
    let d = tmp("deskew-at-bad");
    simulate(
        &d,
        &[
            "--scene",
            "seed-ellipse",
            "--noise",
            "none",
            "--duration",
            "3",
        ],
    );
    let imu = d.join("imu.csv");
    let base = [
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--from",
        "1000000000",
        "--to",
        "1500000000",
    ];
    for (at, msg) in [
        ("900000000", "outside the window"),
        ("1400000000,1200000000", "earlier than the previous query"),
        ("6x", "invalid"),
    ] {
        let o = run(&[&base[..], &["--at", at]].concat());
        assert_eq!(o.status.code(), Some(2), "--at {at}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(msg), "--at {at}: {err}");
    }
}
