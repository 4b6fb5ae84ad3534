//! `preint::second_order`: how the term scales with the noise densities, what it does with a
//! rotated sensor, and typed errors for bad input. Its effect at the point of use (the factor's
//! χ² at the true states) is measured in `tests/tests/factor_logmap_nees.rs`.

mod common;

use common::Scene;
use nalgebra::{Matrix3, Vector3};
use preint::lie::SO3;
use preint::{
    ImuBias, ImuSample, Level, PreintError, PreintParams, Scheme, SensorPose, preintegrate,
    second_order,
};

fn params(sigma_g: f64, sigma_a: f64) -> PreintParams {
    densities(
        Matrix3::identity() * sigma_g * sigma_g,
        Matrix3::identity() * sigma_a * sigma_a,
    )
}

fn densities(gyro_cov: Matrix3<f64>, acc_cov: Matrix3<f64>) -> PreintParams {
    PreintParams {
        gyro_cov,
        acc_cov,
        ..PreintParams::default()
    }
    .with_scheme(Scheme::Midpoint)
    .with_level(Level::Covariance)
}

fn term(p: &PreintParams, s: &[ImuSample]) -> nalgebra::SMatrix<f64, 9, 9> {
    let (t0, t1) = (s[0].t_ns, s[s.len() - 1].t_ns);
    let m = preintegrate(p, &ImuBias::zero(), s, t0, t1).unwrap();
    second_order::covariance(p, s, &m).unwrap()
}

#[test]
fn the_term_is_fourth_order_in_the_gyro_density_and_needs_gyro_noise() {
    let s = Scene::smooth().samples(5_000_000, 5_000_000_000);
    // σ_a = 0: P ∝ σ_g² and each interval's rotation noise ∝ σ_g², so the term ∝ σ_g⁴, up to
    // its own share inside the bracket (order σ_g⁶: relative 3e-4 at σ_g = 0.01, 3e-6 here).
    let (a, b) = (term(&params(0.001, 0.0), &s), term(&params(0.002, 0.0), &s));
    assert!(a.norm() > 0.0);
    let rel = (b - a * 16.0).norm() / b.norm();
    assert!(rel <= 1e-5, "{rel}");
    // No gyro noise: no rotation error to rotate anything, no term.
    assert_eq!(term(&params(0.0, 0.05), &s).norm(), 0.0);
    // Both: the accelerometer adds `K_a(P_φφ)` and σ_g² σ_a²-terms, so more than gyro alone.
    let both = term(&params(0.001, 0.05), &s);
    assert!(both.trace() > a.trace());
}

#[test]
fn a_rotated_sensor_gives_the_body_term_of_the_rotated_samples() {
    let s = Scene::smooth().samples(5_000_000, 3_000_000_000);
    let r_bs = SO3::exp(&Vector3::new(0.3, -0.7, 1.1));
    let sensor: Vec<ImuSample> = s
        .iter()
        .map(|x| {
            let rt = r_bs.matrix().transpose();
            ImuSample::new(x.t_ns, rt * x.gyro, rt * x.acc)
        })
        .collect();
    // Anisotropic densities, given in the sensor's axes.
    let d = Matrix3::from_diagonal(&Vector3::new(1e-4, 4e-4, 2e-4));
    let mounted =
        densities(d, d * 10.0).with_body_p_sensor(SensorPose::new(r_bs, Vector3::zeros()));
    let rm = r_bs.matrix();
    let body = densities(rm * d * rm.transpose(), rm * d * rm.transpose() * 10.0);
    let (a, b) = (term(&mounted, &sensor), term(&body, &s));
    assert!(
        (a - b).norm() <= 1e-9 * b.norm(),
        "{}",
        (a - b).norm() / b.norm()
    );
}

#[test]
fn bad_input_is_a_typed_error() {
    let mut s = Scene::smooth().samples(5_000_000, 1_000_000_000);
    let p = params(0.01, 0.01);
    let m = preintegrate(&p, &ImuBias::zero(), &s, 0, 1_000_000_000).unwrap();
    s[7].gyro.y = f64::NAN;
    assert!(matches!(
        second_order::covariance(&p, &s, &m),
        Err(PreintError::NonFinite { index: 7, .. })
    ));
    let short = &s[100..];
    assert!(matches!(
        second_order::covariance(&p, short, &m),
        Err(PreintError::KeyframeOutsideSamples { .. })
    ));
}
