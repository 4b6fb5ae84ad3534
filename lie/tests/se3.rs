//! SE(3)-specific tests: Q coefficients against high-precision references, round trips at the
//! hard angles and on random transforms, hat/vee against the matrix exponential, and the
//! tangent order. The properties and Jacobians shared with SO(3) are in `group.rs`.
#![allow(clippy::excessive_precision)] // 21-digit references from mpmath, kept as printed.

mod common;
use common::SplitMix;
use nalgebra::{Matrix4, Vector3, Vector6};
use preint_lie::se3::{hat6, q_coeffs, vee6};
use preint_lie::{Manifold, SE3, SO3};
use std::f64::consts::PI;

/// (θ, [(θ² + 2cosθ − 2)/(2θ⁴), (2θ − 3 sinθ + θ cosθ)/(2θ⁵)]) from mpmath at 100 digits,
/// evaluated at the exact binary value of the f64 θ (`mpmath.mpf(θ)`; generator
/// `tests/data/gen_tables.py`).
const QREF: &[(f64, [f64; 2])] = &[
    (1e-08, [0.0416666666666666665278, 0.00833333333333333329365]),
    (0.01, [0.0416665277780257933752, 0.00833329365087632265111]),
    (0.5, [0.0413209902459634578605, 0.00823464212123771581243]),
    (1.0, [0.0403023058681397174009, 0.00794467572222509872171]),
    (1.9999, [0.0364913039807025019484, 0.0068722285924506480391]),
    (
        2.0001,
        [0.0364903414337811743066, 0.00687196035402378586429],
    ),
    (3.0, [0.0309877469555500560831, 0.00536350305765239086807]),
];

#[test]
fn q_coefficients_match_high_precision() {
    let mut worst = [0.0f64; 2];
    for &(t, r) in QREF {
        let (_, b, c) = q_coeffs(t * t);
        // Above θ = 2 the closed forms cancel a few bits (c: 2θ − 3 sin θ + θ cos θ, ~3 bits).
        let tol = if t < 2.0 { 4e-16 } else { 2e-15 };
        let (eb, ec) = ((b - r[0]).abs() / r[0], (c - r[1]).abs() / r[1]);
        if t < 2.0 {
            worst[0] = worst[0].max(eb.max(ec));
        } else {
            worst[1] = worst[1].max(eb.max(ec));
        }
        assert!(eb <= tol, "b({t}) = {b} vs {}: rel {eb:e}", r[0]);
        assert!(ec <= tol, "c({t}) = {c} vs {}: rel {ec:e}", r[1]);
    }
    println!(
        "Q coefficients: max rel error, series {:.1e}, closed form {:.1e}",
        worst[0], worst[1]
    );
}

fn xi(rho: Vector3<f64>, theta: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(rho.x, rho.y, rho.z, theta.x, theta.y, theta.z)
}

/// Round-trip errors of `Exp(Log T)` against `T`: (‖ΔR‖_F, ‖Δt‖/‖t‖) (absolute for t = 0).
///
/// Why a *relative* translation bound: `Log` gives `ρ = Jl⁻¹(θ)t` and `Exp` returns
/// `Jl(θ)ρ` with the *same* computed θ, so an error in θ cancels and only the rounding of
/// the two three-term sums `t − ½θ×t + Dθ×(θ×t)` and `ρ + bθ×ρ + cθ×(θ×ρ)` remains. For
/// θ ≤ π their terms sum in magnitude to ≤ (1 + π/2 + 1)‖t‖ ≈ 3.6‖t‖ and
/// ≤ (1 + 2/π + 1)‖ρ‖ ≈ 2.6‖ρ‖ ≤ 4.2‖t‖ (‖Jl⁻¹‖ ≤ π/2, ‖Jl‖ ≤ 1), each term carrying two or
/// three roundings: ‖Δt‖ ≲ 20 ε ‖t‖ whatever θ and the scale of t. An absolute bound would
/// have to grow with ‖t‖.
fn exp_log_errors(g: &SE3) -> (f64, f64) {
    let back = SE3::exp(&g.log());
    let er = (back.r.matrix() - g.r.matrix()).norm();
    let tn = g.t.norm();
    let et = if tn == 0.0 {
        (back.t - g.t).norm()
    } else {
        (back.t - g.t).norm() / tn
    };
    (er, et)
}

/// Rotation part: ‖Exp(Log R) − R‖_F ≤ 4e-15 (the SO(3) bound is 1e-14; measured
/// ≤ 1.8e-15, i.e. a few ε per entry from Log's atan2/Shepperd and Rodrigues' sums).
const ROT_TOL: f64 = 4e-15;
/// Translation part: ‖Δt‖ ≤ 20 ε ‖t‖ ≈ 4.4e-15 ‖t‖, the rounding bound of [`exp_log_errors`]
/// (measured ≤ 2 ε, printed).
const TRANS_REL_TOL: f64 = 20.0 * f64::EPSILON;

#[test]
fn round_trips_at_the_hard_angles() {
    let axes = [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.2, -0.5, 0.8),
        Vector3::new(1.0, -2.0, 3.0),
        Vector3::new(-0.3, 0.1, -0.9),
    ];
    let rhos = [
        Vector3::zeros(),
        Vector3::new(0.3, -1.2, 2.5),
        Vector3::new(1e-3, 0.0, 2e-3),
        Vector3::new(700.0, -350.0, 140.0),
        // Along and across the rotation axis (Jl acts as 1 along it, sin(θ/2)/(θ/2) across).
        Vector3::new(1.0, -2.0, 3.0),
        Vector3::new(3.0, 0.0, -1.0),
    ];
    let (mut wr, mut wt, mut wl) = (0.0f64, 0.0f64, 0.0f64);
    for &t in &[
        0.0,
        1e-300,
        1e-15,
        1e-8,
        1e-4,
        1.0,
        2.0,
        3.0,
        PI - 1e-6,
        PI - 1e-10,
        PI,
    ] {
        for a in &axes {
            for rho in &rhos {
                let x = xi(*rho, a.normalize() * t);
                let g = SE3::exp(&x);
                let (er, et) = exp_log_errors(&g);
                (wr, wt) = (wr.max(er), wt.max(et));
                assert!(er <= ROT_TOL, "θ = {t}, ρ = {rho:?}: ‖ΔR‖ = {er:e}");
                assert!(
                    et <= TRANS_REL_TOL,
                    "θ = {t}, ρ = {rho:?}: ‖Δt‖/‖t‖ = {et:e}"
                );
                if t <= PI - 1e-6 {
                    let e = (g.log() - x).norm() / x.norm().max(f64::MIN_POSITIVE);
                    wl = wl.max(e);
                    assert!(e <= 1e-14, "θ = {t}, ρ = {rho:?}: Log(Exp ξ) rel err {e:e}");
                }
            }
        }
    }
    println!(
        "SE3 hard angles: max ‖Exp(Log T) − T‖: rotation {wr:.2e} (F-norm), translation {wt:.2e} relative ({:.1} ε); max Log(Exp ξ) rel err {wl:.2e}",
        wt / f64::EPSILON
    );
}

#[test]
fn exp_log_round_trip_on_random_transforms() {
    // Uniform random rotations (from unit quaternions: near-π ones included, unlike Exp of a
    // box of vectors) and translations of random direction with norms 1e-3 … 1e3.
    let mut rng = SplitMix::new(5);
    let (mut wr, mut wt) = (0.0f64, 0.0f64);
    for _ in 0..20_000 {
        let r = SO3::from_quaternion(&rng.unit_quaternion());
        let t = rng.unit_vector() * 10f64.powf(rng.range(-3.0, 3.0));
        let (er, et) = exp_log_errors(&SE3::new(r, t));
        (wr, wt) = (wr.max(er), wt.max(et));
        assert!(
            er <= ROT_TOL && et <= TRANS_REL_TOL,
            "R = {}, t = {t:?}: {er:e} {et:e}",
            r.matrix()
        );
    }
    println!(
        "SE3 random: max ‖ΔR‖_F {wr:.2e}, max ‖Δt‖/‖t‖ {wt:.2e} ({:.1} ε)",
        wt / f64::EPSILON
    );
}

#[test]
fn hat_vee_and_matrix_exp() {
    let x = xi(Vector3::new(0.1, 0.2, -0.3), Vector3::new(0.4, -0.1, 0.2));
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

#[test]
fn tangent_order_is_translation_first() {
    // ξ = [ρ, θ]: a pure-ρ step translates along the body axes, R unchanged.
    let t = SE3::exp(&Vector6::new(1.0, -2.0, 0.5, 0.3, -1.1, 0.7));
    let step = t.retract(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(step.r, t.r);
    assert!((step.t - (t.t + t.r.matrix().column(0))).amax() < 1e-15);
}
