//! One test suite for every Lie group of the crate, as manif's common tester does: the
//! properties and Jacobians that read the same for SO(3) and SE(3), written once against
//! [`LieGroup`] and run for each group. Jacobians are checked against central differences on
//! the manifold (`common::num_jac`, through the `Manifold` trait). What differs between the
//! groups, evaluation points, sampling, distances and, where the groups differ, bounds, comes
//! from [`Fixture`]. Group-specific tests (hard angles, coefficient references, quaternion
//! conversions, SE(3)'s Q coefficients) are in `so3.rs` and `se3.rs`.

mod common;
use common::*;
use nalgebra::{DMatrix, SMatrix, SVector, Vector3, Vector6};
use preint_lie::{LieGroup, SE3, SO3};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::f64::consts::PI;

/// Step of the central differences.
const H: f64 = 1e-6;

/// Every vector entry, translation and tangent of the manifold round trip is bounded by
/// `SCALE` in magnitude, so rounding errors of sums are bounded by a few ε·SCALE: the
/// translation distances there are relative to it (a relative-to-the-result measure would be
/// meaningless when y ≈ 0 but x is large).
const SCALE: f64 = 100.0;

/// Half-widths `(ρ, θ)` of a box of tangent vectors: θ for the rotation part, ρ for SE(3)'s
/// translation part (ignored by SO(3)).
type Box2 = (f64, f64);

/// Bounds and sampling boxes of the property tests, per group.
struct Spec {
    /// Cases of every property test.
    cases: u32,
    /// `|Jr·Jr⁻¹ − I|`, `|Jl·Jl⁻¹ − I|` at [`Fixture::jacobian_points`].
    jj_inv_at_points: f64,
    /// `|Log(Exp τ) − τ| ≤ rel·|τ|` for τ in the box with |θ| < π − 1e-6.
    round_trip: (Box2, f64),
    /// `|Jr·Jr⁻¹ − I|`, `|Jl·Jl⁻¹ − I|` < tol for τ in the box with |θ| < θ_max:
    /// (box, θ_max, tol).
    jj_inv_random: (Box2, f64, f64),
    /// `Exp(τ + δ) ⊖ Exp(τ)·Exp(Jr δ)` at δ = 1e-3·dir and 5e-4·dir: (τ box, dir box, bound
    /// on the first error if any, floor added to 0.3× the first error).
    second_order: (Box2, Box2, Option<f64>, f64),
    /// `X·Exp(τ)·X⁻¹ = Exp(Ad(X) τ)`: (box of both, tol on [`Fixture::dist`]).
    conjugation: (Box2, f64),
    /// Group axioms for X, Y, Z = Exp of the box: (box, associativity tol, X·X⁻¹ = I tol).
    axioms: (Box2, f64, f64),
}

/// What the suite needs besides [`LieGroup`], per group.
trait Fixture<const N: usize>:
    LieGroup<Tangent = SVector<f64, N>, Jacobian = SMatrix<f64, N, N>, ActJacobian = SMatrix<f64, 3, N>>
{
    const NAME: &'static str;
    /// Points where every Jacobian is checked against central differences.
    fn jacobian_points() -> Vec<SVector<f64, N>>;
    /// The second operand of `compose`.
    fn other() -> Self;
    /// Largest absolute entry of the difference of the matrix representations.
    fn dist(a: &Self, b: &Self) -> f64;
    /// [`Fixture::dist`] with translations divided by [`SCALE`] (the manifold round trip).
    fn scaled_dist(a: &Self, b: &Self) -> f64;
    /// A uniformly rotated random element (translations up to 20 for SE(3)).
    fn random(rng: &mut SplitMix) -> Self;
    /// A random tangent with |θ| < π − 1e-6 (and |ρ| < 10 for SE(3)).
    fn random_tangent(rng: &mut SplitMix) -> SVector<f64, N>;
    /// A tangent vector with `rho` in the translation part and `theta` in the rotation part
    /// (SO(3) takes `theta`).
    fn tangent(rho: Vector3<f64>, theta: Vector3<f64>) -> SVector<f64, N>;
    /// The rotation part of a tangent vector.
    fn rotation(tau: &SVector<f64, N>) -> Vector3<f64>;
    /// `(x, δ, y)` for the right-perturbation test: x and δ do not commute.
    fn perturbation_case() -> (Self, SVector<f64, N>, Self);
    /// The fixed small tangent of the ⊕/⊖ axiom.
    fn small_step() -> SVector<f64, N>;
    fn spec() -> Spec;
}

fn rot_dist(a: &SO3, b: &SO3) -> f64 {
    (a.matrix() - b.matrix()).amax()
}

/// A random rotation vector with |φ| < π − 1e-6 (inside the domain where Log(Exp φ) = φ).
fn tangent3(rng: &mut SplitMix) -> Vector3<f64> {
    rng.unit_vector() * rng.range(0.0, PI - 1e-6)
}

impl Fixture<3> for SO3 {
    const NAME: &'static str = "SO3";
    /// θ exactly 0, tiny, small, generic, large and near π (on a coordinate and an oblique
    /// axis).
    fn jacobian_points() -> Vec<Vector3<f64>> {
        vec![
            Vector3::zeros(),
            Vector3::new(1e-9, -2e-9, 1e-9),
            Vector3::new(1e-4, 3e-4, -2e-4),
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(-1.1, 0.9, 1.7),
            Vector3::new(0.0, 0.0, PI - 1e-3),
            Vector3::new(1.0, -2.0, 3.0).normalize() * (PI - 1e-3),
        ]
    }
    fn other() -> Self {
        SO3::exp(&Vector3::new(0.2, 0.7, -0.4))
    }
    fn dist(a: &Self, b: &Self) -> f64 {
        rot_dist(a, b)
    }
    fn scaled_dist(a: &Self, b: &Self) -> f64 {
        rot_dist(a, b)
    }
    fn random(rng: &mut SplitMix) -> Self {
        SO3::from_quaternion(&rng.unit_quaternion())
    }
    fn random_tangent(rng: &mut SplitMix) -> Vector3<f64> {
        tangent3(rng)
    }
    fn tangent(_rho: Vector3<f64>, theta: Vector3<f64>) -> Vector3<f64> {
        theta
    }
    fn rotation(tau: &Vector3<f64>) -> Vector3<f64> {
        *tau
    }
    fn perturbation_case() -> (Self, Vector3<f64>, Self) {
        (
            SO3::exp(&Vector3::new(0.3, -1.1, 0.7)),
            Vector3::new(0.2, 0.1, -0.4),
            SO3::exp(&Vector3::new(-0.5, 0.4, 1.2)),
        )
    }
    fn small_step() -> Vector3<f64> {
        Vector3::new(0.1, -0.2, 0.05)
    }
    fn spec() -> Spec {
        Spec {
            cases: 300,
            jj_inv_at_points: 1e-13,
            round_trip: ((0.0, 1.8), 1e-14),
            jj_inv_random: ((0.0, 1.8), PI, 1e-12),
            second_order: ((0.0, 1.5), (0.0, 1.0), Some(1e-5), 1e-15),
            conjugation: ((0.0, 1.8), 1e-14),
            axioms: ((0.0, 3.0), 1e-14, 1e-14),
        }
    }
}

fn xi(rho: Vector3<f64>, theta: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(rho.x, rho.y, rho.z, theta.x, theta.y, theta.z)
}

impl Fixture<6> for SE3 {
    const NAME: &'static str = "SE3";
    /// θ exactly 0, tiny, small, generic, large (|θ| ≈ 2.2), past the Q-series switch at 2,
    /// and near π on a coordinate and an oblique axis; ρ fixed, plus ρ = 0 at two of them.
    fn jacobian_points() -> Vec<Vector6<f64>> {
        let rho = Vector3::new(0.7, -1.3, 0.4);
        let mut v: Vec<Vector6<f64>> = [
            Vector3::zeros(),
            Vector3::new(1e-9, -2e-9, 1e-9),
            Vector3::new(1e-4, 3e-4, -2e-4),
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(-1.1, 0.9, 1.7),
            Vector3::new(1.5, -1.2, 1.6), // |θ| ≈ 2.5: Q's closed form
            Vector3::new(0.0, 0.0, PI - 1e-3),
            Vector3::new(1.0, -2.0, 3.0).normalize() * (PI - 1e-3),
        ]
        .iter()
        .map(|th| xi(rho, *th))
        .collect();
        v.push(xi(Vector3::zeros(), Vector3::new(0.3, -0.2, 0.5)));
        v.push(xi(Vector3::zeros(), Vector3::new(0.0, 0.0, PI - 1e-3)));
        v
    }
    fn other() -> Self {
        SE3::exp(&xi(
            Vector3::new(0.5, -0.2, 0.1),
            Vector3::new(0.2, 0.7, -0.4),
        ))
    }
    fn dist(a: &Self, b: &Self) -> f64 {
        (a.matrix() - b.matrix()).amax()
    }
    fn scaled_dist(a: &Self, b: &Self) -> f64 {
        rot_dist(&a.r, &b.r).max((a.t - b.t).amax() / SCALE)
    }
    fn random(rng: &mut SplitMix) -> Self {
        SE3::new(
            SO3::from_quaternion(&rng.unit_quaternion()),
            rng.unit_vector() * rng.range(0.0, 20.0),
        )
    }
    fn random_tangent(rng: &mut SplitMix) -> Vector6<f64> {
        let (r, t) = (rng.unit_vector() * rng.range(0.0, 10.0), tangent3(rng));
        xi(r, t)
    }
    fn tangent(rho: Vector3<f64>, theta: Vector3<f64>) -> Vector6<f64> {
        xi(rho, theta)
    }
    fn rotation(tau: &Vector6<f64>) -> Vector3<f64> {
        tau.fixed_rows::<3>(3).into()
    }
    fn perturbation_case() -> (Self, Vector6<f64>, Self) {
        (
            SE3::exp(&Vector6::new(1.0, -2.0, 0.5, 0.3, -1.1, 0.7)),
            Vector6::new(0.4, 0.3, -0.2, 0.2, 0.1, -0.4),
            SE3::exp(&Vector6::new(0.2, 0.5, -1.0, -0.5, 0.4, 1.2)),
        )
    }
    fn small_step() -> Vector6<f64> {
        Vector6::new(0.3, 0.1, -0.2, 0.1, -0.2, 0.05)
    }
    fn spec() -> Spec {
        Spec {
            cases: 200,
            jj_inv_at_points: 1e-12,
            round_trip: ((5.0, 1.8), 2e-14),
            jj_inv_random: ((5.0, 1.8), PI - 1e-3, 1e-14),
            second_order: ((3.0, 1.5), (1.0, 1.0), None, 1e-14),
            conjugation: ((3.0, 1.8), 1e-13),
            axioms: ((3.0, 3.0), 1e-13, 1e-14),
        }
    }
}

/// Asserts that `an` matches `num` to 1e-8 relative and returns the error.
fn check<const R: usize, const C: usize>(
    group: &str,
    name: &str,
    an: &SMatrix<f64, R, C>,
    num: DMatrix<f64>,
) -> f64 {
    let e = rel_err(&dm(an), &num);
    assert!(
        e < 1e-8,
        "{group} {name}: relative error {e:e}\nanalytic {an}\nnumeric {num}"
    );
    e
}

fn jacobians_match_central_differences<G: Fixture<N>, const N: usize>() {
    let other = G::other();
    let p = Vector3::new(1.5, -0.3, 2.2);
    let g = G::NAME;
    let tol = G::spec().jj_inv_at_points;
    for x in G::jacobian_points() {
        let t = G::exp(&x);
        // Exp: d Exp(τ + δ) w.r.t. δ, as a right perturbation of the result = Jr(τ).
        check(
            g,
            "Jr",
            &G::jr(&x),
            num_jac(|v: &SVector<f64, N>| G::exp(v), &x, H),
        );
        check(
            g,
            "exp_jac",
            &G::exp_jac(&x).1,
            num_jac(|v: &SVector<f64, N>| G::exp(v), &x, H),
        );
        // Left Jacobian: Exp(τ + δ) = Exp(Jl δ)·Exp(τ): differentiate Log(Exp(τ + δ)·Exp(τ)⁻¹).
        let e0 = G::exp(&x);
        check(
            g,
            "Jl",
            &G::jl(&x),
            num_jac(
                |v: &SVector<f64, N>| G::exp(v).compose(&e0.inverse()).log(),
                &x,
                H,
            ),
        );
        check(g, "log", &t.log_jac().1, num_jac(|a: &G| a.log(), &t, H));
        check(
            g,
            "inverse",
            &t.inverse_jac().1,
            num_jac(|a: &G| a.inverse(), &t, H),
        );
        let (_, ja, jb) = t.compose_jac(&other);
        check(
            g,
            "compose/a",
            &ja,
            num_jac(|a: &G| a.compose(&other), &t, H),
        );
        check(
            g,
            "compose/b",
            &jb,
            num_jac(|a: &G| t.compose(a), &other, H),
        );
        let (_, jt, jp) = t.act_jac(&p);
        check(g, "act/X", &jt, num_jac(|a: &G| a.act(&p), &t, H));
        check(g, "act/p", &jp, num_jac(|v: &Vector3<f64>| t.act(v), &p, H));
        // Inverses.
        let id = SMatrix::<f64, N, N>::identity();
        assert!(
            (G::jr(&x) * G::jr_inv(&x) - id).amax() < tol,
            "{g} Jr·Jr⁻¹ at {x}"
        );
        assert!(
            (G::jl(&x) * G::jl_inv(&x) - id).amax() < tol,
            "{g} Jl·Jl⁻¹ at {x}"
        );
    }
}

#[test]
fn so3_jacobians_match_central_differences() {
    jacobians_match_central_differences::<SO3, 3>();
}

#[test]
fn se3_jacobians_match_central_differences() {
    jacobians_match_central_differences::<SE3, 6>();
}

/// Jr⁻¹(τ) = ∂ Log(Exp(τ)·Exp(δ))/∂δ and Jl⁻¹(τ) = ∂ Log(Exp(δ)·Exp(τ))/∂δ at δ = 0 (Solà
/// eqs. 144, 146 for SO(3)), differentiated directly rather than through Jr·Jr⁻¹ = I.
fn inverse_jacobians_match_central_differences_of_log<G: Fixture<N>, const N: usize>() {
    let mut worst = 0.0f64;
    for x in G::jacobian_points() {
        let e = G::exp(&x);
        let z = SVector::<f64, N>::zeros();
        let right = num_jac(|d: &SVector<f64, N>| e.compose(&G::exp(d)).log(), &z, H);
        let left = num_jac(|d: &SVector<f64, N>| G::exp(d).compose(&e).log(), &z, H);
        worst = worst.max(check(G::NAME, "Jr⁻¹", &G::jr_inv(&x), right));
        worst = worst.max(check(G::NAME, "Jl⁻¹", &G::jl_inv(&x), left));
    }
    println!(
        "{} Jr⁻¹/Jl⁻¹ vs central differences (h = {H:e}): max relative error {worst:.2e}",
        G::NAME
    );
}

#[test]
fn so3_inverse_jacobians_match_central_differences_of_log() {
    inverse_jacobians_match_central_differences_of_log::<SO3, 3>();
}

#[test]
fn se3_inverse_jacobians_match_central_differences_of_log() {
    inverse_jacobians_match_central_differences_of_log::<SE3, 6>();
}

/// Deterministic sample of |Jr·Jr⁻¹ − I| and |Jl·Jl⁻¹ − I| with the worst case printed (the
/// property test below shrinks failures): 20 000 τ with |θ| < π − 1e-3 and |ρ| < 5, bound
/// as [`Spec::jj_inv_random`].
fn jr_times_inverse_is_identity_sampled<G: Fixture<N>, const N: usize>() {
    let mut rng = SplitMix::new(9);
    let tol = G::spec().jj_inv_random.2;
    let id = SMatrix::<f64, N, N>::identity();
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let th = rng.unit_vector() * rng.range(0.0, PI - 1e-3);
        let rho = rng.unit_vector() * rng.range(0.0, 5.0);
        let x = G::tangent(rho, th);
        let e = (G::jr(&x) * G::jr_inv(&x) - id)
            .amax()
            .max((G::jl(&x) * G::jl_inv(&x) - id).amax());
        worst = worst.max(e);
        assert!(e < tol, "{} τ = {x:?}: {e:e}", G::NAME);
    }
    println!(
        "{} max |Jr·Jr⁻¹ − I|, |Jl·Jl⁻¹ − I| for |θ| < π − 1e-3, |ρ| < 5: {worst:.2e}",
        G::NAME
    );
}

#[test]
fn so3_jr_times_inverse_is_identity_sampled() {
    jr_times_inverse_is_identity_sampled::<SO3, 3>();
}

#[test]
fn se3_jr_times_inverse_is_identity_sampled() {
    jr_times_inverse_is_identity_sampled::<SE3, 6>();
}

/// `(x ⊕ (y ⊖ x), (x ⊕ δ) ⊖ x − δ)` errors, the second relative to `max(1, |δ|∞)`; asserts
/// `x ⊖ x = 0` to round-off.
fn round_trip<G: Fixture<N>, const N: usize>(x: &G, y: &G, delta: &SVector<f64, N>) -> (f64, f64) {
    let d = x.local_vec(y);
    assert_eq!(d.len(), x.dim());
    let e1 = G::scaled_dist(&x.retract(d.as_slice()), y);
    let back = x.local_vec(&x.retract(delta.as_slice()));
    let scale = delta.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let e2 = (back - DMatrix::from_column_slice(N, 1, delta.as_slice())).amax() / scale;
    // ⊖ of a point with itself is zero (to round-off: x⁻¹x ≈ I).
    assert!(x.local_vec(x).amax() <= 1e-15, "x ⊖ x ≠ 0");
    (e1, e2)
}

/// The `Manifold` impl of a group: `x ⊕ (y ⊖ x) = y` and `(x ⊕ δ) ⊖ x = δ` on 5 000 random
/// pairs. x ⊕ (y ⊖ x) = x·Exp(Log(x⁻¹y)): Exp(Log) reproduces a rotation to a few ε per entry,
/// plus two products with x (printed). (x ⊕ δ) ⊖ x = Log(x⁻¹·(x·Exp δ)) = δ up to the ε-level
/// non-orthonormality of x⁻¹x, with |θ| up to π − 1e-6: bound ≈ 3× the measured maxima.
fn retract_and_local_are_inverse<G: Fixture<N>, const N: usize>(seed: u64) {
    let mut rng = SplitMix::new(seed);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..5_000 {
        let (x, y) = (G::random(&mut rng), G::random(&mut rng));
        let d = G::random_tangent(&mut rng);
        let e = round_trip(&x, &y, &d);
        worst = (worst.0.max(e.0), worst.1.max(e.1));
    }
    println!(
        "{}: max |x ⊕ (y ⊖ x) − y| {:.2e}, |(x ⊕ δ) ⊖ x − δ| {:.2e}",
        G::NAME,
        worst.0,
        worst.1
    );
    assert!(worst.1 < 1e-13, "{} (x ⊕ δ) ⊖ x: {:e}", G::NAME, worst.1);
}

#[test]
fn so3_retract_and_local_are_inverse() {
    retract_and_local_are_inverse::<SO3, 3>(2);
}

#[test]
fn se3_retract_and_local_are_inverse() {
    retract_and_local_are_inverse::<SE3, 6>(12);
}

/// x ⊕ δ = x·Exp(δ) (body side), not Exp(δ)·x; y ⊖ x = Log(x⁻¹y).
fn perturbations_are_on_the_right<G: Fixture<N>, const N: usize>() {
    let (x, d, y) = G::perturbation_case();
    let right = x.compose(&G::exp(&d));
    let left = G::exp(&d).compose(&x);
    assert!(G::scaled_dist(&x.retract(d.as_slice()), &right) < 1e-15);
    assert!(
        G::scaled_dist(&right, &left) > 0.1,
        "the test needs non-commuting x, δ"
    );
    let mut out = [0.0; N];
    x.local(&y, &mut out);
    assert!((SVector::<f64, N>::from(out) - x.inverse().compose(&y).log()).amax() < 1e-15);
}

#[test]
fn so3_perturbations_are_on_the_right() {
    perturbations_are_on_the_right::<SO3, 3>();
}

#[test]
fn se3_perturbations_are_on_the_right() {
    perturbations_are_on_the_right::<SE3, 6>();
}

/// Tangent vectors in the box `(ρ, θ)` of [`Box2`], uniform per component.
fn tangent_box<G: Fixture<N>, const N: usize>(b: Box2) -> impl Strategy<Value = SVector<f64, N>> {
    let (r, a) = b;
    // SO(3) draws only θ; SE(3) draws ρ then θ.
    let n_rho = N - 3;
    prop::collection::vec(-1.0f64..1.0, N).prop_map(move |u| {
        SVector::<f64, N>::from_fn(|i, _| if i < n_rho { r * u[i] } else { a * u[i] })
    })
}

/// Runs a property over `cases` inputs as `proptest!` does (random seed, shrinking, the same
/// environment overrides), for a strategy built from the group's [`Spec`].
fn property<S: Strategy>(
    name: &str,
    cases: u32,
    strategy: S,
    test: impl Fn(S::Value) -> Result<(), TestCaseError>,
) {
    let mut config = ProptestConfig::with_cases(cases);
    config.source_file = Some(file!());
    if let Err(e) = TestRunner::new(config).run(&strategy, test) {
        panic!("{name}: {e}");
    }
}

/// `Log(Exp τ) = τ` to a relative bound for |θ| < π − 1e-6.
fn exp_log_round_trip<G: Fixture<N>, const N: usize>() {
    let (b, rel) = G::spec().round_trip;
    property(G::NAME, G::spec().cases, tangent_box::<G, N>(b), |x| {
        prop_assume!(G::rotation(&x).norm() < PI - 1e-6);
        prop_assert!((G::exp(&x).log() - x).norm() <= rel * x.norm().max(1e-300));
        Ok(())
    });
}

#[test]
fn so3_exp_log_round_trip() {
    exp_log_round_trip::<SO3, 3>();
}

#[test]
fn se3_exp_log_round_trip() {
    exp_log_round_trip::<SE3, 6>();
}

fn jr_times_inverse_is_identity<G: Fixture<N>, const N: usize>() {
    let (b, theta_max, tol) = G::spec().jj_inv_random;
    let id = SMatrix::<f64, N, N>::identity();
    property(G::NAME, G::spec().cases, tangent_box::<G, N>(b), |x| {
        prop_assume!(G::rotation(&x).norm() < theta_max);
        prop_assert!((G::jr(&x) * G::jr_inv(&x) - id).amax() < tol);
        prop_assert!((G::jl(&x) * G::jl_inv(&x) - id).amax() < tol);
        Ok(())
    });
}

#[test]
fn so3_jr_times_inverse_is_identity() {
    jr_times_inverse_is_identity::<SO3, 3>();
}

#[test]
fn se3_jr_times_inverse_is_identity() {
    jr_times_inverse_is_identity::<SE3, 6>();
}

/// Exp(τ + δ) = Exp(τ)·Exp(Jr δ) + O(|δ|²): halving δ must quarter the error.
fn exp_of_sum_second_order<G: Fixture<N>, const N: usize>() {
    let (b, dir_box, e1_max, floor) = G::spec().second_order;
    let s = (tangent_box::<G, N>(b), tangent_box::<G, N>(dir_box));
    property(G::NAME, G::spec().cases, s, |(x, dir)| {
        prop_assume!(dir.norm() > 0.1);
        let err = |s: f64| {
            let d = dir * s;
            G::exp(&(x + d))
                .minus(&G::exp(&x).compose(&G::exp(&(G::jr(&x) * d))))
                .norm()
        };
        let (e1, e2) = (err(1e-3), err(5e-4));
        if let Some(m) = e1_max {
            prop_assert!(e1 < m);
        }
        prop_assert!(e2 < 0.3 * e1 + floor, "e1 {e1:e} e2 {e2:e}");
        Ok(())
    });
}

#[test]
fn so3_exp_of_sum_second_order() {
    exp_of_sum_second_order::<SO3, 3>();
}

#[test]
fn se3_exp_of_sum_second_order() {
    exp_of_sum_second_order::<SE3, 6>();
}

/// `X·Exp(τ)·X⁻¹ = Exp(Ad(X) τ)`.
fn conjugation_is_adjoint<G: Fixture<N>, const N: usize>() {
    let (b, tol) = G::spec().conjugation;
    let s = (tangent_box::<G, N>(b), tangent_box::<G, N>(b));
    property(G::NAME, G::spec().cases, s, |(a, x)| {
        let t = G::exp(&a);
        let lhs = t.compose(&G::exp(&x)).compose(&t.inverse());
        let rhs = G::exp(&(t.adjoint() * x));
        prop_assert!(G::dist(&lhs, &rhs) < tol);
        Ok(())
    });
}

#[test]
fn so3_conjugation_is_adjoint() {
    conjugation_is_adjoint::<SO3, 3>();
}

#[test]
fn se3_conjugation_is_adjoint() {
    conjugation_is_adjoint::<SE3, 6>();
}

/// Associativity, inverse, identity (exact), action of a product and of the inverse, and
/// ⊕/⊖ inverse to each other.
fn group_axioms<G: Fixture<N>, const N: usize>() {
    let (b, assoc, inv) = G::spec().axioms;
    let s = (
        tangent_box::<G, N>(b),
        tangent_box::<G, N>(b),
        tangent_box::<G, N>(b),
    );
    property(G::NAME, G::spec().cases, s, |(a, b, c)| {
        let (x, y, z) = (G::exp(&a), G::exp(&b), G::exp(&c));
        prop_assert!(G::dist(&x.compose(&y).compose(&z), &x.compose(&y.compose(&z))) < assoc);
        prop_assert!(G::dist(&x.compose(&x.inverse()), &G::identity()) < inv);
        prop_assert!(x.compose(&G::identity()) == x);
        let pt = Vector3::new(0.3, 0.2, -0.1);
        prop_assert!((x.compose(&y).act(&pt) - x.act(&y.act(&pt))).norm() < 1e-13);
        prop_assert!((x.inverse().act(&x.act(&pt)) - pt).norm() < 1e-13);
        let d = G::small_step();
        prop_assert!((x.plus(&d).minus(&x) - d).norm() < 1e-14);
        Ok(())
    });
}

#[test]
fn so3_group_axioms() {
    group_axioms::<SO3, 3>();
}

#[test]
fn se3_group_axioms() {
    group_axioms::<SE3, 6>();
}
