//! The `Manifold` trait: retract (`x ⊕ δ`) and local coordinates (`y ⊖ x`) are inverse to each
//! other, `x ⊕ (y ⊖ x) = y` and `(x ⊕ δ) ⊖ x = δ`, for vectors (f64, SVector, DVector) and
//! products (Vec, tuples) of vectors and groups; products concatenate the tangents in order.
//! The groups' own implementations (round trips, perturbations on the right) are checked for
//! every group in `group.rs`.

mod common;
use common::*;
use nalgebra::{DVector, SVector, Vector3, Vector6};
use preint_lie::{Manifold, SE3, SO3};
use std::f64::consts::PI;

/// `(dist(x ⊕ (y ⊖ x), y), max |(x ⊕ δ) ⊖ x − δ| / scale)`.
fn round_trip_scaled<M: Manifold>(
    x: &M,
    y: &M,
    delta: &[f64],
    dist: impl Fn(&M, &M) -> f64,
    scale: f64,
) -> (f64, f64) {
    assert_eq!(delta.len(), x.dim());
    let d = x.local_vec(y);
    assert_eq!(d.len(), x.dim());
    let e1 = dist(&x.retract(d.as_slice()), y);
    let back = x.local_vec(&x.retract(delta));
    let want = DVector::from_column_slice(delta);
    let e2 = (back - &want).amax() / scale;
    // ⊖ of a point with itself is zero (to round-off for the groups: x⁻¹x ≈ I).
    assert!(x.local_vec(x).amax() <= 1e-15, "x ⊖ x ≠ 0");
    (e1, e2)
}

/// [`round_trip_scaled`] with the error of δ relative to `max(1, |δ|∞)`.
fn round_trip<M: Manifold>(
    x: &M,
    y: &M,
    delta: &[f64],
    dist: impl Fn(&M, &M) -> f64,
) -> (f64, f64) {
    let scale = delta.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    round_trip_scaled(x, y, delta, dist, scale)
}

fn rot_dist(a: &SO3, b: &SO3) -> f64 {
    (a.matrix() - b.matrix()).amax()
}

/// Every vector entry, translation and tangent in these tests is bounded by `SCALE` in
/// magnitude, so rounding errors of sums are bounded by a few ε·SCALE: the distances below are
/// relative to it (a relative-to-the-result measure would be meaningless when y ≈ 0 but x is
/// large).
const SCALE: f64 = 100.0;

fn pose_dist(a: &SE3, b: &SE3) -> f64 {
    rot_dist(&a.r, &b.r).max((a.t - b.t).amax() / SCALE)
}

fn vec_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / SCALE)
        .fold(0.0, f64::max)
}

/// A random rotation vector with |φ| < π − 1e-6 (inside the domain where Log(Exp φ) = φ).
fn tangent3(rng: &mut SplitMix) -> Vector3<f64> {
    rng.unit_vector() * rng.range(0.0, PI - 1e-6)
}

fn pose(rng: &mut SplitMix) -> SE3 {
    SE3::new(
        SO3::from_quaternion(&rng.unit_quaternion()),
        rng.unit_vector() * rng.range(0.0, 20.0),
    )
}

fn tangent6(rng: &mut SplitMix) -> Vector6<f64> {
    let (r, t) = (rng.unit_vector() * rng.range(0.0, 10.0), tangent3(rng));
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

#[test]
fn vectors_retract_and_local_are_inverse() {
    let mut rng = SplitMix::new(1);
    let mut worst = (0.0f64, 0.0f64);
    for _ in 0..2_000 {
        let mut u = || rng.range(-100.0, 100.0);
        let (x, y, d) = (u(), u(), u());
        let e = round_trip_scaled(&x, &y, &[d], |a, b| vec_dist(&[*a], &[*b]), SCALE);
        worst = (worst.0.max(e.0), worst.1.max(e.1));
        let (x, y, d) = (
            SVector::<f64, 4>::from_fn(|_, _| u()),
            SVector::<f64, 4>::from_fn(|_, _| u()),
            SVector::<f64, 4>::from_fn(|_, _| u()),
        );
        let e = round_trip_scaled(
            &x,
            &y,
            d.as_slice(),
            |a, b| vec_dist(a.as_slice(), b.as_slice()),
            SCALE,
        );
        worst = (worst.0.max(e.0), worst.1.max(e.1));
        let (x, y, d) = (
            DVector::from_fn(7, |_, _| u()),
            DVector::from_fn(7, |_, _| u()),
            DVector::from_fn(7, |_, _| u()),
        );
        let e = round_trip_scaled(
            &x,
            &y,
            d.as_slice(),
            |a, b| vec_dist(a.as_slice(), b.as_slice()),
            SCALE,
        );
        worst = (worst.0.max(e.0), worst.1.max(e.1));
    }
    println!(
        "vectors: max |x ⊕ (y ⊖ x) − y|, |(x ⊕ δ) ⊖ x − δ| relative to the operand scale: {:.2e}, {:.2e}",
        worst.0, worst.1
    );
    // Plain addition and subtraction: two roundings, each ≤ ½ ulp of a magnitude ≤ 2·SCALE.
    assert!(
        worst.0 <= 2.0 * f64::EPSILON && worst.1 <= 2.0 * f64::EPSILON,
        "{worst:?}"
    );
    assert_eq!(DVector::<f64>::zeros(0).dim(), 0);
    assert_eq!(SVector::<f64, 4>::zeros().dim(), 4);
    assert_eq!(2.5f64.retract(&[0.5]), 3.0);
}

#[test]
fn products_concatenate_tangents_in_order() {
    let mut rng = SplitMix::new(3);
    let r = SO3::from_quaternion(&rng.unit_quaternion());
    let v = Vector3::new(1.0, 2.0, 3.0);
    // Tuple (f64, SO3, Vector3): tangent [a | φ | v], dim 1 + 3 + 3.
    let x = (0.5f64, r, v);
    assert_eq!(x.dim(), 7);
    let d = [0.25, 0.1, -0.2, 0.3, -1.0, 0.0, 2.0];
    let y = x.retract(&d);
    assert_eq!(y.0, 0.75);
    assert!(rot_dist(&y.1, &(r * SO3::exp(&Vector3::new(0.1, -0.2, 0.3)))) < 1e-15);
    assert_eq!(y.2, Vector3::new(0.0, 2.0, 5.0));
    let back = x.local_vec(&y);
    assert!((back - DVector::from_column_slice(&d)).amax() < 1e-15);

    // Vec<SE3>: a perturbation of block k moves element k only.
    let xs: Vec<SE3> = (0..4).map(|_| pose(&mut rng)).collect();
    assert_eq!(xs.dim(), 24);
    let mut d = vec![0.0; 24];
    d[2 * 6 + 4] = 0.3; // element 2, θ_y
    let ys = xs.retract(&d);
    for (k, (a, b)) in xs.iter().zip(&ys).enumerate() {
        if k == 2 {
            assert!(
                pose_dist(
                    b,
                    &a.compose(&SE3::exp(&Vector6::new(0.0, 0.0, 0.0, 0.0, 0.3, 0.0)))
                ) < 1e-15
            );
        } else {
            assert_eq!(a, b, "element {k} moved");
        }
    }
}

#[test]
fn products_retract_and_local_are_inverse() {
    let mut rng = SplitMix::new(4);
    let mut worst = (0.0f64, 0.0f64);
    let mut keep = |e: (f64, f64)| worst = (worst.0.max(e.0), worst.1.max(e.1));
    for _ in 0..1_000 {
        // Pair, triple, quadruple and quintuple of mixed types, and Vec<SO3>, Vec<(SE3, f64)>.
        let r = |rng: &mut SplitMix| SO3::from_quaternion(&rng.unit_quaternion());
        let v3 = |rng: &mut SplitMix| {
            Vector3::new(
                rng.range(-9.0, 9.0),
                rng.range(-9.0, 9.0),
                rng.range(-9.0, 9.0),
            )
        };
        let (x2, y2) = ((r(&mut rng), v3(&mut rng)), (r(&mut rng), v3(&mut rng)));
        let d2: Vec<f64> = tangent3(&mut rng)
            .iter()
            .chain(v3(&mut rng).iter())
            .copied()
            .collect();
        keep(round_trip(&x2, &y2, &d2, |a, b| {
            rot_dist(&a.0, &b.0).max(vec_dist(a.1.as_slice(), b.1.as_slice()))
        }));

        let x3 = (pose(&mut rng), v3(&mut rng), 1.5f64);
        let y3 = (pose(&mut rng), v3(&mut rng), -2.0f64);
        let d3: Vec<f64> = tangent6(&mut rng)
            .iter()
            .chain(v3(&mut rng).iter())
            .chain([0.7].iter())
            .copied()
            .collect();
        keep(round_trip(&x3, &y3, &d3, |a, b| {
            pose_dist(&a.0, &b.0)
                .max(vec_dist(a.1.as_slice(), b.1.as_slice()))
                .max(vec_dist(&[a.2], &[b.2]))
        }));

        let x4 = (
            r(&mut rng),
            v3(&mut rng),
            v3(&mut rng),
            DVector::from_element(2, 1.0),
        );
        let y4 = (
            r(&mut rng),
            v3(&mut rng),
            v3(&mut rng),
            DVector::from_element(2, -3.0),
        );
        let d4: Vec<f64> = (0..11)
            .map(|k| if k < 3 { 0.5 } else { rng.range(-1.0, 1.0) })
            .collect();
        keep(round_trip(&x4, &y4, &d4, |a, b| {
            rot_dist(&a.0, &b.0)
                .max(vec_dist(a.1.as_slice(), b.1.as_slice()))
                .max(vec_dist(a.2.as_slice(), b.2.as_slice()))
                .max(vec_dist(a.3.as_slice(), b.3.as_slice()))
        }));

        let x5 = (1.0f64, 2.0f64, r(&mut rng), pose(&mut rng), v3(&mut rng));
        let y5 = (-1.0f64, 4.0f64, r(&mut rng), pose(&mut rng), v3(&mut rng));
        let d5: Vec<f64> = [0.1, 0.2]
            .iter()
            .chain(tangent3(&mut rng).iter())
            .chain(tangent6(&mut rng).iter())
            .chain(v3(&mut rng).iter())
            .copied()
            .collect();
        assert_eq!(x5.dim(), 14);
        keep(round_trip(&x5, &y5, &d5, |a, b| {
            vec_dist(&[a.0, a.1], &[b.0, b.1])
                .max(rot_dist(&a.2, &b.2))
                .max(pose_dist(&a.3, &b.3))
                .max(vec_dist(a.4.as_slice(), b.4.as_slice()))
        }));

        let xs: Vec<SO3> = (0..5).map(|_| r(&mut rng)).collect();
        let ys: Vec<SO3> = (0..5).map(|_| r(&mut rng)).collect();
        let ds: Vec<f64> = (0..5)
            .flat_map(|_| tangent3(&mut rng).iter().copied().collect::<Vec<_>>())
            .collect();
        keep(round_trip(&xs, &ys, &ds, |a, b| {
            a.iter()
                .zip(b)
                .map(|(p, q)| rot_dist(p, q))
                .fold(0.0, f64::max)
        }));

        let xp: Vec<(SE3, f64)> = (0..3).map(|k| (pose(&mut rng), k as f64)).collect();
        let yp: Vec<(SE3, f64)> = (0..3).map(|k| (pose(&mut rng), -(k as f64))).collect();
        let dp: Vec<f64> = (0..3)
            .flat_map(|_| {
                tangent6(&mut rng)
                    .iter()
                    .copied()
                    .chain([0.3])
                    .collect::<Vec<_>>()
            })
            .collect();
        keep(round_trip(&xp, &yp, &dp, |a, b| {
            a.iter()
                .zip(b)
                .map(|(p, q)| pose_dist(&p.0, &q.0).max(vec_dist(&[p.1], &[q.1])))
                .fold(0.0, f64::max)
        }));
    }
    println!(
        "products: max |x ⊕ (y ⊖ x) − y| {:.2e}, |(x ⊕ δ) ⊖ x − δ| {:.2e}",
        worst.0, worst.1
    );
    // The components' own bounds (≈ 3× their measured maxima).
    assert!(worst.0 < 4e-15 && worst.1 < 6e-15, "{worst:?}");
}
