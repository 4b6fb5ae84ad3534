//! SO(3): precision at the hard angles, coefficients against high-precision references,
//! properties, and every Jacobian (including Jr⁻¹ and Jl⁻¹ directly) against central
//! differences on the manifold.
#![allow(clippy::excessive_precision, clippy::approx_constant)] // 21-digit references from mpmath, kept as printed.

mod common;
use common::*;
use nalgebra::{Matrix3, Quaternion, Rotation3, Unit, UnitQuaternion, Vector3};
use preint_lie::so3::{RodriguesCoeffs, d_coeff, exp_coeffs, exp_quat_coeffs, jac_coeffs};
use preint_lie::{SO3, hat, jl, jr, vee};
use proptest::prelude::*;
use std::f64::consts::PI;

/// (θ, [sinθ/θ, (1−cosθ)/θ², (θ−sinθ)/θ³, D]) from mpmath at 100 digits (independent of this
/// code), evaluated at `√(mpmath.mpf(θ·θ))`: the square root of the **exact f64 θ²** (θ·θ
/// rounded, as the code forms it), which is what the θ²-taking coefficient functions receive.
/// (They differ: at θ = 3.14159 the rounding of θ² alone moves sin θ/θ by ~1e-11 relative, so a
/// reference at θ would test the rounding of the square, not the function.)
/// Generator: `tests/data/gen_tables.py`. The angles straddle the branch edges θ = 0.1 (series
/// → polynomial) and π (polynomial → closed form), and θ = ½ and 1.
const REF: &[(f64, [f64; 4])] = &[
    (
        1e-08,
        [
            0.999999999999999983333,
            0.499999999999999995833,
            0.166666666666666665833,
            0.0833333333333333334722,
        ],
    ),
    (
        0.0001,
        [
            0.999999998333333334167,
            0.499999999583333333472,
            0.166666666583333333353,
            0.0833333333472222222255,
        ],
    ),
    (
        0.01,
        [
            0.999983333416666468253,
            0.49999583334722219742,
            0.166665833335317457562,
            0.0833334722225529108796,
        ],
    ),
    (
        0.09999,
        [
            0.99833449945178384897,
            0.499583555471057709381,
            0.166583369829747361809,
            0.0833472227509655196101,
        ],
    ),
    (
        0.10001,
        [
            0.998333833451545804389,
            0.499583388915472397417,
            0.166583336512283738025,
            0.083347228309167570236,
        ],
    ),
    (
        0.3,
        [
            0.985067355537798584235,
            0.496261231937710893001,
            0.16591827180223795909,
            0.0834586017945276133158,
        ],
    ),
    (
        0.49999,
        [
            0.958852702563277197584,
            0.489670162203101858672,
            0.16459577351199338113,
            0.0836826212984077671138,
        ],
    ),
    (
        0.50001,
        [
            0.958849451822664514375,
            0.489669342665995121069,
            0.164595608819150957448,
            0.0836826494099998780185,
        ],
    ),
    (
        1.0,
        [
            0.841470984807896506653,
            0.459697694131860282599,
            0.158529015192103493347,
            0.084756139143774040366,
        ],
    ),
    (
        2.0,
        [
            0.454648713412840847698,
            0.354036709136785596749,
            0.136337821646789788075,
            0.0894768460164173242484,
        ],
    ),
    (
        3.0,
        [
            0.0470400026866224073669,
            0.221110277400049495252,
            0.105884444145930843626,
            0.0992919703940023696463,
        ],
    ),
    (
        3.14159,
        [
            8.44664578568033619424e-7,
            0.202642709614122916111,
            0.101321269224680364419,
            0.101321143641095180238,
        ],
    ),
    (
        3.5,
        [
            -0.100223779339891385177,
            0.15807809692169766022,
            0.0898141860685625620553,
            0.107510789142881360539,
        ],
    ),
    (
        4.0,
        [
            -0.189200623826982062843,
            0.103352726303975744665,
            0.0743250389891863789277,
            0.119707194295035720469,
        ],
    ),
];

#[test]
fn coefficients_match_high_precision_on_both_sides_of_every_branch() {
    let mut worst = [0.0f64; 4];
    for &(t, r) in REF {
        let k = RodriguesCoeffs::new(&Vector3::new(0.0, t, 0.0));
        let d = d_coeff(t * t);
        // All relative, a(3.14159) ≈ 8.4e-7 included: the polynomial branch factors the zero of
        // sin θ/θ at π out, so a keeps its relative precision up to π.
        for (i, (got, want, name)) in [(k.a, r[0], "a"), (k.b, r[1], "b"), (k.c, r[2], "c")]
            .into_iter()
            .enumerate()
        {
            let e = (got - want).abs() / want.abs();
            worst[i] = worst[i].max(e);
            assert!(e <= 4e-16, "{name}({t}) = {got} vs {want}: rel {e:e}");
        }
        // D: series, polynomial up to π, closed form (no cancellation) above.
        let e = (d - r[3]).abs() / r[3];
        worst[3] = worst[3].max(e);
        assert!(e <= 4e-16, "D({t}) = {d} vs {}: rel {e:e}", r[3]);
    }
    println!(
        "max relative error vs mpmath: a {:.1e}, b {:.1e}, c {:.1e}, D {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

/// Relative error of `got` against the reference `hi + lo` (an unevaluated double-double), in
/// units of ε = 2⁻⁵².
fn rel_eps(got: f64, hi: f64, lo: f64) -> f64 {
    ((got - hi) - lo).abs() / (hi.abs() * f64::EPSILON)
}

#[test]
fn coefficients_within_a_few_eps_on_dense_angles() {
    // tests/data/coeff_ref.txt (generator gen_coeff_ref.py beside it): 300 random θ ∈ [1, π],
    // 100 log-uniform θ ∈ [1e-8, 1], 50 random θ ∈ [3.5, 5.5], π − 10⁻ᵏ (k = 1…15), π and the
    // doubles on either side of 0.1, ½ and 1, each with 60-digit mpmath references at
    // √(exact f64 θ²), stored as hi + lo pairs.
    // Three branches: Taylor series (θ < 0.1), polynomials in θ² (0.1 ≤ θ ≤ π), closed form.
    let mut worst = [[0.0f64; 4]; 3];
    let mut n = [0; 3];
    for line in include_str!("data/coeff_ref.txt").lines() {
        let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
        let (t, t2) = (v[0], v[0] * v[0]);
        let k = RodriguesCoeffs::new(&Vector3::new(t, 0.0, 0.0));
        let (ea, eb) = exp_coeffs(t2);
        let (jb, jc) = jac_coeffs(t2);
        let e = |i: usize, g: f64| rel_eps(g, v[1 + 2 * i], v[2 + 2 * i]);
        let errs = [
            e(0, k.a).max(e(0, ea)),
            e(1, k.b).max(e(1, eb)).max(e(1, jb)),
            e(2, k.c).max(e(2, jc)),
            e(3, d_coeff(t2)),
        ];
        let branch = if t < 0.1 {
            0
        } else if t2 <= PI * PI {
            1
        } else {
            2
        };
        n[branch] += 1;
        for i in 0..4 {
            worst[branch][i] = worst[branch][i].max(errs[i]);
        }
    }
    assert!(
        n[0] > 40 && n[1] > 300 && n[2] >= 50,
        "reference file truncated: {n:?} lines per branch"
    );
    for (name, w) in ["series", "polynomial", "closed form"].iter().zip(&worst) {
        println!(
            "max relative error / ε, {name}: a {:.2} b {:.2} c {:.2} D {:.2}",
            w[0], w[1], w[2], w[3]
        );
    }
    // Bounds ≈ 1.5× the measured maxima (printed above), rows series / polynomial / closed
    // form, columns a, b, c, D. Series: a few roundings of a Horner sum. Polynomial: the
    // printed maxima of `lie/tools/fit_poly.py` (20 000 points) plus the factor (π² − θ²) of
    // a. Closed form (θ > π): sin_cos (< 1 ulp) and one or two divisions, after sqrt's
    // half-ulp rounding of θ, which a = sin θ/θ amplifies by |θ cot θ − 1| (≤ 6.5 at 5.5 rad).
    let tols = [
        [1.0, 1.0, 1.0, 1.0],
        [2.7, 1.8, 1.3, 1.2],
        [1.5, 2.5, 1.5, 3.0],
    ];
    for (b, (w, tol)) in worst.iter().zip(&tols).enumerate() {
        for i in 0..4 {
            assert!(
                w[i] <= tol[i],
                "branch {b}, coefficient {i}: {} ε > {}",
                w[i],
                tol[i]
            );
        }
    }
}

#[test]
fn quaternion_exp_coefficients_within_an_ulp() {
    // tests/data/quat_ref.txt (generator gen_quat_ref.py beside it): 60-digit references of
    // cos(θ/2) and sin(θ/2)/θ at √(exact f64 θ²), 200 angles on the series branch (θ < 0.1),
    // 100 on the closed form up to 6 rad, and the edge.
    let mut worst = [[0.0f64; 2]; 2];
    let mut worst_r = [0.0f64; 2];
    let mut n = [0; 2];
    for line in include_str!("data/quat_ref.txt").lines() {
        let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
        let t = v[0];
        let (c, s) = exp_quat_coeffs(t * t);
        let branch = usize::from(t >= 0.1);
        n[branch] += 1;
        // cos(θ/2) in units of ε absolute (it is a unit quaternion's component and crosses
        // zero at π); sin(θ/2)/θ relative.
        let ec = ((c - v[1]) - v[2]).abs() / f64::EPSILON;
        // Above π, sin(θ/2)/θ is only as precise as θ = √θ², whose half-ulp rounding it
        // amplifies by |x cot x − 1|, x = θ/2 (as for a = sin θ/θ, module docs); that part is
        // taken out of the error before it is compared.
        let x = 0.5 * t;
        let amp = if t > PI {
            (x / x.tan() - 1.0).abs() * 0.5
        } else {
            0.0
        };
        let es = (rel_eps(s, v[3], v[4]) - amp).max(0.0);
        worst[branch][0] = worst[branch][0].max(ec);
        worst[branch][1] = worst[branch][1].max(es);
        // The quaternion is the matrix Exp's rotation: entries within a few ε.
        let phi = Vector3::new(0.36, -0.48, 0.8) * t;
        let q = UnitQuaternion::new_unchecked(Quaternion::new(c, s * phi.x, s * phi.y, s * phi.z));
        let e = (q.to_rotation_matrix().matrix() - SO3::exp(&phi).matrix()).amax();
        worst_r[branch] = worst_r[branch].max(e);
        assert!(
            e <= [4e-16, 1.2e-15][branch],
            "θ = {t}: R(q) − Exp(φ) = {e:e}"
        );
    }
    assert!(
        n[0] >= 200 && n[1] >= 100,
        "reference file truncated: {n:?}"
    );
    println!(
        "quaternion Exp coefficients / ε: series cos {:.2} sin/θ {:.2}; closed form cos {:.2} sin/θ {:.2}; max |R(q) − Exp(φ)| {:.1e} / {:.1e}",
        worst[0][0], worst[0][1], worst[1][0], worst[1][1], worst_r[0], worst_r[1]
    );
    // ≈ 1.5× the measured maxima (printed above). Series: a five-term Horner sum led by 1 or
    // ½. Closed form: sqrt's rounding of θ, sin_cos (< 1 ulp) and a division.
    let tols = [[0.4, 0.4], [0.6, 0.9]];
    for b in 0..2 {
        for i in 0..2 {
            assert!(
                worst[b][i] <= tols[b][i],
                "branch {b}, coefficient {i}: {} ε > {}",
                worst[b][i],
                tols[b][i]
            );
        }
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

/// The hard angles: exactly 0, subnormal-scale, tiny, small, generic, and π from below and
/// exactly; π − 1e-6 is the edge of the domain where Log(Exp φ) = φ is checked.
const HARD_ANGLES: [f64; 9] = [
    0.0,
    1e-300,
    1e-15,
    1e-8,
    1e-4,
    1.0,
    PI - 1e-6,
    PI - 1e-10,
    PI,
];

#[test]
fn round_trips_at_the_hard_angles() {
    let axes = [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(1.0, -2.0, 3.0),
        Vector3::new(-0.3, 0.1, -0.9),
    ];
    let (mut w1, mut w2) = (0.0f64, 0.0f64);
    for &t in &HARD_ANGLES {
        for a in &axes {
            let (e_exp_log, e_log_exp) = exp_log_round_trip(t, *a);
            w1 = w1.max(e_exp_log);
            assert!(
                e_exp_log <= 1e-14,
                "‖Exp(Log R) − R‖ = {e_exp_log:e} at θ = {t}"
            );
            if t <= PI - 1e-6 {
                w2 = w2.max(e_log_exp);
                assert!(
                    e_log_exp <= 1e-14,
                    "Log(Exp φ) rel err {e_log_exp:e} at θ = {t}"
                );
            }
        }
    }
    println!("hard angles: max ‖Exp(Log R) − R‖_F {w1:.2e}, max Log(Exp φ) rel err {w2:.2e}");
}

/// Log(Exp φ) at 200 000 angles from 0.02 rad to π − 1e-6, random axes, across every branch
/// edge of Log: the arcsine series (sin θ < 0.1), the half angle (cos θ ≥ ½, θ ≤ π/3), the
/// cotangent (|cos θ| < ½), atan2 (cos θ > −0.9, θ < 2.691) and Shepperd's extraction.
/// Relative error, in ε. (A six-term arcsine series would be off by up to 1.7e-14 ≈ 78 ε just
/// below sin θ = 0.1; this test catches it.)
#[test]
fn log_of_exp_within_a_few_eps_across_every_branch() {
    let mut rng = SplitMix::new(11);
    let n = 200_000;
    let edges = [0.1002, 1.0472, 2.0944, 2.6906, 4.0];
    let mut worst = [0.0f64; 5];
    for i in 0..n {
        let t = 0.02 + (PI - 1e-6 - 0.02) * (i as f64 + rng.uniform()) / n as f64;
        let phi = rng.unit_vector() * t;
        let e = (SO3::exp(&phi).log() - phi).norm() / t / f64::EPSILON;
        let b = edges.iter().position(|&x| t < x).unwrap();
        worst[b] = worst[b].max(e);
    }
    println!(
        "Log(Exp φ): max relative error / ε: series {:.2}, half angle {:.2}, cotangent {:.2}, \
         atan2 {:.2}, Shepperd {:.2}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    // ≈ 1.5× the measured maxima.
    let tol = [2.0, 4.0, 4.0, 3.0, 2.5];
    for b in 0..5 {
        assert!(
            worst[b] <= tol[b],
            "branch {b}: {} ε > {}",
            worst[b],
            tol[b]
        );
    }
}

#[test]
fn exp_log_on_rotations_not_built_by_exp() {
    // Rotations from uniform random unit quaternions (nalgebra's quaternion → matrix), from
    // quaternions within 1e-17…1e-3 of θ = π (w ≈ 0: Log's diagonal branch), and from
    // re-orthonormalised perturbed matrices (SO3::from_matrix).
    let mut rng = SplitMix::new(7);
    let mut worst = [0.0f64; 3];
    let mut orth = 0.0f64;
    let mut check = |r: &SO3, which: usize| {
        let e = (SO3::exp(&r.log()).matrix() - r.matrix()).norm();
        worst[which] = worst[which].max(e);
        assert!(
            e <= 1e-14,
            "‖Exp(Log R) − R‖ = {e:e} for R = {}",
            r.matrix()
        );
    };
    for _ in 0..20_000 {
        check(&SO3::from_quaternion(&rng.unit_quaternion()), 0);
    }
    for &w in &[0.0f64, 1e-17, 1e-12, 1e-8, 1e-5, 1e-3] {
        for _ in 0..500 {
            let n = rng.unit_vector() * (1.0 - w * w).sqrt();
            let q = UnitQuaternion::new_unchecked(Quaternion::new(w, n.x, n.y, n.z));
            let r = SO3::from_quaternion(&q);
            check(&r, 1);
            // The angle is 2·acos(w) (|w| ≤ 1e-3 here, so acos is well conditioned).
            let theta = r.log().norm();
            assert!(
                (theta - 2.0 * w.acos()).abs() < 1e-14,
                "w = {w}: θ = {theta}"
            );
        }
    }
    for k in 0..5_000 {
        let base = SO3::from_quaternion(&rng.unit_quaternion());
        let scale = [1e-12, 1e-6, 1e-3, 0.1][k % 4];
        let noise = Matrix3::from_fn(|_, _| rng.normal() * scale);
        let r = SO3::from_matrix(&(base.matrix() + noise));
        orth = orth.max(r.orthonormality_error());
        assert!(
            r.orthonormality_error() < 4e-15,
            "{}",
            r.orthonormality_error()
        );
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-14);
        check(&r, 2);
    }
    println!(
        "max ‖Exp(Log R) − R‖_F: random quaternions {:.2e}, near π {:.2e}, from_matrix {:.2e} (its max |RᵀR − I| {orth:.2e})",
        worst[0], worst[1], worst[2]
    );
}

/// Polar factor of `m` (det m > 0) by the scaled Newton iteration `X ← ½(ζX + ζ⁻¹X⁻ᵀ)`,
/// `ζ = |det X|^(−1/3)` (Higham, Functions of Matrices, § 8.6): an independent reference.
fn newton_polar(m: &Matrix3<f64>) -> Matrix3<f64> {
    let mut x = *m;
    for _ in 0..60 {
        let z = x.determinant().abs().powf(-1.0 / 3.0);
        let next = (x * z + x.try_inverse().unwrap().transpose() / z) * 0.5;
        let done = (next - x).amax() < 1e-16;
        x = next;
        if done {
            break;
        }
    }
    // Two unscaled steps to settle the last bits.
    for _ in 0..2 {
        x = (x + x.try_inverse().unwrap().transpose()) * 0.5;
    }
    x
}

#[test]
fn from_matrix_is_the_nearest_rotation() {
    // The nearest rotation R to M (Frobenius) makes RᵀM symmetric; for det M > 0 it is the
    // polar factor (RᵀM positive definite), checked against a Newton-iteration polar factor.
    // For det M < 0 the nearest *rotation* has RᵀM with exactly one negative eigenvalue, the
    // smallest in magnitude. Both cases are also checked directly: no nearby rotation
    // R·Exp(δ) is closer to M.
    let mut rng = SplitMix::new(11);
    let (mut asym, mut dpol, mut orth) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..2_000 {
        let base = SO3::from_quaternion(&rng.unit_quaternion());
        let noise = Matrix3::from_fn(|_, _| rng.normal() * 0.2);
        let sign = if k % 5 == 0 { -1.0 } else { 1.0 };
        let m = base.matrix() * sign + noise;
        let r = SO3::from_matrix(&m);
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-14);
        orth = orth.max(r.orthonormality_error());
        assert!(r.orthonormality_error() < 4e-15);
        let p = r.matrix().transpose() * m;
        let a = (p - p.transpose()).amax() / m.amax();
        asym = asym.max(a);
        assert!(a < 1e-14, "RᵀM not symmetric: {a:e}");
        let mut ev: Vec<f64> = ((p + p.transpose()) * 0.5)
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .collect();
        ev.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
        if m.determinant() > 0.0 {
            assert!(ev[0] > 0.0, "RᵀM not positive definite: {ev:?}");
            let e = (r.matrix() - newton_polar(&m)).amax();
            dpol = dpol.max(e);
            assert!(e < 1e-14, "from_matrix vs Newton polar: {e:e}");
        } else {
            assert!(ev[0] < 0.0 && ev[1] > 0.0 && ev[2] > 0.0, "{ev:?}");
        }
        let d0 = (m - r.matrix()).norm();
        for _ in 0..4 {
            let d = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 1e-4;
            assert!(
                (m - r.plus(&d).matrix()).norm() > d0,
                "a closer rotation exists"
            );
        }
    }
    println!(
        "from_matrix: max |RᵀM − MᵀR|/max|M| {asym:.2e}, max |R − polar(M)| {dpol:.2e}, max |RᵀR − I| {orth:.2e}"
    );
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

/// `min(‖a − b‖, ‖a + b‖)`: q and −q are the same rotation.
fn quat_dist(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    (a.coords - b.coords)
        .norm()
        .min((a.coords + b.coords).norm())
}

#[test]
fn quaternion_and_matrix_conversions_at_the_hard_angles() {
    // References built independently: q = (cos θ/2, sin θ/2 n) by hand, R by nalgebra's
    // Rotation3::from_axis_angle.
    let axes = [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(1.0, -2.0, 3.0).normalize(),
        Vector3::new(-0.3, 0.1, -0.9).normalize(),
    ];
    let (mut wq, mut wr, mut wt) = (0.0f64, 0.0f64, 0.0f64);
    for &t in HARD_ANGLES.iter().chain(&[2.0, 3.0, PI - 1e-3]) {
        for n in &axes {
            let (s, c) = (0.5 * t).sin_cos();
            let q_ref =
                UnitQuaternion::new_unchecked(Quaternion::new(c, s * n.x, s * n.y, s * n.z));
            let r_ref = Rotation3::from_axis_angle(&Unit::new_unchecked(*n), t);
            // quaternion → matrix
            let r = SO3::from_quaternion(&q_ref);
            let er = (r.matrix() - r_ref.matrix()).amax();
            wr = wr.max(er);
            assert!(
                er <= 4.0 * f64::EPSILON,
                "θ = {t}: from_quaternion off by {er:e}"
            );
            // matrix → quaternion (Shepperd), w ≥ 0; relative precision in the vector part
            // for tiny angles.
            let q = SO3::exp(&(n * t)).to_quaternion();
            assert!(q.w >= 0.0);
            let eq = quat_dist(&q, &q_ref);
            wq = wq.max(eq);
            assert!(
                eq <= 4.0 * f64::EPSILON,
                "θ = {t}: to_quaternion off by {eq:e}"
            );
            if t > 0.0 && t < 1e-4 {
                let rel = (q.imag() - q_ref.imag()).amax() / q_ref.imag().amax();
                assert!(
                    rel <= 4.0 * f64::EPSILON,
                    "θ = {t}: vector part rel err {rel:e}"
                );
            }
            // round trips
            let et = quat_dist(&SO3::from_quaternion(&q_ref).to_quaternion(), &q_ref);
            wt = wt.max(et);
            assert!(et <= 4.0 * f64::EPSILON, "θ = {t}: q → R → q off by {et:e}");
            let k = 3.7;
            let r2 = SO3::from_wxyz(k * q_ref.w, k * q_ref.i, k * q_ref.j, k * q_ref.k).unwrap();
            assert!((r2.matrix() - r.matrix()).amax() <= 4.0 * f64::EPSILON);
        }
    }
    println!(
        "conversions: max |R(q) − R_ref| {wr:.2e}, |q(R) − q_ref| {wq:.2e}, |q(R(q)) − q| {wt:.2e}"
    );
    assert!(SO3::from_wxyz(0.0, 0.0, 0.0, 0.0).is_none());
    assert!(SO3::from_wxyz(f64::NAN, 0.0, 0.0, 1.0).is_none());
}

#[test]
fn quaternion_round_trip_on_random_rotations() {
    let mut rng = SplitMix::new(3);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let q = rng.unit_quaternion();
        let r = SO3::from_quaternion(&q);
        let e = quat_dist(&r.to_quaternion(), &q);
        worst = worst.max(e);
        assert!(e <= 4.0 * f64::EPSILON, "q → R → q off by {e:e}");
        // Same rotation as nalgebra's own conversion.
        assert!((r.matrix() - q.to_rotation_matrix().matrix()).amax() <= 2.0 * f64::EPSILON);
    }
    println!("random quaternions: max |q(R(q)) − q| {worst:.2e}");
}

#[test]
fn drifted_matrix_is_reorthonormalised_to_the_nearby_rotation() {
    let phi = Vector3::new(0.4, -1.1, 2.3);
    let r = SO3::exp(&phi);
    let drifted = r.matrix() + Matrix3::new(1e-6, 2e-6, 0.0, 0.0, -1e-6, 0.0, 3e-6, 0.0, 1e-6);
    let fixed = SO3::from_matrix(&drifted);
    assert!(fixed.orthonormality_error() < 1e-15);
    assert!((fixed.matrix() - r.matrix()).amax() < 1e-5);
    assert!(
        SO3::from_matrix(r.matrix())
            .matrix()
            .relative_eq(r.matrix(), 1e-15, 1e-15)
    );
}

fn vec3(r: f64) -> impl Strategy<Value = Vector3<f64>> {
    [-r..r, -r..r, -r..r].prop_map(|a| Vector3::new(a[0], a[1], a[2]))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    // Log(Exp φ) = φ for every group is in `group.rs`; here the rotation matrix itself.
    #[test]
    fn exp_log_round_trip_random(phi in vec3(1.8)) {
        prop_assume!(phi.norm() < PI - 1e-6);
        let r = SO3::exp(&phi);
        prop_assert!((SO3::exp(&r.log()).matrix() - r.matrix()).norm() <= 1e-14);
        // Rodrigues with correctly rounded coefficients: RᵀR − I = (2b − a² − b²θ²)[φ]×², a few
        // ε·θ². Measured over 2·10⁶ random φ in this box: worst 1.33e-15 (6 ε), 1 in 36 000
        // above 1e-15 (so a bound of 1e-15 would fail ~1 run in 100 of these 300 cases).
        prop_assert!(r.orthonormality_error() < 1.5e-15);
    }

    #[test]
    fn exp_log_round_trip_random_quaternion(q in prop::array::uniform4(-1.0f64..1.0)) {
        let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        prop_assume!(n > 0.1 && n < 1.0); // uniform on S³ after normalising
        let r = SO3::from_wxyz(q[0], q[1], q[2], q[3]).unwrap();
        prop_assert!((SO3::exp(&r.log()).matrix() - r.matrix()).norm() <= 1e-14);
    }

    // Jr·Jr⁻¹ = I for every group is in `group.rs`; SO(3)'s Jl is also Jr transposed.
    #[test]
    fn jl_is_jr_transposed(phi in vec3(1.8)) {
        prop_assume!(phi.norm() < PI);
        prop_assert!((jl(&phi) - jr(&phi).transpose()).amax() < 1e-15);
    }
}
