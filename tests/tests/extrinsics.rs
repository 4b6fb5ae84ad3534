//! An IMU away from the body origin (`PreintParams::body_p_sensor`, `preint::SensorPose`):
//! the body deltas against the exact truth, bias Jacobians against re-integration, the
//! covariance against Monte Carlo, and merging.
//!
//! Setup. The simulator moves the body along a scene and synthesises what an IMU mounted at
//! `body_P_sensor` reads (`SceneState::sensor_sample`: the rate in sensor axes and the
//! specific force of the sensor's own point, from the scene's analytic ω, ω̇ and a). The truth
//! is the body's: `preint_sim::exact_deltas` of the scene. Window `[1 s, 2 s]` at 200 Hz.
//! The mount: `r = 0.3 m` along `(1, −2, 2)/3` and `R_bs = Exp((0.3, −0.5, 0.8))`.
//!
//! Output: `target/evidence/extrinsics.json` (errors per scheme, the alternatives' errors,
//! mean NEES).

use evidence::monte_carlo::{MonteCarlo, SampleNoise, combined_error, nees};
use evidence::{full_run, integrate_all as run, mean, scene_bias, write_json};
use nalgebra::{SMatrix, Vector3};
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, LeverArm, PreintParams, PreintegratedImu, Scheme,
    SensorPose, merge, preintegrate,
};
use preint_lie::SO3;
use preint_sim::{Scene, exact_deltas, scene_by_name, t_s};

const T_I: i64 = 1_000_000_000;
const T_J: i64 = 2_000_000_000;
const PERIOD: i64 = 5_000_000;

fn g() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -9.81)
}

fn mount(r_m: f64) -> SensorPose {
    SensorPose::new(
        SO3::exp(&Vector3::new(0.3, -0.5, 0.8)),
        Vector3::new(1.0, -2.0, 2.0) * (r_m / 3.0),
    )
}

/// The readings of an ideal IMU at `pose` over `[t0, t1]` every `period` ns.
fn sensor_stream(
    scene: &dyn Scene,
    pose: &SensorPose,
    t0: i64,
    t1: i64,
    period: i64,
) -> Vec<ImuSample> {
    (0..=(t1 - t0) / period)
        .map(|k| {
            let t = t0 + k * period;
            scene.state(t_s(t)).sensor_sample(t, &g(), pose)
        })
        .collect()
}

fn params(scheme: Scheme, level: Level, pose: Option<SensorPose>) -> PreintParams {
    let mut p = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level)
        .with_gravity(g());
    p.body_p_sensor = pose;
    p
}

/// Both ways of removing the lever arm: the closed form (default) and GTSAM's per-sample
/// centripetal model.
const MODES: [LeverArm; 2] = [LeverArm::Exact, LeverArm::Centripetal];

fn with_mode(p: PreintParams, lever_arm: LeverArm) -> PreintParams {
    PreintParams { lever_arm, ..p }
}

/// (rotation [rad], Δv [m/s], Δp [m]) errors of `m` against the scene's exact body deltas.
fn errors(scene: &dyn Scene, m: &PreintegratedImu) -> (f64, f64, f64) {
    let (r, v, p) = exact_deltas(scene, m.t_i_ns, m.t_j_ns, g());
    (
        m.delta_r.minus(&r).norm(),
        (m.delta_v - v).norm(),
        (m.delta_p - p).norm(),
    )
}

/// The body deltas from an IMU at 0.3 m, rotated, carry each scheme's own integration error
/// (the error of the IMU at the body origin, within a factor 2 or 1e-9), and for the 4th-order
/// scheme at 200 Hz Δv is within 1e-4 m/s of the truth. Beside it, what the alternatives leave
/// on the same samples (reported; asserted only to show they are worse): the centripetal-only
/// correction of GTSAM's `correctMeasurementsBySensorPose`, and a per-sample correction with
/// `ω̇` from the 2nd-order central difference.
#[test]
fn lever_arm_body_deltas_match_the_exact_truth() {
    let scene = scene_by_name("aggressive").unwrap();
    let pose = mount(0.3);
    let sensor = sensor_stream(scene.as_ref(), &pose, T_I, T_J, PERIOD);
    let body = sensor_stream(
        scene.as_ref(),
        &SensorPose::new(SO3::identity(), Vector3::zeros()),
        T_I,
        T_J,
        PERIOD,
    );
    let b0 = ImuBias::zero();
    let mut out = serde_json::Map::new();
    for scheme in Scheme::ALL {
        let with = run(&params(*scheme, Level::Deltas, Some(pose)), &b0, &sensor);
        let at_origin = run(&params(*scheme, Level::Deltas, None), &b0, &body);
        let (er, ev, ep) = errors(scene.as_ref(), &with);
        let (or, ov, op) = errors(scene.as_ref(), &at_origin);
        println!(
            "{:<9} lever arm: |δφ| {er:.2e} rad, |δv| {ev:.2e} m/s, |δp| {ep:.2e} m; \
             IMU at the origin: {or:.2e}, {ov:.2e}, {op:.2e}",
            scheme.name()
        );
        for (e, o) in [(er, or), (ev, ov), (ep, op)] {
            assert!(e <= 2.0 * o + 1e-9, "{scheme:?}: {e:e} vs {o:e}");
        }
        out.insert(
            scheme.name().into(),
            serde_json::json!({"lever_arm": [er, ev, ep], "imu_at_origin": [or, ov, op]}),
        );
    }
    let h4 = run(
        &params(Scheme::Hermite4, Level::Deltas, Some(pose)),
        &b0,
        &sensor,
    );
    let (_, ev, _) = errors(scene.as_ref(), &h4);
    assert!(ev <= 1e-4, "hermite4 Δv error {ev:e}");

    // The alternatives, as body samples integrated by hermite4.
    let r = pose.translation;
    let rot = |s: &ImuSample| (pose.rotation.act(&s.gyro), pose.rotation.act(&s.acc));
    let centripetal: Vec<ImuSample> = sensor
        .iter()
        .map(|s| {
            let (w, f) = rot(s);
            ImuSample::new(s.t_ns, w, f - w.cross(&w.cross(&r)))
        })
        .collect();
    let second_order: Vec<ImuSample> = (0..sensor.len())
        .map(|k| {
            let (w, f) = rot(&sensor[k]);
            let (lo, hi) = (k.saturating_sub(1), (k + 1).min(sensor.len() - 1));
            let span = (sensor[hi].t_ns - sensor[lo].t_ns) as f64 * 1e-9;
            let w_dot = (rot(&sensor[hi]).0 - rot(&sensor[lo]).0) / span;
            ImuSample::new(
                sensor[k].t_ns,
                w,
                f - w.cross(&w.cross(&r)) - w_dot.cross(&r),
            )
        })
        .collect();
    let p_body = params(Scheme::Hermite4, Level::Deltas, None);
    let (_, ev_c, _) = errors(scene.as_ref(), &run(&p_body, &b0, &centripetal));
    let (_, ev_2, _) = errors(scene.as_ref(), &run(&p_body, &b0, &second_order));
    println!(
        "hermite4 200 Hz Δv error over [1 s, 2 s]: exact lever arm {ev:.2e} m/s; \
         centripetal only {ev_c:.2e}; per-sample ω̇ by central differences {ev_2:.2e}"
    );
    assert!(ev_c > 100.0 * ev && ev_2 > ev, "{ev_c:e} {ev_2:e} {ev:e}");
    // `LeverArm::Centripetal` is that centripetal-only correction, done inside the library.
    let lib = run(
        &with_mode(
            params(Scheme::Hermite4, Level::Deltas, Some(pose)),
            LeverArm::Centripetal,
        ),
        &b0,
        &sensor,
    );
    let manual = run(&p_body, &b0, &centripetal);
    let d = (lib.delta_v - manual.delta_v).norm();
    println!("LeverArm::Centripetal vs the centripetal-corrected body samples: |ΔΔv| {d:.1e}");
    assert!(d < 1e-9, "{d:e}");
    out.insert(
        "hermite4_dv_error".into(),
        serde_json::json!({"exact": ev, "centripetal_only": ev_c, "central_difference_w_dot": ev_2}),
    );
    write_json("extrinsics", &serde_json::Value::Object(out));
}

/// IMUs at the body origin and at ±3 m on a boom (the same rigid body) give the same body
/// deltas with the 4th-order scheme at 1 kHz: to 1e-9 (relative) on the constant-rate `spin`
/// (GTSAM's boom case is a constant rate), and to 1e-8 on `aggressive`, where the 3 m
/// sensors' own motion (up to ~40 m/s² of tangential and centripetal acceleration) carries the
/// scheme's O(h⁴) error (measured 1.3e-9 for Δp).
#[test]
fn imus_on_a_boom_give_the_same_body_deltas() {
    for name in ["spin", "aggressive"] {
        let scene = scene_by_name(name).unwrap();
        let p = params(Scheme::Hermite4, Level::Deltas, None);
        let deltas = |x: f64| {
            let pose = SensorPose::new(SO3::identity(), Vector3::new(x, 0.0, 0.0));
            let s = sensor_stream(scene.as_ref(), &pose, T_I, T_J, 1_000_000);
            run(
                &params(Scheme::Hermite4, Level::Deltas, Some(pose)),
                &ImuBias::zero(),
                &s,
            )
        };
        let origin = run(
            &p,
            &ImuBias::zero(),
            &sensor_stream(
                scene.as_ref(),
                &SensorPose::new(SO3::identity(), Vector3::zeros()),
                T_I,
                T_J,
                1_000_000,
            ),
        );
        for x in [3.0, -3.0] {
            let m = deltas(x);
            let dr = m.delta_r.minus(&origin.delta_r).norm();
            let dv = (m.delta_v - origin.delta_v).norm() / origin.delta_v.norm();
            let dp = (m.delta_p - origin.delta_p).norm() / origin.delta_p.norm();
            println!(
                "{name} boom x = {x:+} m: |δφ| {dr:.1e}, rel |δv| {dv:.1e}, rel |δp| {dp:.1e}"
            );
            let tol = if name == "spin" { 1e-9 } else { 1e-8 };
            assert!(
                dr <= tol && dv <= tol && dp <= tol,
                "{name} {x}: {dr:e} {dv:e} {dp:e}"
            );
        }
    }
}

/// The bias Jacobians of the body measurement (sensor-frame biases) against central
/// differences of re-integrations with a perturbed bias estimate, every scheme, both lever-arm
/// models.
#[test]
fn bias_jacobians_with_a_lever_arm_match_reintegration() {
    let scene = scene_by_name("aggressive").unwrap();
    let pose = mount(0.3);
    let s = sensor_stream(scene.as_ref(), &pose, T_I, T_J, PERIOD);
    let b0 = scene_bias();
    for (mode, scheme) in MODES
        .iter()
        .flat_map(|m| Scheme::ALL.iter().map(move |s| (*m, *s)))
    {
        let p = with_mode(params(scheme, Level::Covariance, Some(pose)), mode);
        let m = run(&p, &b0, &s);
        let eps = 1e-6;
        let mut num = SMatrix::<f64, 9, 6>::zeros();
        for c in 0..6 {
            let shift = |sign: f64| {
                let mut b = b0;
                if c < 3 {
                    b.gyro[c] += sign * eps;
                } else {
                    b.acc[c - 3] += sign * eps;
                }
                run(&p, &b, &s)
            };
            let (plus, minus) = (shift(1.0), shift(-1.0));
            num.fixed_view_mut::<9, 1>(0, c)
                .copy_from(&((plus.delta_error(&minus)) / (2.0 * eps)));
        }
        let ana = m.jac.as_matrix();
        let err = (ana - num).amax() / num.amax();
        println!(
            "{mode:?} {:<9} bias Jacobians vs central differences: max rel {err:.1e}",
            scheme.name()
        );
        assert!(err < 1e-6, "{scheme:?}: {err:e}");
    }
}

/// Monte Carlo: with the lever arm the 9-dim NEES of the body deltas (`Level::Covariance`)
/// and the 15-dim NEES with bias random walk (`Level::Combined`) are χ²-consistent. The
/// noisy-MEMS densities (gyro 0.015 rad/s/√Hz, accelerometer 0.019 m/s²/√Hz, so that the
/// gyroscope noise moved into the velocity rows by the lever arm is a visible share of them) and 2 000 realisations (std of
/// the mean 0.095 for 9 dof): asserted within 9 ± 0.3 and 15 ± 4√(30/N). Without the end-rate
/// terms (the covariance of the sensor's deltas rotated into the body) the mean is reported
/// and must fall outside the band.
///
/// `LeverArm::Centripetal` (GTSAM's model) is checked the same way at ten times the EuRoC
/// densities (those of the GTSAM fixture): at the noisy-MEMS gyro noise its per-sample
/// `ω × (ω × r)` rectifies the noise (`E[n × (n × r)] = −2σ²r` per sample, 0.027 m/s over this
/// window), which no first-order covariance holds; its mean NEES there is reported.
#[test]
fn lever_arm_covariance_is_consistent() {
    let seed_course = ImuNoise {
        gyro_noise_density: 0.015,
        acc_noise_density: 0.019,
        ..ImuNoise::euroc()
    };
    let euroc_x10 = ImuNoise {
        gyro_noise_density: 1.6968e-3,
        acc_noise_density: 2.0e-2,
        ..ImuNoise::euroc()
    };
    let mut out = serde_json::Map::new();
    for (mode, noise, asserted) in [
        (LeverArm::Exact, seed_course, true),
        (LeverArm::Centripetal, euroc_x10, true),
        (LeverArm::Centripetal, seed_course, false),
    ] {
        nees_runs(mode, &noise, asserted, &mut out);
    }
    write_json("extrinsics_nees", &serde_json::Value::Object(out));
}

fn nees_runs(
    mode: LeverArm,
    noise: &ImuNoise,
    asserted: bool,
    out: &mut serde_json::Map<String, serde_json::Value>,
) {
    let n_real = if full_run() { 20_000 } else { 2_000 };
    let scene = scene_by_name("aggressive").unwrap();
    let pose = mount(0.3);
    let clean = sensor_stream(scene.as_ref(), &pose, T_I, T_J, PERIOD);
    let mc = MonteCarlo {
        clean: &clean,
        noise: SampleNoise::at(noise, PERIOD as f64 * 1e-9),
        n: n_real,
    };
    let b0 = ImuBias::zero();
    let a = rotation_only(&pose);
    for scheme in Scheme::ALL.iter().copied() {
        let mk = |level| {
            let mut p = PreintParams::from_noise(noise)
                .with_scheme(scheme)
                .with_level(level)
                .with_gravity(g());
            p.body_p_sensor = Some(pose);
            with_mode(p, mode)
        };
        let (p9, p15) = (mk(Level::Covariance), mk(Level::Combined));
        let m0 = run(&p9, &b0, &clean);
        let m0_15 = run(&p15, &b0, &clean);
        // NEES9 with the body covariance, and with the sensor's covariance rotated only.
        let f9 = mc.white(0xE7_0000, |noisy| {
            let m = run(&p9, &b0, noisy);
            let e = m.delta_error(&m0);
            let ms = run(&params_like(&p9, None), &b0, noisy);
            [nees(&e, &m.cov), nees(&e, &(a * ms.cov * a.transpose()))]
        });
        let f15 = mc.walk(0xE7_8000_0000, |noisy, walk| {
            let m = run(&p15, &b0, noisy);
            [nees(
                &combined_error(&m.delta_error(&m0_15), walk),
                &m.cov15,
            )]
        });
        let (n9, naive, n15) = (&f9[0], &f9[1], &f15[0]);
        let (m9, m15, mn) = (mean(n9), mean(n15), mean(naive));
        let bound15 = 4.0 * (30.0 / n_real as f64).sqrt();
        let sg_density = noise.gyro_noise_density;
        println!(
            "{mode:?} {:<9} σ_g {sg_density} N = {n_real}: mean NEES9 {m9:.3}, NEES15 {m15:.3} \
             (±{bound15:.2}); sensor covariance rotated only: {mn:.3}",
            scheme.name()
        );
        if asserted {
            assert!((m9 - 9.0).abs() <= 0.3, "{mode:?} {scheme:?} NEES9 {m9}");
            assert!(
                (m15 - 15.0).abs() <= bound15,
                "{mode:?} {scheme:?} NEES15 {m15}"
            );
        }
        if asserted && mode == LeverArm::Exact {
            assert!((mn - 9.0).abs() > 0.3, "{scheme:?} rotated-only {mn}");
        }
        out.insert(
            format!("{mode:?}/{sg_density}/{}", scheme.name()),
            serde_json::json!({"nees9": m9, "nees15": m15, "rotated_only_nees9": mn}),
        );
    }
}

fn params_like(p: &PreintParams, pose: Option<SensorPose>) -> PreintParams {
    PreintParams {
        body_p_sensor: pose,
        ..p.clone()
    }
}

/// `diag(R, R, R)`: the sensor's error rotated into the body, lever-arm terms left out.
fn rotation_only(pose: &SensorPose) -> SMatrix<f64, 9, 9> {
    let mut a = SMatrix::<f64, 9, 9>::zeros();
    for k in 0..3 {
        a.fixed_view_mut::<3, 3>(3 * k, 3 * k)
            .copy_from(pose.rotation.matrix());
    }
    a
}

/// Consecutive keyframe windows with a lever arm merge into the single window over both
/// (deltas, covariance, combined covariance and bias Jacobians to round-off, every scheme)
/// when split at a sample: the end rates' noise is shared through the edge sources and the
/// end-rate terms at the common keyframe cancel. Split between samples, the merge is the
/// stream with the boundary sample inserted (`preint::merge` docs), so it differs from the
/// single window by the scheme's integration error: no more than without a lever arm (×2).
#[test]
fn lever_arm_windows_merge_exactly() {
    let scene = scene_by_name("aggressive").unwrap();
    let pose = mount(0.3);
    let s = sensor_stream(scene.as_ref(), &pose, 0, 3_000_000_000, PERIOD);
    let b = scene_bias();
    for (mode, scheme) in MODES
        .iter()
        .flat_map(|m| Scheme::ALL.iter().map(move |s| (*m, *s)))
    {
        let p = with_mode(params(scheme, Level::Combined, Some(pose)), mode);
        let split = |p: &PreintParams, t_k: i64| {
            let a = preintegrate(p, &b, &s, T_I, t_k).unwrap();
            let c = preintegrate(p, &b, &s, t_k, T_J).unwrap();
            let whole = preintegrate(p, &b, &s, T_I, T_J).unwrap();
            (merge(&a, &c).unwrap(), whole)
        };
        let rel = |x: f64, scale: f64| x / scale.max(1e-300);
        let (m, whole) = split(&p, 1_500_000_000);
        let dv = rel((m.delta_v - whole.delta_v).amax(), whole.delta_v.amax());
        let cov = rel((m.cov - whole.cov).amax(), whole.cov.amax());
        let c15 = rel((m.cov15 - whole.cov15).amax(), whole.cov15.amax());
        let jac = rel(
            (m.jac.d_v_d_bg - whole.jac.d_v_d_bg).amax(),
            whole.jac.d_v_d_bg.amax(),
        );
        println!(
            "{:<9} split at a sample: rel Δv {dv:.1e}, cov {cov:.1e}, cov15 {c15:.1e}, J {jac:.1e}",
            scheme.name()
        );
        assert!(
            dv < 1e-12 && cov < 1e-9 && c15 < 1e-9 && jac < 1e-12,
            "{scheme:?}"
        );
        let between = 1_502_500_000;
        let (m, whole) = split(&p, between);
        let (m0, whole0) = split(&params_like(&p, None), between);
        let d = (m.delta_v - whole.delta_v).norm();
        let d0 = (m0.delta_v - whole0.delta_v).norm();
        println!(
            "{:<9} split between samples: |Δv merged − whole| {d:.1e} (IMU as body: {d0:.1e})",
            scheme.name()
        );
        assert!(d <= 2.0 * d0 + 1e-12, "{scheme:?}: {d:e} vs {d0:e}");
    }
}

/// `Σ_k J_k Q_k J_kᵀ` over the samples `ks` of `s`: `J_k` the central differences of
/// `window(samples)`'s deltas with respect to sample k's six readings, `Q_k` its noise with the
/// cell `cell(k)` [s] (the densities of `noise`).
fn numeric_cov(
    s: &[ImuSample],
    ks: std::ops::Range<usize>,
    noise: &ImuNoise,
    cell: impl Fn(usize) -> f64,
    window: impl Fn(&[ImuSample]) -> PreintegratedImu,
) -> SMatrix<f64, 9, 9> {
    let eps = 1e-6;
    let mut num = SMatrix::<f64, 9, 9>::zeros();
    for k in ks {
        let mut jk = SMatrix::<f64, 9, 6>::zeros();
        for c in 0..6 {
            let shifted = |sign: f64| {
                let mut v = s.to_vec();
                if c < 3 {
                    v[k].gyro[c] += sign * eps;
                } else {
                    v[k].acc[c - 3] += sign * eps;
                }
                window(&v)
            };
            let d = shifted(1.0).delta_error(&shifted(-1.0)) / (2.0 * eps);
            jk.fixed_view_mut::<9, 1>(0, c).copy_from(&d);
        }
        let mut q = SMatrix::<f64, 6, 6>::zeros();
        for i in 0..3 {
            q[(i, i)] = noise.gyro_noise_density.powi(2) / cell(k);
            q[(i + 3, i + 3)] = noise.acc_noise_density.powi(2) / cell(k);
        }
        num += jk * q * jk.transpose();
    }
    num
}

/// The noisy-MEMS densities (σ_g = 0.015 rad/s/√Hz, σ_a = 0.019 m/s²/√Hz), every (lever-arm
/// model, scheme) pair and its parameters at `Level::Covariance` with the mount of [`mount`].
fn covariance_cases() -> Vec<(LeverArm, Scheme, ImuNoise, PreintParams)> {
    let noise = ImuNoise {
        gyro_noise_density: 0.015,
        acc_noise_density: 0.019,
        ..ImuNoise::euroc()
    };
    MODES
        .iter()
        .flat_map(|m| Scheme::ALL.iter().map(move |s| (*m, *s)))
        .map(|(mode, scheme)| {
            let p = PreintParams {
                body_p_sensor: Some(mount(0.3)),
                lever_arm: mode,
                ..PreintParams::from_noise(&noise)
                    .with_scheme(scheme)
                    .with_level(Level::Covariance)
                    .with_gravity(g())
            };
            (mode, scheme, noise, p)
        })
        .collect()
}

/// The 9×9 covariance with a lever arm, both models, every scheme, against the covariance
/// built from numeric derivatives ([`numeric_cov`]; each sample's cell by the scheme's rule on
/// its neighbours). 0.1 s at 200 Hz on `aggressive`, the noisy-MEMS densities.
#[test]
fn lever_arm_covariance_matches_numeric_derivatives() {
    let scene = scene_by_name("aggressive").unwrap();
    let s = sensor_stream(scene.as_ref(), &mount(0.3), T_I, T_I + 100_000_000, PERIOD);
    let b0 = ImuBias::zero();
    for (mode, scheme, noise, p) in covariance_cases() {
        let m = run(&p, &b0, &s);
        let span = |a: usize, b: usize| (s[b].t_ns - s[a].t_ns) as f64 * 1e-9;
        let cell = |k: usize| {
            let left = if k > 0 { span(k - 1, k) } else { 0.0 };
            let right = if k + 1 < s.len() { span(k, k + 1) } else { 0.0 };
            scheme.cell_rule().cell_s(left, right)
        };
        let num = numeric_cov(&s, 0..s.len(), &noise, cell, |v| run(&p, &b0, v));
        let err = (m.cov - num).amax() / num.amax();
        println!(
            "{mode:?} {:<9} covariance vs numeric derivatives: max rel {err:.1e}",
            scheme.name()
        );
        assert!(err < 1e-5, "{mode:?} {scheme:?}: {err:e}");
    }
}

/// Keyframes between samples: the window's boundary samples are interpolated from the stream
/// (linear for euler and midpoint, cubic for hermite4), and so are the end rates of the lever
/// arm. The 9×9 covariance of such a window against [`numeric_cov`] with respect to every
/// stream sample the window reads (cells from the stream neighbours), both models, every
/// scheme.
#[test]
fn lever_arm_covariance_with_keyframes_between_samples() {
    let scene = scene_by_name("aggressive").unwrap();
    let s = sensor_stream(scene.as_ref(), &mount(0.3), T_I, T_I + 150_000_000, PERIOD);
    let (t_i, t_j) = (T_I + 12_500_000, T_I + 101_000_000);
    let b0 = ImuBias::zero();
    for (mode, scheme, noise, p) in covariance_cases() {
        let m = preintegrate(&p, &b0, &s, t_i, t_j).unwrap();
        let cell = |_| scheme.cell_rule().cell_s(0.005, 0.005);
        let window = |v: &[ImuSample]| preintegrate(&p, &b0, v, t_i, t_j).unwrap();
        let num = numeric_cov(&s, 1..s.len() - 1, &noise, cell, window);
        let err = (m.cov - num).amax() / num.amax();
        println!(
            "{mode:?} {:<9} keyframes between samples: covariance vs numeric {err:.1e}",
            scheme.name()
        );
        assert!(err < 1e-5, "{mode:?} {scheme:?}: {err:e}");
    }
}
