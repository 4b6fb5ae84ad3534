//! Static calibration ([`solver::bias::calibrate_static`]) of 1 h at 200 Hz (720 000 samples,
//! EuRoC noise densities). Target (issue 5): ≤ 0.5 s. The data are generated once, outside the
//! timed loop.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use preint::{ImuNoise, ImuSample};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use solver::bias::{StaticOptions, calibrate_static};
use std::hint::black_box;

fn samples() -> Vec<ImuSample> {
    let mut rng = StdRng::seed_from_u64(0);
    let noise = ImuNoise::euroc();
    let dt: f64 = 0.005;
    let (sg, sa) = (
        noise.gyro_noise_density / dt.sqrt(),
        noise.acc_noise_density / dt.sqrt(),
    );
    let mut g = || -> Vector3<f64> {
        Vector3::new(
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
            rng.sample(StandardNormal),
        )
    };
    (0..720_000i64)
        .map(|k| {
            ImuSample::new(
                k * 5_000_000,
                Vector3::new(0.001, -0.002, 0.003) + g() * sg,
                Vector3::new(0.1, -0.2, 9.8) + g() * sa,
            )
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let s = samples();
    let noise = ImuNoise::euroc();
    let opts = StaticOptions::default();
    let mut g = c.benchmark_group("calibration");
    g.sample_size(10);
    g.bench_function("static_1h_200Hz", |b| {
        b.iter(|| calibrate_static(black_box(&s), &noise, &opts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
