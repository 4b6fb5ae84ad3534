//! The state inside a window (`preint::deskew`): at every query time, the deltas equal those of
//! `preintegrate` over the window ending there, for every scheme, with a lever arm and with Earth
//! rotation; GTSAM 4.3's `deskewPointsAtTimes` reproduced where its model is exact; errors.

mod common;

use common::gtsam_fixture::{json, mat, v3};
use common::*;
use preint::deskew::WindowDeltas;
use preint::deskew::{DeskewTarget, deltas_at, deskew_points, states_at};
use preint::{
    ImuBias, ImuSample, Level, LeverArm, NavState, PreintError, PreintParams, Scheme, SensorPose,
    predict, preintegrate,
};
use preint_lie::SO3;

const STEP: i64 = 5_000_000;

/// `Scene::smooth` at 200 Hz over 3 s, timestamps jittered by a fixed pattern (±20 %) so that
/// no two intervals are equal.
fn stream() -> Vec<ImuSample> {
    let sc = Scene::smooth();
    (0..=600i64)
        .map(|k| {
            let jitter = ((k * 7919) % 41 - 20) * STEP / 100;
            sc.sample(k * STEP + if k == 0 { 0 } else { jitter })
        })
        .collect()
}

fn prm(scheme: Scheme, level: Level) -> PreintParams {
    PreintParams::default()
        .with_scheme(scheme)
        .with_level(level)
        .with_gravity(gravity())
}

/// Query times in `(t_i, t_j]`: every sample, mid-interval, 1 µs after and before a sample, and
/// 1/16 of an interval from a sample (inside hermite4's close-sample distance), plus `t_j`.
fn queries(s: &[ImuSample], t_i: i64, t_j: i64) -> Vec<i64> {
    let mut q = vec![t_i];
    for w in s.windows(2) {
        let (a, b) = (w[0].t_ns, w[1].t_ns);
        let h = b - a;
        for t in [a, a + 1000, a + h / 16, a + h / 2, b - h / 16, b - 1000] {
            if t > t_i && t < t_j {
                q.push(t);
            }
        }
    }
    q.push(t_j);
    q.sort();
    q.dedup();
    q
}

fn rel(a: &V3, b: &V3) -> f64 {
    (a - b).norm() / b.norm().max(1e-300)
}

/// Largest relative difference between the deltas at each query and `preintegrate` over
/// `[t_i, t]` (rotation: angle of `ΔR_aᵀ ΔR_b`).
fn max_diff(p: &PreintParams, bias: &ImuBias, s: &[ImuSample], t_i: i64, t_j: i64) -> f64 {
    let q = queries(s, t_i, t_j);
    let at = deltas_at(p, bias, s, (t_i, t_j), &q).unwrap();
    assert_eq!(at.len(), q.len());
    let mut worst: f64 = 0.0;
    for (d, &t) in at.iter().zip(&q) {
        assert_eq!(d.t_ns, t);
        if t == t_i {
            assert_eq!((d.delta_t, d.delta_r), (0.0, SO3::identity()));
            continue;
        }
        let w = preintegrate(p, bias, s, t_i, t).unwrap();
        assert_eq!(d.delta_t, w.delta_t);
        let dr = (d.delta_r.inverse() * w.delta_r).log().norm();
        worst = worst
            .max(dr)
            .max(rel(&d.delta_v, &w.delta_v))
            .max(rel(&d.delta_p, &w.delta_p));
    }
    worst
}

fn bias() -> ImuBias {
    ImuBias::new(V3::new(0.01, -0.02, 0.005), V3::new(0.1, 0.05, -0.2))
}

/// Windows with keyframes between samples, on a sample, and just after one (hermite4's
/// close-sample rule at `t_i`); every scheme; at `Level::Combined` (the window's own step) the
/// deltas are bit-for-bit those of `preintegrate`, at `Level::Deltas` (its quaternion fast
/// path) within 1e-12.
#[test]
fn deltas_inside_a_window_equal_the_window_ending_there_for_every_scheme() {
    let s = stream();
    let windows = [
        (s[100].t_ns + 1_234_567, s[300].t_ns - 777_777),
        (s[100].t_ns, s[300].t_ns),
        (s[100].t_ns + 100_000, s[102].t_ns + 2_000_000),
        (s[3].t_ns + 10, s[4].t_ns - 10),
        (s[0].t_ns, s[600].t_ns),
    ];
    for &scheme in Scheme::ALL {
        for &(t_i, t_j) in &windows {
            let exact = max_diff(&prm(scheme, Level::Combined), &bias(), &s, t_i, t_j);
            assert_eq!(exact, 0.0, "{scheme:?} [{t_i}, {t_j}]");
            let fast = max_diff(&prm(scheme, Level::Deltas), &bias(), &s, t_i, t_j);
            assert!(
                fast <= 1e-12,
                "{scheme:?} [{t_i}, {t_j}] Level::Deltas: {fast:e}"
            );
        }
    }
}

/// A window longer than the 1024 intervals after which ΔR is re-orthonormalised.
#[test]
fn long_windows_renormalise_as_the_window_does() {
    let sc = Scene::smooth();
    let s: Vec<ImuSample> = (0..=2100i64).map(|k| sc.sample(k * 1_000_000)).collect();
    for &scheme in Scheme::ALL {
        let p = prm(scheme, Level::Combined);
        let (t_i, t_j) = (1_500_000, 2_099_500_000);
        let q = [1_025_000_000, 1_026_500_000, 2_000_000_000, t_j];
        let at = deltas_at(&p, &bias(), &s, (t_i, t_j), &q).unwrap();
        for (d, &t) in at.iter().zip(&q) {
            let w = preintegrate(&p, &bias(), &s, t_i, t).unwrap();
            assert_eq!(
                (d.delta_r, d.delta_v, d.delta_p),
                (w.delta_r, w.delta_v, w.delta_p)
            );
        }
    }
}

/// States through `predict`: with a lever arm (both models) and with Earth rotation, the state
/// at each query equals `predict(preintegrate([t_i, t]), state_i, bias)` bit for bit.
#[test]
fn states_equal_the_prediction_of_the_window_with_lever_arm_and_earth_rotation() {
    let s = stream();
    let pose = SensorPose::new(SO3::exp(&V3::new(0.1, -0.3, 0.2)), V3::new(0.2, -0.1, 0.3));
    let state_i = NavState::new(
        SO3::exp(&V3::new(0.3, 0.2, -1.0)),
        V3::new(10.0, -5.0, 2.0),
        V3::new(1.0, 2.0, -0.5),
    );
    let (t_i, t_j) = (s[50].t_ns + 2_000_000, s[250].t_ns - 1_000_000);
    for &scheme in Scheme::ALL {
        let base = prm(scheme, Level::Combined);
        let cases = [
            PreintParams {
                body_p_sensor: Some(pose),
                ..base.clone()
            },
            PreintParams {
                body_p_sensor: Some(pose),
                lever_arm: LeverArm::Centripetal,
                ..base.clone()
            },
            PreintParams {
                omega_coriolis: Some(V3::new(0.0, 4e-5, 6e-5)),
                ..base.clone()
            },
        ];
        for p in &cases {
            let q = queries(&s, t_i, t_j);
            let at = states_at(p, &bias(), &s, (t_i, t_j), &state_i, &q).unwrap();
            for (x, &t) in at.iter().zip(&q).skip(1) {
                let w = preintegrate(p, &bias(), &s, t_i, t).unwrap();
                let want = predict(&w, &state_i, &bias());
                assert_eq!(x.state, want, "{scheme:?} t = {t}");
                assert_eq!(x.deltas.delta_r, w.delta_r);
            }
            assert_eq!(at[0].state, state_i);
        }
    }
}

/// Deskewing against states written out independently: each point lands at
/// `R_refᵀ (p(t) + R(t) x − p_ref)` with the states of `states_at`, for both targets.
#[test]
fn deskewed_points_are_the_points_moved_through_the_predicted_states() {
    let s = stream();
    let p = prm(Scheme::Hermite4, Level::Deltas);
    let state_i = NavState::new(
        SO3::exp(&V3::new(0.0, 0.1, 0.5)),
        V3::zeros(),
        V3::new(1.0, 0.5, 0.0),
    );
    let (t_i, t_j) = (s[20].t_ns + 5, s[120].t_ns + 7);
    let points: Vec<(i64, V3)> = (0..50)
        .map(|k| {
            (
                t_i + k * (t_j - t_i) / 50,
                V3::new(5.0, (k as f64).sin(), 1.0),
            )
        })
        .collect();
    let times: Vec<i64> = points.iter().map(|x| x.0).chain([t_j]).collect();
    let st = states_at(&p, &ImuBias::zero(), &s, (t_i, t_j), &state_i, &times).unwrap();
    let end = st.last().unwrap().state;
    for (target, reference) in [(DeskewTarget::Start, state_i), (DeskewTarget::End, end)] {
        let out = deskew_points(
            &p,
            &ImuBias::zero(),
            &s,
            (t_i, t_j),
            &state_i,
            &points,
            target,
        )
        .unwrap();
        for ((x, (_, xb)), st) in out.iter().zip(&points).zip(&st) {
            let world = st.state.p + st.state.r.act(xb);
            let want = reference.r.inverse().act(&(world - reference.p));
            assert!((x - want).norm() <= 1e-12 * want.norm(), "{x} vs {want}");
        }
    }
}

/// GTSAM 4.3's `deskewPointsAtTimes` (fixture `deskew_yaw.json`) on the motion where its
/// model (constant-rate rotation, constant velocity in frame i) is exact: a constant yaw rate at
/// constant world velocity, readings (0, 0, ω) and (0, 0, 9.81). Ours, from the samples, agrees
/// to 1e-12 m for every scheme.
#[test]
fn gtsam_deskew_points_at_times_where_its_model_is_exact() {
    let f = json("deskew_yaw.json");
    let w = f["yaw_rate"].as_f64().unwrap();
    let rate = f["rate_hz"].as_i64().unwrap();
    let n = f["samples"].as_i64().unwrap();
    let period = 1_000_000_000 / rate;
    let s: Vec<ImuSample> = (0..=n)
        .map(|k| ImuSample::new(k * period, V3::new(0.0, 0.0, w), V3::new(0.0, 0.0, 9.81)))
        .collect();
    let v_b = v3(&f["velocity_i"]);
    let pts = mat(&f["points"]);
    let times: Vec<f64> = f["times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let want = mat(&f["deskewed"]);
    let yaw0 = 0.4;
    let r_i = SO3::exp(&V3::new(0.0, 0.0, yaw0));
    let state_i = NavState::new(r_i, V3::new(1.0, 2.0, 3.0), r_i.act(&v_b));
    for &scheme in Scheme::ALL {
        let p = prm(scheme, Level::Combined);
        let mut points = vec![];
        let mut cols = vec![];
        for (c, t) in times.iter().enumerate() {
            for row in (0..pts.nrows()).step_by(3) {
                let x = V3::new(pts[(row, c)], pts[(row + 1, c)], pts[(row + 2, c)]);
                points.push(((t * 1e9).round() as i64, x));
                cols.push((row, c));
            }
        }
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by_key(|&k| points[k].0);
        let sorted: Vec<(i64, V3)> = order.iter().map(|&k| points[k]).collect();
        let t_j = n * period;
        let out = deskew_points(
            &p,
            &ImuBias::zero(),
            &s,
            (0, t_j),
            &state_i,
            &sorted,
            DeskewTarget::Start,
        )
        .unwrap();
        for (x, &k) in out.iter().zip(&order) {
            let (row, c) = cols[k];
            let g = V3::new(want[(row, c)], want[(row + 1, c)], want[(row + 2, c)]);
            assert!((x - g).norm() <= 1e-12, "{scheme:?}: {x} vs GTSAM {g}");
        }
    }
}

/// A preintegrator that kept its samples: the deltas inside equal `preintegrate` on its samples
/// and, at its last sample, its own `finish`; one that did not keep them is refused.
#[test]
fn a_preintegrator_with_kept_samples_answers_inside_its_window() {
    let s = stream();
    for &scheme in Scheme::ALL {
        let p = prm(scheme, Level::Combined);
        let mut pi = preint::Preintegrator::new(p.clone(), bias()).unwrap();
        pi.integrate_slice(&s[40..200]).unwrap();
        let (t_i, t_j) = (s[40].t_ns, s[199].t_ns);
        let mut w = WindowDeltas::of_preintegrator(&pi).unwrap();
        let mid = s[120].t_ns + 1_111_111;
        let at_mid = w.at(mid).unwrap();
        let want = preintegrate(&p, &bias(), &s[40..200], t_i, mid).unwrap();
        assert_eq!(
            (at_mid.delta_r, at_mid.delta_v),
            (want.delta_r, want.delta_v)
        );
        let end = w.at(t_j).unwrap();
        let m = pi.finish().unwrap();
        assert_eq!(
            (end.delta_r, end.delta_v, end.delta_p),
            (m.delta_r, m.delta_v, m.delta_p)
        );
        let mut p2 = p.clone();
        p2.keep_samples = false;
        let mut pi = preint::Preintegrator::new(p2, bias()).unwrap();
        pi.integrate_slice(&s[40..200]).unwrap();
        assert!(matches!(
            WindowDeltas::of_preintegrator(&pi),
            Err(PreintError::SamplesNotKept { count: 160 })
        ));
    }
}

#[test]
fn bad_queries_and_inputs_are_typed_errors() {
    let s = stream();
    let p = prm(Scheme::Midpoint, Level::Deltas);
    let b = ImuBias::zero();
    let (t_i, t_j) = (s[10].t_ns, s[20].t_ns);
    let e = deltas_at(&p, &b, &s, (t_i, t_j), &[t_i - 1]).unwrap_err();
    assert!(
        matches!(e, PreintError::QueryOutsideWindow { index: 0, .. }),
        "{e}"
    );
    let e = deltas_at(&p, &b, &s, (t_i, t_j), &[t_i + 5, t_j + 1]).unwrap_err();
    assert!(matches!(e, PreintError::QueryOutsideWindow { index: 1, t_ns, .. } if t_ns == t_j + 1));
    let e = deltas_at(&p, &b, &s, (t_i, t_j), &[t_i + 9, t_i + 5]).unwrap_err();
    assert!(
        matches!(e, PreintError::QueryNotSorted { index: 1, .. }),
        "{e}"
    );
    let e = deltas_at(&p, &b, &s, (t_j, t_i), &[t_i]).unwrap_err();
    assert!(matches!(e, PreintError::NonPositiveWindow { .. }), "{e}");
    let e = deltas_at(&p, &b, &s, (t_i, s[600].t_ns + 1), &[t_i]).unwrap_err();
    assert!(
        matches!(e, PreintError::KeyframeOutsideSamples { .. }),
        "{e}"
    );
    let mut bad = s.clone();
    bad[15].acc.x = f64::NAN;
    let e = deltas_at(&p, &b, &bad, (t_i, t_j), &[t_i]).unwrap_err();
    assert!(matches!(e, PreintError::NonFinite { index: 15, .. }), "{e}");
    let nan_bias = ImuBias::new(V3::new(f64::NAN, 0.0, 0.0), V3::zeros());
    assert!(matches!(
        deltas_at(&p, &nan_bias, &s, (t_i, t_j), &[t_i]),
        Err(PreintError::InvalidParameter { .. })
    ));
    let mut st = NavState::identity();
    st.v.y = f64::INFINITY;
    assert!(matches!(
        states_at(&p, &b, &s, (t_i, t_j), &st, &[t_i]),
        Err(PreintError::InvalidParameter {
            name: "state_i",
            ..
        })
    ));
    let pts = [
        (t_i + 1, V3::zeros()),
        (t_i + 2, V3::new(0.0, f64::NAN, 0.0)),
    ];
    let e = deskew_points(
        &p,
        &b,
        &s,
        (t_i, t_j),
        &NavState::identity(),
        &pts,
        DeskewTarget::End,
    )
    .unwrap_err();
    assert!(
        matches!(e, PreintError::NonFinitePoint { index: 1, .. }),
        "{e}"
    );
    let pts = [(t_i + 9, V3::zeros()), (t_i + 2, V3::zeros())];
    let e = deskew_points(
        &p,
        &b,
        &s,
        (t_i, t_j),
        &NavState::identity(),
        &pts,
        DeskewTarget::End,
    )
    .unwrap_err();
    assert!(
        matches!(e, PreintError::QueryNotSorted { index: 1, .. }),
        "{e}"
    );
    // The cursor keeps working after a rejected query.
    let mut w = WindowDeltas::new(&p, &b, &s, t_i, t_j).unwrap();
    w.at(t_i + 100).unwrap();
    assert!(w.at(t_i + 50).is_err());
    assert_eq!(w.at(t_j).unwrap().t_ns, t_j);
}
