//! Static recording at one attitude: gyro bias and gravity direction (roll, pitch).
//!
//! # Model
//! At rest (`ω_b = 0`, `a_w = 0`), with `b_g`, `b_a` constant over the recording:
//!
//! ```text
//! ω_m,k = b_g + n_g,k                       n_g,k ~ N(0, σ_g²/Δt · I)
//! a_m,k = R_wbᵀ(−g) + b_a + n_a,k           n_a,k ~ N(0, σ_a²/Δt · I)
//! ```
//!
//! The per-sample least-squares problem `Σ_k ‖(ω_m,k − b_g)‖²Δt/σ_g² + …` equals, up to a
//! constant (the within-recording scatter), the problem on the means `ω̄`, `f̄` of the N samples
//! with standard deviations `σ/√T`, `T = N·Δt`, so the solver sees these six whitened residuals
//! (O(1) work after one O(N) pass):
//!
//! ```text
//! r_g = (ω̄ − b_g) / s_g                 s_g² = σ_g²/T + σ_bg²·T/12
//! r_a = (f̄ − R_wbᵀ(−g) − b_a) / s_a      s_a² = σ_a²/T + σ_ba²·T/12
//! [r_p = (b_a − μ_p) / σ_p]              only with a prior on b_a
//! ```
//!
//! The `σ_b²·T/12` terms are the variance of a bias random walk's time average about its value
//! at mid-recording (the bias these estimates refer to); they vanish for a zero random walk.
//! Unknowns: `b_g` (3) and `R_wb` (SO3, right perturbation), plus `b_a` (3) with a prior.
//! `∂r_a/∂δφ = −[R_wbᵀ(−g)]× / s_a`: the rotation about the body gravity axis (yaw) is in the
//! null space, which the solver's rank analysis reports; roll and pitch do not depend on it.
//!
//! # Accelerometer bias
//! `f̄ = R_wbᵀ(−g) + b_a` has 3 equations for 2 attitude angles plus 3 bias components: the bias
//! is **not separable from tilt**. Without a prior, `b_a` is left out of the model
//! (`acc_bias = None`): the reported roll/pitch are those of the measured specific force, which
//! equal the attitude's only if `b_a = 0` (a horizontal bias `b_h` tilts them by ≈ `b_h/|g|`
//! rad). With an [`AccBiasPrior`] `N(μ_p, diag σ_p²)`, `b_a` is estimated and its standard
//! deviation is essentially the prior's (the data add only the component along gravity).
//!
//! # Goodness of fit
//! [`StaticCalibration::fit`] tests the per-sample problem: the means' χ² plus the scatter of
//! the samples about them, so the noise densities are checked against the samples themselves.
//!
//! # Outputs
//! Standard deviations from the solver covariance `(JᵀJ)⁻¹` of the whitened residuals: they are
//! predicted from the noise densities. The measured per-axis densities
//! `std(samples)·√Δt` are returned too, to check the densities given.

use super::tilt::{attitude_from_roll_pitch, attitude_from_up, roll_pitch_with_cov};
use super::validate::{check_gravity, check_noise, check_samples};
use super::{BiasError, SegmentStats};
use crate::gauss_newton::{GaussNewton, LeastSquares, Solution, StopReason, solve};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Vector3};
use preint::{ImuNoise, ImuSample};
use preint_lie::{SO3, hat};

/// Gaussian prior on the accelerometer bias: mean `mean` [m/s²], per-axis standard deviation
/// `std` [m/s²] (> 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccBiasPrior {
    /// Prior mean μ_p [m/s²].
    pub mean: Vector3<f64>,
    /// Prior per-axis standard deviation σ_p [m/s²].
    pub std: Vector3<f64>,
}

impl AccBiasPrior {
    /// Checks a finite mean and finite standard deviations > 0.
    fn validate(&self) -> Result<(), BiasError> {
        if self.mean.iter().all(|v| v.is_finite())
            && self.std.iter().all(|v| v.is_finite() && *v > 0.0)
        {
            Ok(())
        } else {
            Err(BiasError::InvalidParameter {
                name: "acc_bias_prior",
                reason: "mean must be finite and std finite and > 0".into(),
            })
        }
    }
}

/// Options of [`calibrate_static`].
#[derive(Clone, Debug, PartialEq)]
pub struct StaticOptions {
    /// World gravity g [m/s²]; default `(0, 0, −9.81)`.
    pub gravity: Vector3<f64>,
    /// Optional prior on b_a (default `None`: b_a unobservable, not estimated).
    pub acc_bias_prior: Option<AccBiasPrior>,
    /// Include the bias random walk term `σ_b²·T/12` in the variance of the means (default
    /// `true`).
    pub include_random_walk: bool,
    /// Gauss-Newton iteration limit (default 20).
    pub max_iters: u64,
    /// Start the solver from the closed-form solution (default `true`: `b_g = ω̄`, attitude
    /// from `f̄`, b_a from the prior mean; the solver then only confirms it, typically in 0–1
    /// iterations). `false`: start from `b_g = 0`, `R_wb = I` (`b_a` = prior mean), so that
    /// the Gauss-Newton iterations do the work (benchmarks, solver tests).
    pub closed_form_start: bool,
}

impl Default for StaticOptions {
    fn default() -> Self {
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            acc_bias_prior: None,
            include_random_walk: true,
            max_iters: 20,
            closed_form_start: true,
        }
    }
}

/// Result of [`calibrate_static`].
#[derive(Clone, Debug)]
pub struct StaticCalibration {
    /// Gyro bias b_g [rad/s] (at mid-recording).
    pub gyro_bias: Vector3<f64>,
    /// Standard deviation of b_g per axis [rad/s].
    pub gyro_bias_std: Vector3<f64>,
    /// Roll \[rad\] of the gravity direction (Z-Y-X convention, see [`super::roll_pitch_of_up`]).
    pub roll: f64,
    /// Pitch \[rad\].
    pub pitch: f64,
    /// Covariance of (roll, pitch) \[rad²\].
    pub roll_pitch_cov: Matrix2<f64>,
    /// Standard deviation of roll \[rad\].
    pub roll_std: f64,
    /// Standard deviation of pitch \[rad\].
    pub pitch_std: f64,
    /// Unit "up" vector in the body frame, `R_wbᵀ(−g)/|g|`.
    pub up_body: Vector3<f64>,
    /// The zero-yaw attitude R_wb consistent with roll/pitch (yaw is unobservable).
    pub attitude: SO3,
    /// Accelerometer bias [m/s²]: `None` without a prior (not separable from tilt).
    pub acc_bias: Option<Vector3<f64>>,
    /// Its standard deviation [m/s²] (prior-dominated), `None` without a prior.
    pub acc_bias_std: Option<Vector3<f64>>,
    /// Why b_a is or is not reported, for humans.
    pub acc_bias_note: String,
    /// Names of the unobservable quantities (always `"yaw"`, plus `"acc_bias"` without prior).
    pub unobservable: Vec<&'static str>,
    /// Number of samples N.
    pub samples: usize,
    /// Averaging time T = N·Δt \[s\].
    pub duration_s: f64,
    /// Measured gyro white-noise density per axis, `std(ω)·√Δt` [rad/s/√Hz].
    pub measured_gyro_density: Vector3<f64>,
    /// Measured accelerometer density per axis, `std(a)·√Δt` [m/s²/√Hz].
    pub measured_acc_density: Vector3<f64>,
    /// χ² = ‖r‖² of the whitened residuals at the estimate (dof = residuals − rank).
    pub chi2: f64,
    /// Degrees of freedom of χ² (1 without prior: |f̄| vs |g|).
    pub dof: usize,
    /// Gauss-Newton iterations.
    pub iterations: u64,
    /// Why the solver stopped.
    pub stop: StopReason,
}

impl StaticCalibration {
    /// The goodness of fit of the per-sample problem (module docs): its χ² is that of the
    /// means (`chi2`, `dof`) plus the samples' scatter about them, `(N − 1)·Σ var·Δt/σ²` over
    /// the six axes with `6(N − 1)` more degrees of freedom, so that it tests the white-noise
    /// densities of `noise` against the samples ([`crate::fit`]). The scatter dominates: the
    /// fit says whether the stated densities describe this sensor (the measured ones are
    /// [`StaticCalibration::measured_gyro_density`] and `measured_acc_density`).
    pub fn fit(&self, noise: &ImuNoise) -> crate::Fit {
        let n1 = self.samples.saturating_sub(1) as f64;
        let scatter = |d: &Vector3<f64>, s: f64| n1 * d.norm_squared() / (s * s);
        let chi2 = self.chi2
            + scatter(&self.measured_gyro_density, noise.gyro_noise_density)
            + scatter(&self.measured_acc_density, noise.acc_noise_density);
        crate::Fit::new(chi2, self.dof + 6 * self.samples.saturating_sub(1))
    }
}

struct StaticProblem {
    w_mean: Vector3<f64>,
    f_mean: Vector3<f64>,
    s_g: Vector3<f64>,
    s_a: Vector3<f64>,
    g: Vector3<f64>,
    prior: Option<AccBiasPrior>,
}

impl LeastSquares for StaticProblem {
    /// (params = `[b_g]` or `[b_g, b_a]`, R_wb).
    type State = (DVector<f64>, SO3);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        let (p, r) = x;
        let has_ba = self.prior.is_some();
        let np = p.len();
        let n = np + 3;
        let m = if has_ba { 9 } else { 6 };
        let bg = Vector3::new(p[0], p[1], p[2]);
        let ba = if has_ba {
            Vector3::new(p[3], p[4], p[5])
        } else {
            Vector3::zeros()
        };
        let up = r.inverse().act(&(-self.g));
        let mut res = DVector::zeros(m);
        let mut j = DMatrix::zeros(m, n);
        let hu: Matrix3<f64> = hat(&up);
        for i in 0..3 {
            res[i] = (self.w_mean[i] - bg[i]) / self.s_g[i];
            j[(i, i)] = -1.0 / self.s_g[i];
            res[3 + i] = (self.f_mean[i] - up[i] - ba[i]) / self.s_a[i];
            for c in 0..3 {
                j[(3 + i, np + c)] = -hu[(i, c)] / self.s_a[i];
            }
            if let Some(pr) = &self.prior {
                j[(3 + i, 3 + i)] = -1.0 / self.s_a[i];
                res[6 + i] = (ba[i] - pr.mean[i]) / pr.std[i];
                j[(6 + i, 3 + i)] = 1.0 / pr.std[i];
            }
        }
        (res, j)
    }
}

/// Calibrates a static recording at one attitude (module docs for the model).
///
/// `samples`: at least 10, finite, strictly increasing timestamps; `noise`: Kalibr densities
/// (white densities > 0). Errors are typed ([`BiasError`]); no panics on bad input.
///
/// ```
/// use nalgebra::Vector3;
/// use preint::{ImuBias, ImuNoise};
/// use preint_calib::bias::{StaticOptions, calibrate_static};
/// use preint_sim::{SimConfig, StaticScene, simulate};
///
/// // 20 s at rest, 200 Hz, EuRoC noise, a constant gyro bias.
/// let noise = ImuNoise::euroc();
/// let bias = Vector3::new(0.01, -0.02, 0.005);
/// let cfg = SimConfig {
///     noise,
///     initial_bias: ImuBias::new(bias, Vector3::zeros()),
///     bias_random_walk: false,
///     ..SimConfig::default()
/// };
/// let rec = simulate(&StaticScene::default(), 200.0, 20.0, &cfg, 1).unwrap();
/// let cal = calibrate_static(&rec.samples, &noise, &StaticOptions::default()).unwrap();
/// for k in 0..3 {
///     // σ ≈ σ_g/√T ≈ 3.8e-5 rad/s.
///     assert!((cal.gyro_bias[k] - bias[k]).abs() < 4.0 * cal.gyro_bias_std[k]);
/// }
/// assert!(cal.acc_bias.is_none()); // not separable from tilt at one attitude
/// ```
pub fn calibrate_static(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &StaticOptions,
) -> Result<StaticCalibration, BiasError> {
    check_samples(samples, 10)?;
    check_noise(noise)?;
    let gnorm = check_gravity("gravity", &opts.gravity)?;
    if let Some(p) = &opts.acc_bias_prior {
        p.validate()?;
    }
    let st = SegmentStats::of(samples);
    let (s_g, s_a) = mean_std_devs(noise, st.averaging_time(), opts.include_random_walk);
    let up_w = -opts.gravity / gnorm;
    let x0 = initial_state(&st, opts, &up_w)?;
    let problem = StaticProblem {
        w_mean: st.gyro_mean,
        f_mean: st.acc_mean,
        s_g: Vector3::repeat(s_g),
        s_a: Vector3::repeat(s_a),
        g: opts.gravity,
        prior: opts.acc_bias_prior,
    };
    let sol = solve(problem, x0, GaussNewton::default(), opts.max_iters)?;
    Ok(report(&st, &up_w, sol))
}

/// Standard deviations `(s_g, s_a)` of the gyro and accelerometer means over the averaging
/// time `t` \[s\]: `s² = σ²/T + σ_b²·T/12` (module docs), the random-walk term only if
/// `include_random_walk`.
fn mean_std_devs(noise: &ImuNoise, t: f64, include_random_walk: bool) -> (f64, f64) {
    let rw = if include_random_walk { t / 12.0 } else { 0.0 };
    let s_g = (noise.gyro_noise_density.powi(2) / t + noise.gyro_random_walk.powi(2) * rw).sqrt();
    let s_a = (noise.acc_noise_density.powi(2) / t + noise.acc_random_walk.powi(2) * rw).sqrt();
    (s_g, s_a)
}

/// The solver's start `([b_g] or [b_g, b_a], R_wb)`: the closed-form solution (`b_g = ω̄`,
/// attitude from `f̄ − μ_p`) or, without [`StaticOptions::closed_form_start`], `b_g = 0`,
/// `R_wb = I`; `b_a` starts at the prior mean. Error when `f̄ − μ_p` is zero (no gravity
/// direction).
fn initial_state(
    st: &SegmentStats,
    opts: &StaticOptions,
    up_w: &Vector3<f64>,
) -> Result<(DVector<f64>, SO3), BiasError> {
    let prior = opts.acc_bias_prior;
    let ba0 = prior.map_or(Vector3::zeros(), |p| p.mean);
    let f_dir = st.acc_mean - ba0;
    if f_dir.norm().is_nan() || f_dir.norm() <= 0.0 {
        return Err(BiasError::InvalidParameter {
            name: "samples",
            reason: "mean specific force (minus the prior bias) is zero: no gravity direction"
                .into(),
        });
    }
    let (r0, w0) = if opts.closed_form_start {
        (attitude_from_up(&f_dir, up_w), st.gyro_mean)
    } else {
        (SO3::identity(), Vector3::zeros())
    };
    let p0 = match prior {
        Some(p) => DVector::from_column_slice(&[w0.x, w0.y, w0.z, p.mean.x, p.mean.y, p.mean.z]),
        None => DVector::from_column_slice(w0.as_slice()),
    };
    Ok((p0, r0))
}

/// The estimates and their standard deviations read from the solution (module docs,
/// "Outputs").
fn report(
    st: &SegmentStats,
    up_w: &Vector3<f64>,
    sol: Solution<(DVector<f64>, SO3)>,
) -> StaticCalibration {
    let (p, r) = &sol.estimate;
    let np = p.len();
    let has_prior = np == 6;
    let (roll, pitch, roll_pitch_cov, up_b) =
        roll_pitch_with_cov(r, up_w, &sol.marginal_covariance::<3>(np));
    let (acc_bias, acc_bias_std, note, unobservable) = if has_prior {
        (
            Some(Vector3::new(p[3], p[4], p[5])),
            Some(sol.marginal_std::<3>(3)),
            "estimated with the given prior; static data at one attitude cannot separate the \
             accelerometer bias from tilt, so its horizontal components are the prior's"
                .to_string(),
            vec!["yaw"],
        )
    } else {
        (
            None,
            None,
            "unobservable: at one attitude the accelerometer bias is not separable from tilt \
             (f̄ = R_wbᵀ(−g) + b_a); roll/pitch are those of the measured specific force. Give a \
             prior or record several attitudes (multi-pose calibration)."
                .to_string(),
            vec!["yaw", "acc_bias"],
        )
    };
    let sqrt_dt = st.dt.sqrt();
    StaticCalibration {
        gyro_bias: Vector3::new(p[0], p[1], p[2]),
        gyro_bias_std: sol.marginal_std::<3>(0),
        roll,
        pitch,
        roll_pitch_cov,
        roll_std: roll_pitch_cov[(0, 0)].max(0.0).sqrt(),
        pitch_std: roll_pitch_cov[(1, 1)].max(0.0).sqrt(),
        up_body: up_b,
        attitude: attitude_from_roll_pitch(roll, pitch),
        acc_bias,
        acc_bias_std,
        acc_bias_note: note,
        unobservable,
        samples: st.count,
        duration_s: st.averaging_time(),
        measured_gyro_density: st.gyro_var.map(|v| v.max(0.0).sqrt() * sqrt_dt),
        measured_acc_density: st.acc_var.map(|v| v.max(0.0).sqrt() * sqrt_dt),
        chi2: 2.0 * sol.cost,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations: sol.iterations,
        stop: sol.stop,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint::ImuBias;
    use preint_sim::{SimConfig, StaticScene, simulate};

    /// The static problem's analytic Jacobian against Ridders, with and without the prior.
    #[test]
    fn analytic_jacobian_matches_ridders() {
        for prior in [
            None,
            Some(AccBiasPrior {
                mean: Vector3::new(0.1, -0.2, 0.05),
                std: Vector3::new(0.02, 0.03, 0.04),
            }),
        ] {
            let problem = StaticProblem {
                w_mean: Vector3::new(0.01, -0.02, 0.003),
                f_mean: Vector3::new(1.2, -2.1, 9.4),
                s_g: Vector3::new(1e-4, 2e-4, 1.5e-4),
                s_a: Vector3::new(1e-3, 2e-3, 3e-3),
                g: Vector3::new(0.0, 0.0, -9.81),
                prior,
            };
            let np = if prior.is_some() { 6 } else { 3 };
            let p = DVector::from_fn(np, |i, _| 0.01 * (i as f64 + 1.0).sin());
            let x = (p, SO3::exp(&Vector3::new(0.3, -0.2, 1.1)));
            let (_, j) = problem.residual_jacobian(&x);
            let blocks = [j.columns(0, np).into_owned(), j.columns(np, 3).into_owned()];
            let rep = check_jacobian(
                |x: &(DVector<f64>, SO3)| problem.residual_jacobian(x).0,
                &x,
                &blocks,
                &CheckOptions::default(),
            )
            .unwrap();
            println!(
                "static problem (prior {}): {:.2e}",
                prior.is_some(),
                rep.worst_rel_error
            );
        }
    }

    /// From `b_g = 0`, `R = I` the solver iterates (what the calibration bench times) and
    /// reaches the closed-form solution.
    #[test]
    fn zero_start_iterates_to_the_closed_form_solution() {
        let noise = ImuNoise::euroc();
        let cfg = SimConfig {
            noise,
            initial_bias: ImuBias::new(Vector3::new(0.01, -0.02, 0.005), Vector3::zeros()),
            ..SimConfig::default()
        };
        let out = simulate(&StaticScene::default(), 200.0, 10.0, &cfg, 1).unwrap();
        let a = calibrate_static(&out.samples, &noise, &StaticOptions::default()).unwrap();
        let zero = StaticOptions {
            closed_form_start: false,
            ..StaticOptions::default()
        };
        let b = calibrate_static(&out.samples, &noise, &zero).unwrap();
        assert!(a.iterations <= 1, "{}", a.iterations);
        assert!(b.iterations >= 3, "{}", b.iterations);
        assert!(b.stop.converged(), "{:?}", b.stop);
        assert!((a.gyro_bias - b.gyro_bias).amax() < 1e-12);
        // The LM stops at a relative cost change of 1e-10; the angles then agree to ≈ 1e-10 rad,
        // 1e-6 of their σ (≈ 6e-5 rad).
        assert!((a.roll - b.roll).abs() < 1e-8 && (a.pitch - b.pitch).abs() < 1e-8);
    }
}
