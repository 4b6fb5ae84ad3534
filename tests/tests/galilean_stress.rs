//! GTSAM 4.3's "one-second inertial stress test" (`Logmap_IMU_NEES.md`, run by its
//! `GalileanImuFactorNEES` notebook) with its parameters, on every scheme: is the factor's
//! covariance right when the input is held over each interval, as the Galilean scheme assumes?
//!
//! Setup (GTSAM's): held body specific force a = (2, −1, 0.5) m/s², rate ω = (1.2, −0.8, 2.0)
//! rad/s, g = 0, 1 s at 20 Hz (21 samples, 20 intervals), state at t_i the identity at rest.
//! Noise: continuous-time densities σ_a = (0.03, 0.04, 0.05) m/s²/√Hz and σ_g = (0.01, 0.015,
//! 0.02) rad/s/√Hz, per axis (`PreintParams::acc_cov`/`gyro_cov` = diag(σ²)), no integration
//! covariance; every sample gets white noise of per-axis standard deviation σ/√Δt (the
//! notebook's `rng.normal * sigma / sqrt(dt)`), drawn by the suite's seeded generator. Truth:
//! the exact state of the noise-free held input, written out here from Rodrigues' formula
//! (`ΔR = Exp(ωT)`, `Δv = J_l(ωT) a T`, `Δp = N(ωT) a T²`, the integrals in
//! `preint/tests/galilean.rs`). Euler and Galilean hold sample k over [t_k, t_k+1] exactly as
//! GTSAM's `integrateMeasurement(a_k, ω_k, Δt)` does (sample 20 is read by midpoint and hermite4
//! only), so `euler` and `galilean` see GTSAM's Manifold and Galilean experiment.
//!
//! Per scheme (euler, midpoint, hermite4, galilean) and trial: χ² of `ImuFactor` in its default
//! (SE₂(3) Logmap) residual at the true states, weighted by the factor's own residual covariance
//! (GTSAM: `state_j.logmap(predict) ᵀ residualCovariance⁻¹ (…)`), and the position and velocity
//! error of the prediction against the truth (navigation frame).
//!
//! Asserted:
//! - the noise-free galilean prediction equals the closed form to 1e-12 (m, m/s, rad);
//! - galilean's mean NEES in GTSAM's 95 % interval of the mean of N = 3 000 trials,
//!   `χ²_{9N}(0.025, 0.975)/N` = [8.849, 9.152] (GTSAM: 8.959; `PREINT_FULL=1`: N = 30 000 and
//!   the same quantiles for that N, [8.952, 9.048]);
//! - euler's mean NEES above that interval (over-confident by its discretisation error);
//! - galilean's position / velocity RMS, `√(mean ‖e‖²)`, within three standard errors of
//!   GTSAM's 0.0427 m / 0.0767 m/s (a different draw of the same distribution; the standard
//!   error of the RMS is `sd(‖e‖²) / (2 RMS √N)`, from our own trials);
//! - euler (= GTSAM's Manifold backend to 1e-15, `preint/tests/gtsam_euler.rs`): mean NEES and
//!   position / velocity RMS within three standard errors (of the mean: `sd(χ²)/√N`) of
//!   GTSAM's Manifold row, 14.502, 0.0578 m, 0.1049 m/s.
//!
//! The other schemes' figures, the noise-free discretisation χ² λ of each (the expected mean is
//! `9 + λ`) and the covariance's own prediction of the RMS, `√tr Σ_pp`, are printed.
//!
//! Output: `target/evidence/galilean_stress.json`.

use evidence::monte_carlo::realise;
use evidence::{Gauss, full_run, mean, write_json};
use nalgebra::{Matrix3, Vector3};
use preint::{
    ImuBias, ImuFactor, ImuSample, Level, NavState, PreintParams, PreintegratedImu, Preintegrator,
    Scheme,
};
use preint_lie::SO3;

type V3 = Vector3<f64>;

const A: [f64; 3] = [2.0, -1.0, 0.5];
const W: [f64; 3] = [1.2, -0.8, 2.0];
const SIGMA_A: [f64; 3] = [0.03, 0.04, 0.05];
const SIGMA_G: [f64; 3] = [0.01, 0.015, 0.02];
const RATE: i64 = 20;
/// GTSAM's Galilean figures (`Logmap_IMU_NEES.md`): position RMS [m], velocity RMS [m/s].
const GTSAM_GALILEAN_RMS: (f64, f64) = (0.0427, 0.0767);
/// GTSAM's Manifold figures (= our `euler`): mean NEES, position RMS [m], velocity RMS [m/s].
const GTSAM_MANIFOLD: (f64, f64, f64) = (14.502, 0.0578, 0.1049);

/// Trials and the 95 % interval of the mean of that many χ²₉ draws, `χ²_{9N}(0.025, 0.975)/N`
/// (Wilson–Hilferty, exact to < 1e-6 at 9N ≥ 27 000 degrees of freedom): GTSAM's N = 3 000,
/// and 30 000 for the full run.
fn trials_and_band() -> (usize, [f64; 2]) {
    if full_run() {
        (30_000, [8.952_054, 9.048_072])
    } else {
        (3_000, [8.848_814, 9.152_449])
    }
}

fn skew(n: &V3) -> Matrix3<f64> {
    Matrix3::new(0.0, -n.z, n.y, n.z, 0.0, -n.x, -n.y, n.x, 0.0)
}

/// The exact state at `t` \[s\] of the held input from the identity at rest (g = 0), from
/// Rodrigues' formula integrated by hand (module docs of `preint/tests/galilean.rs`).
fn exact_state(t: f64) -> NavState {
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
    NavState::new(SO3::from_matrix(&r), p, v)
}

fn params(scheme: Scheme) -> PreintParams {
    let mut p = PreintParams::default()
        .with_scheme(scheme)
        .with_level(Level::Covariance)
        .with_gravity(V3::zeros());
    p.acc_cov = Matrix3::from_diagonal(&V3::from(SIGMA_A).map(|s| s * s));
    p.gyro_cov = Matrix3::from_diagonal(&V3::from(SIGMA_G).map(|s| s * s));
    p.integration_cov = None;
    p
}

/// The 21 samples of 1 s at 20 Hz, each with white noise of per-axis std σ/√Δt when `rng` is
/// given (drawn per sample: gyro x, y, z, then accelerometer x, y, z).
fn samples(mut rng: Option<&mut Gauss>) -> Vec<ImuSample> {
    let step = 1_000_000_000 / RATE;
    let sq = (1.0 / RATE as f64).sqrt();
    (0..=RATE)
        .map(|k| {
            let (mut g, mut a) = (V3::from(W), V3::from(A));
            if let Some(r) = rng.as_deref_mut() {
                g += V3::from_fn(|i, _| r.normal() * SIGMA_G[i] / sq);
                a += V3::from_fn(|i, _| r.normal() * SIGMA_A[i] / sq);
            }
            ImuSample::new(k * step, g, a)
        })
        .collect()
}

fn integrate(scheme: Scheme, s: &[ImuSample]) -> PreintegratedImu {
    let mut pi = Preintegrator::new(params(scheme), ImuBias::zero()).unwrap();
    pi.integrate_slice(s).unwrap();
    pi.finish().unwrap()
}

/// Per-trial figures of one scheme.
struct Stats<'a> {
    chi2: &'a [f64],
    /// ‖p̂_j − p_j‖² [m²].
    pos2: &'a [f64],
    /// ‖v̂_j − v_j‖² [m²/s²].
    vel2: &'a [f64],
}

/// Sample standard deviation.
fn sd(x: &[f64]) -> f64 {
    let m = mean(x);
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// `(RMS, its standard error)`: `RMS = √mean(e2)` and, by the delta method,
/// `sd(e2) / (2 RMS √N)`.
fn rms_and_se(e2: &[f64]) -> (f64, f64) {
    let rms = mean(e2).sqrt();
    (rms, sd(e2) / (2.0 * rms * (e2.len() as f64).sqrt()))
}

#[test]
fn galilean_is_consistent_on_gtsams_held_input_stress_test() {
    let (n, band) = trials_and_band();
    let (xi, xj) = (NavState::identity(), exact_state(1.0));
    let b0 = ImuBias::zero();

    // Noise-free: galilean is the closed form; λ of every scheme.
    let clean = samples(None);
    let pred = ImuFactor::new(integrate(Scheme::Galilean, &clean))
        .unwrap()
        .predict(&xi, &b0);
    let e0 = [
        evidence::rot_angle(&pred.r, &xj.r),
        (pred.v - xj.v).norm(),
        (pred.p - xj.p).norm(),
    ];
    println!(
        "noise-free galilean vs closed form: rotation {:.1e} rad, velocity {:.1e} m/s, position {:.1e} m",
        e0[0], e0[1], e0[2]
    );
    assert!(e0.iter().all(|e| *e <= 1e-12), "{e0:?}");

    let schemes = Scheme::ALL;
    let lambda: Vec<f64> = schemes
        .iter()
        .map(|s| {
            ImuFactor::new(integrate(*s, &clean))
                .unwrap()
                .chi2(&xi, &xj, &b0)
        })
        .collect();
    let mut model_rms = vec![(0.0, 0.0); schemes.len()];
    // Per trial and scheme: χ², squared position and velocity errors of the prediction.
    let figures = realise(
        n,
        0x6A1_0000_0000,
        |rng| samples(Some(rng)),
        |t, noisy| {
            let mut out = Vec::with_capacity(3 * schemes.len());
            for (k, scheme) in schemes.iter().enumerate() {
                let m = integrate(*scheme, noisy);
                if t == 0 {
                    let c = &m.cov;
                    let tr = |o: usize| (0..3).map(|i| c[(o + i, o + i)]).sum::<f64>().sqrt();
                    model_rms[k] = (tr(6), tr(3));
                }
                let f = ImuFactor::new(m).unwrap();
                let p = f.predict(&xi, &b0);
                out.extend([
                    f.chi2(&xi, &xj, &b0),
                    (p.p - xj.p).norm_squared(),
                    (p.v - xj.v).norm_squared(),
                ]);
            }
            out
        },
    );
    let stats: Vec<Stats> = figures
        .chunks(3)
        .map(|f| Stats {
            chi2: &f[0],
            pos2: &f[1],
            vel2: &f[2],
        })
        .collect();

    println!(
        "GTSAM's one-second stress test, N = {n} trials, 95 % interval of the mean NEES [{:.3}, {:.3}]",
        band[0], band[1]
    );
    println!(
        "{:<9} {:>10} {:>9} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "scheme",
        "λ",
        "mean NEES",
        "± s.e.",
        "pos RMS",
        "± s.e.",
        "model",
        "vel RMS",
        "± s.e.",
        "model"
    );
    let mut rows = vec![];
    for (k, scheme) in schemes.iter().enumerate() {
        let st = &stats[k];
        let (pr, pse) = rms_and_se(st.pos2);
        let (vr, vse) = rms_and_se(st.vel2);
        let (nees, nees_se) = (mean(st.chi2), sd(st.chi2) / (n as f64).sqrt());
        println!(
            "{:<9} {:>10.2e} {:>9.3} {:>7.3} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            scheme.name(),
            lambda[k],
            nees,
            nees_se,
            pr,
            pse,
            model_rms[k].0,
            vr,
            vse,
            model_rms[k].1
        );
        rows.push(serde_json::json!({
            "scheme": scheme.name(), "discretisation_chi2": lambda[k], "mean_nees": nees,
            "mean_nees_se": nees_se, "position_rms_m": pr, "position_rms_se_m": pse, "position_rms_model_m": model_rms[k].0,
            "velocity_rms_m_s": vr, "velocity_rms_se_m_s": vse,
            "velocity_rms_model_m_s": model_rms[k].1,
        }));
    }
    println!(
        "GTSAM 4.3 (N = 3 000): Manifold NEES {}, RMS {} m / {} m/s; \
         Galilean NEES 8.959, RMS {} m / {} m/s",
        GTSAM_MANIFOLD.0,
        GTSAM_MANIFOLD.1,
        GTSAM_MANIFOLD.2,
        GTSAM_GALILEAN_RMS.0,
        GTSAM_GALILEAN_RMS.1
    );
    write_json(
        "galilean_stress.json",
        &serde_json::json!({
            "description": "GTSAM's one-second inertial stress test: held a, w, g = 0, 20 Hz, \
                            anisotropic noise; mean NEES of ImuFactor (Logmap) at the truth and \
                            RMS of the prediction against the truth",
            "trials": n, "band95": band,
            "gtsam": {"galilean": {"mean_nees": 8.959, "position_rms_m": 0.0427,
                                   "velocity_rms_m_s": 0.0767},
                      "manifold": {"mean_nees": 14.502, "position_rms_m": 0.0578,
                                   "velocity_rms_m_s": 0.1049}},
            "rows": rows,
        }),
    );

    let gi = schemes.iter().position(|s| *s == Scheme::Galilean).unwrap();
    let ei = schemes.iter().position(|s| *s == Scheme::Euler).unwrap();
    let g_nees = mean(stats[gi].chi2);
    assert!(
        (band[0]..=band[1]).contains(&g_nees),
        "galilean mean NEES {g_nees} outside {band:?}"
    );
    let e_nees = mean(stats[ei].chi2);
    assert!(
        e_nees > band[1],
        "euler mean NEES {e_nees} not above {band:?}"
    );
    let e_se = sd(stats[ei].chi2) / (n as f64).sqrt();
    assert!(
        (e_nees - GTSAM_MANIFOLD.0).abs() <= 3.0 * e_se,
        "euler mean NEES {e_nees} vs GTSAM Manifold's {} (s.e. {e_se})",
        GTSAM_MANIFOLD.0
    );
    for (e2, gtsam, what) in [
        (stats[ei].pos2, GTSAM_MANIFOLD.1, "position"),
        (stats[ei].vel2, GTSAM_MANIFOLD.2, "velocity"),
    ] {
        let (r, se) = rms_and_se(e2);
        assert!(
            (r - gtsam).abs() <= 3.0 * se,
            "euler {what} RMS {r} vs GTSAM Manifold's {gtsam} (s.e. {se})"
        );
    }
    let (pr, pse) = rms_and_se(stats[gi].pos2);
    let (vr, vse) = rms_and_se(stats[gi].vel2);
    assert!(
        (pr - GTSAM_GALILEAN_RMS.0).abs() <= 3.0 * pse,
        "position RMS {pr} vs GTSAM's {} (s.e. {pse})",
        GTSAM_GALILEAN_RMS.0
    );
    assert!(
        (vr - GTSAM_GALILEAN_RMS.1).abs() <= 3.0 * vse,
        "velocity RMS {vr} vs GTSAM's {} (s.e. {vse})",
        GTSAM_GALILEAN_RMS.1
    );
}
