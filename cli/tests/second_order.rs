//! `integrate --second-order` and `factor --second-order`: the second-order covariance term of a
//! long window (`preint::second_order`) on a simulated recording with a noisy MEMS
//! gyroscope (σ_g = 0.015 rad/s/√Hz, σ_a = 0.019 m/s²/√Hz), and its absence of effect at
//! EuRoC densities.

mod common;

use common::{json, simulate, tmp};
use nalgebra::SMatrix;

fn matrix9(v: &serde_json::Value) -> SMatrix<f64, 9, 9> {
    SMatrix::<f64, 9, 9>::from_fn(|i, j| v[i][j].as_f64().unwrap())
}

/// A Kalibr imu.yaml with the given white-noise densities and EuRoC's random walks.
fn noise_yaml(dir: &std::path::Path, gyro: f64, acc: f64) -> String {
    let path = dir.join("noise.yaml");
    std::fs::write(
        &path,
        format!(
            "gyroscope_noise_density: {gyro}\naccelerometer_noise_density: {acc}\n\
             gyroscope_random_walk: 1.9393e-05\naccelerometer_random_walk: 3.0e-03\n\
             update_rate: 200.0\n"
        ),
    )
    .unwrap();
    path.to_str().unwrap().to_string()
}

/// `integrate --second-order` over [1 s, 11 s] of a 12 s `aggressive` recording.
fn term(dir: &std::path::Path, noise: &str) -> serde_json::Value {
    simulate(
        dir,
        &[
            "--scene",
            "aggressive",
            "--duration",
            "12",
            "--noise",
            noise,
        ],
    );
    let imu = dir.join("imu.csv");
    json(&[
        "integrate",
        "--imu",
        imu.to_str().unwrap(),
        "--noise",
        noise,
        "--scheme",
        "hermite4",
        "--from",
        "1000000000",
        "--to",
        "11000000000",
        "--second-order",
    ])
}

#[test]
fn integrate_reports_a_positive_term_that_matters_only_for_a_noisy_gyro() {
    let dir = tmp("second-order-seed");
    let out = term(&dir, &noise_yaml(&dir, 0.015, 0.019));
    let s = matrix9(&out["second_order"]["covariance"]);
    let eig = s.symmetric_eigen().eigenvalues;
    let (lo, hi) = (eig.min(), eig.max());
    assert!(
        hi > 0.0 && lo > -1e-12 * hi,
        "not positive semi-definite: {eig:?}"
    );
    assert!((s - s.transpose()).norm() <= 1e-12 * s.norm());
    // The mean χ² it accounts for: the Monte Carlo excess of the first-order weight on this
    // scene is 0.23 (9 dof, `tests/tests/factor_logmap_nees.rs`).
    let inc = out["second_order"]["chi2_increase"].as_f64().unwrap();
    println!("noisy-MEMS densities: chi2 increase {inc:.3}");
    assert!((0.1..0.6).contains(&inc), "{inc}");

    let dir = tmp("second-order-euroc");
    let out = term(&dir, &noise_yaml(&dir, 1.6968e-4, 2.0e-3));
    let inc = out["second_order"]["chi2_increase"].as_f64().unwrap();
    println!("EuRoC densities: chi2 increase {inc:.2e}");
    assert!(inc < 1e-3, "{inc}");
}

#[test]
fn factor_weighted_with_the_term_has_a_smaller_chi2() {
    let dir = tmp("second-order-factor");
    let noise = noise_yaml(&dir, 0.015, 0.019);
    simulate(
        &dir,
        &[
            "--scene",
            "aggressive",
            "--duration",
            "12",
            "--noise",
            &noise,
        ],
    );
    let (imu, gt) = (dir.join("imu.csv"), dir.join("groundtruth.csv"));
    let run = |extra: &[&str]| {
        let mut a = vec![
            "factor",
            "--imu",
            imu.to_str().unwrap(),
            "--poses",
            gt.to_str().unwrap(),
            "--noise",
            &noise,
            "--scheme",
            "hermite4",
            "--from",
            "1000000000",
            "--to",
            "11000000000",
        ];
        a.extend_from_slice(extra);
        json(&a)
    };
    let (plain, second) = (run(&[]), run(&["--second-order"]));
    let chi2 = |v: &serde_json::Value| v["chi2"].as_f64().unwrap();
    println!("χ² {} plain, {} with the term", chi2(&plain), chi2(&second));
    assert_eq!(second["second_order"], true);
    assert_eq!(plain["second_order"], false);
    assert!(
        chi2(&second) < chi2(&plain),
        "{} {}",
        chi2(&second),
        chi2(&plain)
    );
}
