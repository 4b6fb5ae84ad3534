//! Multi-position static calibration (Tedaldi, Pretto, Menegatti, ICRA 2014; imu_tk), with the
//! still intervals linked by gyro preintegration and the model chosen by BIC.
//!
//! # Data
//! The IMU is held still in K ≥ 3 attitudes and rotated between them. Still intervals are
//! detected automatically ([`super::still`]). For interval k (averaging time `T_k = N_k·Δt`)
//! the means `ω̄_k`, `f̄_k` are kept; between consecutive intervals the gyro samples from the
//! last sample of interval k to the first of interval k+1 are kept for re-integration.
//!
//! # Model (constant biases over the recording)
//! ```text
//! gyro     ω_m = S_g ω_b + b_g + n_g              S_g = I + diag(s_g)
//! accel    a_m = S_a R_kᵀ(−g) + b_a + n_a (rest)  S_a = I + diag(s_a)
//! ```
//! Unknowns: `b_g`, `b_a` [rad/s, m/s²], optionally `s_a`, `s_g` (dimensionless), and the
//! attitude `R_k` (SO3, right perturbation) of every still interval. Residuals, whitened:
//!
//! ```text
//! r_ω,k = (ω̄_k − b_g) / s_ω,k                      s_ω,k = σ_g/√T_k
//! r_f,k = (f̄_k − S_a R_kᵀ(−g) − b_a) / s_f,k       s_f,k = σ_a/√T_k
//! r_R,k = U_k · Log(ΔR_k(b_g, s_g)ᵀ R_kᵀ R_k+1)     U_kᵀU_k = Σ_φ,k⁻¹
//! ```
//!
//! `ΔR_k(b_g, s_g)` is the midpoint-rule rotation preintegration (the `preint` midpoint scheme,
//! ΔR ← ΔR·Exp(½(u_i + u_i+1)Δt_i)) of the corrected rates `u = S_g⁻¹(ω_m − b_g)` over the
//! link window, re-integrated exactly at every evaluation together with its right Jacobians
//! `J_b = ∂ΔR/∂b_g` (for `s_g = 0` this is preint's `d_r_d_bg`) and `J_s = ∂ΔR/∂s_g`:
//! `J ← Exp(φ_i)ᵀ J + Jr(φ_i) ∂φ_i/∂θ` ([`rotation_preintegration`]). `Σ_φ,k` is the rotation
//! block of `preint`'s covariance of that window ([`preint::preintegrate`], midpoint, at the
//! initial gyro bias). With `E = Exp(r_R)`: `∂r_R/∂δφ_k+1 = Jr⁻¹(r_R)`,
//! `∂r_R/∂δφ_k = −Jr⁻¹(r_R) R_k+1ᵀ R_k`, `∂r_R/∂θ = −Jr⁻¹(r_R) Eᵀ J_θ` (then whitened by `U_k`).
//!
//! Gauge: a common rotation of all attitudes about the world gravity axis changes no residual
//! (one null direction); the solver's rank analysis reports it and the estimates that do not
//! depend on it (biases, scales, roll/pitch) get their marginal covariance from the
//! pseudo-inverse. The initial attitudes chain from the first interval at zero yaw.
//!
//! # Model selection
//! Candidates [`MultiPoseModel::BiasOnly`], [`MultiPoseModel::AccScale`],
//! [`MultiPoseModel::Scale`] (accelerometer and gyro diagonal scale factors). Each is solved;
//! `BIC = χ² + k·ln m` (χ² = ‖r‖² of the whitened residuals = −2 log-likelihood up to a constant
//! since the noise is known, k = number of observable parameters = rank of JᵀJ, m = number of
//! scalar residuals). A model whose parameters are not all observable (rank < dim − 1) is not
//! eligible. The lowest BIC wins; every BIC is reported ([`ModelFit`]), and the reason names the
//! runner-up and the difference (ΔBIC > 10: "very strong" evidence, Kass & Raftery 1995).
//!
//! Limits: biases are assumed constant over the whole protocol (keep it short compared with
//! the bias random walk's time scale); misalignment is not modelled.

use super::still::{StillInterval, StillOptions, detect_still_intervals};
use super::{
    BiasError, SegmentStats, attitude_from_up, check_gravity, check_noise, check_samples,
    roll_pitch_of_up,
};
use crate::gauss_newton::{GaussNewton, LeastSquares, StopReason, solve};
use lie::{SO3, hat, jr_inv};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use preint::factor::sqrt_information;
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};

/// Candidate calibration models, from the simplest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MultiPoseModel {
    /// `b_g`, `b_a` and the attitudes.
    BiasOnly,
    /// Plus accelerometer diagonal scale factors `s_a`.
    AccScale,
    /// Plus accelerometer and gyro diagonal scale factors `s_a`, `s_g`.
    Scale,
}

impl MultiPoseModel {
    fn acc_scale(self) -> bool {
        !matches!(self, MultiPoseModel::BiasOnly)
    }
    fn gyro_scale(self) -> bool {
        matches!(self, MultiPoseModel::Scale)
    }
    /// Number of parameters besides the attitudes.
    pub fn param_count(self) -> usize {
        6 + if self.acc_scale() { 3 } else { 0 } + if self.gyro_scale() { 3 } else { 0 }
    }
    /// Short name (`"bias-only"`, `"acc-scale"`, `"scale"`).
    pub fn name(self) -> &'static str {
        match self {
            MultiPoseModel::BiasOnly => "bias-only",
            MultiPoseModel::AccScale => "acc-scale",
            MultiPoseModel::Scale => "scale",
        }
    }
}

/// Options of [`calibrate_multi_pose`].
#[derive(Clone, Debug, PartialEq)]
pub struct MultiPoseOptions {
    /// World gravity [m/s²]; default `(0, 0, −9.81)`.
    pub gravity: Vector3<f64>,
    /// Still detector options; `None` (default): [`StillOptions::from_noise`] at the measured
    /// sample rate.
    pub still: Option<StillOptions>,
    /// Candidate models (default: all three).
    pub models: Vec<MultiPoseModel>,
    /// Minimum number of still intervals (default 3; scale models need more attitudes to be
    /// observable, which the rank check enforces).
    pub min_intervals: usize,
    /// Gauss-Newton iteration limit per model (default 50).
    pub max_iters: u64,
}

impl Default for MultiPoseOptions {
    fn default() -> Self {
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            still: None,
            models: vec![
                MultiPoseModel::BiasOnly,
                MultiPoseModel::AccScale,
                MultiPoseModel::Scale,
            ],
            min_intervals: 3,
            max_iters: 50,
        }
    }
}

/// Fit statistics of one candidate model.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelFit {
    /// The model.
    pub model: MultiPoseModel,
    /// χ² = ‖r‖² of the whitened residuals at the estimate.
    pub chi2: f64,
    /// Number of observable parameters k (rank of JᵀJ).
    pub params: usize,
    /// Number of scalar residuals m.
    pub residuals: usize,
    /// `χ² + k·ln m`.
    pub bic: f64,
    /// All parameters observable up to the yaw gauge (rank = dim − 1).
    pub identifiable: bool,
    /// The solver converged.
    pub converged: bool,
}

/// Result of [`calibrate_multi_pose`] (the estimates are those of the chosen model).
#[derive(Clone, Debug)]
pub struct MultiPoseCalibration {
    /// The model chosen by BIC.
    pub model: MultiPoseModel,
    /// All candidates' statistics, in the order tried.
    pub fits: Vec<ModelFit>,
    /// Why the model won (BIC values and differences), for humans.
    pub reason: String,
    /// Gyro bias b_g [rad/s].
    pub gyro_bias: Vector3<f64>,
    /// Its standard deviation [rad/s].
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias b_a [m/s²].
    pub acc_bias: Vector3<f64>,
    /// Its standard deviation [m/s²].
    pub acc_bias_std: Vector3<f64>,
    /// Accelerometer scale errors `s_a` (`S_a = I + diag(s_a)`), if in the model.
    pub acc_scale: Option<Vector3<f64>>,
    /// Their standard deviations.
    pub acc_scale_std: Option<Vector3<f64>>,
    /// Gyro scale errors `s_g` (`S_g = I + diag(s_g)`), if in the model.
    pub gyro_scale: Option<Vector3<f64>>,
    /// Their standard deviations.
    pub gyro_scale_std: Option<Vector3<f64>>,
    /// The still intervals used.
    pub intervals: Vec<StillInterval>,
    /// Attitude R_wb of each interval (yaw gauge: the solver's, starting from zero yaw).
    pub attitudes: Vec<SO3>,
    /// Roll, pitch [rad] of each interval and their standard deviations [rad]:
    /// `(roll, pitch, roll_std, pitch_std)`.
    pub roll_pitch: Vec<(f64, f64, f64, f64)>,
    /// χ² of the chosen model.
    pub chi2: f64,
    /// Its degrees of freedom (residuals − rank).
    pub dof: usize,
    /// Gauss-Newton iterations of the chosen model.
    pub iterations: u64,
    /// Why its solver stopped.
    pub stop: StopReason,
}

/// Midpoint rotation preintegration of `u_i = (ω_i − b_g) ⊘ (1 + s_g)` over `samples`
/// (module docs) with its right Jacobians: returns `(ΔR, ∂ΔR/∂b_g, ∂ΔR/∂s_g)` [-, s, rad].
/// `samples` must have increasing timestamps (not checked here).
pub fn rotation_preintegration(
    samples: &[ImuSample],
    b_g: &Vector3<f64>,
    s_g: &Vector3<f64>,
) -> (SO3, Matrix3<f64>, Matrix3<f64>) {
    let inv = Vector3::new(
        1.0 / (1.0 + s_g.x),
        1.0 / (1.0 + s_g.y),
        1.0 / (1.0 + s_g.z),
    );
    let u = |s: &ImuSample| (s.gyro - b_g).component_mul(&inv);
    let mut dr = SO3::identity();
    let mut jb = Matrix3::zeros();
    let mut js = Matrix3::zeros();
    for w in samples.windows(2) {
        let dt = (w[1].t_ns - w[0].t_ns) as f64 * 1e-9;
        let phi = (u(&w[0]) + u(&w[1])) * (0.5 * dt);
        let (e, jrp) = SO3::exp_jr(&phi);
        let et = e.inverse();
        let et_m = *et.matrix();
        jb = et_m * jb - jrp * Matrix3::from_diagonal(&inv) * dt;
        js = et_m * js - jrp * Matrix3::from_diagonal(&phi.component_mul(&inv));
        dr = dr.compose(&e);
    }
    (dr, jb, js)
}

struct Interval {
    w_mean: Vector3<f64>,
    f_mean: Vector3<f64>,
    s_w: f64,
    s_f: f64,
}

struct Link {
    samples: Vec<ImuSample>,
    sqrt_info: Matrix3<f64>,
}

struct Problem<'a> {
    intervals: &'a [Interval],
    links: &'a [Link],
    g: Vector3<f64>,
    model: MultiPoseModel,
}

impl Problem<'_> {
    fn np(&self) -> usize {
        self.model.param_count()
    }
    fn eval(&self, x: &(DVector<f64>, Vec<SO3>), want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
        let (p, rs) = x;
        let np = self.np();
        let k = self.intervals.len();
        let n = np + 3 * k;
        let m = 6 * k + 3 * self.links.len();
        let mut r = DVector::zeros(m);
        let mut j = if want_j {
            DMatrix::zeros(m, n)
        } else {
            DMatrix::zeros(0, 0)
        };
        let v3 = |o: usize| Vector3::new(p[o], p[o + 1], p[o + 2]);
        let bg = v3(0);
        let ba = v3(3);
        let sa = if self.model.acc_scale() {
            v3(6)
        } else {
            Vector3::zeros()
        };
        let sg_off = if self.model.acc_scale() { 9 } else { 6 };
        let sg = if self.model.gyro_scale() {
            v3(sg_off)
        } else {
            Vector3::zeros()
        };
        for (i, iv) in self.intervals.iter().enumerate() {
            let u = rs[i].inverse().act(&(-self.g));
            let pred = u + sa.component_mul(&u) + ba;
            let row = 6 * i;
            for c in 0..3 {
                r[row + c] = (iv.w_mean[c] - bg[c]) / iv.s_w;
                r[row + 3 + c] = (iv.f_mean[c] - pred[c]) / iv.s_f;
            }
            if want_j {
                let hu = hat(&u);
                for c in 0..3 {
                    j[(row + c, c)] = -1.0 / iv.s_w;
                    j[(row + 3 + c, 3 + c)] = -1.0 / iv.s_f;
                    if self.model.acc_scale() {
                        j[(row + 3 + c, 6 + c)] = -u[c] / iv.s_f;
                    }
                    for d in 0..3 {
                        j[(row + 3 + c, np + 3 * i + d)] = -(1.0 + sa[c]) * hu[(c, d)] / iv.s_f;
                    }
                }
            }
        }
        for (l, link) in self.links.iter().enumerate() {
            let (dr, jb, js) = rotation_preintegration(&link.samples, &bg, &sg);
            let e = dr.inverse().compose(&rs[l].inverse().compose(&rs[l + 1]));
            let res = e.log();
            let row = 6 * k + 3 * l;
            let ur = link.sqrt_info * res;
            r.fixed_rows_mut::<3>(row).copy_from(&ur);
            if want_j {
                let jri = jr_inv(&res);
                let u = link.sqrt_info;
                let d_next = u * jri;
                let d_prev = -u * jri * (rs[l + 1].inverse().compose(&rs[l])).matrix();
                let et = e.matrix().transpose();
                let d_bg = -u * jri * et * jb;
                j.view_mut((row, np + 3 * (l + 1)), (3, 3))
                    .copy_from(&d_next);
                j.view_mut((row, np + 3 * l), (3, 3)).copy_from(&d_prev);
                j.view_mut((row, 0), (3, 3)).copy_from(&d_bg);
                if self.model.gyro_scale() {
                    let d_sg = -u * jri * et * js;
                    j.view_mut((row, sg_off), (3, 3)).copy_from(&d_sg);
                }
            }
        }
        (r, j)
    }
}

impl LeastSquares for Problem<'_> {
    type State = (DVector<f64>, Vec<SO3>);
    fn residual_jacobian(&self, x: &Self::State) -> (DVector<f64>, DMatrix<f64>) {
        self.eval(x, true)
    }
    fn residual(&self, x: &Self::State) -> DVector<f64> {
        self.eval(x, false).0
    }
}

/// Calibrates a multi-position static recording (module docs): detects still intervals, builds
/// the problem, solves every candidate model and keeps the one with the lowest BIC.
///
/// Errors: invalid samples/noise/options, fewer than `min_intervals` still intervals
/// ([`BiasError::TooFew`]), preintegration or solver failures; no panics on bad input.
pub fn calibrate_multi_pose(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &MultiPoseOptions,
) -> Result<MultiPoseCalibration, BiasError> {
    check_samples(samples, 3)?;
    check_noise(noise)?;
    let gnorm = check_gravity(&opts.gravity)?;
    if opts.models.is_empty() {
        return Err(BiasError::InvalidParameter {
            name: "models",
            reason: "no candidate model".into(),
        });
    }
    let n = samples.len();
    let dt_mean = (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (n - 1) as f64;
    let still_opts = opts
        .still
        .unwrap_or_else(|| StillOptions::from_noise(noise, 1.0 / dt_mean));
    let ivs = detect_still_intervals(samples, &still_opts)?;
    let needed = opts.min_intervals.max(2);
    if ivs.len() < needed {
        return Err(BiasError::TooFew {
            what: "still intervals",
            found: ivs.len(),
            needed,
        });
    }
    let intervals: Vec<Interval> = ivs
        .iter()
        .map(|iv| {
            let st = SegmentStats::of(&samples[iv.start..iv.end]);
            let t = st.averaging_time();
            Interval {
                w_mean: st.gyro_mean,
                f_mean: st.acc_mean,
                s_w: noise.gyro_noise_density / t.sqrt(),
                s_f: noise.acc_noise_density / t.sqrt(),
            }
        })
        .collect();
    let tw: f64 = ivs.iter().map(|iv| iv.len() as f64).sum();
    let bg0 = ivs
        .iter()
        .zip(&intervals)
        .map(|(iv, d)| d.w_mean * iv.len() as f64)
        .sum::<Vector3<f64>>()
        / tw;
    let mut params = PreintParams::from_noise(noise).with_scheme(Scheme::Midpoint);
    params.max_gap_ns = i64::MAX;
    let bias0 = ImuBias::new(bg0, Vector3::zeros());
    let mut links = Vec::with_capacity(ivs.len() - 1);
    for w in ivs.windows(2) {
        let seg = &samples[w[0].end - 1..=w[1].start];
        let pim = preintegrate(&params, &bias0, seg, seg[0].t_ns, seg[seg.len() - 1].t_ns)?;
        let cov: Matrix3<f64> = pim.cov.fixed_view::<3, 3>(0, 0).into_owned();
        let sqrt_info = sqrt_information(&cov).map_err(|e| BiasError::InvalidParameter {
            name: "noise",
            reason: format!("rotation covariance of a link window: {e}"),
        })?;
        links.push(Link {
            samples: seg.to_vec(),
            sqrt_info,
        });
    }
    // Initial attitudes: first from its specific force at zero yaw, then chained by ΔR(b_g0).
    let up_w = -opts.gravity / gnorm;
    let mut r0 = Vec::with_capacity(ivs.len());
    r0.push(attitude_from_up(&intervals[0].f_mean, &up_w));
    for (l, link) in links.iter().enumerate() {
        let (dr, _, _) = rotation_preintegration(&link.samples, &bg0, &Vector3::zeros());
        let next = r0[l].compose(&dr);
        r0.push(next);
    }

    let mut results = Vec::new();
    let mut fits = Vec::new();
    for &model in &opts.models {
        let np = model.param_count();
        let mut p0 = DVector::zeros(np);
        p0.fixed_rows_mut::<3>(0).copy_from(&bg0);
        let problem = Problem {
            intervals: &intervals,
            links: &links,
            g: opts.gravity,
            model,
        };
        let sol = solve(
            problem,
            (p0, r0.clone()),
            GaussNewton::default(),
            opts.max_iters,
        )?;
        let dim = np + 3 * intervals.len();
        let m = sol.residual_count;
        let chi2 = 2.0 * sol.cost;
        let fit = ModelFit {
            model,
            chi2,
            params: sol.rank,
            residuals: m,
            bic: chi2 + sol.rank as f64 * (m as f64).ln(),
            identifiable: sol.rank + 1 >= dim,
            converged: sol.stop.converged(),
        };
        fits.push(fit);
        results.push(sol);
    }
    let eligible: Vec<usize> = (0..fits.len())
        .filter(|&i| fits[i].identifiable && fits[i].converged)
        .collect();
    let pool: Vec<usize> = if eligible.is_empty() {
        (0..fits.len()).collect()
    } else {
        eligible
    };
    let mut order = pool.clone();
    order.sort_by(|&a, &b| fits[a].bic.total_cmp(&fits[b].bic));
    let best = order[0];
    let listing = fits
        .iter()
        .map(|f| {
            format!(
                "{}: BIC {:.1} (χ² {:.1}, k {}, m {}{}{})",
                f.model.name(),
                f.bic,
                f.chi2,
                f.params,
                f.residuals,
                if f.identifiable {
                    ""
                } else {
                    ", not identifiable"
                },
                if f.converged { "" } else { ", not converged" }
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let reason = match order.get(1) {
        Some(&second) => format!(
            "{} has the lowest BIC, {:.1} below {} ({}). {}",
            fits[best].model.name(),
            fits[second].bic - fits[best].bic,
            fits[second].model.name(),
            if fits[second].bic - fits[best].bic > 10.0 {
                "very strong evidence"
            } else {
                "weak evidence: the simpler model is usually the safer choice"
            },
            listing
        ),
        None => format!("only eligible model. {listing}"),
    };
    if eligible_is_empty(&fits) {
        return Err(BiasError::InvalidParameter {
            name: "samples",
            reason: format!(
                "no candidate model is identifiable from these attitudes (need more, diverse \
                 still attitudes). {listing}"
            ),
        });
    }
    let model = fits[best].model;
    let sol = results.swap_remove(best);
    let (p, rs) = &sol.estimate;
    let np = model.param_count();
    let cov = &sol.covariance;
    let v3 = |o: usize| Vector3::new(p[o], p[o + 1], p[o + 2]);
    let s3 = |o: usize| Vector3::from_fn(|i, _| cov[(o + i, o + i)].max(0.0).sqrt());
    let (acc_scale, acc_scale_std) = if model.acc_scale() {
        (Some(v3(6)), Some(s3(6)))
    } else {
        (None, None)
    };
    let (gyro_scale, gyro_scale_std) = if model.gyro_scale() {
        (Some(v3(9)), Some(s3(9)))
    } else {
        (None, None)
    };
    let roll_pitch = rs
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let u = r.inverse().act(&up_w);
            let (roll, pitch, d) = roll_pitch_of_up(&u);
            let jrp = d * hat(&u);
            let c: Matrix3<f64> = cov.fixed_view::<3, 3>(np + 3 * i, np + 3 * i).into_owned();
            let crp = jrp * c * jrp.transpose();
            (
                roll,
                pitch,
                crp[(0, 0)].max(0.0).sqrt(),
                crp[(1, 1)].max(0.0).sqrt(),
            )
        })
        .collect();
    Ok(MultiPoseCalibration {
        model,
        reason,
        gyro_bias: v3(0),
        gyro_bias_std: s3(0),
        acc_bias: v3(3),
        acc_bias_std: s3(3),
        acc_scale,
        acc_scale_std,
        gyro_scale,
        gyro_scale_std,
        intervals: ivs,
        attitudes: rs.clone(),
        roll_pitch,
        chi2: fits[best].chi2,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations: sol.iterations,
        stop: sol.stop.clone(),
        fits,
    })
}

fn eligible_is_empty(fits: &[ModelFit]) -> bool {
    !fits.iter().any(|f| f.identifiable)
}
