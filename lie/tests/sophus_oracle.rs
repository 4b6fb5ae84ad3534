//! sophus_lie 0.15 as an oracle for exp, log, compose and SE(3) log, and a demonstration of its
//! small-angle left-Jacobian defect (wrong sign of the ½ω̂ term for θ ≤ 1e-3).

mod common;
use common::*;
use nalgebra::{Vector3, Vector6};
use preint_lie::{SE3, SO3, jl, jl_inv};
use sophus_lie::{Isometry3F64, Rotation3F64};

fn angles() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1e-5, -2e-5, 3e-5),
        Vector3::new(0.3, -0.2, 0.5),
        Vector3::new(-1.1, 0.9, 1.7),
        Vector3::new(0.0, 3.0, 0.0),
    ]
}

#[test]
fn so3_exp_log_compose_agree_with_sophus() {
    for phi in angles() {
        let ours = SO3::exp(&phi);
        let theirs = Rotation3F64::exp(phi);
        assert!(
            (ours.matrix() - theirs.matrix()).amax() < 1e-15,
            "exp at {phi}"
        );
        assert!((ours.log() - theirs.log()).amax() < 1e-14, "log at {phi}");
        let b = Vector3::new(0.4, 0.1, -0.7);
        let oc = ours.compose(&SO3::exp(&b));
        let tc = theirs.group_mul(Rotation3F64::exp(b));
        assert!(
            (oc.matrix() - tc.matrix()).amax() < 1e-15,
            "compose at {phi}"
        );
    }
}

fn taylor_exp(a: &nalgebra::Matrix4<f64>) -> nalgebra::Matrix4<f64> {
    let (mut term, mut sum) = (nalgebra::Matrix4::identity(), nalgebra::Matrix4::identity());
    for k in 1..30 {
        term = term * a / k as f64;
        sum += term;
    }
    sum
}

#[test]
fn se3_exp_log_agree_with_sophus() {
    // Ours is [ρ (translation), θ (rotation)]; sophus-rs 0.15 orders it [θ, ρ].
    let swap = |v: &Vector6<f64>| Vector6::new(v[3], v[4], v[5], v[0], v[1], v[2]);
    for phi in angles() {
        let x = Vector6::new(0.7, -1.3, 0.4, phi.x, phi.y, phi.z);
        let ours = SE3::exp(&x);
        let theirs = Isometry3F64::exp(swap(&x));
        if phi.norm() > 0.0 && phi.norm() <= 1e-3 {
            // sophus-rs truncates V = Jl(θ) to I + ½θ̂ below θ = 1e-3 (error θ²|ρ|/6). Ours
            // matches the matrix-exponential series; theirs is off by about that amount.
            let series = taylor_exp(&preint_lie::se3::hat6(&x));
            assert!((ours.matrix() - series).amax() < 1e-15);
            let off = (theirs.matrix() - series).amax();
            assert!(
                off > 0.1 * phi.norm_squared() / 6.0,
                "sophus now exact: {off:e}"
            );
            continue;
        }
        assert!(
            (ours.matrix() - theirs.matrix()).amax() < 1e-14,
            "exp at {x}: ours {} theirs {}",
            ours.matrix(),
            theirs.matrix()
        );
        assert!(
            (ours.log() - swap(&theirs.log())).amax() < 1e-13,
            "log at {x}"
        );
        assert!((ours.log() - x).amax() < 1e-14);
    }
}

#[test]
fn sophus_small_angle_left_jacobian_is_wrong_and_ours_is_right() {
    let phi = Vector3::new(2e-4, -5e-4, 3e-4); // θ ≈ 6e-4 ≤ 1e-3: sophus' small-angle branch
    // Jl(φ) by central differences: Exp(φ + δ) Exp(φ)ᵀ = Exp(Jl δ).
    let e0 = SO3::exp(&phi);
    let num = num_jac(
        |p: &Vector3<f64>| SO3::exp(p).compose(&e0.inverse()).log(),
        &phi,
        1e-7,
    );
    let ours = rel_err(&dm(&jl(&phi)), &num);
    let theirs = rel_err(&dm(&Rotation3F64::left_jacobian(phi)), &num);
    assert!(ours < 1e-8, "ours: {ours:e}");
    // Their error is |φ| (the ½ω̂ term with the wrong sign): ~6e-4, far above round-off.
    assert!(theirs > 1e-4, "sophus agrees unexpectedly: {theirs:e}");
    let inv_num = num.clone().try_inverse().unwrap();
    assert!(rel_err(&dm(&jl_inv(&phi)), &inv_num) < 1e-8);
    assert!(rel_err(&dm(&Rotation3F64::inv_left_jacobian(phi)), &inv_num) > 1e-4);
    // Above the threshold sophus is right, so the disagreement is the branch, not a convention.
    let big = Vector3::new(0.2, -0.5, 0.3);
    assert!((Rotation3F64::left_jacobian(big) - jl(&big)).amax() < 1e-14);
}
