//! Cost of the second-order covariance term (`preint::second_order::covariance`) of a 10 s
//! window (2 000 samples at 200 Hz) beside `preintegrate` of the same window with covariance
//! (`Level::Covariance`), in the same run.
//!
//! `CARGO_TARGET_DIR=… cargo bench -p preint --bench second_order -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, criterion_group, criterion_main};
use preint::{ImuBias, ImuNoise, Level, PreintParams, Scheme, preintegrate, second_order};
use preint_sim::synthetic_stream;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let s = synthetic_stream(2_001);
    let (t_i, t_j) = (s[0].t_ns, s[2_000].t_ns);
    let mut g = c.benchmark_group("second_order");
    g.sample_size(20);
    for scheme in [Scheme::Midpoint, Scheme::Hermite4] {
        let prm = PreintParams::from_noise(&ImuNoise::euroc())
            .with_scheme(scheme)
            .with_level(Level::Covariance);
        let m = preintegrate(&prm, &ImuBias::zero(), &s, t_i, t_j).unwrap();
        g.bench_function(format!("{scheme:?}/preintegrate"), |b| {
            b.iter(|| {
                black_box(preintegrate(
                    &prm,
                    &ImuBias::zero(),
                    black_box(&s),
                    t_i,
                    t_j,
                ))
            })
        });
        g.bench_function(format!("{scheme:?}/second_order"), |b| {
            b.iter(|| black_box(second_order::covariance(&prm, black_box(&s), &m)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
