//! Per-sample cost of each scheme on a long synthetic stream (10⁵ samples, 200 Hz), with
//! deltas only, with the 9×9 covariance and bias Jacobians, and with the combined 15×15.
//! The same stream, parameters and loop (`integrate_slice`, `keep_samples` off) as
//! `preint speed`, so the two must agree within the machine's noise; `per_sample/…` measures
//! the one-sample-at-a-time `integrate` API for comparison.
//!
//! `CARGO_TARGET_DIR=… cargo bench -p preint --bench preint -- --warm-up-time 1 --measurement-time 3`
//! Throughput is reported per sample (elements/s ⇒ ns/sample = 1e9 / rate).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use preint::{ImuBias, ImuNoise, Level, PreintParams, Preintegrator, Scheme};
use preint_sim::synthetic_stream;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let n = 100_000;
    let s = synthetic_stream(n);
    let mut g = c.benchmark_group("preint");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(10);
    for &scheme in Scheme::ALL {
        for level in [Level::Deltas, Level::Covariance, Level::Combined] {
            let mut prm = PreintParams::from_noise(&ImuNoise::euroc())
                .with_scheme(scheme)
                .with_level(level);
            prm.keep_samples = false;
            g.bench_function(format!("{scheme:?}/{level:?}"), |b| {
                b.iter(|| {
                    let mut pi = Preintegrator::new(prm.clone(), ImuBias::zero()).unwrap();
                    pi.integrate_slice(black_box(&s)).unwrap();
                    black_box(pi.finish().unwrap())
                })
            });
            if level == Level::Covariance {
                g.bench_function(format!("per_sample/{scheme:?}/{level:?}"), |b| {
                    b.iter(|| {
                        let mut pi = Preintegrator::new(prm.clone(), ImuBias::zero()).unwrap();
                        for x in &s {
                            pi.integrate(black_box(x)).unwrap();
                        }
                        black_box(pi.finish().unwrap())
                    })
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
