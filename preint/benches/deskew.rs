//! Cost of the state inside a window (`preint::deskew`): one window of 20 000 samples (200 Hz,
//! 100 s) queried at M = 1 (`t_j`: the pass alone), 20 000 or 200 000 sorted times (between
//! samples), against
//! `preintegrate` of the same window at `Level::Deltas`. The pass costs about one deltas step
//! per sample; each query adds at most three (hermite4) or one (Euler, midpoint) steps.
//!
//! `CARGO_TARGET_DIR=… cargo bench -p preint --bench deskew -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, criterion_group, criterion_main};
use preint::deskew::deltas_at;
use preint::{ImuBias, Level, PreintParams, Scheme, preintegrate};
use preint_sim::synthetic_stream;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let s = synthetic_stream(20_010);
    let (t_i, t_j) = (s[3].t_ns + 1_234, s[20_003].t_ns - 4_321);
    let mut g = c.benchmark_group("deskew");
    g.sample_size(10);
    for &scheme in Scheme::ALL {
        let prm = PreintParams::default()
            .with_scheme(scheme)
            .with_level(Level::Deltas);
        g.bench_function(format!("{scheme:?}/window"), |b| {
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
        for m in [1i64, 20_000, 200_000] {
            let times: Vec<i64> = (1..=m).map(|k| t_i + k * ((t_j - t_i) / m)).collect();
            g.bench_function(format!("{scheme:?}/queries_{m}"), |b| {
                b.iter(|| {
                    black_box(deltas_at(
                        &prm,
                        &ImuBias::zero(),
                        black_box(&s),
                        (t_i, t_j),
                        &times,
                    ))
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
