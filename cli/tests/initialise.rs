//! `preint initialise` through the binary: keyframe poses of a simulated flight, in a world
//! turned 90° about x and known up to a scale of 0.25 m per unit, give the scale within 3σ,
//! gravity along the poses' world −y, and a ready verdict; a window too short to see the
//! scale still exits 0 with `ready: false` and says why; bad keyframe files and flags are
//! refused naming them.

mod common;

use common::{json, nums, run, simulate, tmp, write};
use preint_lie::SO3;

const SCALE: f64 = 0.25;

/// The ground truth as `t,x,y,z,qw,qx,qy,qz` in a world turned 90° about x, positions divided
/// by `SCALE` (metres per unit).
fn up_to_scale_poses(dir: &std::path::Path) -> std::path::PathBuf {
    let gt = preint_io::read_euroc_groundtruth(&dir.join("groundtruth.csv")).unwrap();
    let r_w = SO3::exp(&nalgebra::Vector3::new(
        std::f64::consts::FRAC_PI_2,
        0.0,
        0.0,
    ));
    let mut text = String::from("# t,x,y,z,qw,qx,qy,qz\n");
    for s in gt.iter().step_by(4) {
        let p = r_w.act(&s.p) / SCALE;
        let q = r_w.compose(&s.rotation()).to_quaternion();
        text.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            s.t_ns, p.x, p.y, p.z, q.w, q.i, q.j, q.k
        ));
    }
    write(dir, "keyframes.csv", &text)
}

#[test]
fn scale_and_gravity_from_up_to_scale_keyframes_through_the_binary() {
    let dir = tmp("initialise");
    simulate(&dir, &["--scene", "aggressive", "--duration", "5"]);
    let poses = up_to_scale_poses(&dir);
    let imu = dir.join("imu.csv");
    let (imu, poses) = (imu.to_str().unwrap(), poses.to_str().unwrap());
    let base = [
        "initialise",
        "--imu",
        imu,
        "--poses",
        poses,
        "--pose-pos-std",
        "1e-3",
        "--pose-rot-std",
        "1e-4",
    ];
    let j = json(&base);
    let (s, sd) = (
        j["scale"].as_f64().unwrap(),
        j["scale_std"].as_f64().unwrap(),
    );
    assert!(
        (s - SCALE).abs() <= 3.0 * sd && sd < 0.01 * SCALE,
        "{s} ± {sd}"
    );
    assert_eq!(j["ready"], true, "{}", j["reason"]);
    let g = nums(&j["gravity"]);
    // World turned 90° about x: (0, 0, −9.81) becomes (0, 9.81, 0).
    assert!(
        (g[1] - 9.81).abs() < 0.01 && g[0].abs() < 0.1 && g[2].abs() < 0.1,
        "{g:?}"
    );
    assert_eq!(j["covariance_order"][0], "s");
    assert_eq!(j["covariance"].as_array().unwrap().len(), 10);
    assert_eq!(
        j["velocities"].as_array().unwrap().len(),
        j["keyframes"].as_u64().unwrap() as usize
    );
    let text = String::from_utf8_lossy(&run(&base).stdout).to_string();
    assert!(
        text.contains("m per unit of the poses") && text.contains("ready:"),
        "{text}"
    );

    // 0.3 s of keyframes: not ready, exit 0, the reason given.
    let t0 = j["velocities"][0]["t_ns"].as_i64().unwrap();
    let to = (t0 + 300_000_000).to_string();
    let mut short = base.to_vec();
    short.extend(["--to", &to]);
    let j = json(&short);
    assert_eq!(j["ready"], false);
    assert!(
        j["reason"]
            .as_str()
            .unwrap()
            .contains("not ready; move more"),
        "{}",
        j["reason"]
    );

    // Metric poses: --scale known gives scale 1 and no scale σ.
    let metric = dir.join("groundtruth.csv");
    let j = json(&[
        "initialise",
        "--imu",
        imu,
        "--poses",
        metric.to_str().unwrap(),
        "--scale",
        "known",
    ]);
    assert_eq!(
        (j["scale"].as_f64(), j["scale_std"].as_f64()),
        (Some(1.0), Some(0.0))
    );
    assert_eq!(j["scale_mode"], "known");
}

#[test]
fn bad_keyframes_and_flags_are_refused_naming_them() {
    let dir = tmp("initialise-bad");
    simulate(&dir, &["--scene", "aggressive", "--duration", "1"]);
    let imu = dir.join("imu.csv");
    let imu = imu.to_str().unwrap();
    let gt = preint_io::read_euroc_groundtruth(&dir.join("groundtruth.csv")).unwrap();
    let mut att = String::from("# t,qw,qx,qy,qz\n");
    for s in gt.iter().step_by(20) {
        att.push_str(&format!("{},1,0,0,0\n", s.t_ns));
    }
    let att = write(&dir, "attitudes.csv", &att);
    let o = run(&["initialise", "--imu", imu, "--poses", att.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("attitudes only") && e.contains("attitudes.csv"),
        "{e}"
    );
    let metric = dir.join("groundtruth.csv");
    let metric = metric.to_str().unwrap();
    for (flags, needle) in [
        (&["--bias-prior-std", "0,0.2"][..], "--bias-prior-std"),
        (&["--pose-spacing", "-1"][..], "--pose-spacing"),
        (&["--scale", "metric"][..], "--scale"),
        (&["--pose-spacing", "5"][..], "fewer than three poses"),
    ] {
        let mut a = vec!["initialise", "--imu", imu, "--poses", metric];
        a.extend_from_slice(flags);
        let o = run(&a);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(needle), "{flags:?}: {e}");
    }
}
