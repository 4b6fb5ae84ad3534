//! Multi-position static calibration (Tedaldi, Pretto, Menegatti, ICRA 2014; imu_tk), with the
//! still intervals linked by gyro preintegration and the model chosen by BIC.
//!
//! # Data
//! The IMU is held still in K ≥ 3 attitudes and rotated between them. Still intervals are
//! detected automatically ([`super::still`]). For interval k (averaging time `T_k = N_k·Δt`)
//! the means `ω̄_k`, `f̄_k` are kept; between consecutive intervals the gyro samples from the
//! last sample of interval k to the first of interval k+1 are kept for re-integration.
//!
//! # Sensor model (constant biases over the recording)
//! ```text
//! gyro     ω_m = S_g ω_b + b_g + n_g            S_g = diag(1 + s_g)·(I + M_g)
//! accel    a_m = S_a R_kᵀ(−g) + b_a + n_a       S_a = diag(1 + s_a)·(I + N_a)   (at rest)
//! ```
//!
//! - `s_a`, `s_g`: scale-factor errors (dimensionless, e.g. 0.01 = 1 %).
//! - `N_a`: accelerometer misalignment, **strictly lower triangular** with 3 small angles \[rad\]
//!   `m_a = (N₁₀, N₂₀, N₂₁)` — the form of `sim::scale_misalignment` and, up to the choice of
//!   triangle, imu_tk's: a general 3×3 `S_a` is triangular × rotation, and the rotation is
//!   absorbed by the free attitudes `R_k`, so the triangle fixes that gauge and defines the
//!   body frame (x along the x accelerometer, y in the plane of the x and y accelerometers).
//! - `M_g`: gyro misalignment w.r.t. that body frame, all 6 off-diagonal entries \[rad\],
//!   order `m_g = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)` (imu_tk's 6 gyro misalignments).
//!
//! Unknowns: `b_g`, `b_a` [rad/s, m/s²], the terms of the chosen model and the attitude `R_k`
//! (SO3, right perturbation) of every still interval. Parameter vector order:
//! `[b_g, b_a, s_a?, m_a?, s_g?, m_g?]` (present terms only, in this order). Residuals,
//! whitened:
//!
//! ```text
//! r_ω,k = (ω̄_k − b_g) / s_ω,k                      s_ω,k = σ_g/√T_k
//! r_f,k = (f̄_k − S_a R_kᵀ(−g) − b_a) / s_f,k       s_f,k = σ_a/√T_k
//! r_R,k = U_k · Log(ΔR_k(b_g, S_g)ᵀ R_kᵀ R_k+1)     U_kᵀU_k = Σ_φ,k⁻¹
//! ```
//!
//! (The still residual `r_ω` uses `ω_b = 0`, so `S_g` does not enter it.) `ΔR_k(b_g, S_g)` is
//! the midpoint-rule rotation preintegration (the `preint` midpoint scheme,
//! ΔR ← ΔR·Exp(½(u_i + u_i+1)Δt_i)) of the corrected rates `u = S_g⁻¹(ω_m − b_g)` over the link
//! window, re-integrated exactly at every evaluation together with its right Jacobians
//! `J_b = ∂ΔR/∂b_g` (for `S_g = I` this is preint's `d_r_d_bg`) and `J_θ = ∂ΔR/∂θ` for each
//! gyro model parameter θ: `J ← Exp(φ_i)ᵀ J + Jr(φ_i) ∂φ_i/∂θ` with
//! `∂φ_i/∂θ = −S_g⁻¹ (∂S_g/∂θ) φ_i` and `∂φ_i/∂b_g = −S_g⁻¹Δt_i`
//! ([`rotation_preintegration_general`]). `Σ_φ,k` is the rotation block of `preint`'s
//! covariance of that window ([`preint::preintegrate`], midpoint, at the initial gyro bias).
//! With `E = Exp(r_R)`: `∂r_R/∂δφ_k+1 = Jr⁻¹(r_R)`, `∂r_R/∂δφ_k = −Jr⁻¹(r_R) R_k+1ᵀ R_k`,
//! `∂r_R/∂θ = −Jr⁻¹(r_R) Eᵀ J_θ` (then whitened by `U_k`); `∂r_f/∂δφ_k = −S_a [u_k]× / s_f`
//! with `u_k = R_kᵀ(−g)`. All are checked against Ridders' numeric Jacobian in this module's tests.
//!
//! Gauge: a common rotation of all attitudes about the world gravity axis changes no residual
//! (one null direction); the solver's rank analysis reports it and the estimates that do not
//! depend on it (biases, scales, misalignments, roll/pitch) get their marginal covariance from
//! the pseudo-inverse. The initial attitudes chain from the first interval at zero yaw.
//!
//! # Model selection
//! Candidates ([`MultiPoseModel`], from the simplest): bias only; accelerometer scale; both
//! scales; accelerometer scale + misalignment; that plus gyro scale; and the full imu_tk model
//! (accelerometer 3 scales + 3 misalignments, gyro 3 scales + 6 misalignments). Each is solved;
//! `BIC = χ² + k·ln m` (χ² = ‖r‖² of the whitened residuals = −2 log-likelihood up to a
//! constant since the noise is known, k = number of observable parameters = rank of JᵀJ,
//! m = number of scalar residuals). A model is eligible only if all its parameters are
//! observable (rank = dim − 1, the yaw gauge) **and** its solver converged; the eligible model
//! with the lowest BIC wins. Every BIC is reported ([`ModelFit`]), and the reason names the
//! winner's and the runner-up's BIC and their difference (ΔBIC > 10: "very strong" evidence,
//! Kass & Raftery 1995), and warns when the winner's χ²/dof exceeds `1 + 3√(2/dof)` (the
//! residuals are not the stated noise, so the ranking is unreliable). No eligible model is an
//! error.
//!
//! Limits: biases are assumed constant over the whole protocol. Keep it short compared with
//! the bias random walk: the per-interval means have σ_a/√T ≈ 1e-3 m/s² (EuRoC, T = 3 s),
//! while EuRoC's σ_ba moves b_a by σ_ba√T ≈ 0.017 m/s² over `sim`'s 33 s `multi-pose-static`
//! scene; on such data χ²/dof of the bias-only model is ≈ 3 (≈ 9 over 120 s) and the scale and
//! misalignment terms absorb the drift (the reason then carries the χ² warning); the accelerometer triad's lever arms (imu_tk ignores them
//! too) and the gyro's g-sensitivity are not modelled.

use super::still::{StillInterval, StillOptions, detect_still_intervals};
use super::{
    BiasError, SegmentStats, attitude_from_up, check_gravity, check_noise, check_samples,
    roll_pitch_of_up,
};
use crate::gauss_newton::{GaussNewton, LeastSquares, StopReason, solve};
use lie::{SO3, hat, jr_inv};
use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};
use preint::factor::sqrt_information;
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};

/// Candidate calibration models, from the simplest (module docs for the sensor model).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MultiPoseModel {
    /// `b_g`, `b_a` and the attitudes (6 parameters besides the attitudes).
    BiasOnly,
    /// Plus accelerometer scale factors `s_a` (9).
    AccScale,
    /// Plus accelerometer and gyro scale factors `s_a`, `s_g` (12).
    Scale,
    /// Bias plus accelerometer scale factors and misalignment `s_a`, `m_a` (12).
    AccMisalignment,
    /// `AccMisalignment` plus gyro scale factors `s_g` (15).
    AccMisalignmentGyroScale,
    /// The full Tedaldi et al. / imu_tk model: `s_a`, `m_a`, `s_g`, `m_g` (21).
    ScaleMisalignment,
}

impl MultiPoseModel {
    /// All candidates, from the simplest.
    pub const ALL: [MultiPoseModel; 6] = [
        MultiPoseModel::BiasOnly,
        MultiPoseModel::AccScale,
        MultiPoseModel::Scale,
        MultiPoseModel::AccMisalignment,
        MultiPoseModel::AccMisalignmentGyroScale,
        MultiPoseModel::ScaleMisalignment,
    ];
    fn acc_scale(self) -> bool {
        !matches!(self, MultiPoseModel::BiasOnly)
    }
    fn acc_mis(self) -> bool {
        matches!(
            self,
            MultiPoseModel::AccMisalignment
                | MultiPoseModel::AccMisalignmentGyroScale
                | MultiPoseModel::ScaleMisalignment
        )
    }
    fn gyro_scale(self) -> bool {
        matches!(
            self,
            MultiPoseModel::Scale
                | MultiPoseModel::AccMisalignmentGyroScale
                | MultiPoseModel::ScaleMisalignment
        )
    }
    fn gyro_mis(self) -> bool {
        matches!(self, MultiPoseModel::ScaleMisalignment)
    }
    /// Offsets of `(s_a, m_a, s_g, m_g)` in the parameter vector (`None` when absent).
    fn layout(self) -> [Option<usize>; 4] {
        let mut o = 6;
        let mut take = |on: bool, n: usize| {
            on.then(|| {
                let at = o;
                o += n;
                at
            })
        };
        [
            take(self.acc_scale(), 3),
            take(self.acc_mis(), 3),
            take(self.gyro_scale(), 3),
            take(self.gyro_mis(), 6),
        ]
    }
    /// Number of parameters besides the attitudes.
    pub fn param_count(self) -> usize {
        6 + 3 * (self.acc_scale() as usize)
            + 3 * (self.acc_mis() as usize)
            + 3 * (self.gyro_scale() as usize)
            + 6 * (self.gyro_mis() as usize)
    }
    /// Number of gyro model parameters (`s_g`, `m_g`) that enter the links.
    fn gyro_params(self) -> usize {
        3 * (self.gyro_scale() as usize) + 6 * (self.gyro_mis() as usize)
    }
    /// Short name (`"bias-only"`, `"acc-scale"`, `"scale"`, `"acc-misalignment"`,
    /// `"acc-misalignment+gyro-scale"`, `"scale-misalignment"`).
    pub fn name(self) -> &'static str {
        match self {
            MultiPoseModel::BiasOnly => "bias-only",
            MultiPoseModel::AccScale => "acc-scale",
            MultiPoseModel::Scale => "scale",
            MultiPoseModel::AccMisalignment => "acc-misalignment",
            MultiPoseModel::AccMisalignmentGyroScale => "acc-misalignment+gyro-scale",
            MultiPoseModel::ScaleMisalignment => "scale-misalignment",
        }
    }
}

/// `diag(1 + s)·(I + N)` with `N` strictly lower triangular, `N₁₀ = m₀, N₂₀ = m₁, N₂₁ = m₂`:
/// the accelerometer scale/misalignment matrix `S_a` (module docs).
pub fn acc_scale_matrix(s: &Vector3<f64>, m: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::from_diagonal(&s.add_scalar(1.0))
        * Matrix3::new(1.0, 0.0, 0.0, m[0], 1.0, 0.0, m[1], m[2], 1.0)
}

/// Index pairs (row, column) of the gyro misalignments `m_g` (module docs).
const GYRO_MIS: [(usize, usize); 6] = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];

/// `diag(1 + s)·(I + M)` with the off-diagonal `M` in the order
/// `m = (M₀₁, M₀₂, M₁₀, M₁₂, M₂₀, M₂₁)`: the gyro
/// scale/misalignment matrix `S_g` (module docs).
pub fn gyro_scale_matrix(s: &Vector3<f64>, m: &SVector<f64, 6>) -> Matrix3<f64> {
    let mut im = Matrix3::identity();
    for (k, &(r, c)) in GYRO_MIS.iter().enumerate() {
        im[(r, c)] = m[k];
    }
    Matrix3::from_diagonal(&s.add_scalar(1.0)) * im
}

/// `S_g` and `∂S_g/∂θ` for the gyro parameters present (`s_g` then `m_g`).
fn gyro_model(s: &Vector3<f64>, m: &SVector<f64, 6>, scale: bool, mis: bool) -> GyroModel {
    let s_mat = gyro_scale_matrix(s, m);
    let mut im = Matrix3::identity();
    for (k, &(r, c)) in GYRO_MIS.iter().enumerate() {
        im[(r, c)] = m[k];
    }
    let mut dirs = Vec::new();
    if scale {
        for k in 0..3 {
            let mut e = Matrix3::zeros();
            e.set_row(k, &im.row(k));
            dirs.push(e);
        }
    }
    if mis {
        for &(r, c) in &GYRO_MIS {
            let mut e = Matrix3::zeros();
            e[(r, c)] = 1.0 + s[r];
            dirs.push(e);
        }
    }
    GyroModel { s: s_mat, dirs }
}

struct GyroModel {
    s: Matrix3<f64>,
    dirs: Vec<Matrix3<f64>>,
}

/// Midpoint rotation preintegration of `u_i = S_g⁻¹(ω_i − b_g)` over `samples` with its right
/// Jacobians (module docs): returns `(ΔR, ∂ΔR/∂b_g \[s\], ∂ΔR/∂θ)` where column k of the 3×K
/// matrix is the derivative along `∂S_g/∂θ_k = dirs[k]` [rad per unit of θ_k]. `S_g` must be
/// invertible (else the result is non-finite); `samples` must have increasing timestamps (not
/// checked here).
pub fn rotation_preintegration_general(
    samples: &[ImuSample],
    b_g: &Vector3<f64>,
    s_g: &Matrix3<f64>,
    dirs: &[Matrix3<f64>],
) -> (SO3, Matrix3<f64>, DMatrix<f64>) {
    let inv = s_g
        .try_inverse()
        .unwrap_or_else(|| Matrix3::from_element(f64::NAN));
    let u = |s: &ImuSample| inv * (s.gyro - b_g);
    let inv_dirs: Vec<Matrix3<f64>> = dirs.iter().map(|d| -inv * d).collect();
    let mut dr = SO3::identity();
    let mut jb = Matrix3::zeros();
    let mut jt = DMatrix::zeros(3, dirs.len());
    for w in samples.windows(2) {
        let dt = (w[1].t_ns - w[0].t_ns) as f64 * 1e-9;
        let phi = (u(&w[0]) + u(&w[1])) * (0.5 * dt);
        let (e, jrp) = SO3::exp_jr(&phi);
        let et_m = *e.inverse().matrix();
        jb = et_m * jb - jrp * inv * dt;
        for (k, d) in inv_dirs.iter().enumerate() {
            let col: Vector3<f64> = et_m * jt.fixed_view::<3, 1>(0, k) + jrp * (d * phi);
            jt.set_column(k, &col);
        }
        dr = dr.compose(&e);
    }
    (dr, jb, jt)
}

/// Midpoint rotation preintegration of `u_i = (ω_i − b_g) ⊘ (1 + s_g)` (diagonal `S_g`) with
/// its right Jacobians: returns `(ΔR, ∂ΔR/∂b_g, ∂ΔR/∂s_g)` [-, s, rad]. Special case of
/// [`rotation_preintegration_general`]. `samples` must have increasing timestamps (not checked
/// here).
pub fn rotation_preintegration(
    samples: &[ImuSample],
    b_g: &Vector3<f64>,
    s_g: &Vector3<f64>,
) -> (SO3, Matrix3<f64>, Matrix3<f64>) {
    let dirs: Vec<Matrix3<f64>> = (0..3)
        .map(|k| {
            let mut e = Matrix3::zeros();
            e[(k, k)] = 1.0;
            e
        })
        .collect();
    let s = Matrix3::from_diagonal(&s_g.add_scalar(1.0));
    let (dr, jb, js) = rotation_preintegration_general(samples, b_g, &s, &dirs);
    (dr, jb, Matrix3::from_column_slice(js.as_slice()))
}

/// Options of [`calibrate_multi_pose`].
#[derive(Clone, Debug, PartialEq)]
pub struct MultiPoseOptions {
    /// World gravity [m/s²]; default `(0, 0, −9.81)`.
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
}

impl Default for MultiPoseOptions {
    fn default() -> Self {
        Self {
            gravity: Vector3::new(0.0, 0.0, -9.81),
            still: None,
            models: MultiPoseModel::ALL.to_vec(),
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

impl ModelFit {
    /// Eligible to win the selection: identifiable and converged.
    pub fn eligible(&self) -> bool {
        self.identifiable && self.converged
    }
}

/// Result of [`calibrate_multi_pose`] (the estimates are those of the chosen model; terms the
/// model does not have are `None`).
#[derive(Clone, Debug)]
pub struct MultiPoseCalibration {
    /// The model chosen by BIC.
    pub model: MultiPoseModel,
    /// All candidates' statistics, in the order tried.
    pub fits: Vec<ModelFit>,
    /// Why the model won: the winner's and runner-up's BIC, their difference and every
    /// candidate's BIC, χ², k and m, for humans.
    pub reason: String,
    /// Gyro bias b_g [rad/s].
    pub gyro_bias: Vector3<f64>,
    /// Its standard deviation [rad/s].
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias b_a [m/s²].
    pub acc_bias: Vector3<f64>,
    /// Its standard deviation [m/s²].
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
}

impl MultiPoseCalibration {
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
    fn eval(&self, x: &(DVector<f64>, Vec<SO3>), want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
        let (p, rs) = x;
        let model = self.model;
        let np = model.param_count();
        let k = self.intervals.len();
        let n = np + 3 * k;
        let m = 6 * k + 3 * self.links.len();
        let mut r = DVector::zeros(m);
        let mut j = if want_j {
            DMatrix::zeros(m, n)
        } else {
            DMatrix::zeros(0, 0)
        };
        let v3 = |o: Option<usize>| o.map_or(Vector3::zeros(), |o| p.fixed_rows::<3>(o).into());
        let [o_sa, o_ma, o_sg, o_mg] = model.layout();
        let bg = v3(Some(0));
        let ba = v3(Some(3));
        let sa = v3(o_sa);
        let ma = v3(o_ma);
        let sg = v3(o_sg);
        let mg: SVector<f64, 6> = o_mg.map_or(SVector::zeros(), |o| p.fixed_rows::<6>(o).into());
        let s_a = acc_scale_matrix(&sa, &ma);
        let lower = Matrix3::new(1.0, 0.0, 0.0, ma[0], 1.0, 0.0, ma[1], ma[2], 1.0);
        for (i, iv) in self.intervals.iter().enumerate() {
            let u = rs[i].inverse().act(&(-self.g));
            let pred = s_a * u + ba;
            let row = 6 * i;
            for c in 0..3 {
                r[row + c] = (iv.w_mean[c] - bg[c]) / iv.s_w;
                r[row + 3 + c] = (iv.f_mean[c] - pred[c]) / iv.s_f;
            }
            if want_j {
                let nu = lower * u;
                for c in 0..3 {
                    j[(row + c, c)] = -1.0 / iv.s_w;
                    j[(row + 3 + c, 3 + c)] = -1.0 / iv.s_f;
                    if let Some(o) = o_sa {
                        j[(row + 3 + c, o + c)] = -nu[c] / iv.s_f;
                    }
                }
                if let Some(o) = o_ma {
                    // ∂(S_a u)/∂N₁₀ = (1+s₁) u₀ e₁, ∂/∂N₂₀ = (1+s₂) u₀ e₂, ∂/∂N₂₁ = (1+s₂) u₁ e₂.
                    j[(row + 4, o)] = -(1.0 + sa[1]) * u[0] / iv.s_f;
                    j[(row + 5, o + 1)] = -(1.0 + sa[2]) * u[0] / iv.s_f;
                    j[(row + 5, o + 2)] = -(1.0 + sa[2]) * u[1] / iv.s_f;
                }
                let d_phi = -(s_a * hat(&u)) / iv.s_f;
                j.view_mut((row + 3, np + 3 * i), (3, 3)).copy_from(&d_phi);
            }
        }
        let gm = gyro_model(&sg, &mg, model.gyro_scale(), model.gyro_mis());
        let o_gyro = o_sg.or(o_mg);
        for (l, link) in self.links.iter().enumerate() {
            let (dr, jb, jt) = rotation_preintegration_general(&link.samples, &bg, &gm.s, &gm.dirs);
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
                let ujet = -u * jri * e.matrix().transpose();
                j.view_mut((row, np + 3 * (l + 1)), (3, 3))
                    .copy_from(&d_next);
                j.view_mut((row, np + 3 * l), (3, 3)).copy_from(&d_prev);
                j.view_mut((row, 0), (3, 3)).copy_from(&(ujet * jb));
                if let Some(o) = o_gyro {
                    let d = DMatrix::from_column_slice(3, 3, ujet.as_slice()) * &jt;
                    j.view_mut((row, o), (3, model.gyro_params())).copy_from(&d);
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

/// Still intervals, their statistics, the links and the initial attitudes and gyro bias.
struct Prepared {
    ivs: Vec<StillInterval>,
    intervals: Vec<Interval>,
    links: Vec<Link>,
    r0: Vec<SO3>,
    bg0: Vector3<f64>,
    up_w: Vector3<f64>,
}

fn prepare(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &MultiPoseOptions,
    gnorm: f64,
) -> Result<Prepared, BiasError> {
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

    Ok(Prepared {
        ivs,
        intervals,
        links,
        r0,
        bg0,
        up_w,
    })
}

/// Calibrates a multi-position static recording (module docs): detects still intervals, builds
/// the problem, solves every candidate model and keeps the eligible one with the lowest BIC.
///
/// Errors: invalid samples/noise/options, fewer than `min_intervals` still intervals
/// ([`BiasError::TooFew`]), no eligible (identifiable and converged) model
/// ([`BiasError::InvalidParameter`] naming every candidate's status), preintegration or
/// solver failures; no panics on bad input.
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
    let Prepared {
        ivs,
        intervals,
        links,
        r0,
        bg0,
        up_w,
    } = prepare(samples, noise, opts, gnorm)?;

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
    let listing = fits
        .iter()
        .map(|f| {
            format!(
                "{}: BIC {:.1} = χ² {:.1} + {}·ln {}{}{}",
                f.model.name(),
                f.bic,
                f.chi2,
                f.params,
                f.residuals,
                if f.identifiable {
                    ""
                } else {
                    " (not identifiable)"
                },
                if f.converged { "" } else { " (not converged)" }
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let mut order: Vec<usize> = (0..fits.len()).filter(|&i| fits[i].eligible()).collect();
    if order.is_empty() {
        return Err(BiasError::InvalidParameter {
            name: "samples",
            reason: format!(
                "no candidate model is both identifiable and converged (need more, diverse \
                 still attitudes). {listing}"
            ),
        });
    }
    order.sort_by(|&a, &b| fits[a].bic.total_cmp(&fits[b].bic));
    let best = order[0];
    let fb = &fits[best];
    let reason = match order.get(1) {
        Some(&second) => {
            let fs = &fits[second];
            let d = fs.bic - fb.bic;
            format!(
                "{} has the lowest BIC of the eligible models, {:.1}, which is {:.1} below the \
                 runner-up {} ({:.1}): {}. All candidates: {listing}",
                fb.model.name(),
                fb.bic,
                d,
                fs.model.name(),
                fs.bic,
                if d > 10.0 {
                    "very strong evidence"
                } else {
                    "weak evidence (ΔBIC ≤ 10)"
                },
            )
        }
        None => format!(
            "{} is the only eligible model (BIC {:.1}). All candidates: {listing}",
            fb.model.name(),
            fb.bic
        ),
    };
    // Goodness of fit of the winner: χ²/dof beyond 1 + 3√(2/dof) (3σ of the χ² distribution)
    // means the residuals are not the stated noise, and the BIC ranking is then unreliable.
    let dof_best = fb.residuals.saturating_sub(fb.params);
    let mut reason = reason;
    if dof_best > 0 {
        let q = fb.chi2 / dof_best as f64;
        if q > 1.0 + 3.0 * (2.0 / dof_best as f64).sqrt() {
            reason.push_str(&format!(
                " WARNING: χ²/dof = {q:.2} for {} dof: the residuals exceed the stated noise \
                 (wrong densities, or biases that drift during the protocol: the model holds \
                 them constant), so the selection is unreliable.",
                dof_best
            ));
        }
    }
    let model = fb.model;
    let chi2 = fb.chi2;
    let sol = results.swap_remove(best);
    let (p, rs) = &sol.estimate;
    let np = model.param_count();
    let cov = &sol.covariance;
    let sd = |o: usize| cov[(o, o)].max(0.0).sqrt();
    let v3 = |o: usize| Vector3::new(p[o], p[o + 1], p[o + 2]);
    let s3 = |o: usize| Vector3::new(sd(o), sd(o + 1), sd(o + 2));
    let [o_sa, o_ma, o_sg, o_mg] = model.layout();
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
        acc_scale: o_sa.map(v3),
        acc_scale_std: o_sa.map(s3),
        acc_misalignment: o_ma.map(v3),
        acc_misalignment_std: o_ma.map(s3),
        gyro_scale: o_sg.map(v3),
        gyro_scale_std: o_sg.map(s3),
        gyro_misalignment: o_mg.map(|o| p.fixed_rows::<6>(o).into()),
        gyro_misalignment_std: o_mg.map(|o| SVector::<f64, 6>::from_fn(|i, _| sd(o + i))),
        intervals: ivs,
        attitudes: rs.clone(),
        roll_pitch,
        chi2,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations: sol.iterations,
        stop: sol.stop.clone(),
        fits,
    })
}

#[cfg(test)]
mod tests {
    //! The problem's analytic Jacobian against Ridders' numeric one ([`crate::check_jacobian`],
    //! relative error ≤ 1e-8), for every candidate model, at a state away from the optimum (so
    //! that residuals, scales and misalignments are all non-zero).
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use lie::Manifold;
    use sim::{MultiPoseStaticScene, SimConfig, scale_misalignment, simulate};

    fn data() -> (Vec<ImuSample>, ImuNoise) {
        let rx = |a: f64| SO3::exp(&Vector3::new(a, 0.0, 0.0));
        let ry = |a: f64| SO3::exp(&Vector3::new(0.0, a, 0.0));
        let rz = |a: f64| SO3::exp(&Vector3::new(0.0, 0.0, a));
        let h = std::f64::consts::FRAC_PI_2;
        let poses = vec![
            SO3::identity(),
            rx(h),
            rx(h).compose(&rz(h)),
            ry(-h).compose(&rz(0.7)),
            rz(-h).compose(&rx(1.1)),
        ];
        let scene = MultiPoseStaticScene::new(poses, 2.0, 1.5, Vector3::zeros()).unwrap();
        let noise = ImuNoise::euroc();
        let cfg = SimConfig {
            noise,
            initial_bias: ImuBias::new(
                Vector3::new(0.003, -0.002, 0.004),
                Vector3::new(0.05, -0.04, 0.08),
            ),
            bias_random_walk: false,
            acc_scale: scale_misalignment(
                &Vector3::new(0.01, -0.01, 0.005),
                &Vector3::new(0.01, -0.005, 0.008),
            ),
            gyro_scale: Matrix3::new(1.01, 0.01, -0.005, 0.004, 0.99, 0.006, -0.008, 0.003, 1.005),
            ..SimConfig::default()
        };
        let out = simulate(&scene, 200.0, scene.duration_s(), &cfg, 7).unwrap();
        (out.samples, noise)
    }

    #[test]
    fn analytic_jacobians_match_ridders_for_every_model() {
        let (samples, noise) = data();
        let opts = MultiPoseOptions::default();
        let pr = prepare(&samples, &noise, &opts, 9.81).unwrap();
        assert_eq!(pr.intervals.len(), 5);
        for model in MultiPoseModel::ALL {
            let np = model.param_count();
            let problem = Problem {
                intervals: &pr.intervals,
                links: &pr.links,
                g: opts.gravity,
                model,
            };
            // Parameters: biases near the truth, every model term non-zero.
            let p = DVector::from_fn(np, |i, _| match i {
                0..=2 => 0.003 - 0.001 * i as f64,
                3..=5 => 0.05 * (i as f64 - 4.0),
                _ => 0.004 * ((i as f64) * 1.3).sin(),
            });
            let rs: Vec<SO3> = pr
                .r0
                .iter()
                .enumerate()
                .map(|(k, r)| r.plus(&Vector3::new(0.01 * k as f64, -0.02, 0.015)))
                .collect();
            let x = (p, rs);
            let (_, j) = problem.residual_jacobian(&x);
            let blocks = [
                j.columns(0, np).into_owned(),
                j.columns(np, j.ncols() - np).into_owned(),
            ];
            let f = |x: &(DVector<f64>, Vec<SO3>)| problem.residual(x);
            let rep = check_jacobian(f, &x, &blocks, &CheckOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", model.name()));
            println!(
                "{}: worst relative error {:.2e}",
                model.name(),
                rep.worst_rel_error
            );
            assert_eq!(x.dim(), np + 15);
        }
    }

    /// The general rotation preintegration's θ-Jacobian against Ridders, for a non-diagonal
    /// `S_g` (all nine directions), and its diagonal special case against the general one.
    #[test]
    fn rotation_preintegration_jacobians_match_ridders() {
        let (samples, _) = data();
        let seg = &samples[300..800];
        let s = Vector3::new(0.01, -0.02, 0.005);
        let m = SVector::<f64, 6>::new(0.01, -0.004, 0.006, 0.002, -0.008, 0.003);
        let gm = gyro_model(&s, &m, true, true);
        let bg = Vector3::new(0.002, -0.001, 0.003);
        let (_, jb, jt) = rotation_preintegration_general(seg, &bg, &gm.s, &gm.dirs);
        let f = |x: &(Vector3<f64>, SVector<f64, 9>)| {
            let sx = Vector3::new(x.1[0], x.1[1], x.1[2]);
            let mx = SVector::<f64, 6>::from_fn(|i, _| x.1[3 + i]);
            rotation_preintegration_general(seg, &x.0, &gyro_scale_matrix(&sx, &mx), &[]).0
        };
        let theta = SVector::<f64, 9>::from_fn(|i, _| if i < 3 { s[i] } else { m[i - 3] });
        let rep = check_jacobian(
            f,
            &(bg, theta),
            &[crate::to_dmatrix(&jb), jt.clone()],
            &CheckOptions::default(),
        )
        .unwrap();
        println!("rotation preintegration: {:.2e}", rep.worst_rel_error);
        let (dr, jb2, js) = rotation_preintegration(seg, &bg, &s);
        let gd = gyro_model(&s, &SVector::zeros(), true, false);
        let (dr3, jb3, js3) = rotation_preintegration_general(seg, &bg, &gd.s, &gd.dirs);
        assert!(dr.minus(&dr3).norm() < 1e-14);
        assert!((jb2 - jb3).amax() < 1e-14);
        assert!((crate::to_dmatrix(&js) - js3).amax() < 1e-14);
    }
}
