//! A measurement preintegrated at `Level::Deltas` has no bias Jacobians: every function that
//! corrects its deltas for a bias refuses a bias other than `bias_hat`
//! (`PreintError::NoBiasJacobians`, or a panic with that message for the infallible forms)
//! instead of returning the deltas of `bias_hat` as if they were those of the new bias; the
//! exact `bias_hat` keeps working, to the bit; a measurement with Jacobians is corrected as
//! before.

mod common;

use common::*;
use preint::{
    ImuBias, ImuFactor, Level, NavState, PreintError, PreintParams, PreintegratedImu,
    Preintegrator, Scheme, predict, preintegrate, try_predict,
};

const SEC: i64 = 1_000_000_000;

fn params(level: Level) -> PreintParams {
    PreintParams::default()
        .with_scheme(Scheme::Midpoint)
        .with_level(level)
        .with_gravity(gravity())
}

fn bias_hat() -> ImuBias {
    ImuBias::new(V3::new(0.002, -0.001, 0.0005), V3::new(0.03, 0.0, -0.02))
}

/// A bias 1e-3 rad/s and 0.01 m/s² away from `bias_hat()`.
fn other_bias() -> ImuBias {
    let b = bias_hat();
    ImuBias::new(
        b.gyro + V3::new(1e-3, 0.0, 0.0),
        b.acc + V3::new(0.0, 0.01, 0.0),
    )
}

fn window(level: Level) -> PreintegratedImu {
    let s = Scene::smooth().samples(5_000_000, 2 * SEC);
    preintegrate(&params(level), &bias_hat(), &s, SEC / 2, 3 * SEC / 2).unwrap()
}

fn state_i() -> NavState {
    let sc = Scene::smooth();
    NavState::new(sc.rot(0.5), sc.pos(0.5), sc.vel(0.5))
}

fn assert_refusal(e: PreintError) {
    assert_eq!(
        e,
        PreintError::NoBiasJacobians {
            bias: other_bias(),
            bias_hat: bias_hat()
        }
    );
    let msg = e.to_string();
    for part in [
        "level deltas, without bias Jacobians",
        "cannot be corrected to bias gyro [0.003, -0.001, 0.0005] rad/s",
        "preintegrate at level covariance or combined, or re-preintegrate at the new bias",
    ] {
        assert!(msg.contains(part), "{msg}");
    }
}

#[test]
fn deltas_level_refuses_another_bias() {
    let m = window(Level::Deltas);
    assert_refusal(try_predict(&m, &state_i(), &other_bias()).unwrap_err());
    assert_refusal(m.try_corrected(&other_bias()).unwrap_err());
    assert_refusal(m.check_bias(&other_bias()).unwrap_err());
    // A rotating frame predicts through another path: refused as well.
    let rotating = PreintegratedImu {
        omega_coriolis: Some(V3::new(0.0, 0.0, 7.292115e-5)),
        ..m.clone()
    };
    assert_refusal(try_predict(&rotating, &state_i(), &other_bias()).unwrap_err());
    // A factor needs the covariance, so it never holds a measurement without Jacobians.
    assert!(ImuFactor::new(m).is_err());
}

#[test]
#[should_panic(expected = "without bias Jacobians: it cannot be corrected to bias")]
fn predict_panics_on_a_bias_it_cannot_apply() {
    predict(&window(Level::Deltas), &state_i(), &other_bias());
}

#[test]
#[should_panic(expected = "without bias Jacobians: it cannot be corrected to bias")]
fn corrected_panics_on_a_bias_it_cannot_apply() {
    window(Level::Deltas).corrected(&other_bias());
}

#[test]
#[should_panic(expected = "without bias Jacobians: it cannot be corrected to bias")]
fn corrected_with_time_offset_panics_on_a_bias_it_cannot_apply() {
    window(Level::Deltas).corrected_with_time_offset(&other_bias(), 0.0);
}

/// At `bias_hat` exactly, the deltas level predicts with its deltas unchanged: Forster eq. 33
/// written out here, equal to the bit.
#[test]
fn deltas_level_at_bias_hat_is_the_uncorrected_prediction() {
    let m = window(Level::Deltas);
    let x = state_i();
    let (dt, g) = (m.delta_t, m.gravity);
    let want = NavState {
        r: x.r.compose(&m.delta_r),
        v: x.v + g * dt + x.r.act(&m.delta_v),
        p: x.p + x.v * dt + g * (0.5 * dt * dt) + x.r.act(&m.delta_p),
    };
    assert_eq!(predict(&m, &x, &bias_hat()), want);
    assert_eq!(try_predict(&m, &x, &bias_hat()).unwrap(), want);
    assert_eq!(
        m.try_corrected(&bias_hat()).unwrap(),
        (m.delta_r, m.delta_v, m.delta_p)
    );
    assert_eq!(m.corrected(&bias_hat()), (m.delta_r, m.delta_v, m.delta_p));
}

/// With bias Jacobians the checked forms equal the infallible ones at any bias, and the
/// correction moves the prediction.
#[test]
fn covariance_level_is_corrected() {
    for level in [Level::Covariance, Level::Combined] {
        let m = window(level);
        let x = state_i();
        let b = other_bias();
        let p = predict(&m, &x, &b);
        assert_eq!(try_predict(&m, &x, &b).unwrap(), p);
        assert_eq!(m.try_corrected(&b).unwrap(), m.corrected(&b));
        let uncorrected = predict(&m, &x, &bias_hat());
        assert!(p.r.minus(&uncorrected.r).norm() > 1e-4, "{level:?}");
        assert!(ImuFactor::new(m).is_ok());
    }
}

fn fed(level: Level, keep_samples: bool) -> (Preintegrator, Vec<preint::ImuSample>) {
    let mut prm = params(level);
    prm.keep_samples = keep_samples;
    let s = Scene::smooth().samples(5_000_000, SEC);
    let mut pi = Preintegrator::new(prm, bias_hat()).unwrap();
    pi.integrate_slice(&s).unwrap();
    (pi, s)
}

/// `measurement_for_bias` at the deltas level: another bias, however small, re-integrates
/// (equal to the bit to a preintegrator started at that bias); without stored samples it is
/// refused; `bias_hat` returns the measurement as `finish` does.
#[test]
fn measurement_for_bias_at_deltas_level() {
    let (pi, s) = fed(Level::Deltas, true);
    let u = pi.measurement_for_bias(&other_bias()).unwrap();
    assert!(u.reintegrated);
    let mut fresh = Preintegrator::new(pi.params().clone(), other_bias()).unwrap();
    fresh.integrate_slice(&s).unwrap();
    assert_eq!(u.measurement, fresh.finish().unwrap());

    let same = pi.measurement_for_bias(&bias_hat()).unwrap();
    assert!(!same.reintegrated);
    assert_eq!(same.measurement, pi.finish().unwrap());

    let (kept_none, _) = fed(Level::Deltas, false);
    assert_refusal(kept_none.measurement_for_bias(&other_bias()).unwrap_err());
    assert!(kept_none.measurement_for_bias(&bias_hat()).is_ok());
}
