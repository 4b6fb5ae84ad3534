//! exp, log, Jr, Jr⁻¹ and SE(3) exp/log, each beside sophus_lie 0.15's equivalent.
//! Run: `cargo bench -p preint-lie --bench lie`.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Vector3, Vector6};
use preint_lie::{SE3, SO3, jr, jr_inv};
use sophus_lie::{Isometry3F64, Rotation3F64};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // A per-sample-sized angle (0.05 rad) and a large one (2 rad).
    for (label, phi) in [
        ("small", Vector3::new(0.02, -0.03, 0.035)),
        ("large", Vector3::new(0.9, -1.2, 1.1)),
    ] {
        let r = SO3::exp(&phi);
        let sr = Rotation3F64::exp(phi);
        let mut g = c.benchmark_group(format!("so3_{label}"));
        g.bench_function("exp/ours", |b| b.iter(|| SO3::exp(black_box(&phi))));
        g.bench_function("exp/sophus", |b| {
            b.iter(|| Rotation3F64::exp(black_box(phi)))
        });
        g.bench_function("log/ours", |b| b.iter(|| black_box(&r).log()));
        g.bench_function("log/sophus", |b| b.iter(|| black_box(&sr).log()));
        g.bench_function("jr/ours", |b| b.iter(|| jr(black_box(&phi))));
        // sophus has only the left Jacobian; Jr(φ) = Jl(−φ).
        g.bench_function("jr/sophus", |b| {
            b.iter(|| Rotation3F64::left_jacobian(-black_box(phi)))
        });
        g.bench_function("jr_inv/ours", |b| b.iter(|| jr_inv(black_box(&phi))));
        g.bench_function("jr_inv/sophus", |b| {
            b.iter(|| Rotation3F64::inv_left_jacobian(-black_box(phi)))
        });
        g.finish();
    }
    let x = Vector6::new(0.7, -1.3, 0.4, 0.9, -1.2, 1.1);
    let xs = Vector6::new(0.9, -1.2, 1.1, 0.7, -1.3, 0.4); // sophus-rs order [θ, ρ]
    let t = SE3::exp(&x);
    let st = Isometry3F64::exp(xs);
    let mut g = c.benchmark_group("se3");
    g.bench_function("exp/ours", |b| b.iter(|| SE3::exp(black_box(&x))));
    g.bench_function("exp/sophus", |b| {
        b.iter(|| Isometry3F64::exp(black_box(xs)))
    });
    g.bench_function("log/ours", |b| b.iter(|| black_box(&t).log()));
    g.bench_function("log/sophus", |b| b.iter(|| black_box(&st).log()));
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
