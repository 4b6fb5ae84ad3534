//! The Galilean scheme on input held constant over each interval, where it is exact: GTSAM 4.3's
//! deterministic stress test (`GalileanImuFactor` documentation: constant body specific force
//! a = (2, −1, 0.5) m/s², rate ω = (1.2, −0.8, 2.0) rad/s, g = 0, 1 s at 10/20/40/80 Hz).
//!
//! The exact deltas of a constant `(ω, a)` over `T` are written out from Rodrigues' formula
//! (`Exp(ωs) = I + sin(ws)[n]× + (1 − cos ws)[n]×²`, `w = |ω|`, `n = ω/w`), integrated by hand:
//!
//! ```text
//! Δv = ∫₀ᵀ Exp(ωs) a ds         = (T I + (1 − cos wT)/w [n]× + (T − sin(wT)/w) [n]×²) a
//! Δp = ∫₀ᵀ (T − s) Exp(ωs) a ds = (T²/2 I + (T/w − sin(wT)/w²) [n]× + (T²/2 − (1 − cos wT)/w²) [n]×²) a
//! ```
//!
//! Covariance and bias Jacobians against numeric differentiation are in the suites that run
//! over every scheme (`linearisation.rs`, `schemes.rs`); GTSAM parity in `galilean_gtsam.rs`.

use nalgebra::{Matrix3, Vector3};
use preint::{ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Preintegrator, Scheme};
use preint_lie::SO3;

type V3 = Vector3<f64>;

const A: [f64; 3] = [2.0, -1.0, 0.5];
const W: [f64; 3] = [1.2, -0.8, 2.0];
const RATES: [i64; 4] = [10, 20, 40, 80];

fn skew(n: &V3) -> Matrix3<f64> {
    Matrix3::new(0.0, -n.z, n.y, n.z, 0.0, -n.x, -n.y, n.x, 0.0)
}

/// The exact `(ΔR, Δv, Δp)` of the constant input over `t` \[s\] (module docs).
fn exact(t: f64) -> (SO3, V3, V3) {
    let (a, w) = (V3::from(A), V3::from(W));
    let wn = w.norm();
    let k = skew(&(w / wn));
    let k2 = k * k;
    let (s, c) = (wn * t).sin_cos();
    let i = Matrix3::identity();
    let r = i + k * s + k2 * (1.0 - c);
    let v = (i * t + k * ((1.0 - c) / wn) + k2 * (t - s / wn)) * a;
    let p = (i * (t * t / 2.0)
        + k * (t / wn - s / (wn * wn))
        + k2 * (t * t / 2.0 - (1.0 - c) / (wn * wn)))
        * a;
    (SO3::from_matrix(&r), v, p)
}

/// 1 s of the constant input at `rate` Hz: `rate + 1` samples, `rate` intervals.
fn run(scheme: Scheme, rate: i64) -> PreintegratedImu {
    let step = 1_000_000_000 / rate;
    let params = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Covariance)
        .with_gravity(V3::zeros());
    let mut pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
    for k in 0..=rate {
        pi.integrate(&ImuSample::new(k * step, V3::from(W), V3::from(A)))
            .unwrap();
    }
    pi.finish().unwrap()
}

/// `(rotation [rad], velocity [m/s], position [m])` errors against the exact deltas.
fn errors(m: &PreintegratedImu) -> (f64, f64, f64) {
    let (r, v, p) = exact(m.delta_t);
    (
        r.inverse().compose(&m.delta_r).log().norm(),
        (m.delta_v - v).norm(),
        (m.delta_p - p).norm(),
    )
}

/// Galilean is exact at every rate (≤ 1e-12 m, m/s, rad); Euler (= GTSAM Manifold) has GTSAM's
/// published errors to three digits; every scheme's errors are printed.
#[test]
fn held_input_is_exact_for_galilean_at_every_rate() {
    // GTSAM 4.3's published Manifold errors: velocity [m/s], position [m].
    let manifold = [
        (0.1447, 0.0774),
        (0.0723, 0.0392),
        (0.0361, 0.0198),
        (0.0181, 0.0099),
    ];
    for (i, &rate) in RATES.iter().enumerate() {
        for &scheme in Scheme::ALL {
            let (er, ev, ep) = errors(&run(scheme, rate));
            eprintln!(
                "{rate:>2} Hz {:<9} rotation {er:.2e} rad, velocity {ev:.4e} m/s, position {ep:.4e} m",
                scheme.name()
            );
            match scheme {
                Scheme::Galilean => {
                    assert!(
                        er < 1e-12 && ev < 1e-12 && ep < 1e-12,
                        "{rate} Hz: {er} {ev} {ep}"
                    );
                }
                Scheme::Euler => {
                    let (v, p) = manifold[i];
                    assert!((ev - v).abs() < 5e-5, "{rate} Hz: velocity {ev} vs {v}");
                    assert!((ep - p).abs() < 5e-5, "{rate} Hz: position {ep} vs {p}");
                }
                // Midpoint and hermite4 read sample k+1 too: printed, not exact.
                _ => assert!(ep > 0.0, "{scheme:?} {rate} Hz: {ep}"),
            }
        }
    }
}

/// The Galilean scheme holds the sample as Euler does: the same rotation, bit for bit, and the
/// same rotation block of the covariance and the same gyro-bias Jacobian of the rotation (only
/// the velocity and position rules differ).
#[test]
fn galilean_rotation_is_eulers() {
    let samples: Vec<ImuSample> = (0..201i64)
        .map(|k| {
            let t = k as f64 * 0.005;
            ImuSample::new(
                k * 5_000_000,
                V3::new((1.3 * t).sin(), 0.4 * t, -0.7),
                V3::new(1.0, (2.0 * t).cos(), 9.81),
            )
        })
        .collect();
    let run = |scheme| {
        let params = PreintParams::default().with_scheme(scheme);
        let mut pi = Preintegrator::new(params, ImuBias::zero()).unwrap();
        pi.integrate_slice(&samples).unwrap();
        pi.finish().unwrap()
    };
    let (g, e) = (run(Scheme::Galilean), run(Scheme::Euler));
    assert_eq!(g.delta_r, e.delta_r);
    let rr = |m: &PreintegratedImu| m.cov.fixed_view::<3, 3>(0, 0).into_owned();
    assert!((rr(&g) - rr(&e)).amax() <= 1e-15 * rr(&e).amax());
    assert!((g.jac.d_r_d_bg - e.jac.d_r_d_bg).amax() <= 1e-14);
    // The velocity rules differ by O(h) per interval on this smooth input.
    assert!((g.delta_v - e.delta_v).norm() > 1e-4);
}
