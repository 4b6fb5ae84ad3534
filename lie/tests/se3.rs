//! SE(3): round trips, properties and Jacobians against central differences.
#![allow(clippy::excessive_precision)] // 20-digit references from mpmath, kept as printed.

mod common;
use common::*;
use lie::se3::{self, hat6, q_coeffs, vee6};
use lie::{SE3, SO3};
use nalgebra::{Matrix4, Matrix6, Vector3, Vector6};
use proptest::prelude::*;
use std::f64::consts::PI;

/// (θ, [(θ² + 2cosθ − 2)/(2θ⁴), (2θ − 3 sinθ + θ cosθ)/(2θ⁵)]) from mpmath, 50 digits.
const QREF: &[(f64, [f64; 2])] = &[
    (1e-8, [0.041666666666666666682, 0.0083333333333333331822]),
    (0.01, [0.041666527778025793375, 0.0083332936508763226511]),
    (0.5, [0.041320990245963457861, 0.0082346421212377158124]),
    (1.0, [0.040302305868139717401, 0.0079446757222250987217]),
    (1.9999, [0.036491303980702502001, 0.0068722285924506480539]),
    (2.0001, [0.036490341433781175322, 0.0068719603540237861473]),
    (3.0, [0.030987746955550056083, 0.0053635030576523908681]),
];

#[test]
fn q_coefficients_match_high_precision() {
    for &(t, r) in QREF {
        let (_, b, c) = q_coeffs(t * t);
        // Above θ = 2 the closed forms cancel a few bits.
        let tol = if t < 2.0 { 4e-16 } else { 1e-14 };
        assert!((b - r[0]).abs() <= tol * r[0], "b({t}) = {b} vs {}", r[0]);
        assert!((c - r[1]).abs() <= tol * r[1], "c({t}) = {c} vs {}", r[1]);
    }
}

fn xi(rho: [f64; 3], theta: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(rho[0], rho[1], rho[2], theta.x, theta.y, theta.z)
}

#[test]
fn round_trips_at_the_hard_angles() {
    let axis = Vector3::new(0.2, -0.5, 0.8).normalize();
    for &t in &[
        0.0,
        1e-300,
        1e-15,
        1e-8,
        1e-4,
        1.0,
        PI - 1e-6,
        PI - 1e-10,
        PI,
    ] {
        let x = xi([0.3, -1.2, 2.5], axis * t);
        let g = SE3::exp(&x);
        let back = SE3::exp(&g.log());
        assert!(
            (back.matrix() - g.matrix()).norm() <= 1e-14 * 4.0,
            "θ = {t}"
        );
        if t <= PI - 1e-6 {
            assert!(
                (g.log() - x).norm() <= 1e-14 * x.norm(),
                "θ = {t}: {:e}",
                (g.log() - x).norm()
            );
        }
    }
}

#[test]
fn hat_vee_and_matrix_exp() {
    let x = xi([0.1, 0.2, -0.3], Vector3::new(0.4, -0.1, 0.2));
    assert_eq!(vee6(&hat6(&x)), x);
    // Matrix exponential by a long Taylor series as an independent reference.
    let a = hat6(&x);
    let mut term = Matrix4::identity();
    let mut sum = Matrix4::identity();
    for k in 1..30 {
        term = term * a / k as f64;
        sum += term;
    }
    assert!((SE3::exp(&x).matrix() - sum).amax() < 1e-15);
}

const H: f64 = 1e-6;

fn check6(name: &str, an: &Matrix6<f64>, num: nalgebra::DMatrix<f64>) {
    let e = rel_err(&dm(an), &num);
    assert!(
        e < 1e-8,
        "{name}: relative error {e:e}\nanalytic {an}\nnumeric {num}"
    );
}

#[test]
fn jacobians_match_central_differences() {
    let other = SE3::exp(&xi([0.5, -0.2, 0.1], Vector3::new(0.2, 0.7, -0.4)));
    let p = Vector3::new(1.5, -0.3, 2.2);
    for theta in [
        Vector3::new(1e-9, -2e-9, 1e-9),
        Vector3::new(1e-4, 3e-4, -2e-4),
        Vector3::new(0.3, -0.2, 0.5),
        Vector3::new(-1.1, 0.9, 1.7),
    ] {
        let x = xi([0.7, -1.3, 0.4], theta);
        let t = SE3::exp(&x);
        check6(
            "Jr",
            &se3::jr(&x),
            num_jac(|v: &Vector6<f64>| SE3::exp(v), &x, H),
        );
        let e0 = SE3::exp(&x);
        check6(
            "Jl",
            &se3::jl(&x),
            num_jac(
                |v: &Vector6<f64>| SE3::exp(v).compose(&e0.inverse()).log(),
                &x,
                H,
            ),
        );
        check6("log", &t.log_jac().1, num_jac(|g: &SE3| g.log(), &t, H));
        check6(
            "inverse",
            &t.inverse_jac().1,
            num_jac(|g: &SE3| g.inverse(), &t, H),
        );
        let (_, ja, jb) = t.compose_jac(&other);
        check6(
            "compose/a",
            &ja,
            num_jac(|g: &SE3| g.compose(&other), &t, H),
        );
        check6("compose/b", &jb, num_jac(|g: &SE3| t.compose(g), &other, H));
        let (_, jt, jp) = t.act_jac(&p);
        let e = rel_err(&dm(&jt), &num_jac(|g: &SE3| g.act(&p), &t, H));
        assert!(e < 1e-8, "act/T {e:e}");
        let e = rel_err(&dm(&jp), &num_jac(|v: &Vector3<f64>| t.act(v), &p, H));
        assert!(e < 1e-8, "act/x {e:e}");
        assert!((se3::jr(&x) * se3::jr_inv(&x) - Matrix6::identity()).amax() < 1e-12);
        assert!((se3::jl(&x) * se3::jl_inv(&x) - Matrix6::identity()).amax() < 1e-12);
    }
}

fn vec6(r: f64, a: f64) -> impl Strategy<Value = Vector6<f64>> {
    [-r..r, -r..r, -r..r, -a..a, -a..a, -a..a]
        .prop_map(|v| Vector6::new(v[0], v[1], v[2], v[3], v[4], v[5]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn exp_log_round_trip(x in vec6(5.0, 1.8)) {
        prop_assume!(x.fixed_rows::<3>(3).norm() < PI - 1e-6);
        prop_assert!((SE3::exp(&x).log() - x).norm() <= 2e-14 * x.norm().max(1e-300));
    }

    #[test]
    fn conjugation_is_adjoint(a in vec6(3.0, 1.8), x in vec6(3.0, 1.8)) {
        let t = SE3::exp(&a);
        let lhs = t.compose(&SE3::exp(&x)).compose(&t.inverse());
        let rhs = SE3::exp(&(t.adjoint() * x));
        prop_assert!((lhs.matrix() - rhs.matrix()).amax() < 1e-13);
    }

    #[test]
    fn exp_of_sum_second_order(x in vec6(3.0, 1.5), dir in vec6(1.0, 1.0)) {
        prop_assume!(dir.norm() > 0.1);
        let err = |s: f64| {
            let d = dir * s;
            SE3::exp(&(x + d)).minus(&SE3::exp(&x).compose(&SE3::exp(&(se3::jr(&x) * d)))).norm()
        };
        let (e1, e2) = (err(1e-3), err(5e-4));
        prop_assert!(e2 < 0.3 * e1 + 1e-14, "e1 {e1:e} e2 {e2:e}");
    }

    #[test]
    fn group_axioms(a in vec6(3.0, 3.0), b in vec6(3.0, 3.0), c in vec6(3.0, 3.0)) {
        let (x, y, z) = (SE3::exp(&a), SE3::exp(&b), SE3::exp(&c));
        prop_assert!((x.compose(&y).compose(&z).matrix() - x.compose(&y.compose(&z)).matrix()).amax() < 1e-13);
        prop_assert!((x.compose(&x.inverse()).matrix() - Matrix4::identity()).amax() < 1e-14);
        let pt = Vector3::new(0.3, 0.2, -0.1);
        prop_assert!((x.compose(&y).act(&pt) - x.act(&y.act(&pt))).norm() < 1e-13);
        prop_assert!((x.inverse().act(&x.act(&pt)) - pt).norm() < 1e-13);
        let _ = SO3::identity();
    }
}
