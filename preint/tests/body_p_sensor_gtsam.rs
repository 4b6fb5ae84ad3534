//! `body_p_sensor` against GTSAM 4.3 (PyPI wheel; fixtures written by
//! `tests/fixtures/gtsam/generate_body_p_sensor.py`, which documents both cases).
//!
//! - Rotation only (`r = 0`), `example.csv`, Euler (= GTSAM
//!   `PreintegratedImuMeasurementsManifold`, Forster's scheme): deltas and covariance equal
//!   GTSAM's to ≤ 1e-12 relative. Bias Jacobians: GTSAM's Manifold backend's analytic ones
//!   leave out `R_bs` and disagree with central differences of its own deltas (by 70–85 %,
//!   asserted > 10 %); ours equal those central differences to ≤ 1e-6 relative (the
//!   differencing error).
//! - Lever arm on GTSAM's exact case (constant rate, body origin at rest): GTSAM subtracts the
//!   centripetal term per sample, which is exact here and makes its Euler deltas exact (the
//!   Euler error of the sensor's circular motion cancels). This crate removes the lever arm by
//!   the exact end-point identity (`preint::SensorPose`), so its deltas carry the scheme's
//!   error on the sensor's own motion: reported per scheme and asserted at each scheme's
//!   order (Euler ≤ 5e-4 m/s at 200 Hz, midpoint ≤ 1e-6, hermite4 ≤ 1e-9). Both covariances
//!   are consistent by Monte Carlo on this stream (GTSAM's mean NEES from the generator, this
//!   crate's measured here with its own seeded noise, 2 000 realisations each).

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};
use preint::lie::SO3;
use preint::{
    ImuBias, ImuSample, Level, LeverArm, PreintParams, Preintegrator, Scheme, SensorPose,
};
use preint_io::parse_euroc_imu;
use serde_json::Value;
mod common;
use common::gtsam_fixture::{dir, json, m3, mat, v3};

fn pose(f: &Value) -> SensorPose {
    SensorPose::new(
        SO3::from_matrix_unchecked(m3(&f["body_R_sensor"])),
        v3(&f["body_t_sensor"]),
    )
}

fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

#[test]
fn rotation_only_equals_gtsam() {
    let f = json("body_p_sensor_rotation.gtsam.json");
    let text = std::fs::read_to_string(dir().join("example.csv")).unwrap();
    let samples = parse_euroc_imu(&text, "example.csv").unwrap();
    let mut p = PreintParams::default()
        .with_scheme(Scheme::Euler)
        .with_level(Level::Covariance)
        .with_gravity(Vector3::new(0.0, 0.0, -9.81))
        .with_body_p_sensor(pose(&f));
    let d = f["gyro_noise_density"].as_f64().unwrap();
    let a = f["accel_noise_density"].as_f64().unwrap();
    p.gyro_cov = Matrix3::identity() * d * d;
    p.acc_cov = Matrix3::identity() * a * a;
    let bias = ImuBias::new(v3(&f["bias_hat"]["gyro"]), v3(&f["bias_hat"]["acc"]));
    let mut pi = Preintegrator::new(p, bias).unwrap();
    pi.integrate_slice(&samples).unwrap();
    let m = pi.finish().unwrap();
    assert_equals_gtsam("rotation only", &m, &f);
    let (fd, ana) = (&f["bias_jacobians_finite_difference"], &f["bias_jacobians"]);
    for (name, _) in jacobians(&m) {
        let g = rel(&mat(&ana[name]), &mat(&fd[name]));
        println!("{name}: GTSAM's analytic vs central differences of its deltas {g:.1e}");
        assert!(g > 0.1, "{name}: GTSAM's analytic Jacobian {g:e}");
    }
}

fn dm(x: &Matrix3<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(3, 3, x.as_slice())
}

/// The five bias Jacobians of `m` with their fixture names.
fn jacobians(m: &preint::PreintegratedImu) -> [(&'static str, Matrix3<f64>); 5] {
    [
        ("dR_dbg", m.jac.d_r_d_bg),
        ("dv_dbg", m.jac.d_v_d_bg),
        ("dv_dba", m.jac.d_v_d_ba),
        ("dp_dbg", m.jac.d_p_d_bg),
        ("dp_dba", m.jac.d_p_d_ba),
    ]
}

/// Asserts `m`'s deltas and covariance equal the fixture's (≤ 1e-12 relative) and its bias
/// Jacobians equal central differences of GTSAM's deltas (≤ 1e-6, the differencing error).
fn assert_equals_gtsam(case: &str, m: &preint::PreintegratedImu, f: &Value) {
    let dv = |x: &Vector3<f64>| DMatrix::from_column_slice(3, 1, x.as_slice());
    let cov = DMatrix::from_column_slice(9, 9, m.cov.as_slice());
    let checks = [
        ("delta_R", rel(&dm(m.delta_r.matrix()), &mat(&f["delta_R"]))),
        ("delta_v", rel(&dv(&m.delta_v), &dv(&v3(&f["delta_v"])))),
        ("delta_p", rel(&dv(&m.delta_p), &dv(&v3(&f["delta_p"])))),
        ("covariance", rel(&cov, &mat(&f["covariance"]))),
    ];
    for (name, e) in checks {
        println!("{case}, {name}: max relative difference to GTSAM {e:.1e}");
        assert!(e <= 1e-12, "{case}, {name}: {e:e}");
    }
    let fd = &f["bias_jacobians_finite_difference"];
    for (name, j) in jacobians(m) {
        let e = rel(&dm(&j), &mat(&fd[name]));
        println!("{case}, {name}: vs central differences of GTSAM's deltas {e:.1e}");
        assert!(e <= 1e-6, "{case}, {name}: {e:e}");
    }
}

/// The lever-arm stream of the generator, rebuilt here from its documented formulas.
fn lever_stream(f: &Value) -> Vec<ImuSample> {
    let pose = pose(f);
    let w = v3(&f["omega_b"]);
    let g = v3(&f["gravity"]);
    let r = pose.translation;
    let rt = pose.rotation.inverse();
    (0..=200i64)
        .map(|k| {
            let t_ns = k * 5_000_000;
            let rwb = SO3::exp(&(w * (t_ns as f64 * 1e-9)));
            let f_b = rwb.inverse().act(&(-g));
            ImuSample::new(t_ns, rt.act(&w), rt.act(&(f_b + w.cross(&w.cross(&r)))))
        })
        .collect()
}

#[test]
fn lever_arm_on_gtsams_exact_case() {
    let f = json("body_p_sensor_lever.gtsam.json");
    let s = lever_stream(&f);
    let (tv, tp) = (v3(&f["true_delta_v"]), v3(&f["true_delta_p"]));
    let gv = (v3(&f["delta_v"]) - tv).norm();
    let gp = (v3(&f["delta_p"]) - tp).norm();
    println!("GTSAM (euler, centripetal per sample): |δv| {gv:.1e} m/s, |δp| {gp:.1e} m");
    assert!(
        gv < 1e-12,
        "the fixture's case is GTSAM's exact one: {gv:e}"
    );
    for (scheme, bound) in [
        (Scheme::Euler, 5e-4),
        (Scheme::Midpoint, 1e-6),
        (Scheme::Hermite4, 1e-9),
    ] {
        let p = PreintParams::default()
            .with_scheme(scheme)
            .with_level(Level::Deltas)
            .with_body_p_sensor(pose(&f));
        let mut pi = Preintegrator::new(p, ImuBias::zero()).unwrap();
        pi.integrate_slice(&s).unwrap();
        let m = pi.finish().unwrap();
        let (ev, ep) = ((m.delta_v - tv).norm(), (m.delta_p - tp).norm());
        println!(
            "{:<9} exact lever-arm identity: |δv| {ev:.1e} m/s, |δp| {ep:.1e} m",
            scheme.name()
        );
        assert!(ev <= bound && ep <= bound, "{scheme:?}: {ev:e} {ep:e}");
    }
    let gtsam_nees = f["monte_carlo"]["mean_nees9"].as_f64().unwrap();
    println!("GTSAM's covariance on this stream: mean NEES {gtsam_nees:.3} (2 000 realisations)");
    assert!((gtsam_nees - 9.0).abs() < 0.4, "{gtsam_nees}");
}

/// Seeded xorshift + Box–Muller, independent of the code under test.
struct Normal(u64);

impl Normal {
    fn next(&mut self) -> f64 {
        let mut u = || {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

#[test]
fn lever_arm_covariance_is_consistent_on_gtsams_case() {
    let f = json("body_p_sensor_lever.gtsam.json");
    let s = lever_stream(&f);
    let (gd, ad) = (
        f["gyro_noise_density"].as_f64().unwrap(),
        f["accel_noise_density"].as_f64().unwrap(),
    );
    let dt: f64 = 0.005;
    let mut p = PreintParams::default()
        .with_scheme(Scheme::Euler)
        .with_level(Level::Covariance)
        .with_body_p_sensor(pose(&f));
    p.gyro_cov = Matrix3::identity() * gd * gd;
    p.acc_cov = Matrix3::identity() * ad * ad;
    let run = |x: &[ImuSample]| {
        let mut pi = Preintegrator::new(p.clone(), ImuBias::zero()).unwrap();
        pi.integrate_slice(x).unwrap();
        pi.finish().unwrap()
    };
    let m0 = run(&s);
    let mut rng = Normal(0x9E37_79B9_7F4A_7C15);
    let trials = 2000;
    let mut sum = 0.0;
    for _ in 0..trials {
        let noisy: Vec<ImuSample> = s
            .iter()
            .map(|x| {
                let mut n3 = |sd: f64| Vector3::new(rng.next(), rng.next(), rng.next()) * sd;
                let (ng, na) = (n3(gd / dt.sqrt()), n3(ad / dt.sqrt()));
                ImuSample::new(x.t_ns, x.gyro + ng, x.acc + na)
            })
            .collect();
        let m = run(&noisy);
        let e = m.delta_error(&m0);
        let cov: SMatrix<f64, 9, 9> = m.cov;
        sum += e.dot(&cov.cholesky().unwrap().solve(&e));
    }
    let mean = sum / trials as f64;
    println!(
        "this crate's covariance with the lever arm: mean NEES {mean:.3} ({trials} realisations)"
    );
    assert!((mean - 9.0).abs() < 0.4, "{mean}");
}

/// `LeverArm::Centripetal` is GTSAM's model: on the lever-arm stream, Euler's deltas and
/// covariance equal GTSAM's to ≤ 1e-12 relative, and its bias Jacobians equal central
/// differences of GTSAM's deltas (GTSAM's Manifold analytic ones omit `R_bs`, as above).
#[test]
fn centripetal_mode_equals_gtsam_with_a_lever_arm() {
    let f = json("body_p_sensor_lever.gtsam.json");
    let s = lever_stream(&f);
    let (gd, ad) = (
        f["gyro_noise_density"].as_f64().unwrap(),
        f["accel_noise_density"].as_f64().unwrap(),
    );
    let mut p = PreintParams::default()
        .with_scheme(Scheme::Euler)
        .with_level(Level::Covariance)
        .with_body_p_sensor(pose(&f));
    p.lever_arm = LeverArm::Centripetal;
    p.gyro_cov = Matrix3::identity() * gd * gd;
    p.acc_cov = Matrix3::identity() * ad * ad;
    let mut pi = Preintegrator::new(p, ImuBias::zero()).unwrap();
    pi.integrate_slice(&s).unwrap();
    let m = pi.finish().unwrap();
    assert_equals_gtsam("centripetal mode", &m, &f);
}
