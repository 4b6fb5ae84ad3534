//! The Rust side of `python/bench/bench.py`: times the same preintegrations the Python package
//! runs, on the same samples, and prints one JSON line of nanoseconds per sample.
//!
//! ```text
//! preint-python-bench-ref SAMPLES.bin SCHEME LEVEL RUNS [WINDOW]
//! ```
//!
//! `SAMPLES.bin`: N, then t_ns (N × i64), gyro (N × 3 f64, rad/s), acc (N × 3 f64, m/s²), all
//! little-endian (written by bench.py). Per run: `preintegrate` over [first, last sample]
//! ("one_call"), `Preintegrator::integrate_slice` + `finish` ("integrate_slice") and, with
//! WINDOW, `preintegrate` of every window of WINDOW samples ("windows"). Parameters: EuRoC noise
//! densities, the scheme and level given, zero bias. Reports the median over RUNS of each.

use preint::nalgebra::Vector3;
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, PreintParams, Preintegrator, Scheme, preintegrate,
};
use std::hint::black_box;
use std::time::Instant;

fn read(path: &str) -> Vec<ImuSample> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let word = |k: usize| <[u8; 8]>::try_from(&bytes[8 * k..8 * k + 8]).expect("8 bytes");
    let n = u64::from_le_bytes(word(0)) as usize;
    assert_eq!(bytes.len(), 8 * (1 + 7 * n), "{path}: not N + 7N words");
    let f = |k: usize| f64::from_le_bytes(word(k));
    let (g0, a0) = (1 + n, 1 + 4 * n);
    (0..n)
        .map(|k| {
            ImuSample::new(
                i64::from_le_bytes(word(1 + k)),
                Vector3::new(f(g0 + 3 * k), f(g0 + 3 * k + 1), f(g0 + 3 * k + 2)),
                Vector3::new(f(a0 + 3 * k), f(a0 + 3 * k + 1), f(a0 + 3 * k + 2)),
            )
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    assert!(
        a.len() >= 5,
        "usage: SAMPLES.bin SCHEME LEVEL RUNS [WINDOW]"
    );
    let s = read(&a[1]);
    let scheme = Scheme::from_name(&a[2]).expect("scheme");
    let level = match a[3].as_str() {
        "deltas" => Level::Deltas,
        "covariance" => Level::Covariance,
        _ => Level::Combined,
    };
    let runs: usize = a[4].parse().expect("RUNS");
    let window: Option<usize> = a.get(5).map(|w| w.parse().expect("WINDOW"));
    let p = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level);
    let b = ImuBias::zero();
    let (t0, t1, n) = (s[0].t_ns, s[s.len() - 1].t_ns, s.len() as f64);
    let (mut one, mut slice, mut win) = (vec![], vec![], vec![]);
    for _ in 0..runs {
        let t = Instant::now();
        black_box(preintegrate(&p, &b, black_box(&s), t0, t1).expect("preintegrate"));
        one.push(t.elapsed().as_secs_f64() * 1e9 / n);

        let t = Instant::now();
        let mut pi = Preintegrator::new(p.clone(), b).expect("params");
        pi.integrate_slice(black_box(&s)).expect("integrate_slice");
        black_box(pi.finish().expect("finish"));
        slice.push(t.elapsed().as_secs_f64() * 1e9 / n);

        if let Some(w) = window {
            let t = Instant::now();
            let out: Vec<_> = (0..(s.len() - 1) / w)
                .map(|k| {
                    preintegrate(&p, &b, &s, s[k * w].t_ns, s[(k + 1) * w].t_ns).expect("window")
                })
                .collect();
            black_box(out);
            win.push(t.elapsed().as_secs_f64() * 1e9 / ((s.len() - 1) / w * w) as f64);
        }
    }
    let windows = if win.is_empty() {
        "null".to_string()
    } else {
        median(win).to_string()
    };
    println!(
        "{{\"one_call\": {}, \"integrate_slice\": {}, \"windows\": {windows}}}",
        median(one),
        median(slice)
    );
}
