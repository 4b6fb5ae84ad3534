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
//! sample / mid-interval / 1 ms after a sample; printed by the test): euler 5.2e-3 / 5.2e-3 /
//! 7.1e-3, galilean 2.5e-3 / 2.5e-3 / 3.8e-3, midpoint 1.8e-5 / 9.2e-6 / 1.7e-5, hermite4 2.0e-9 /
//! 3.9e-9 / 9.6e-9 (5e-10 at 400 and 800 Hz, the central differences' floor); halving the period
//! halves the euler and galilean errors and quarters midpoint's. The closed form itself is
//! checked to 2e-10 against central differences of exact continuous-time deltas (last test).
//! Asserted: hermite4 ≤ 1e-6 at every rate; midpoint ≤ 1e-4 and euler and galilean ≤ 1e-2 at
//! 200 Hz; and each error falls with the rate at the scheme's order (the
//! 200 → 800 Hz ratio ≥ 3 for order 1, ≥ 10 for order 2: 4 and 16 expected), which a wrong
//! closed form (an O(1) discrepancy) would fail.

use nalgebra::{SVector, Vector3};
use preint::time_offset::{measurement_for_time_offset, preintegrate_with_offset};
use preint::{
    ImuBias, ImuSample, Level, PreintParams, PreintegratedImu, Scheme, SensorPose, merge,
    preintegrate,
};
use preint_lie::SO3;

mod common;

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
    ImuBias::new(
        Vector3::new(0.01, -0.02, 0.005),
        Vector3::new(0.1, 0.05, -0.08),
    )
}

/// Central difference of the deltas (in the chart at the unshifted window) of `[t_i, t_j]`
/// shifted together by `±eps_ns`.
fn central(
    p: &PreintParams,
    s: &[ImuSample],
    (ti, tj): (i64, i64),
    eps_ns: i64,
) -> SVector<f64, 9> {
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
            assert!(
                e[0] <= bound200,
                "{scheme:?} {what}: {:e} > {bound200:e}",
                e[0]
            );
            match order {
                4 => assert!(e.iter().all(|x| *x <= 1e-6), "{scheme:?} {what}: {e:?}"),
                2 => assert!(e[0] / e[2] >= 10.0, "{scheme:?} {what}: {e:?}"),
                _ => assert!(e[0] / e[2] >= 3.0, "{scheme:?} {what}: {e:?}"),
            }
        }
    }
}

/// Merging windows split on a sample or between samples gives the closed form of the merged
/// window (the inner keyframe's terms cancel): `A J_a + B J_b` equals `time_offset::jacobian` of
/// the merged deltas with the outer end samples to 1e-12 relative, every scheme; for a split on
/// a sample the merged deltas are the whole window's, and so is the column.
#[test]
fn merged_column_is_the_closed_form_of_the_merged_window() {
    let s = stream(200);
    let (ti, tj) = (SEC, 2 * SEC);
    let b = bias();
    let end = |t: i64| {
        let x = s.iter().find(|x| x.t_ns == t).unwrap();
        (x.gyro - b.gyro, x.acc - b.acc)
    };
    let ((wi, ai), (wj, aj)) = (end(ti), end(tj));
    for scheme in Scheme::ALL {
        let p = params(*scheme);
        let whole = preintegrate(&p, &b, &s, ti, tj).unwrap();
        for t_k in [1_500_000_000, 1_502_345_678] {
            let m = merge(
                &preintegrate(&p, &b, &s, ti, t_k).unwrap(),
                &preintegrate(&p, &b, &s, t_k, tj).unwrap(),
            )
            .unwrap();
            let deltas = (m.delta_r.matrix(), &m.delta_v, &m.delta_p);
            let closed = preint::time_offset::jacobian((&wi, &ai), (&wj, &aj), deltas, m.delta_t);
            let e = (m.jac_td - closed).norm() / closed.norm();
            assert!(e <= 1e-12, "{scheme:?} split at {t_k}: {e:e}");
            if t_k == 1_500_000_000 {
                let e = (m.jac_td - whole.jac_td).norm() / whole.jac_td.norm();
                assert!(e <= 1e-12, "{scheme:?} on a sample: {e:e}");
            }
        }
    }
}

/// The column depends on the window's ends: distinct from zero, and the ends' terms both
/// present (shifting only the end or only the start gives two different derivatives whose
/// sum is the column; checked with central differences of one-sided shifts on hermite4).
#[test]
fn both_ends_contribute() {
    let s = stream(800);
    let p = params(Scheme::Hermite4);
    let (ti, tj) = (SEC, 2 * SEC);
    let m = preintegrate(&p, &bias(), &s, ti, tj).unwrap();
    let eps = 20_000;
    let d = |a: i64, b: i64| preintegrate(&p, &bias(), &s, ti + a, tj + b).unwrap();
    let h = 2.0 * eps as f64 * 1e-9;
    let end = (d(0, eps).delta_error(&m) - d(0, -eps).delta_error(&m)) / h;
    let start = (d(eps, 0).delta_error(&m) - d(-eps, 0).delta_error(&m)) / h;
    assert!(end.norm() > 1.0 && start.norm() > 1.0);
    assert!((end + start - m.jac_td).norm() <= 1e-6 * m.jac_td.norm());
}

/// `corrected_with_time_offset` at `δt_d = 0` is `corrected`, for both bias corrections; the
/// column is zero at `Level::Deltas` and with a lever arm, and a rotation-only sensor pose maps
/// it by `diag(R, R, R)` (checked against central differences, hermite4 at 800 Hz).
#[test]
fn correction_levels_and_sensor_pose() {
    let s = stream(200);
    let b2 = ImuBias::new(
        Vector3::new(0.013, -0.018, 0.0),
        Vector3::new(0.12, 0.0, -0.1),
    );
    for c in preint::BiasCorrection::ALL {
        let p = params(Scheme::Midpoint).with_bias_correction(Some(c));
        let m = preintegrate(&p, &bias(), &s, SEC, 2 * SEC).unwrap();
        let (r0, v0, p0) = m.corrected(&b2);
        let (r1, v1, p1) = m.corrected_with_time_offset(&b2, 0.0);
        assert!(r0.minus(&r1).norm() <= 1e-15 && (v0 - v1).norm() <= 1e-14);
        assert!((p0 - p1).norm() <= 1e-14, "{c:?}");
    }
    let deltas = preintegrate(
        &params(Scheme::Midpoint).with_level(Level::Deltas),
        &bias(),
        &s,
        SEC,
        2 * SEC,
    );
    assert_eq!(deltas.unwrap().jac_td, SVector::<f64, 9>::zeros());
    let r_bs = SO3::exp(&Vector3::new(0.3, -0.2, 0.5));
    let lever = params(Scheme::Midpoint)
        .with_body_p_sensor(SensorPose::new(r_bs, Vector3::new(0.1, 0.0, 0.05)));
    let m = preintegrate(&lever, &bias(), &s, SEC, 2 * SEC).unwrap();
    assert_eq!(m.jac_td, SVector::<f64, 9>::zeros());
    let s8 = stream(800);
    let rot = params(Scheme::Hermite4).with_body_p_sensor(SensorPose::new(r_bs, Vector3::zeros()));
    let m = preintegrate(&rot, &bias(), &s8, SEC, 2 * SEC).unwrap();
    let fd = central(&rot, &s8, (SEC, 2 * SEC), 20_000);
    assert!(
        (m.jac_td - fd).norm() <= 1e-6 * m.jac_td.norm(),
        "{:e}",
        (m.jac_td - fd).norm()
    );
}

/// Below the threshold the first-order correction (closer to re-integration than the
/// uncorrected deltas by at least 20×, at 0.8 × the threshold), above it re-integration, which equals
/// `preintegrate_with_offset` at the new offset.
#[test]
fn reintegration_switch() {
    let s = stream(200);
    let p = params(Scheme::Midpoint);
    let w = (SEC, 2 * SEC);
    let td_hat = 3_000_000;
    let m = preintegrate_with_offset(&p, &bias(), &s, w, td_hat).unwrap();
    let small = td_hat + offset_ns(0.8 * p.reintegrate_time_offset_threshold);
    let u = measurement_for_time_offset(&p, &s, w, &m, (td_hat, small)).unwrap();
    assert!(!u.reintegrated);
    assert_eq!(
        (u.measurement.t_i_ns, u.measurement.t_j_ns),
        (SEC + small, 2 * SEC + small)
    );
    let exact = preintegrate_with_offset(&p, &bias(), &s, w, small).unwrap();
    let e_corr = u.measurement.delta_error(&exact).norm();
    let e_none = m.delta_error(&exact).norm();
    println!("δt_d = 0.8 × threshold: corrected {e_corr:.2e}, uncorrected {e_none:.2e}");
    assert!(e_corr * 20.0 <= e_none);
    let large = td_hat + 2 * offset_ns(p.reintegrate_time_offset_threshold);
    let u = measurement_for_time_offset(&p, &s, w, &m, (td_hat, large)).unwrap();
    assert!(u.reintegrated);
    let exact = preintegrate_with_offset(&p, &bias(), &s, w, large).unwrap();
    assert_eq!(u.measurement, exact);
}

fn offset_ns(s: f64) -> i64 {
    preint::time_offset::offset_ns(s)
}

/// A hand-made measurement has a zero column: `preintegrate` fills it, nothing else invents it.
#[test]
fn hand_made_measurement_has_no_column() {
    let s = stream(200);
    let m: PreintegratedImu =
        preintegrate(&params(Scheme::Euler), &bias(), &s, SEC, 2 * SEC).unwrap();
    assert!(m.jac_td.norm() > 0.0);
    let z = PreintegratedImu {
        jac_td: SVector::zeros(),
        ..m.clone()
    };
    let (r, _, _) = z.corrected_with_time_offset(&m.bias_hat, 0.01);
    assert_eq!(r, m.delta_r);
}

/// The closed form itself, on exact continuous-time deltas (no scheme): `time_offset::jacobian`
/// of the exact deltas and exact end samples against central differences of the exact deltas
/// of the window shifted by ±ε (ε = 1e-5 s), on the analytic scene of `common` (rates 1–2
/// rad/s): ≤ 1e-8 relative (the central difference's own error is ~1e-10).
#[test]
fn closed_form_is_the_derivative_of_the_exact_deltas() {
    let sc = common::Scene::smooth();
    for (t0, t1) in [(1.0, 2.0), (0.37, 0.52), (2.0, 5.5)] {
        let (r, v, p) = sc.exact(t0, t1);
        let (si, sj) = (sc.sample((t0 * 1e9) as i64), sc.sample((t1 * 1e9) as i64));
        let j = preint::time_offset::jacobian(
            (&si.gyro, &si.acc),
            (&sj.gyro, &sj.acc),
            (r.matrix(), &v, &p),
            t1 - t0,
        );
        let eps = 1e-5;
        let (rp, vp, pp) = sc.exact(t0 + eps, t1 + eps);
        let (rm, vm, pm) = sc.exact(t0 - eps, t1 - eps);
        let mut fd = SVector::<f64, 9>::zeros();
        fd.fixed_rows_mut::<3>(0)
            .copy_from(&((rp.minus(&r) - rm.minus(&r)) / (2.0 * eps)));
        fd.fixed_rows_mut::<3>(3)
            .copy_from(&((vp - vm) / (2.0 * eps)));
        fd.fixed_rows_mut::<3>(6)
            .copy_from(&((pp - pm) / (2.0 * eps)));
        let e = (j - fd).norm() / j.norm();
        println!("[{t0}, {t1}] s: closed form vs exact central differences {e:.2e}");
        assert!(e <= 1e-8, "[{t0}, {t1}]: {e:e}");
    }
}
