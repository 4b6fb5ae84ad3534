//! `integrate --truncation`: the window's own discretisation error, estimated from its samples,
//! against the error the ground truth shows.

mod common;

use common::{json, nums, simulate, tmp, true_delta_v};
use nalgebra::Vector3;

#[test]
fn integrate_truncation_estimates_the_error_the_ground_truth_shows() {
    let dir = tmp("truncation");
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--noise",
            "none",
            "--rate",
            "20",
            "--duration",
            "3",
        ],
    );
    let imu = dir.join("imu.csv");
    // The body's true Δv over [1 s, 2 s] from the written ground truth.
    let dv_true = true_delta_v(&dir, 1_000_000_000, 2_000_000_000);
    for scheme in ["euler", "midpoint"] {
        let out = json(&[
            "integrate",
            "--imu",
            imu.to_str().unwrap(),
            "--scheme",
            scheme,
            "--from",
            "1000000000",
            "--to",
            "2000000000",
            "--truncation",
        ]);
        let dv = nums(&out["delta_v"]);
        let e_true = Vector3::new(dv[0], dv[1], dv[2]) - dv_true;
        let e = nums(&out["truncation"]["error"]);
        let e_est = Vector3::new(e[3], e[4], e[5]);
        let rel = (e_est - e_true).norm() / e_true.norm();
        println!(
            "{scheme}: true Δv error {:.3e} m/s, estimate {:.3e}, relative {rel:.1e}",
            e_true.norm(),
            e_est.norm()
        );
        assert!(rel < 0.02, "{scheme}: {rel}");
        assert_eq!(out["truncation"]["method"], "hermite4 companion");
    }
    let plain = json(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--from",
        "1000000000",
        "--to",
        "2000000000",
    ]);
    assert!(plain["truncation"].is_null());
}
