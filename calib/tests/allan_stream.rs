//! Streaming Allan analysis ([`AllanStream`]): equal to the in-memory analysis while it holds
//! the samples themselves, block means that equal directly computed ones after merging, and
//! agreement with the full overlapping estimator within its confidence at large τ. A recording
//! and its block means give the same white-noise density (a first-order low-pass, like an
//! IMU's internal filter, puts the curve below the white-noise line at short τ). The stillness
//! check passes a static recording and refuses a tilted one. And, with `PREINT_FULL=1`, the
//! real ADIS16405 hour at 100 Hz (`../shared/data/static_adis16405`) against its committed
//! 10 Hz block means.

use nalgebra::Vector3;
use preint::{ImuNoise, ImuSample};
use preint_calib::allan::{
    AllanStream, ImuAllan, StillnessMonitor, StillnessOptions, allan_deviation,
    log_spaced_cluster_sizes,
};
use preint_lie::SO3;
use preint_sim::{SimConfig, StaticScene, simulate};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

/// `sim` static samples at `rate` for `duration` s (white noise and bias random walk).
fn sim_static(rate: f64, duration: f64, seed: u64) -> Vec<ImuSample> {
    let noise = ImuNoise {
        gyro_noise_density: 1e-3,
        gyro_random_walk: 1e-4,
        acc_noise_density: 2e-3,
        acc_random_walk: 3e-4,
        update_rate_hz: rate,
    };
    let cfg = SimConfig {
        noise,
        ..SimConfig::default()
    };
    let scene = StaticScene::new(SO3::exp(&Vector3::new(0.2, -0.1, 0.3)), Vector3::zeros());
    simulate(&scene, rate, duration, &cfg, seed)
        .unwrap()
        .samples
}

fn stream_of(samples: &[ImuSample], max_blocks: usize) -> AllanStream {
    let mut s = AllanStream::with_max_blocks(max_blocks);
    for x in samples {
        s.push(x).unwrap();
    }
    s
}

fn channel(s: &ImuSample, c: usize) -> f64 {
    if c < 3 { s.gyro[c] } else { s.acc[c - 3] }
}

/// While the store holds the samples themselves (b = 1) the streamed curves and fits are those
/// of [`ImuAllan::from_samples`] (up to the round-off of the reference subtracted).
#[test]
fn one_sample_blocks_equal_the_in_memory_analysis() {
    let samples = sim_static(100.0, 600.0, 1);
    let s = stream_of(&samples, 1 << 20);
    assert_eq!(s.block_len(), 1);
    let a = s.finish(10).unwrap();
    let b = ImuAllan::from_samples(&samples, 10).unwrap();
    assert_eq!(a.tau0, a.dt);
    for c in 0..6 {
        assert_eq!(a.curves[c].len(), b.curves[c].len());
        for (p, q) in a.curves[c].iter().zip(&b.curves[c]) {
            assert_eq!(p.m, q.m);
            assert!((p.adev / q.adev - 1.0).abs() < 1e-9, "{p:?} vs {q:?}");
        }
        let (f, g) = (&a.fits[c], &b.fits[c]);
        assert!((f.white_density / g.white_density - 1.0).abs() < 1e-9);
        assert!((f.random_walk / g.random_walk - 1.0).abs() < 1e-9);
    }
}

/// With a store of 64 blocks, 10 000 samples end in blocks of 256 samples (39 of them; the last
/// 16 samples are left out), each the mean of its samples summed here directly.
#[test]
fn merged_blocks_are_the_means_of_their_samples() {
    let samples = &sim_static(100.0, 100.0, 2)[..10_000];
    let s = stream_of(samples, 64);
    assert_eq!(s.block_len(), 256);
    let a = s.finish(10).unwrap();
    assert!((a.tau0 - 2.56).abs() < 1e-9, "{}", a.tau0);
    for c in [0, 4] {
        let means: Vec<f64> = samples
            .chunks_exact(256)
            .map(|b| b.iter().map(|x| channel(x, c)).sum::<f64>() / 256.0)
            .collect();
        assert_eq!(means.len(), 39);
        let direct = allan_deviation(&means, 2.56, &[1, 2, 4]).unwrap();
        for q in direct {
            let p = a.curves[c].iter().find(|p| p.m == q.m).unwrap();
            assert!((p.adev / q.adev - 1.0).abs() < 1e-9, "{p:?} vs {q:?}");
        }
    }
}

/// The block-mean estimator at τ = mτ₀ (starts stepping by τ₀ = 64Δt) against the full
/// overlapping one (stepping by Δt) on 2 h at 50 Hz of white noise and random walk: within
/// twice the point's 1-σ error `σ/√(2ν)` at every τ with at least 8 clusters.
#[test]
fn block_means_agree_with_the_full_estimator_within_its_confidence() {
    let samples = sim_static(50.0, 7200.0, 3);
    let s = stream_of(&samples, 8192);
    assert_eq!(s.block_len(), 64);
    let a = s.finish(10).unwrap();
    let mut compared = 0;
    for c in 0..6 {
        let y: Vec<f64> = samples.iter().map(|x| channel(x, c)).collect();
        let ms: Vec<usize> = a.curves[c].iter().map(|p| p.m * 64).collect();
        let full = allan_deviation(&y, 0.02, &ms).unwrap();
        for (p, q) in a.curves[c].iter().zip(&full) {
            assert!((p.tau - q.tau).abs() < 1e-9);
            if q.clusters < 8.0 {
                continue;
            }
            assert!(
                (p.adev - q.adev).abs() <= 2.0 * q.adev_err,
                "channel {c}, τ {}: {} vs {} ± {}",
                p.tau,
                p.adev,
                q.adev,
                q.adev_err
            );
            compared += 1;
        }
    }
    assert!(compared >= 6 * 15, "{compared}");
}

/// First-order low-passed white noise at 100 Hz (y_k = αy_{k−1} + (1 − α)x_k, α = 0.2, i.e.
/// α = e^{−Δt/T} with T = 6.2 ms; unit DC gain, so the density seen at long τ is the input's),
/// N = 1e-3 (gyro channels) and 2e-3 (accelerometer channels), one hour. `σ√τ / N` of this
/// filter is 0.73 at τ = Δt and 0.966 at τ = 10Δt (numerical Allan variance of the AR(1)
/// process); the ADIS16405 gyros show 0.78 and 0.963.
fn filtered_hour(seed: u64) -> Vec<Vec<f64>> {
    let (dt, alpha) = (0.01f64, 0.2);
    let mut rng = StdRng::seed_from_u64(seed);
    (0..6)
        .map(|c| {
            let sd = if c < 3 { 1e-3 } else { 2e-3 } / dt.sqrt();
            let mut y = 0.0;
            (0..360_000)
                .map(|_| {
                    let x: f64 = rng.sample::<f64, _>(StandardNormal) * sd;
                    y = alpha * y + (1.0 - alpha) * x;
                    y
                })
                .collect()
        })
        .collect()
}

/// The 100 Hz recording and its 10 Hz block means give the same N within their combined 1-σ
/// errors (×2), and both lie within 4 % of the true density (the filter's deficit at τ = 0.1 s,
/// where the fit of N starts, is 3.4 % in σ). The test has teeth: at τ = Δt the curve lies
/// ≥ 15 % below the white-noise line, where a fit reading it would land.
#[test]
fn a_filtered_recording_and_its_block_means_give_the_same_density() {
    let raw = filtered_hour(4);
    let blocks: Vec<Vec<f64>> = raw
        .iter()
        .map(|c| {
            c.chunks_exact(10)
                .map(|b| b.iter().sum::<f64>() / 10.0)
                .collect()
        })
        .collect();
    let ch = |v: &[Vec<f64>]| -> [Vec<f64>; 6] { std::array::from_fn(|c| v[c].clone()) };
    let (r, b) = (ch(&raw), ch(&blocks));
    let fast = ImuAllan::from_channels(std::array::from_fn(|c| r[c].as_slice()), 0.01, 10).unwrap();
    let slow = ImuAllan::from_channels(std::array::from_fn(|c| b[c].as_slice()), 0.1, 10).unwrap();
    for c in 0..6 {
        let truth = if c < 3 { 1e-3 } else { 2e-3 };
        let (f, s) = (&fast.fits[c], &slow.fits[c]);
        println!(
            "channel {c}: N 100 Hz {:.4e} ± {:.1e}, 10 Hz block means {:.4e} ± {:.1e}, truth {truth:e}",
            f.white_density, f.white_density_err, s.white_density, s.white_density_err
        );
        assert!(!f.white_density_is_bound && !s.white_density_is_bound);
        let tol = 2.0 * f.white_density_err.hypot(s.white_density_err);
        assert!(
            (f.white_density - s.white_density).abs() <= tol,
            "channel {c}: {} vs {} (tolerance {tol:e})",
            f.white_density,
            s.white_density
        );
        for n in [f.white_density, s.white_density] {
            assert!(
                (n / truth - 1.0).abs() <= 0.04,
                "channel {c}: {n} vs {truth}"
            );
        }
        let first = fast.curves[c][0];
        assert!(first.adev * first.tau.sqrt() < 0.85 * truth, "{first:?}");
    }
}

/// Stillness: 10 min of a static `sim` recording is still (every window); the same with the
/// sensor tilted by 3° after 5 min (one step, so nearly every window is still) is
/// refused for its tilt.
#[test]
fn stillness_passes_a_static_recording_and_refuses_a_tilted_one() {
    let samples = sim_static(100.0, 600.0, 5);
    let opts = StillnessOptions::default();
    let mut m = StillnessMonitor::new(opts);
    samples.iter().for_each(|s| m.push(s));
    let st = m.finish();
    assert!(st.windows >= 590, "{st:?}");
    assert_eq!(st.still_fraction(), 1.0, "{st:?}");
    assert!(st.verdict(&opts).is_ok());
    // About an axis across gravity, so the gravity direction turns by the full 3°.
    let up = samples[..100].iter().map(|s| s.acc).sum::<Vector3<f64>>();
    let axis = up.cross(&Vector3::x()).normalize();
    let tilt = SO3::exp(&(axis * 3f64.to_radians()));
    let mut m = StillnessMonitor::new(opts);
    for (k, s) in samples.iter().enumerate() {
        let mut s = *s;
        if k >= 30_000 {
            s.acc = tilt.inverse().act(&s.acc);
        }
        m.push(&s);
    }
    let st = m.finish();
    assert!(st.still_fraction() > 0.99, "{st:?}");
    assert!((st.max_tilt_deg - 3.0).abs() < 0.1, "{st:?}");
    assert!((st.step_tilt_deg - 3.0).abs() < 0.1, "{st:?}");
    let e = st.verdict(&opts).unwrap_err().to_string();
    assert!(e.contains("not static") && e.contains("3.0"), "{e}");
}

/// The accelerometer bias walk is not tilt: 2 h of a static `sim` recording whose
/// accelerometer bias walks at 0.01 m/s³/√Hz (0.85 m/s² per axis: several degrees of apparent
/// tilt) is static; a recording whose bias walks at 1e-3 m/s³/√Hz turned slowly by 10° about
/// a horizontal axis over its length (every window still) is refused for the turn, and a
/// recording too short to compare two windows is "too short", not "100 % of its 0 windows".
#[test]
fn stillness_tells_a_bias_walk_from_a_turn() {
    let (rate, duration) = (20.0, 7200.0);
    let walking = |acc_random_walk: f64| {
        let noise = ImuNoise {
            gyro_noise_density: 1e-3,
            gyro_random_walk: 1e-4,
            acc_noise_density: 2e-3,
            acc_random_walk,
            update_rate_hz: rate,
        };
        let cfg = SimConfig {
            noise,
            bias_random_walk: true,
            ..SimConfig::default()
        };
        let scene = StaticScene::new(SO3::exp(&Vector3::new(0.2, -0.1, 0.3)), Vector3::zeros());
        simulate(&scene, rate, duration, &cfg, 3).unwrap().samples
    };
    let samples = walking(1e-2);
    let opts = StillnessOptions::default();
    let mut m = StillnessMonitor::new(opts);
    samples.iter().for_each(|s| m.push(s));
    let st = m.finish();
    assert!(
        st.max_tilt_deg > opts.max_tilt_deg,
        "the walk must look like tilt: {st:?}"
    );
    assert!(st.tilt_is_bias_walk() && st.step_tilt_deg < 0.5, "{st:?}");
    assert!(st.verdict(&opts).is_ok(), "{:?}", st.verdict(&opts));

    let samples = walking(1e-3);
    let up = samples[..20].iter().map(|s| s.acc).sum::<Vector3<f64>>();
    let axis = up.cross(&Vector3::x()).normalize();
    let mut m = StillnessMonitor::new(opts);
    for (k, s) in samples.iter().enumerate() {
        let angle = 10f64.to_radians() * k as f64 / samples.len() as f64;
        let mut s = *s;
        s.acc = SO3::exp(&(axis * angle)).inverse().act(&s.acc);
        m.push(&s);
    }
    let st = m.finish();
    assert!(st.still_fraction() > 0.99, "{st:?}");
    assert!(!st.tilt_is_bias_walk(), "{st:?}");
    let e = st.verdict(&opts).unwrap_err().to_string();
    assert!(e.contains("not static") && e.contains("it turned"), "{e}");

    let mut m = StillnessMonitor::new(opts);
    samples[..30].iter().for_each(|s| m.push(s));
    let e = m.finish().verdict(&opts).unwrap_err().to_string();
    assert!(e.contains("too short") && !e.contains("0 windows"), "{e}");
}

/// `PREINT_FULL=1`: the real ADIS16405 hour at 100 Hz (`../shared/data/static_adis16405`,
/// read through `preint_io` from deg/s and g) streamed, against the committed 10 Hz block means
/// of the same hour (`tests/data/adis16405`): the gyro densities agree within twice their
/// combined 1-σ errors, the accelerometer densities (bounds or fits) within 2 %.
#[test]
fn adis16405_hour_at_100_hz_and_its_block_means_agree() {
    if std::env::var("PREINT_FULL").is_ok_and(|v| v == "1") {
        let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        let raw =
            root.join("../shared/data/static_adis16405/adis16405_static_run1_100Hz_first3600s.csv");
        let means = root.join("tests/data/adis16405/adis16405_run1_first3600s_10Hz_blockmean.csv");
        let analyse = |p: &std::path::Path| {
            let reader = preint_io::ImuReader::open(p, &preint_io::ReadOptions::default())
                .unwrap_or_else(|e| panic!("{e} (PREINT_FULL=1 needs the shared data)"));
            let mut s = AllanStream::new();
            for x in reader {
                s.push(&x.unwrap()).unwrap();
            }
            s.finish(10).unwrap()
        };
        let (fast, slow) = (analyse(&raw), analyse(&means));
        let deg = std::f64::consts::PI / 180.0;
        for c in 0..6 {
            let (f, s) = (&fast.fits[c], &slow.fits[c]);
            let unit = if c < 3 { deg } else { 9.80665 };
            println!(
                "channel {c}: N 100 Hz {:.4e}{} ± {:.1e}, 10 Hz {:.4e}{} ± {:.1e} ({})",
                f.white_density / unit,
                if f.white_density_is_bound {
                    " (bound)"
                } else {
                    ""
                },
                f.white_density_err / unit,
                s.white_density / unit,
                if s.white_density_is_bound {
                    " (bound)"
                } else {
                    ""
                },
                s.white_density_err / unit,
                if c < 3 { "deg/s/√Hz" } else { "g/√Hz" }
            );
            if c < 3 {
                let tol = 2.0 * f.white_density_err.hypot(s.white_density_err);
                assert!(
                    (f.white_density - s.white_density).abs() <= tol,
                    "channel {c}"
                );
            } else {
                assert!(
                    (f.white_density / s.white_density - 1.0).abs() <= 0.02,
                    "channel {c}"
                );
            }
        }
    }
}

/// The cluster sizes of the block curves are log-spaced in units of τ₀ (the grid of
/// [`log_spaced_cluster_sizes`] over the blocks).
#[test]
fn block_curve_grid_is_log_spaced_in_tau0() {
    let samples = &sim_static(100.0, 100.0, 6)[..10_000];
    let a = stream_of(samples, 64).finish(10).unwrap();
    let ms: Vec<usize> = a.curves[0].iter().map(|p| p.m).collect();
    assert_eq!(ms, log_spaced_cluster_sizes(39 / 2, 10));
}
