//! Allan deviation of 1 h at 200 Hz, six channels (720 000 samples each), 10 τ per decade,
//! including the N/K/B fits. Target: ≤ 1 s.

use criterion::{Criterion, criterion_group, criterion_main};
use preint_calib::allan::ImuAllan;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use std::hint::black_box;

fn channels() -> Vec<Vec<f64>> {
    let mut rng = StdRng::seed_from_u64(0);
    let dt: f64 = 0.005;
    (0..6)
        .map(|c| {
            let (n, k) = if c < 3 {
                (1.7e-4, 1.9e-5)
            } else {
                (2e-3, 3e-3)
            };
            let mut b = if c == 5 { 9.81 } else { 0.0 };
            (0..720_000)
                .map(|_| {
                    let w: f64 = rng.sample(StandardNormal);
                    let z: f64 = rng.sample(StandardNormal);
                    let y = b + w * n / dt.sqrt();
                    b += z * k * dt.sqrt();
                    y
                })
                .collect()
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let ch = channels();
    let mut g = c.benchmark_group("allan");
    g.sample_size(10);
    g.bench_function("six_channels_1h_200Hz", |b| {
        b.iter(|| {
            ImuAllan::from_channels(
                [&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]],
                black_box(0.005),
                10,
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
