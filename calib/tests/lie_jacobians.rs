//! Re-checks every Jacobian of `lie` with Ridders' method (relative error ≤ 1e-8) at generic
//! points, at θ = 1e-6 and at θ = π − 1e-3, written once for every `LieGroup` and run for
//! SO(3) and SE(3), and checks that the checker catches a wrong one.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};
use preint_calib::{CheckError, CheckOptions, NumDiffOptions, check_jacobian, to_dmatrix};
use preint_lie::{LieGroup, Manifold, SE3, SO3, hat, jl};

/// Rotation vectors: generic, tiny (θ = 1e-6), and close to π (θ = π − 1e-3).
fn phis() -> Vec<(Vector3<f64>, &'static str)> {
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    vec![
        (Vector3::new(0.4, -0.7, 1.1), "generic"),
        (axis * 1e-6, "tiny"),
        (axis * (std::f64::consts::PI - 1e-3), "near pi"),
    ]
}

/// What the generic checks need besides [`LieGroup`], per group.
trait Fixture<const N: usize>:
    LieGroup<Tangent = SVector<f64, N>, Jacobian = SMatrix<f64, N, N>, ActJacobian = SMatrix<f64, 3, N>>
{
    const NAME: &'static str;
    /// The tangents at which everything is checked: [`phis`] as rotation parts (SE(3) with a
    /// fixed translation part).
    fn points() -> Vec<(SVector<f64, N>, &'static str)>;
    /// The other operand of `compose`.
    fn other() -> Self;
    /// The point acted on.
    fn point() -> Vector3<f64>;
}

impl Fixture<3> for SO3 {
    const NAME: &'static str = "SO3";
    fn points() -> Vec<(Vector3<f64>, &'static str)> {
        phis()
    }
    fn other() -> Self {
        SO3::exp(&Vector3::new(-0.2, 0.9, 0.3))
    }
    fn point() -> Vector3<f64> {
        Vector3::new(1.5, -0.4, 2.0)
    }
}

impl Fixture<6> for SE3 {
    const NAME: &'static str = "SE3";
    fn points() -> Vec<(Vector6<f64>, &'static str)> {
        let rho = Vector3::new(0.7, -1.2, 0.4);
        phis()
            .into_iter()
            .map(|(t, tag)| (Vector6::new(rho[0], rho[1], rho[2], t[0], t[1], t[2]), tag))
            .collect()
    }
    fn other() -> Self {
        SE3::exp(&Vector6::new(0.1, 0.5, -0.9, 0.4, -0.3, 0.2))
    }
    fn point() -> Vector3<f64> {
        Vector3::new(-0.3, 2.2, 1.0)
    }
}

/// Ridders base step: the default (1e-2, first step 0.32) except where the function takes `Log`
/// of a rotation at θ = π − 1e-3: there every step must stay below the 1e-3 distance to the
/// cut, so the base step is 1e-5 (first step 3.2e-4). Elsewhere the default step is used even
/// near π (smaller steps only add round-off).
fn opts(tag: &str, log_near_cut: bool) -> CheckOptions {
    CheckOptions {
        numdiff: if tag == "near pi" && log_near_cut {
            NumDiffOptions::with_ridders_step(1e-5)
        } else {
            NumDiffOptions::default()
        },
        ..CheckOptions::default()
    }
}

fn check<X: Manifold, Y: Manifold>(
    what: &str,
    tag: &str,
    f: impl Fn(&X) -> Y,
    x: &X,
    blocks: &[DMatrix<f64>],
) {
    // Functions whose name mentions log / inverse Jacobians take Log near the cut.
    let cut = what.contains("log") || what.contains("inv");
    match check_jacobian(f, x, blocks, &opts(tag, cut)) {
        Ok(r) => {
            eprintln!(
                "{what:>24} {tag:>8}: worst rel err {:.1e}",
                r.worst_rel_error
            );
            assert!(r.worst_rel_error <= 1e-8, "{what} at {tag}: {r}")
        }
        Err(e) => panic!("{what} at {tag}: {e}"),
    }
}

/// `exp_jac` (Jr), `log_jac` (Jr⁻¹ of Log) and `inverse_jac` (−Ad).
fn exp_log_inverse<G: Fixture<N>, const N: usize>() {
    let g = G::NAME;
    for (tau, tag) in G::points() {
        let (_, jexp) = G::exp_jac(&tau);
        check(
            &format!("{g} exp"),
            tag,
            |p: &SVector<f64, N>| G::exp(p),
            &tau,
            &[to_dmatrix(&jexp)],
        );
        let x = G::exp(&tau);
        let (_, jlog) = x.log_jac();
        check(
            &format!("{g} log"),
            tag,
            |a: &G| a.log(),
            &x,
            &[to_dmatrix(&jlog)],
        );
        let (_, jinv) = x.inverse_jac();
        check(
            &format!("{g} inverse"),
            tag,
            |a: &G| a.inverse(),
            &x,
            &[to_dmatrix(&jinv)],
        );
    }
}

#[test]
fn so3_exp_log_inverse() {
    exp_log_inverse::<SO3, 3>();
}

#[test]
fn se3_exp_log_inverse() {
    exp_log_inverse::<SE3, 6>();
}

/// `compose_jac` w.r.t. both arguments, with the checked point on either side, and `act_jac`
/// w.r.t. the element and the point.
fn compose_and_act_both_arguments<G: Fixture<N>, const N: usize>() {
    let g = G::NAME;
    let (u, p) = (G::other(), G::point());
    for (tau, tag) in G::points() {
        let x = G::exp(&tau);
        for (a, b, order) in [(x, u, "X·U"), (u, x, "U·X")] {
            let (_, ja, jb) = a.compose_jac(&b);
            check(
                &format!("{g} compose {order}"),
                tag,
                |x: &(G, G)| x.0.compose(&x.1),
                &(a, b),
                &[to_dmatrix(&ja), to_dmatrix(&jb)],
            );
        }
        let (_, jx, jp) = x.act_jac(&p);
        check(
            &format!("{g} act"),
            tag,
            |x: &(G, Vector3<f64>)| x.0.act(&x.1),
            &(x, p),
            &[to_dmatrix(&jx), to_dmatrix(&jp)],
        );
    }
}

#[test]
fn so3_compose_and_act_both_arguments() {
    compose_and_act_both_arguments::<SO3, 3>();
}

#[test]
fn se3_compose_and_act_both_arguments() {
    compose_and_act_both_arguments::<SE3, 6>();
}

/// Jr, Jl, Jr⁻¹ and Jl⁻¹ by their defining properties, and the identities between them.
fn right_and_left_jacobians_and_inverses<G: Fixture<N>, const N: usize>() {
    let g = G::NAME;
    let id = SMatrix::<f64, N, N>::identity();
    for (tau, tag) in G::points() {
        let x0 = G::exp(&tau);
        // Jr: Exp(τ + δ) = Exp(τ)·Exp(Jr δ)  ⇒  d Log(Exp(τ)⁻¹ Exp(τ + δ))/dδ = Jr(τ).
        check(
            &format!("{g} Jr"),
            tag,
            |p: &SVector<f64, N>| x0.inverse().compose(&G::exp(p)).log(),
            &tau,
            &[to_dmatrix(&G::jr(&tau))],
        );
        // Jl: Exp(τ + δ) = Exp(Jl δ)·Exp(τ)  ⇒  d Log(Exp(τ + δ) Exp(τ)⁻¹)/dδ = Jl(τ).
        check(
            &format!("{g} Jl"),
            tag,
            |p: &SVector<f64, N>| G::exp(p).compose(&x0.inverse()).log(),
            &tau,
            &[to_dmatrix(&G::jl(&tau))],
        );
        // Jr⁻¹: d Log(Exp(τ)·Exp(δ))/dδ; Jl⁻¹: d Log(Exp(δ)·Exp(τ))/dδ.
        let zero = SVector::<f64, N>::zeros();
        check(
            &format!("{g} Jr_inv"),
            tag,
            |d: &SVector<f64, N>| x0.compose(&G::exp(d)).log(),
            &zero,
            &[to_dmatrix(&G::jr_inv(&tau))],
        );
        check(
            &format!("{g} Jl_inv"),
            tag,
            |d: &SVector<f64, N>| G::exp(d).compose(&x0).log(),
            &zero,
            &[to_dmatrix(&G::jl_inv(&tau))],
        );
        // Identities (not numeric): Jl(τ) = Jr(−τ), Jl(τ) = Ad(Exp τ)·Jr(τ) (R·Jr for SO(3)),
        // Jr·Jr⁻¹ = Jl·Jl⁻¹ = I.
        let e1 = (G::jl(&tau) - G::jr(&-tau)).amax();
        let e2 = (G::jl(&tau) - x0.adjoint() * G::jr(&tau)).amax();
        let e3 = (G::jr(&tau) * G::jr_inv(&tau) - id).amax();
        let e4 = (G::jl(&tau) * G::jl_inv(&tau) - id).amax();
        eprintln!("{g} identities {tag:>8}: {e1:.1e} {e2:.1e} {e3:.1e} {e4:.1e}");
        assert!(e1 < 1e-15 && e2 < 1e-14, "{g} {tag}: {e1} {e2}");
        // Jr⁻¹ grows like 1/(π − θ) near π: allow that conditioning.
        assert!(e3 < 1e-11 && e4 < 1e-11, "{g} {tag}: {e3} {e4}");
    }
}

#[test]
fn so3_right_and_left_jacobians_and_inverses() {
    right_and_left_jacobians_and_inverses::<SO3, 3>();
}

#[test]
fn se3_right_and_left_jacobians_and_inverses() {
    right_and_left_jacobians_and_inverses::<SE3, 6>();
}

/// sophus_lie 0.15's small-angle `left_jacobian` (θ ≤ 1e-3): `I − ½ŵ` instead of `I + ½ŵ`.
/// Put in block 1 of a product input, the checker must fail and point at block 1 and at an
/// off-diagonal entry carrying the largest component of w (here w_z: entries (0,1), (1,0)).
#[test]
fn checker_catches_sophus_sign_bug_and_names_block_and_entry() {
    let w = Vector3::new(1e-4, -2e-4, 4e-4);
    let bad_jl = Matrix3::identity() - hat(&w) * 0.5;
    let r0 = SO3::exp(&w);
    let f = |x: &(Vector3<f64>, Vector3<f64>)| x.0 + SO3::exp(&x.1).compose(&r0.inverse()).log();
    let x = (Vector3::new(0.5, 0.1, -0.2), w);
    // The correct Jacobian passes …
    let good = check_jacobian(
        f,
        &x,
        &[to_dmatrix(&Matrix3::identity()), to_dmatrix(&jl(&w))],
        &CheckOptions::default(),
    )
    .unwrap();
    assert!(good.worst_rel_error < 1e-8, "{good}");
    // … the flipped sign does not.
    let err = check_jacobian(
        f,
        &x,
        &[to_dmatrix(&Matrix3::identity()), to_dmatrix(&bad_jl)],
        &CheckOptions::default(),
    )
    .unwrap_err();
    let CheckError::Mismatch { report, .. } = err else {
        panic!("expected a mismatch, got {err}");
    };
    assert_eq!(report.block, 1, "{report}");
    assert!(
        matches!((report.row, report.col), (0, 1) | (1, 0)),
        "{report}"
    );
    // ŵ(0,1) = −w_z, ŵ(1,0) = w_z: the flipped ½ŵ term gives ∓2e-4 where the truth is ±2e-4
    // (up to the ŵ²/6 term, here w_x·w_y/6 ≈ 3e-9): opposite signs, magnitude |w_z|/2.
    assert!((report.analytic + report.numeric).abs() < 1e-8, "{report}");
    assert!((report.numeric.abs() - 2e-4).abs() < 1e-8, "{report}");
    // Relative error |a − n| / floor = 4e-4 / 1e-3 (floor_rel × max|block| = 1e-3 × 1).
    assert!((report.worst_rel_error - 0.4).abs() < 1e-4, "{report}");
}

#[test]
fn checker_rejects_bad_shapes() {
    let r = SO3::exp(&Vector3::new(0.1, 0.2, 0.3));
    let e = check_jacobian(
        |a: &SO3| a.log(),
        &r,
        &[DMatrix::zeros(3, 2)],
        &CheckOptions::default(),
    );
    assert!(matches!(e, Err(CheckError::Shape { .. })));
    let e = check_jacobian(
        |a: &SO3| a.log(),
        &r,
        &[DMatrix::zeros(2, 3)],
        &CheckOptions::default(),
    );
    assert!(matches!(e, Err(CheckError::Shape { block: 0, .. })));
    let e = check_jacobian(
        |a: &SO3| a.log(),
        &r,
        &[DMatrix::from_element(3, 3, f64::NAN)],
        &CheckOptions::default(),
    );
    assert!(matches!(e, Err(CheckError::NonFiniteAnalytic { .. })));
}
