//! Multi-position static calibration (Tedaldi, Pretto, Menegatti, ICRA 2014; imu_tk), with the
//! still intervals linked by gyro preintegration, the bias random walk marginalised and the
//! model chosen by BIC.
//!
//! # Data
//! The IMU is held still in K ≥ 3 attitudes and rotated between them. Still intervals are
//! detected automatically ([`super::still`]). For interval k (averaging time `T_k = N_k·Δt`)
//! the means `ω̄_k`, `f̄_k` are kept; between consecutive intervals the gyro samples from the
//! last sample of interval k to the first of interval k+1 are kept for re-integration.
//!
//! # Sensor model ([`model`])
//! ```text
//! gyro     ω_m = S_g ω_b + b_g(t) + n_g         S_g = diag(1 + s_g)·(I + M_g)
//! accel    a_m = S_a R_kᵀ(−g) + b_a(t) + n_a    S_a = diag(1 + s_a)·(I + N_a)   (at rest)
//! biases   b(t) = b̄ + w(t)                      w: bias random walk, w(t_ref) = 0
//! ```
//!
//! Unknowns: `b_g`, `b_a` \[rad/s, m/s²\] (the biases `b̄` at the reference time `t_ref`), the
//! terms of the chosen model and the attitude `R_k` (SO3, right perturbation) of every still
//! interval. Parameter vector order: `[b_g, b_a, s_a?, m_a?, s_g?, m_g?]` (present terms only,
//! in this order).
//!
//! # Residuals
//! ```text
//! e_ω,k = ω̄_k − b_g                            white-noise covariance s_ω,k² I,  s_ω,k = σ_g/√T_k
//! e_f,k = f̄_k − S_a R_kᵀ(−g) − b_a             white-noise covariance s_f,k² I,  s_f,k = σ_a/√T_k
//! e_R,k = Log(ΔR_k(b_g, S_g)ᵀ R_kᵀ R_k+1)      white-noise covariance Σ_φ,k
//! ```
//!
//! `ΔR_k(b_g, S_g)` is the midpoint-rule rotation preintegration of the corrected rates
//! `S_g⁻¹(ω_m − b_g)` over link window k, re-integrated at every evaluation with its Jacobians
//! ([`link_rotation`]); `Σ_φ,k` is the rotation block of `preint`'s covariance of that window.
//! The solver sees the whitened `r = L⁻¹e` with `L Lᵀ = Σ = D + Σ_w`, `D` the block-diagonal
//! white-noise part above and `Σ_w` the bias random walk's part, so χ² = ‖r‖² = eᵀΣ⁻¹e. The
//! analytic Jacobians are checked against Ridders' numeric ones in the tests.
//!
//! # Bias random walk ([`random_walk`])
//! The walk is integrated out: every residual block gets a drift term linear in the walk at the
//! sample times it uses (interval means of the walk; for a link, the walk integrated over the
//! motion and carried to the window's end frame), whose covariance `Σ_w` correlates different
//! intervals and links. With [`MultiPoseOptions::include_random_walk`] off (or a zero random
//! walk density) `Σ = D` and the biases are held constant. The biases are those at `t_ref`: by
//! default the sample time nearest the middle of the span from the first still interval's start
//! to the last one's end ([`MultiPoseOptions::reference_time_ns`]), as the static problem
//! reports its bias at mid-recording; χ² does not depend on `t_ref`.
//!
//! # Gauge
//! A common rotation of all attitudes about the world gravity axis changes no residual (one
//! null direction); the solver's rank analysis reports it and the estimates that do not depend
//! on it (biases, scales, misalignments, roll/pitch) get their marginal covariance from the
//! pseudo-inverse. The initial attitudes chain from the first interval at zero yaw.
//!
//! # Model selection ([`selection`])
//! Each candidate model is solved and the identifiable, converged one with the lowest
//! `BIC = χ² + k·ln m` wins; the reason text reports every candidate and warns when the
//! winner's χ²/dof shows that the residuals are not the stated noise.
//!
//! # Limits
//! The bias random walk is modelled with the stated densities: if the real drift is larger
//! (temperature transients, turn-on), χ²/dof grows and the reason warns. Without the
//! marginalisation biases are held constant; then keep the protocol short compared with the
//! random walk: the interval means have σ_a/√T ≈ 1e-3 m/s² (EuRoC, T = 3 s) while EuRoC's σ_ba
//! moves b_a by σ_ba√T ≈ 0.017 m/s² over `preint-sim`'s 33 s `multi-pose-static` scene
//! (bias-only χ²/dof ≈ 3 there, ≈ 9 over 120 s, and scale/misalignment terms absorb the drift).
//! The accelerometer triad's lever arms (imu_tk ignores them too) and the gyro's g-sensitivity
//! are not modelled.

pub mod data;
pub mod link_rotation;
pub mod model;
pub mod random_walk;
pub mod residuals;
pub mod selection;
#[cfg(test)]
mod test_data;

pub use link_rotation::{rotation_preintegration, rotation_preintegration_general};
pub use model::{MultiPoseModel, acc_scale_matrix, gyro_scale_matrix};
pub use random_walk::{rotation_drift_coefficients, wiener_cross_covariance};
pub use selection::ModelFit;

use super::BiasError;
use super::still::{StillInterval, StillOptions};
use super::tilt::roll_pitch_with_cov;
use super::validate::{check_gravity, check_noise, check_samples};
use crate::gauss_newton::{GaussNewton, Solution, StopReason, solve};
use data::{Prepared, prepare};
use nalgebra::{DVector, Matrix3, SVector, Vector3};
use preint::{ImuNoise, ImuSample};
use preint_lie::SO3;
use residuals::{Problem, State};

/// Options of [`calibrate_multi_pose`].
#[derive(Clone, Debug, PartialEq)]
pub struct MultiPoseOptions {
    /// World gravity \[m/s²\]; default `(0, 0, −9.81)`.
    pub gravity: Vector3<f64>,
    /// Still detector options; `None` (default): [`StillOptions::from_noise`] at the measured
    /// sample rate.
    pub still: Option<StillOptions>,
    /// Candidate models (default: all six, [`MultiPoseModel::ALL`]).
    pub models: Vec<MultiPoseModel>,
    /// Minimum number of still intervals (default 3; richer models need more attitudes to be
    /// observable, which the rank check enforces).
    pub min_intervals: usize,
    /// Gauss-Newton iteration limit per model (default 50).
    pub max_iters: u64,
    /// Marginalise the bias random walk (module docs, "Bias random walk"): add its covariance
    /// `Σ_w` to the residual covariance (default `true`). It is active only when the noise has
    /// a non-zero random walk density; `false` holds the biases constant over the recording.
    pub include_random_walk: bool,
    /// Reference time `t_ref` \[ns\] of the estimated biases `b̄ = b(t_ref)`; `None` (default):
    /// the sample time nearest the middle of the still intervals' span. Must lie within the
    /// recording's time span.
    pub reference_time_ns: Option<i64>,
}

impl Default for MultiPoseOptions {
    fn default() -> Self {
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            still: None,
            models: MultiPoseModel::ALL.to_vec(),
            min_intervals: 3,
            max_iters: 50,
            include_random_walk: true,
            reference_time_ns: None,
        }
    }
}

/// Result of [`calibrate_multi_pose`] (the estimates are those of the chosen model; terms the
/// model does not have are `None`).
#[derive(Clone, Debug)]
pub struct MultiPoseCalibration {
    /// The model chosen by BIC.
    pub model: MultiPoseModel,
    /// All candidates' statistics, in the order of [`MultiPoseOptions::models`].
    pub fits: Vec<ModelFit>,
    /// Why the model won: the winner's and runner-up's BIC, their difference and every
    /// candidate's BIC, χ², k and m, for humans.
    pub reason: String,
    /// Gyro bias b_g \[rad/s\] at [`MultiPoseCalibration::reference_time_ns`].
    pub gyro_bias: Vector3<f64>,
    /// Its standard deviation \[rad/s\] (white noise and, when marginalised, the random walk).
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias b_a \[m/s²\] at [`MultiPoseCalibration::reference_time_ns`].
    pub acc_bias: Vector3<f64>,
    /// Its standard deviation \[m/s²\].
    pub acc_bias_std: Vector3<f64>,
    /// Accelerometer scale errors `s_a` (`S_a = diag(1 + s_a)(I + N_a)`), if in the model.
    pub acc_scale: Option<Vector3<f64>>,
    /// Their standard deviations.
    pub acc_scale_std: Option<Vector3<f64>>,
    /// Accelerometer misalignment `m_a = (N₁₀, N₂₀, N₂₁)` \[rad\], if in the model.
    pub acc_misalignment: Option<Vector3<f64>>,
    /// Its standard deviations \[rad\].
    pub acc_misalignment_std: Option<Vector3<f64>>,
    /// Gyro scale errors `s_g` (`S_g = diag(1 + s_g)(I + M_g)`), if in the model.
    pub gyro_scale: Option<Vector3<f64>>,
    /// Their standard deviations.
    pub gyro_scale_std: Option<Vector3<f64>>,
    /// Gyro misalignment `m_g = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)` \[rad\], if in the model.
    pub gyro_misalignment: Option<SVector<f64, 6>>,
    /// Its standard deviations \[rad\].
    pub gyro_misalignment_std: Option<SVector<f64, 6>>,
    /// The still intervals used.
    pub intervals: Vec<StillInterval>,
    /// Attitude R_wb of each interval (yaw gauge: the solver's, starting from zero yaw).
    pub attitudes: Vec<SO3>,
    /// Roll, pitch \[rad\] of each interval and their standard deviations \[rad\]:
    /// `(roll, pitch, roll_std, pitch_std)` (ZYX convention, [`super::roll_pitch_of_up`]).
    pub roll_pitch: Vec<(f64, f64, f64, f64)>,
    /// χ² of the chosen model.
    pub chi2: f64,
    /// Its degrees of freedom (residuals − rank).
    pub dof: usize,
    /// Gauss-Newton iterations of the chosen model.
    pub iterations: u64,
    /// Why its solver stopped.
    pub stop: StopReason,
    /// The reference time `t_ref` \[ns\] the biases refer to (module docs).
    pub reference_time_ns: i64,
    /// Whether the bias random walk was marginalised (option on and a non-zero random walk
    /// density); otherwise the biases were held constant.
    pub random_walk_marginalised: bool,
}

impl MultiPoseCalibration {
    /// The goodness of fit of the chosen model: `chi2` against `χ²_dof` ([`crate::fit`]).
    pub fn fit(&self) -> crate::Fit {
        crate::Fit::new(self.chi2, self.dof)
    }
    /// The accelerometer matrix `S_a` of the chosen model (identity without scale terms).
    pub fn acc_scale_matrix(&self) -> Matrix3<f64> {
        acc_scale_matrix(
            &self.acc_scale.unwrap_or_else(Vector3::zeros),
            &self.acc_misalignment.unwrap_or_else(Vector3::zeros),
        )
    }
    /// The gyro matrix `S_g` of the chosen model (identity without scale terms).
    pub fn gyro_scale_matrix(&self) -> Matrix3<f64> {
        gyro_scale_matrix(
            &self.gyro_scale.unwrap_or_else(Vector3::zeros),
            &self.gyro_misalignment.unwrap_or_else(SVector::zeros),
        )
    }
}

/// Calibrates a multi-position static recording (module docs): detects still intervals, builds
/// the problem, solves every candidate model and keeps the eligible one with the lowest BIC.
///
/// Errors: invalid samples/noise/options, fewer than `min_intervals` still intervals
/// ([`BiasError::TooFew`]), no eligible (identifiable and converged) model
/// ([`BiasError::InvalidParameter`] naming every candidate's status), preintegration or
/// solver failures; no panics on bad input.
///
/// ```
/// use nalgebra::Vector3;
/// use preint::{ImuBias, ImuNoise};
/// use preint_calib::bias::{MultiPoseModel, MultiPoseOptions, calibrate_multi_pose};
/// use preint_lie::SO3;
/// use preint_sim::{MultiPoseStaticScene, SimConfig, simulate};
///
/// // Four attitudes (level, on either side, on its nose), 2 s still each, 1 s turns.
/// let h = std::f64::consts::FRAC_PI_2;
/// let poses = vec![
///     SO3::identity(),
///     SO3::exp(&Vector3::new(h, 0.0, 0.0)),
///     SO3::exp(&Vector3::new(0.0, h, 0.0)),
///     SO3::exp(&Vector3::new(-h, 0.0, 0.0)),
/// ];
/// let scene = MultiPoseStaticScene::new(poses, 2.0, 1.0, Vector3::zeros()).unwrap();
/// let noise = ImuNoise::euroc();
/// let (b_g, b_a) = (Vector3::new(0.003, -0.002, 0.004), Vector3::new(0.05, -0.04, 0.08));
/// let cfg = SimConfig {
///     noise,
///     initial_bias: ImuBias::new(b_g, b_a),
///     bias_random_walk: false,
///     ..SimConfig::default()
/// };
/// let rec = simulate(&scene, 200.0, scene.duration_s(), &cfg, 7).unwrap();
/// let opts = MultiPoseOptions {
///     models: vec![MultiPoseModel::BiasOnly, MultiPoseModel::AccScale],
///     ..MultiPoseOptions::default()
/// };
/// let cal = calibrate_multi_pose(&rec.samples, &noise, &opts).unwrap();
/// assert_eq!(cal.intervals.len(), 4);
/// for k in 0..3 {
///     assert!((cal.gyro_bias[k] - b_g[k]).abs() < 4.0 * cal.gyro_bias_std[k]);
///     assert!((cal.acc_bias[k] - b_a[k]).abs() < 4.0 * cal.acc_bias_std[k]);
/// }
/// assert_eq!(cal.fits.len(), 2); // every candidate's BIC is reported
/// ```
pub fn calibrate_multi_pose(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &MultiPoseOptions,
) -> Result<MultiPoseCalibration, BiasError> {
    check_samples(samples, 3)?;
    check_noise(noise)?;
    let gnorm = check_gravity("gravity", &opts.gravity)?;
    if opts.models.is_empty() {
        return Err(BiasError::InvalidParameter {
            name: "models",
            reason: "no candidate model".into(),
        });
    }
    let pr = prepare(samples, noise, opts, gnorm)?;
    let mut solutions = Vec::with_capacity(opts.models.len());
    let mut fits = Vec::with_capacity(opts.models.len());
    for &model in &opts.models {
        let sol = solve_model(&pr, model, opts)?;
        let dim = model.param_count() + 3 * pr.obs.intervals.len();
        fits.push(ModelFit::of(model, &sol, dim));
        solutions.push(sol);
    }
    let ctx = selection::Context {
        noise,
        marginalised: pr.marginalised,
        t_ref_ns: pr.obs.t_ref_ns,
    };
    let (best, reason) = selection::select(&fits, &ctx)?;
    let (model, chi2) = (fits[best].model, fits[best].chi2);
    let sol = solutions.swap_remove(best);
    Ok(calibration(model, chi2, reason, fits, sol, pr))
}

/// Solves one candidate model from the prepared initial state (`b_g` = its initial value, every
/// other parameter 0).
fn solve_model(
    pr: &Prepared,
    model: MultiPoseModel,
    opts: &MultiPoseOptions,
) -> Result<Solution<State>, BiasError> {
    let mut p0 = DVector::zeros(model.param_count());
    p0.fixed_rows_mut::<3>(0).copy_from(&pr.obs.bg0);
    let problem = Problem {
        obs: &pr.obs,
        g: opts.gravity,
        model,
        whitening: &pr.whitening,
    };
    Ok(solve(
        problem,
        (p0, pr.r0.clone()),
        GaussNewton::default(),
        opts.max_iters,
    )?)
}

/// The result of the chosen model: its estimates and their marginal standard deviations.
fn calibration(
    model: MultiPoseModel,
    chi2: f64,
    reason: String,
    fits: Vec<ModelFit>,
    sol: Solution<State>,
    pr: Prepared,
) -> MultiPoseCalibration {
    let (p, rs) = &sol.estimate;
    let np = model.param_count();
    let params = model.unpack(p);
    let layout = model.layout();
    let s3 = |o: usize| sol.marginal_std::<3>(o);
    let roll_pitch = rs
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let c = sol.marginal_covariance::<3>(np + 3 * i);
            let (roll, pitch, crp, _) = roll_pitch_with_cov(r, &pr.up_w, &c);
            (
                roll,
                pitch,
                crp[(0, 0)].max(0.0).sqrt(),
                crp[(1, 1)].max(0.0).sqrt(),
            )
        })
        .collect();
    MultiPoseCalibration {
        model,
        reason,
        gyro_bias: params.b_g,
        gyro_bias_std: s3(0),
        acc_bias: params.b_a,
        acc_bias_std: s3(3),
        acc_scale: layout.acc_scale.map(|_| params.s_a),
        acc_scale_std: layout.acc_scale.map(s3),
        acc_misalignment: layout.acc_mis.map(|_| params.m_a),
        acc_misalignment_std: layout.acc_mis.map(s3),
        gyro_scale: layout.gyro_scale.map(|_| params.s_g),
        gyro_scale_std: layout.gyro_scale.map(s3),
        gyro_misalignment: layout.gyro_mis.map(|_| params.m_g),
        gyro_misalignment_std: layout.gyro_mis.map(|o| sol.marginal_std::<6>(o)),
        intervals: pr.obs.ivs,
        attitudes: rs.clone(),
        roll_pitch,
        chi2,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations: sol.iterations,
        stop: sol.stop.clone(),
        fits,
        reference_time_ns: pr.obs.t_ref_ns,
        random_walk_marginalised: pr.marginalised,
    }
}
