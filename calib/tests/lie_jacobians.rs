//! Re-checks every Jacobian of `lie` with Ridders' method (relative error ≤ 1e-8) at generic
//! points, at θ = 1e-6 and at θ = π − 1e-3, and checks that the checker catches a wrong one.

use nalgebra::{DMatrix, Matrix3, Vector3, Vector6};
use preint_calib::{CheckError, CheckOptions, NumDiffOptions, check_jacobian, to_dmatrix};
use preint_lie::{SE3, SO3, hat, jl, jl_inv, jr, jr_inv, se3};

/// Rotation vectors: generic, tiny (θ = 1e-6), and close to π (θ = π − 1e-3).
fn phis() -> Vec<(Vector3<f64>, &'static str)> {
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    vec![
        (Vector3::new(0.4, -0.7, 1.1), "generic"),
        (axis * 1e-6, "tiny"),
        (axis * (std::f64::consts::PI - 1e-3), "near pi"),
    ]
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

fn check<X: preint_lie::Manifold, Y: preint_lie::Manifold>(
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

#[test]
fn so3_exp_log_inverse() {
    for (phi, tag) in phis() {
        let (_, jr_a) = SO3::exp_jr(&phi);
        check(
            "SO3 exp",
            tag,
            |p: &Vector3<f64>| SO3::exp(p),
            &phi,
            &[to_dmatrix(&jr_a)],
        );
        let r = SO3::exp(&phi);
        let (_, jlog) = r.log_jac();
        check("SO3 log", tag, |a: &SO3| a.log(), &r, &[to_dmatrix(&jlog)]);
        let (_, jinv) = r.inverse_jac();
        check(
            "SO3 inverse",
            tag,
            |a: &SO3| a.inverse(),
            &r,
            &[to_dmatrix(&jinv)],
        );
    }
}

#[test]
fn so3_compose_and_act_both_arguments() {
    let v = Vector3::new(1.5, -0.4, 2.0);
    for (phi, tag) in phis() {
        let r = SO3::exp(&phi);
        let s = SO3::exp(&Vector3::new(-0.2, 0.9, 0.3));
        let (_, ja, jb) = r.compose_jac(&s);
        check(
            "SO3 compose",
            tag,
            |x: &(SO3, SO3)| x.0.compose(&x.1),
            &(r, s),
            &[to_dmatrix(&ja), to_dmatrix(&jb)],
        );
        // Also with the near-π rotation on the right-hand side.
        let (_, ja, jb) = s.compose_jac(&r);
        check(
            "SO3 compose (swapped)",
            tag,
            |x: &(SO3, SO3)| x.0.compose(&x.1),
            &(s, r),
            &[to_dmatrix(&ja), to_dmatrix(&jb)],
        );
        let (_, jr_, jv) = r.act_jac(&v);
        check(
            "SO3 act",
            tag,
            |x: &(SO3, Vector3<f64>)| x.0.act(&x.1),
            &(r, v),
            &[to_dmatrix(&jr_), to_dmatrix(&jv)],
        );
    }
}

#[test]
fn so3_right_and_left_jacobians_and_inverses() {
    for (phi, tag) in phis() {
        let r0 = SO3::exp(&phi);
        // Jr: Exp(φ + δ) = Exp(φ)·Exp(Jr δ)  ⇒  d Log(Exp(φ)ᵀ Exp(φ + δ))/dδ = Jr(φ).
        check(
            "Jr",
            tag,
            |p: &Vector3<f64>| r0.inverse().compose(&SO3::exp(p)).log(),
            &phi,
            &[to_dmatrix(&jr(&phi))],
        );
        // Jl: Exp(φ + δ) = Exp(Jl δ)·Exp(φ)  ⇒  d Log(Exp(φ + δ) Exp(φ)ᵀ)/dδ = Jl(φ).
        check(
            "Jl",
            tag,
            |p: &Vector3<f64>| SO3::exp(p).compose(&r0.inverse()).log(),
            &phi,
            &[to_dmatrix(&jl(&phi))],
        );
        // Jr⁻¹: d Log(Exp(φ)·Exp(δ))/dδ; Jl⁻¹: d Log(Exp(δ)·Exp(φ))/dδ.
        let zero = Vector3::zeros();
        check(
            "Jr_inv",
            tag,
            |d: &Vector3<f64>| r0.compose(&SO3::exp(d)).log(),
            &zero,
            &[to_dmatrix(&jr_inv(&phi))],
        );
        check(
            "Jl_inv",
            tag,
            |d: &Vector3<f64>| SO3::exp(d).compose(&r0).log(),
            &zero,
            &[to_dmatrix(&jl_inv(&phi))],
        );
        // Identities (not numeric): Jl(φ) = Jr(−φ), Jl(φ) = R Jr(φ), Jr Jr⁻¹ = I.
        let e1 = (jl(&phi) - jr(&-phi)).amax();
        let e2 = (jl(&phi) - r0.matrix() * jr(&phi)).amax();
        let e3 = (jr(&phi) * jr_inv(&phi) - Matrix3::identity()).amax();
        let e4 = (jl(&phi) * jl_inv(&phi) - Matrix3::identity()).amax();
        assert!(e1 < 1e-15 && e2 < 1e-14, "{tag}: {e1} {e2}");
        // Jr⁻¹ grows like 1/(π − θ) near π: allow that conditioning.
        assert!(e3 < 1e-11 && e4 < 1e-11, "{tag}: {e3} {e4}");
    }
}

fn xis() -> Vec<(Vector6<f64>, &'static str)> {
    let rho = Vector3::new(0.7, -1.2, 0.4);
    phis()
        .into_iter()
        .map(|(t, tag)| (Vector6::new(rho[0], rho[1], rho[2], t[0], t[1], t[2]), tag))
        .collect()
}

#[test]
fn se3_exp_log_inverse() {
    for (xi, tag) in xis() {
        let (_, jexp) = SE3::exp_jac(&xi);
        check(
            "SE3 exp",
            tag,
            |p: &Vector6<f64>| SE3::exp(p),
            &xi,
            &[to_dmatrix(&jexp)],
        );
        let t = SE3::exp(&xi);
        let (_, jlog) = t.log_jac();
        check("SE3 log", tag, |a: &SE3| a.log(), &t, &[to_dmatrix(&jlog)]);
        let (_, jinv) = t.inverse_jac();
        check(
            "SE3 inverse",
            tag,
            |a: &SE3| a.inverse(),
            &t,
            &[to_dmatrix(&jinv)],
        );
        // se3::jl / jl_inv by their defining property, jr_inv as the inverse of jr.
        let zero = Vector6::zeros();
        check(
            "SE3 Jl",
            tag,
            |p: &Vector6<f64>| SE3::exp(p).compose(&t.inverse()).log(),
            &xi,
            &[to_dmatrix(&se3::jl(&xi))],
        );
        check(
            "SE3 Jl_inv",
            tag,
            |d: &Vector6<f64>| SE3::exp(d).compose(&t).log(),
            &zero,
            &[to_dmatrix(&se3::jl_inv(&xi))],
        );
        check(
            "SE3 Jr_inv",
            tag,
            |d: &Vector6<f64>| t.compose(&SE3::exp(d)).log(),
            &zero,
            &[to_dmatrix(&se3::jr_inv(&xi))],
        );
    }
}

#[test]
fn se3_compose_and_act_both_arguments() {
    let p = Vector3::new(-0.3, 2.2, 1.0);
    for (xi, tag) in xis() {
        let t = SE3::exp(&xi);
        let u = SE3::exp(&Vector6::new(0.1, 0.5, -0.9, 0.4, -0.3, 0.2));
        for (a, b, order) in [(t, u, "T·U"), (u, t, "U·T")] {
            let (_, ja, jb) = a.compose_jac(&b);
            check(
                &format!("SE3 compose {order}"),
                tag,
                |x: &(SE3, SE3)| x.0.compose(&x.1),
                &(a, b),
                &[to_dmatrix(&ja), to_dmatrix(&jb)],
            );
        }
        let (_, jt, jp) = t.act_jac(&p);
        check(
            "SE3 act",
            tag,
            |x: &(SE3, Vector3<f64>)| x.0.act(&x.1),
            &(t, p),
            &[to_dmatrix(&jt), to_dmatrix(&jp)],
        );
    }
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
