use preint::{ImuBias, ImuNoise, Level, PreintParams, Preintegrator, Scheme};
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let level = match a[1].as_str() {
        "deltas" => Level::Deltas,
        "cov" => Level::Covariance,
        _ => Level::Combined,
    };
    let scheme = match a[2].as_str() {
        "euler" => Scheme::Euler,
        "mid" => Scheme::Midpoint,
        _ => Scheme::Rk4,
    };
    let n: usize = a[3].parse().unwrap();
    let reps: usize = a[4].parse().unwrap();
    let s = preint::sample::synthetic_stream(n);
    let mut p = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level);
    p.keep_samples = false;
    let mut best = f64::INFINITY;
    let mut sink = 0.0;
    for _ in 0..reps {
        let mut pi = Preintegrator::new(p.clone(), ImuBias::default()).unwrap();
        let t = Instant::now();
        if std::env::var_os("ONE").is_some() {
            for x in &s {
                pi.integrate(x).unwrap();
            }
        } else {
            pi.integrate_slice(&s).unwrap();
        }
        let e = t.elapsed().as_secs_f64() * 1e9 / n as f64;
        sink += pi.finish().unwrap().delta_v.x;
        best = best.min(e);
    }
    println!("{:.2} ns/sample (sink {sink:e})", best);
}
