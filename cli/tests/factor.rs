//! `preint factor`: the IMU factor at ground-truth states, end to end.

mod common;

use common::{EUROC_DENSITIES, json, nums, run, simulate, tmp, vec3, write_noise_yaml};
use serde_json::Value;

/// Simulates `aggressive` at 200 Hz with the EuRoC densities, with (`walk`) or without the
/// bias random walk.
fn simulate_aggressive(dir: &std::path::Path, seed: u64, duration: &str, walk: bool) {
    let mut d = EUROC_DENSITIES;
    if !walk {
        (d[1], d[3]) = (0.0, 0.0);
    }
    let yaml = write_noise_yaml(dir, "noise.yaml", d, 200.0);
    let out = simulate(
        dir,
        &[
            "--noise",
            yaml.to_str().unwrap(),
            "--scene",
            "aggressive",
            "--rate",
            "200",
            "--duration",
            duration,
            "--seed",
            &seed.to_string(),
        ],
    );
    assert_eq!(out["scene"], "aggressive");
}

fn factor(dir: &std::path::Path, extra: &[&str]) -> Value {
    let imu = dir.join("imu.csv");
    let gt = dir.join("groundtruth.csv");
    let mut args = vec![
        "factor",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
        "--noise",
    ];
    let yaml = dir.join("imu.yaml");
    args.push(yaml.to_str().unwrap());
    args.extend_from_slice(extra);
    json(&args)
}

/// On simulated data (EuRoC densities) the factor at the simulator's truth has χ² distributed
/// as χ²₉ (ImuFactor, data with a constant bias: the 9-dim factor holds the bias fixed over the
/// window) and χ²₁₅ (CombinedImuFactor, data whose bias follows its random walk): the mean
/// over 40 seeds of 2 s windows is within 4 standard deviations of the mean
/// (9 ± 4·√(18/40) = 9 ± 2.7, 15 ± 4·√(30/40) = 15 ± 3.5). The combined factor weighted with
/// the error state's delta–bias blocks instead of the residual's gives 32.4 here, outside.
/// Also the JSON contract: the residual's order and length, `‖U r‖² = χ²`, keyframes on
/// ground-truth rows, the ground truth's bias at i as the estimate.
#[test]
fn chi2_at_the_simulated_truth_is_consistent() {
    let d = tmp("factor-mc");
    let seeds = 40u64;
    let (mut sum9, mut sum15) = (0.0, 0.0);
    for seed in 0..seeds {
        // 1.0026 s is between two ground-truth rows (5 ms apart): the nearer one, 1.005 s.
        let range = [
            "--from",
            "1002600000",
            "--to",
            "3000000000",
            "--scheme",
            "rk4",
        ];
        simulate_aggressive(&d, seed + 100, "3", false);
        let f9 = factor(&d, &range);
        simulate_aggressive(&d, seed + 100, "3", true);
        let mut args = range.to_vec();
        args.push("--combined");
        let f15 = factor(&d, &args);
        for (f, dof) in [(&f9, 9usize), (&f15, 15)] {
            assert_eq!(f["dof"].as_u64().unwrap() as usize, dof);
            assert_eq!(f["residual_order"].as_array().unwrap().len(), dof);
            assert_eq!(f["residual_order"][3], "r_v_x");
            let w = nums(&f["whitened_residual"]);
            assert_eq!(w.len(), dof);
            let chi2 = f["chi2"].as_f64().unwrap();
            let norm2: f64 = w.iter().map(|x| x * x).sum();
            assert!((norm2 - chi2).abs() <= 1e-12 * chi2.max(1.0));
            assert_eq!(f["t_i_ns"].as_i64().unwrap(), 1_005_000_000);
            assert_eq!(f["t_j_ns"].as_i64().unwrap(), 3_000_000_000);
            assert_eq!(
                vec3(&f["bias_hat"]["gyro"]),
                vec3(&f["state_i"]["bias_gyro"])
            );
        }
        assert_eq!(f15["factor"], "CombinedImuFactor");
        sum9 += f9["chi2"].as_f64().unwrap();
        sum15 += f15["chi2"].as_f64().unwrap();
    }
    let (m9, m15) = (sum9 / seeds as f64, sum15 / seeds as f64);
    println!("mean χ² over {seeds} seeds: ImuFactor {m9:.3}, CombinedImuFactor {m15:.3}");
    assert!(
        (m9 - 9.0).abs() <= 4.0 * (18.0 / seeds as f64).sqrt(),
        "{m9}"
    );
    assert!(
        (m15 - 15.0).abs() <= 4.0 * (30.0 / seeds as f64).sqrt(),
        "{m15}"
    );
}

/// The ground truth's own errors enter the weight: larger stated errors, smaller χ².
#[test]
fn ground_truth_noise_lowers_chi2() {
    let d = tmp("factor-gtnoise");
    simulate_aggressive(&d, 7, "3", false);
    let base = ["--from", "1000000000", "--to", "2000000000"];
    let plain = factor(&d, &base)["chi2"].as_f64().unwrap();
    let mut args = base.to_vec();
    args.extend_from_slice(&["--pose-rot-std", "0.01", "--pose-pos-std", "0.05"]);
    let noisy = factor(&d, &args);
    assert!(
        noisy["chi2"].as_f64().unwrap() < 0.5 * plain,
        "{plain} {noisy}"
    );
    assert_eq!(noisy["ground_truth_noise"]["pos_m"], 0.05);
}

#[test]
fn bad_keyframes_and_flags_are_usage_errors() {
    let d = tmp("factor-bad");
    simulate_aggressive(&d, 1, "1", true);
    let imu = d.join("imu.csv");
    let gt = d.join("groundtruth.csv");
    let base = [
        "factor",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
    ];
    let err = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{extra:?}");
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    // Both times snap to the same row (or the order is reversed).
    let e = err(&["--from", "500000000", "--to", "500000001"]);
    assert!(
        e.contains("two different rows") && e.contains("groundtruth.csv"),
        "{e}"
    );
    let e = err(&["--from", "800000000", "--to", "200000000"]);
    assert!(
        e.contains("--from 800000000 is not before --to 200000000"),
        "{e}"
    );
    let e = err(&["--from", "0", "--to", "900000000", "--pose-pos-std=-1"]);
    assert!(e.contains("--pose-pos-std"), "{e}");
    let o = run(&[
        "factor",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        "/nonexistent/gt.csv",
        "--from",
        "0",
        "--to",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/gt.csv"));
}

/// `--residual component|logmap`: the default is the library's (Logmap), printed in the JSON
/// and the text; the two residuals share the rotation rows and differ in the velocity and
/// position rows (rotated by ΔRᵀ and sheared by Jl(r_φ)⁻¹), their χ² agree to first order in
/// the residual; an unknown name is a usage error.
#[test]
fn residual_mode_flag() {
    let d = tmp("factor-residual");
    simulate_aggressive(&d, 3, "3", true);
    let base = ["--from", "1000000000", "--to", "3000000000"];
    for combined in [false, true] {
        let mut a = base.to_vec();
        if combined {
            a.push("--combined");
        }
        let default = factor(&d, &a);
        let mut al = a.clone();
        al.extend_from_slice(&["--residual", "logmap"]);
        let lm = factor(&d, &al);
        let mut ac = a.clone();
        ac.extend_from_slice(&["--residual", "component"]);
        let cw = factor(&d, &ac);
        assert_eq!(default["residual_mode"], "logmap");
        assert_eq!(default["residual"], lm["residual"]);
        assert_eq!(cw["residual_mode"], "component");
        let (rl, rc) = (nums(&lm["residual"]), nums(&cw["residual"]));
        assert_eq!(rl[..3], rc[..3], "same rotation rows");
        assert_eq!(rl[9..], rc[9..], "same bias rows");
        let diff = (3..9).map(|k| (rl[k] - rc[k]).abs()).fold(0.0, f64::max);
        assert!(diff > 1e-6, "velocity/position rows differ: {diff}");
        let (xl, xc) = (lm["chi2"].as_f64().unwrap(), cw["chi2"].as_f64().unwrap());
        assert!((xl - xc).abs() < 0.05 * xc, "χ² {xl} vs {xc}");
        assert!(lm["weight"].as_str().unwrap().contains("Logmap"));
    }
    let imu = d.join("imu.csv");
    let gt = d.join("groundtruth.csv");
    let yaml = d.join("imu.yaml");
    let mut args = vec![
        "factor",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        gt.to_str().unwrap(),
        "--noise",
        yaml.to_str().unwrap(),
    ];
    args.extend_from_slice(&base);
    let o = run(&args);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("ImuFactor (logmap residual)"), "{text}");
    args.extend_from_slice(&["--residual", "tangent"]);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("component or logmap"));
}
