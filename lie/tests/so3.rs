//! SO(3): precision at the hard angles, coefficients against 50-digit references, properties,
#![allow(clippy::excessive_precision, clippy::approx_constant)] // 20-digit references from mpmath, kept as printed.
//! and every Jacobian against central differences on the manifold.

mod common;
use common::*;
use lie::so3::{RodriguesCoeffs, d_coeff};
use lie::{SO3, hat, jl, jl_inv, jr, jr_inv, vee};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use std::f64::consts::PI;

/// (θ, [sinθ/θ, (1−cosθ)/θ², (θ−sinθ)/θ³, D]) from mpmath at 50 digits (independent of this code).
const REF: &[(f64, [f64; 4])] = &[
    (
        1e-8,
        [
            0.99999999999999998333,
            0.49999999999999999583,
            0.16666666666666666583,
            0.083333333333333333472,
        ],
    ),
    (
        1e-4,
        [
            0.99999999833333333417,
            0.49999999958333333347,
            0.16666666658333333335,
            0.083333333347222222226,
        ],
    ),
    (
        0.01,
        [
            0.99998333341666646825,
            0.49999583334722219742,
            0.16666583333531745756,
            0.08333347222255291088,
        ],
    ),
    (
        0.3,
        [
            0.98506735553779858368,
            0.49626123193771089286,
            0.16591827180223795906,
            0.08345860179452761332,
        ],
    ),
    (
        0.49999,
        [
            0.9588527025632771973,
            0.4896701622031018586,
            0.16459577351199338112,
            0.083682621298407767116,
        ],
    ),
    (
        0.50001,
        [
            0.95884945182266450832,
            0.48966934266599511954,
            0.16459560881915095714,
            0.083682649409999878071,
        ],
    ),
    (
        0.99999,
        [
            0.84147399648272919336,
            0.45969847337252506234,
            0.15852917408489958723,
            0.084756109992077159012,
        ],
    ),
    (
        1.00001,
        [
            0.84146797310915045725,
            0.459696914884455956,
            0.1585288562978706997,
            0.084756168295790984045,
        ],
    ),
    (
        2.0,
        [
            0.4546487134128408477,
            0.35403670913678559675,
            0.13633782164678978808,
            0.089476846016417324248,
        ],
    ),
    (
        3.0,
        [
            0.047040002686622407367,
            0.22111027740004949525,
            0.10588444414593084363,
            0.099291970394002369646,
        ],
    ),
    (
        3.14159,
        [
            8.4466457852085995228e-7,
            0.20264270961412289699,
            0.10132126922468035964,
            0.10132114364109518247,
        ],
    ),
];

#[test]
fn coefficients_match_high_precision_on_both_sides_of_every_branch() {
    for &(t, r) in REF {
        let k = RodriguesCoeffs::new(&Vector3::new(0.0, t, 0.0));
        let d = d_coeff(t * t);
        // a at 3.14159 is tiny: compare it absolutely (it multiplies θ̂, |θ̂| ≈ π).
        assert!(
            (k.a - r[0]).abs() <= 4e-16 * r[0].abs().max(0.1),
            "a({t}) = {} vs {}",
            k.a,
            r[0]
        );
        for (got, want, name) in [(k.b, r[1], "b"), (k.c, r[2], "c")] {
            assert!(
                (got - want).abs() <= 4e-16 * want,
                "{name}({t}) = {got} vs {want}"
            );
        }
        // D's closed form (θ ≥ ½) may lose a few bits; it enters Jr⁻¹ multiplied by θ².
        let tol = if t < 0.5 { 4e-16 } else { 4e-14 };
        assert!((d - r[3]).abs() <= tol * r[3], "D({t}) = {d} vs {}", r[3]);
    }
}

fn exp_log_round_trip(theta: f64, axis: Vector3<f64>) -> (f64, f64) {
    let phi = axis.normalize() * theta;
    let r = SO3::exp(&phi);
    let back = r.log();
    let r2 = SO3::exp(&back);
    let e1 = (r2.matrix() - r.matrix()).norm();
    let e2 = if theta == 0.0 {
        back.norm()
    } else {
        (back - phi).norm() / theta
    };
    (e1, e2)
}

#[test]
fn round_trips_at_the_hard_angles() {
    let axes = [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(1.0, -2.0, 3.0),
        Vector3::new(-0.3, 0.1, -0.9),
    ];
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
        for a in &axes {
            let (e_exp_log, e_log_exp) = exp_log_round_trip(t, *a);
            assert!(
                e_exp_log <= 1e-14,
                "‖Exp(Log R) − R‖ = {e_exp_log:e} at θ = {t}"
            );
            if t <= PI - 1e-6 {
                assert!(
                    e_log_exp <= 1e-14,
                    "Log(Exp φ) rel err {e_log_exp:e} at θ = {t}"
                );
            }
        }
    }
}

#[test]
fn log_at_exactly_pi_returns_a_vector_of_norm_pi() {
    for axis in [
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        Vector3::new(1.0, 1.0, 1.0).normalize(),
    ] {
        let r = SO3::exp(&(axis * PI));
        let phi = r.log();
        assert!((phi.norm() - PI).abs() < 1e-14);
        assert!(phi.normalize().cross(&axis).norm() < 1e-14);
    }
}

#[test]
fn tiny_angles_keep_relative_precision() {
    // Exp(1e-300 e_x) must carry the 1e-300 off-diagonal, and Log must return it.
    let phi = Vector3::new(1e-300, -2e-300, 3e-300);
    let r = SO3::exp(&phi);
    assert_eq!(r.matrix()[(2, 1)], 1e-300);
    assert_eq!(r.log(), phi);
    let phi = Vector3::new(1e-15, 2e-15, -3e-15);
    assert!((SO3::exp(&phi).log() - phi).norm() <= 1e-30);
}

#[test]
fn hat_vee_and_skew_identities() {
    let v = Vector3::new(0.3, -1.2, 2.0);
    let w = Vector3::new(-0.7, 0.4, 0.1);
    assert_eq!(hat(&v) * w, v.cross(&w));
    assert_eq!(vee(&hat(&v)), v);
}

#[test]
fn quaternion_and_matrix_conversions() {
    let phi = Vector3::new(0.4, -1.1, 2.3);
    let r = SO3::exp(&phi);
    let q = r.to_quaternion();
    let nq = nalgebra::UnitQuaternion::from_scaled_axis(phi);
    assert!((q.coords - nq.coords).norm() < 1e-15 || (q.coords + nq.coords).norm() < 1e-15);
    assert!((SO3::from_quaternion(&q).matrix() - r.matrix()).amax() < 1e-15);
    // Re-orthonormalisation of a drifted matrix gives the nearest rotation.
    let drifted = r.matrix() + Matrix3::new(1e-6, 2e-6, 0.0, 0.0, -1e-6, 0.0, 3e-6, 0.0, 1e-6);
    let fixed = SO3::from_matrix(&drifted);
    assert!(fixed.orthonormality_error() < 1e-15);
    assert!((fixed.matrix() - r.matrix()).amax() < 1e-5);
    assert!(SO3::from_wxyz(0.0, 0.0, 0.0, 0.0).is_none());
    assert!(SO3::from_wxyz(f64::NAN, 0.0, 0.0, 1.0).is_none());
}

const H: f64 = 1e-6;

fn check(name: &str, an: &Matrix3<f64>, num: nalgebra::DMatrix<f64>) {
    let e = rel_err(&dm(an), &num);
    assert!(
        e < 1e-8,
        "{name}: relative error {e:e}\nanalytic {an}\nnumeric {num}"
    );
}

fn jacobian_points() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(1e-9, -2e-9, 1e-9),
        Vector3::new(1e-4, 3e-4, -2e-4),
        Vector3::new(0.3, -0.2, 0.5),
        Vector3::new(-1.1, 0.9, 1.7),
        Vector3::new(0.0, 0.0, PI - 1e-3),
    ]
}

#[test]
fn jacobians_match_central_differences() {
    let other = SO3::exp(&Vector3::new(0.2, 0.7, -0.4));
    let v = Vector3::new(1.5, -0.3, 2.2);
    for phi in jacobian_points() {
        let r = SO3::exp(&phi);
        // Exp: d Exp(φ + δ) w.r.t. δ, as a right perturbation of the result = Jr(φ).
        check(
            "Jr",
            &jr(&phi),
            num_jac(|p: &Vector3<f64>| SO3::exp(p), &phi, H),
        );
        check(
            "exp_jr",
            &SO3::exp_jr(&phi).1,
            num_jac(|p: &Vector3<f64>| SO3::exp(p), &phi, H),
        );
        // Left Jacobian: Exp(φ + δ) = Exp(Jl δ) Exp(φ): differentiate Log(Exp(φ+δ) Exp(φ)ᵀ).
        let e0 = SO3::exp(&phi);
        check(
            "Jl",
            &jl(&phi),
            num_jac(
                |p: &Vector3<f64>| SO3::exp(p).compose(&e0.inverse()).log(),
                &phi,
                H,
            ),
        );
        if phi.norm() < PI - 0.1 {
            check("log", &r.log_jac().1, num_jac(|x: &SO3| x.log(), &r, H));
        }
        check(
            "inverse",
            &r.inverse_jac().1,
            num_jac(|x: &SO3| x.inverse(), &r, H),
        );
        let (_, ja, jb) = r.compose_jac(&other);
        check(
            "compose/a",
            &ja,
            num_jac(|x: &SO3| x.compose(&other), &r, H),
        );
        check("compose/b", &jb, num_jac(|x: &SO3| r.compose(x), &other, H));
        let (_, jr_, jv) = r.act_jac(&v);
        check("act/R", &jr_, num_jac(|x: &SO3| x.act(&v), &r, H));
        check("act/v", &jv, num_jac(|x: &Vector3<f64>| r.act(x), &v, H));
        // Inverses.
        assert!((jr(&phi) * jr_inv(&phi) - Matrix3::identity()).amax() < 1e-13);
        assert!((jl(&phi) * jl_inv(&phi) - Matrix3::identity()).amax() < 1e-13);
    }
}

fn vec3(r: f64) -> impl Strategy<Value = Vector3<f64>> {
    [-r..r, -r..r, -r..r].prop_map(|a| Vector3::new(a[0], a[1], a[2]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn exp_log_round_trip_random(phi in vec3(1.8)) {
        prop_assume!(phi.norm() < PI - 1e-6);
        let r = SO3::exp(&phi);
        prop_assert!((r.log() - phi).norm() <= 1e-14 * phi.norm().max(1e-300));
        prop_assert!((SO3::exp(&r.log()).matrix() - r.matrix()).norm() <= 1e-14);
        prop_assert!(r.orthonormality_error() < 1e-15);
    }

    #[test]
    fn jr_times_inverse_is_identity(phi in vec3(1.8)) {
        prop_assume!(phi.norm() < PI);
        prop_assert!((jr(&phi) * jr_inv(&phi) - Matrix3::identity()).amax() < 1e-12);
        prop_assert!((jl(&phi) - jr(&phi).transpose()).amax() < 1e-15);
    }

    #[test]
    fn exp_of_sum_second_order(phi in vec3(1.5), dir in vec3(1.0)) {
        // Exp(φ + δ) = Exp(φ) Exp(Jr δ) + O(|δ|²): halving δ must quarter the error.
        prop_assume!(dir.norm() > 0.1);
        let err = |s: f64| {
            let d = dir * s;
            SO3::exp(&(phi + d)).minus(&SO3::exp(&phi).compose(&SO3::exp(&(jr(&phi) * d)))).norm()
        };
        let (e1, e2) = (err(1e-3), err(5e-4));
        prop_assert!(e1 < 1e-5);
        prop_assert!(e2 < 0.3 * e1 + 1e-15, "e1 {e1:e} e2 {e2:e}");
    }

    #[test]
    fn conjugation_is_adjoint(a in vec3(1.8), phi in vec3(1.8)) {
        let r = SO3::exp(&a);
        let lhs = r.compose(&SO3::exp(&phi)).compose(&r.inverse());
        let rhs = SO3::exp(&(r.adjoint() * phi));
        prop_assert!((lhs.matrix() - rhs.matrix()).amax() < 1e-14);
    }

    #[test]
    fn group_axioms(a in vec3(3.0), b in vec3(3.0), c in vec3(3.0)) {
        let (x, y, z) = (SO3::exp(&a), SO3::exp(&b), SO3::exp(&c));
        prop_assert!(((x * y) * z).matrix().relative_eq((x * (y * z)).matrix(), 1e-14, 1e-14));
        prop_assert!((x * x.inverse()).matrix().relative_eq(&Matrix3::identity(), 1e-14, 1e-14));
        prop_assert!((x * SO3::identity()).matrix() == x.matrix());
        // ⊕/⊖ are inverse to each other.
        let d = Vector3::new(0.1, -0.2, 0.05);
        prop_assert!((x.plus(&d).minus(&x) - d).norm() < 1e-14);
    }
}
