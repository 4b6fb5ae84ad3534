//! Multi-position static calibration (Tedaldi, Pretto, Menegatti, ICRA 2014; imu_tk), with the
//! still intervals linked by gyro preintegration and the model chosen by BIC.
//!
//! # Data
//! The IMU is held still in K ≥ 3 attitudes and rotated between them. Still intervals are
//! detected automatically ([`super::still`]). For interval k (averaging time `T_k = N_k·Δt`)
//! the means `ω̄_k`, `f̄_k` are kept; between consecutive intervals the gyro samples from the
//! last sample of interval k to the first of interval k+1 are kept for re-integration.
//!
//! # Sensor model
//! ```text
//! gyro     ω_m = S_g ω_b + b_g(t) + n_g         S_g = diag(1 + s_g)·(I + M_g)
//! accel    a_m = S_a R_kᵀ(−g) + b_a(t) + n_a    S_a = diag(1 + s_a)·(I + N_a)   (at rest)
//! biases   b(t) = b̄ + w(t)                      w: bias random walk, w(t_ref) = 0
//! ```
//!
//! Unknowns: `b_g`, `b_a` [rad/s, m/s²] (the biases `b̄` at the reference time `t_ref`, see
//! below), the terms of the chosen model and the attitude `R_k` (SO3, right perturbation) of
//! every still interval. Parameter vector order: `[b_g, b_a, s_a?, m_a?, s_g?, m_g?]` (present
//! terms only, in this order). Raw residuals, stacked as `[e_ω,0, e_f,0, …, e_ω,K−1, e_f,K−1,
//! e_R,0, …, e_R,K−2]` (m = 6K + 3(K − 1) scalars):
//!
//! ```text
//! e_ω,k = ω̄_k − b_g                            white-noise covariance s_ω,k² I,  s_ω,k = σ_g/√T_k
//! e_f,k = f̄_k − S_a R_kᵀ(−g) − b_a             white-noise covariance s_f,k² I,  s_f,k = σ_a/√T_k
//! e_R,k = Log(ΔR_k(b_g, S_g)ᵀ R_kᵀ R_k+1)      white-noise covariance Σ_φ,k
//! ```
//!
//! and the solver sees the whitened `r = L⁻¹e` with `L Lᵀ = Σ`, the covariance of `e` at the
//! truth: `Σ = D + Σ_w`, `D` the block-diagonal white-noise part above, `Σ_w` the bias random
//! walk's part (next section; dense, it correlates different intervals and links). Without a
//! random walk (or with [`MultiPoseOptions::include_random_walk`] off) `Σ = D` and the whitening
//! is block by block: `r_ω,k = e_ω,k/s_ω,k`, `r_f,k = e_f,k/s_f,k`, `r_R,k = U_k e_R,k` with
//! `U_kᵀU_k = Σ_φ,k⁻¹`. χ² = ‖r‖² = eᵀΣ⁻¹e either way.
//!
//! (The still residual `e_ω` uses `ω_b = 0`, so `S_g` does not enter it.) `ΔR_k(b_g, S_g)` is
//! the midpoint-rule rotation preintegration (the `preint` midpoint scheme,
//! ΔR ← ΔR·Exp(½(u_i + u_i+1)Δt_i)) of the corrected rates `u = S_g⁻¹(ω_m − b_g)` over the link
//! window, re-integrated exactly at every evaluation together with its right Jacobians
//! `J_b = ∂ΔR/∂b_g` (for `S_g = I` this is preint's `d_r_d_bg`) and `J_θ = ∂ΔR/∂θ` for each
//! gyro model parameter θ: `J ← Exp(φ_i)ᵀ J + Jr(φ_i) ∂φ_i/∂θ` with
//! `∂φ_i/∂θ = −S_g⁻¹ (∂S_g/∂θ) φ_i` and `∂φ_i/∂b_g = −S_g⁻¹Δt_i`
//! ([`rotation_preintegration_general`]). `Σ_φ,k` is the rotation block of `preint`'s
//! covariance of that window ([`preint::preintegrate`], midpoint, at the initial gyro bias).
//! With `E = Exp(e_R)`: `∂e_R/∂δφ_k+1 = Jr⁻¹(e_R)`, `∂e_R/∂δφ_k = −Jr⁻¹(e_R) R_k+1ᵀ R_k`,
//! `∂e_R/∂θ = −Jr⁻¹(e_R) Eᵀ J_θ`; `∂e_f/∂δφ_k = −S_a [u_k]×` with `u_k = R_kᵀ(−g)`; the
//! whitened Jacobian is `L⁻¹ ∂e/∂x` (Σ does not depend on the state). All are checked against
//! Ridders' numeric Jacobian in this module's tests, with both whitenings.
//!
//! # Bias random walk (marginalised)
//! The biases follow random walks of densities `σ_bg` [rad/s²/√Hz], `σ_ba` [m/s³/√Hz]
//! ([`ImuNoise`], Kalibr units). Write `b(t) = b̄ + w(t)` with `b̄ = b(t_ref)` and `w` a
//! two-sided Wiener process from `t_ref` (for every component, independent):
//!
//! ```text
//! Cov(w(s), w(t)) = σ_b² κ(s, t) I,   κ(s, t) = min(|s − t_ref|, |t − t_ref|)  if s, t on the same side of t_ref
//!                                                0                             otherwise
//! ```
//!
//! With a flat prior on `b̄` this is the same law of `b(·)` for every `t_ref` (increments are
//! independent with variance `σ_b²|t − s|`), so χ² does not depend on `t_ref` (tested); `t_ref`
//! only says which bias `b̄` is: by default the sample time nearest the middle of the span from
//! the first still interval's start to the last one's end
//! ([`MultiPoseOptions::reference_time_ns`]), as the static problem reports its bias at
//! mid-recording. No parameter is added (the walk is integrated out), so the BIC's `k` stays
//! the number of calibration parameters.
//!
//! Every raw residual block β (3 rows) gets, to first order, a drift term linear in the walk at
//! the sample times it uses, `d_β = Σ_i C_β,i w(t_i)`:
//!
//! - still interval k (N_k samples, both sensors): `e_ω,k`, `e_f,k` contain the interval means
//!   of the walk, `C_i = I/N_k` for every sample of the interval (the averaging over the
//!   interval's duration; centred on `t_ref`, the variance is `σ_b²T/12`, the static problem's
//!   term).
//! - link k (gyro): the link window is integrated with `b̄_g`, the truth with `b̄_g + w(t)`, so
//!   the midpoint increments differ by `δφ_j = −½Δt_j (w(t_j) + w(t_j+1))`, and
//!   `ΔR_true = Π Exp(φ_j + δφ_j) ≈ ΔR·Exp(Σ_j B_j δφ_j)` with `B_j = ΔR_j+1,nᵀ Jr(φ_j)`
//!   (the rotation from the end of step j to the end of the window). Hence
//!   `C_i = −½ (B_i−1 Δt_i−1 + B_i Δt_i)` (missing terms at the two ends are 0) and
//!   `Σ_i C_i = J_b` (a constant offset of the bias moves `e_R` by `J_b w`). Without rotation
//!   (`B_j = I`) `d = −∫ (b_g(t) − b̄_g) dt`, the bias drift integrated over the motion; with it
//!   the drift is carried to the end frame of the window.
//!
//! Then `Cov(d_β, d_γ) = σ_b² Σ_i Σ_j C_β,i C_γ,jᵀ κ(t_i, t_j)`, and with
//! `min(a, b) = ∫₀^∞ 1[s ≤ a]·1[s ≤ b] ds` on each side of `t_ref` (`s = |t − t_ref|`):
//!
//! ```text
//! Cov(d_β, d_γ) = σ_b² Σ_sides ∫₀^∞ T_β(s) T_γ(s)ᵀ ds,     T_β(s) = Σ_{i on the side, s_i ≥ s} C_β,i
//! ```
//!
//! (step functions; O(n_β + n_γ) per pair). For blocks on the same side with all of β's
//! samples nearer `t_ref` than all of γ's this is `σ_b² (Σ_i C_β,i s_i)(Σ_j C_γ,j)ᵀ`: e.g. two
//! interval means after `t_ref` covary by `σ_b²·(mean time of the earlier one − t_ref)`. Blocks
//! of different sensors are independent. The coefficients are evaluated once, at the initial
//! gyro bias and `S_g = I` (as `Σ_φ`; the error is second order: products of the drift with
//! the bias error or with `s_g`). `Σ_w` is added to `D`, `Σ = L Lᵀ` by Cholesky (m ≈ 100), and
//! the stacked residual is whitened with `L⁻¹` ([`rotation_drift_coefficients`] gives the links'
//! `C_i`, [`wiener_cross_covariance`] the integral).
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
//! constant since the noise is known — `ln det Σ` is the same for every model —, k = number of
//! observable parameters = rank of JᵀJ, m = number of scalar residuals). A model is eligible
//! only if all its parameters are observable (rank = dim − 1, the yaw gauge) **and** its solver
//! converged; the eligible model with the lowest BIC wins. Every BIC is reported ([`ModelFit`]),
//! and the reason names the winner's and the runner-up's BIC and their difference (ΔBIC > 10:
//! "very strong" evidence, Kass & Raftery 1995), and warns when the winner's χ²/dof exceeds
//! `1 + 3√(2/dof)` (the residuals are not the stated noise, so the ranking is unreliable). No
//! eligible model is an error.
//!
//! Limits: the bias random walk is modelled with the stated densities: if the real drift is
//! larger (temperature transients, turn-on), χ²/dof grows and the reason warns. Without the
//! marginalisation (option off) biases are held constant; then keep the protocol short compared
//! with the random walk: the interval means have σ_a/√T ≈ 1e-3 m/s² (EuRoC, T = 3 s) while
//! EuRoC's σ_ba moves b_a by σ_ba√T ≈ 0.017 m/s² over `sim`'s 33 s `multi-pose-static` scene
//! (bias-only χ²/dof ≈ 3 there, ≈ 9 over 120 s, and scale/misalignment terms absorb the drift).
//! The accelerometer triad's lever arms (imu_tk ignores them too) and the gyro's g-sensitivity
//! are not modelled.

use super::still::{StillInterval, StillOptions, detect_still_intervals};
use super::{
    BiasError, SegmentStats, attitude_from_up, check_gravity, check_noise, check_samples,
    roll_pitch_of_up,
};
use crate::gauss_newton::{GaussNewton, LeastSquares, StopReason, solve};
use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};
use preint::factor::sqrt_information;
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};
use preint_lie::{SO3, hat, jr_inv};

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

/// Per-sample drift coefficients `C_i` of a link rotation residual (module docs, "Bias random
/// walk"): to first order, if the true gyro bias at sample i is `b_g + w_i` while the window
/// is integrated (midpoint rule, `S_g = I`) with the constant `b_g`,
/// `Log(ΔR(b_g)ᵀ ΔR_true) ≈ Σ_i C_i w_i`, with `C_i = −½(B_i−1 Δt_i−1 + B_i Δt_i)`,
/// `B_j = ΔR_j+1,nᵀ Jr(φ_j)`. Units: \[s\]. `Σ_i C_i = ∂ΔR/∂b_g` of
/// [`rotation_preintegration`]. One entry per sample; `samples` must have increasing
/// timestamps (not checked here).
pub fn rotation_drift_coefficients(samples: &[ImuSample], b_g: &Vector3<f64>) -> Vec<Matrix3<f64>> {
    let n = samples.len();
    let mut prefix = SO3::identity();
    // (ΔR_0,j+1 Jr(φ_j), Δt_j) per step j.
    let mut steps = Vec::with_capacity(n.saturating_sub(1));
    for w in samples.windows(2) {
        let dt = (w[1].t_ns - w[0].t_ns) as f64 * 1e-9;
        let phi = (w[0].gyro + w[1].gyro - 2.0 * b_g) * (0.5 * dt);
        let (e, jr) = SO3::exp_jr(&phi);
        prefix = prefix.compose(&e);
        steps.push((prefix.matrix() * jr, dt));
    }
    // ΔR_j+1,nᵀ = ΔR_0,nᵀ ΔR_0,j+1.
    let total_t = prefix.matrix().transpose();
    let mut c = vec![Matrix3::zeros(); n];
    for (j, (pj, dt)) in steps.iter().enumerate() {
        let half = total_t * pj * (-0.5 * dt);
        c[j] += half;
        c[j + 1] += half;
    }
    c
}

/// `Σ_i Σ_j A_i B_jᵀ κ(t_i, t_j)` \[s × units of A·B\] for two linear functionals
/// `Σ_i A_i w(t_i)`, `Σ_j B_j w(t_j)` of a two-sided unit Wiener process from `t_ref_ns`
/// (module docs, "Bias random walk": `κ(s, t) = min(|s − t_ref|, |t − t_ref|)` on the same
/// side, else 0): their cross-covariance per unit random-walk density² (multiply by `σ_b²`).
/// Terms are `(t_ns, coefficient)` in any order; computed as
/// `Σ_sides ∫₀^∞ T_A(s) T_B(s)ᵀ ds` over the step functions `T(s) = Σ_{s_i ≥ s} C_i`, in
/// O((n_A + n_B) log(n_A + n_B)).
pub fn wiener_cross_covariance(
    a: &[(i64, Matrix3<f64>)],
    b: &[(i64, Matrix3<f64>)],
    t_ref_ns: i64,
) -> Matrix3<f64> {
    let mut out = Matrix3::zeros();
    for after in [true, false] {
        // (s [s], which functional, coefficient) of the terms strictly on this side.
        let mut ev: Vec<(f64, bool, &Matrix3<f64>)> = Vec::new();
        for (is_a, list) in [(true, a), (false, b)] {
            for (t, c) in list {
                let d = if after { t - t_ref_ns } else { t_ref_ns - t };
                if d > 0 {
                    ev.push((d as f64 * 1e-9, is_a, c));
                }
            }
        }
        ev.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut ta: Matrix3<f64> = ev.iter().filter(|e| e.1).map(|e| e.2).sum();
        let mut tb: Matrix3<f64> = ev.iter().filter(|e| !e.1).map(|e| e.2).sum();
        let mut s_prev = 0.0;
        for (s, is_a, c) in ev {
            if s > s_prev {
                out += ta * tb.transpose() * (s - s_prev);
                s_prev = s;
            }
            // T(s') for s' > s no longer holds this term.
            if is_a {
                ta -= c;
            } else {
                tb -= c;
            }
        }
    }
    out
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
    /// Gyro bias b_g [rad/s] at [`MultiPoseCalibration::reference_time_ns`].
    pub gyro_bias: Vector3<f64>,
    /// Its standard deviation [rad/s] (white noise and, when marginalised, the random walk).
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias b_a [m/s²] at [`MultiPoseCalibration::reference_time_ns`].
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
    /// The reference time `t_ref` \[ns\] the biases refer to (module docs).
    pub reference_time_ns: i64,
    /// Whether the bias random walk was marginalised (option on and a non-zero random walk
    /// density); otherwise the biases were held constant.
    pub random_walk_marginalised: bool,
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
    /// White-noise covariance Σ_φ of the link rotation \[rad²\].
    cov: Matrix3<f64>,
    /// `U` with `UᵀU = Σ_φ⁻¹`.
    sqrt_info: Matrix3<f64>,
}

/// How the raw residual vector `e` is whitened (module docs).
enum Whitening {
    /// `Σ = D`: per interval `1/s_ω`, `1/s_f`, per link `U_k`.
    Block,
    /// `Σ = D + Σ_w`: `r = W e` with `W = L⁻¹`, `L Lᵀ = Σ` (lower triangular, m×m).
    Full(DMatrix<f64>),
}

struct Problem<'a> {
    intervals: &'a [Interval],
    links: &'a [Link],
    g: Vector3<f64>,
    model: MultiPoseModel,
    whitening: &'a Whitening,
}

impl Problem<'_> {
    /// Raw (unwhitened) residuals `e` and, if `want_j`, `∂e/∂x` (module docs).
    fn eval_raw(&self, x: &(DVector<f64>, Vec<SO3>), want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
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
                r[row + c] = iv.w_mean[c] - bg[c];
                r[row + 3 + c] = iv.f_mean[c] - pred[c];
            }
            if want_j {
                let nu = lower * u;
                for c in 0..3 {
                    j[(row + c, c)] = -1.0;
                    j[(row + 3 + c, 3 + c)] = -1.0;
                    if let Some(o) = o_sa {
                        j[(row + 3 + c, o + c)] = -nu[c];
                    }
                }
                if let Some(o) = o_ma {
                    // ∂(S_a u)/∂N₁₀ = (1+s₁) u₀ e₁, ∂/∂N₂₀ = (1+s₂) u₀ e₂, ∂/∂N₂₁ = (1+s₂) u₁ e₂.
                    j[(row + 4, o)] = -(1.0 + sa[1]) * u[0];
                    j[(row + 5, o + 1)] = -(1.0 + sa[2]) * u[0];
                    j[(row + 5, o + 2)] = -(1.0 + sa[2]) * u[1];
                }
                let d_phi = -(s_a * hat(&u));
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
            r.fixed_rows_mut::<3>(row).copy_from(&res);
            if want_j {
                let jri = jr_inv(&res);
                let d_prev = -jri * (rs[l + 1].inverse().compose(&rs[l])).matrix();
                let jet = -jri * e.matrix().transpose();
                j.view_mut((row, np + 3 * (l + 1)), (3, 3)).copy_from(&jri);
                j.view_mut((row, np + 3 * l), (3, 3)).copy_from(&d_prev);
                j.view_mut((row, 0), (3, 3)).copy_from(&(jet * jb));
                if let Some(o) = o_gyro {
                    let d = DMatrix::from_column_slice(3, 3, jet.as_slice()) * &jt;
                    j.view_mut((row, o), (3, model.gyro_params())).copy_from(&d);
                }
            }
        }
        (r, j)
    }

    /// Whitened residuals `r` and Jacobian `∂r/∂x` (module docs).
    fn eval(&self, x: &(DVector<f64>, Vec<SO3>), want_j: bool) -> (DVector<f64>, DMatrix<f64>) {
        let (mut e, mut j) = self.eval_raw(x, want_j);
        match self.whitening {
            Whitening::Full(w) => {
                let r = w * &e;
                let jw = if want_j { w * &j } else { j };
                (r, jw)
            }
            Whitening::Block => {
                let k = self.intervals.len();
                for (i, iv) in self.intervals.iter().enumerate() {
                    let row = 6 * i;
                    e.rows_mut(row, 3).unscale_mut(iv.s_w);
                    e.rows_mut(row + 3, 3).unscale_mut(iv.s_f);
                    if want_j {
                        j.rows_mut(row, 3).unscale_mut(iv.s_w);
                        j.rows_mut(row + 3, 3).unscale_mut(iv.s_f);
                    }
                }
                for (l, link) in self.links.iter().enumerate() {
                    let row = 6 * k + 3 * l;
                    let u = link.sqrt_info;
                    let ue = u * e.fixed_rows::<3>(row);
                    e.fixed_rows_mut::<3>(row).copy_from(&ue);
                    if want_j {
                        let uj = u * j.rows(row, 3);
                        j.rows_mut(row, 3).copy_from(&uj);
                    }
                }
                (e, j)
            }
        }
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
    whitening: Whitening,
    t_ref_ns: i64,
    marginalised: bool,
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
            cov,
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

    let t_ref_ns = match opts.reference_time_ns {
        Some(t) => {
            if !(samples[0].t_ns..=samples[n - 1].t_ns).contains(&t) {
                return Err(BiasError::InvalidParameter {
                    name: "reference_time_ns",
                    reason: format!(
                        "{t} ns is outside the recording [{}, {}] ns",
                        samples[0].t_ns,
                        samples[n - 1].t_ns
                    ),
                });
            }
            t
        }
        None => {
            let (a, b) = (ivs[0].t_start_ns, ivs[ivs.len() - 1].t_end_ns);
            let mid = a + (b - a) / 2;
            let k = samples.partition_point(|s| s.t_ns < mid).min(n - 1);
            let k = if k > 0 && mid - samples[k - 1].t_ns <= samples[k].t_ns - mid {
                k - 1
            } else {
                k
            };
            samples[k].t_ns
        }
    };
    let marginalised =
        opts.include_random_walk && (noise.gyro_random_walk > 0.0 || noise.acc_random_walk > 0.0);
    let whitening = if marginalised {
        Whitening::Full(full_whitening(
            samples, noise, &ivs, &intervals, &links, &bg0, t_ref_ns,
        )?)
    } else {
        Whitening::Block
    };

    Ok(Prepared {
        ivs,
        intervals,
        links,
        r0,
        bg0,
        up_w,
        whitening,
        t_ref_ns,
        marginalised,
    })
}

/// Terms `(t_ns, C_i)` of a linear functional `Σ_i C_i w(t_i)` of a bias random walk.
type WalkTerms = Vec<(i64, Matrix3<f64>)>;

/// The covariance `Σ = D + Σ_w` of the stacked raw residual at the truth (module docs).
fn residual_covariance(
    samples: &[ImuSample],
    noise: &ImuNoise,
    ivs: &[StillInterval],
    intervals: &[Interval],
    links: &[Link],
    bg0: &Vector3<f64>,
    t_ref_ns: i64,
) -> DMatrix<f64> {
    let k = intervals.len();
    let m = 6 * k + 3 * links.len();
    let mut cov = DMatrix::zeros(m, m);
    for (i, iv) in intervals.iter().enumerate() {
        for c in 0..3 {
            cov[(6 * i + c, 6 * i + c)] = iv.s_w * iv.s_w;
            cov[(6 * i + 3 + c, 6 * i + 3 + c)] = iv.s_f * iv.s_f;
        }
    }
    for (l, link) in links.iter().enumerate() {
        let row = 6 * k + 3 * l;
        cov.view_mut((row, row), (3, 3)).copy_from(&link.cov);
    }
    // Drift functionals (first row, terms): gyro (interval means, links), accelerometer.
    let mean_terms = |iv: &StillInterval| {
        let c = Matrix3::identity() / iv.len() as f64;
        samples[iv.start..iv.end]
            .iter()
            .map(|s| (s.t_ns, c))
            .collect::<Vec<_>>()
    };
    let mut gyro: Vec<(usize, WalkTerms)> = Vec::new();
    let mut acc: Vec<(usize, WalkTerms)> = Vec::new();
    for (i, iv) in ivs.iter().enumerate() {
        let terms = mean_terms(iv);
        gyro.push((6 * i, terms.clone()));
        acc.push((6 * i + 3, terms));
    }
    for (l, link) in links.iter().enumerate() {
        let c = rotation_drift_coefficients(&link.samples, bg0);
        let terms = link.samples.iter().map(|s| s.t_ns).zip(c).collect();
        gyro.push((6 * k + 3 * l, terms));
    }
    for (sigma, fs) in [
        (noise.gyro_random_walk, &gyro),
        (noise.acc_random_walk, &acc),
    ] {
        if sigma == 0.0 {
            continue;
        }
        let s2 = sigma * sigma;
        for (a, (ra, ta)) in fs.iter().enumerate() {
            for (rb, tb) in &fs[a..] {
                let c = wiener_cross_covariance(ta, tb, t_ref_ns) * s2;
                let mut blk = cov.view_mut((*ra, *rb), (3, 3));
                blk += c;
                if ra != rb {
                    let mut blk = cov.view_mut((*rb, *ra), (3, 3));
                    blk += c.transpose();
                }
            }
        }
    }
    cov
}

/// `W = L⁻¹` of the Cholesky factor of [`residual_covariance`].
fn full_whitening(
    samples: &[ImuSample],
    noise: &ImuNoise,
    ivs: &[StillInterval],
    intervals: &[Interval],
    links: &[Link],
    bg0: &Vector3<f64>,
    t_ref_ns: i64,
) -> Result<DMatrix<f64>, BiasError> {
    let cov = residual_covariance(samples, noise, ivs, intervals, links, bg0, t_ref_ns);
    let m = cov.nrows();
    let chol = cov.cholesky().ok_or_else(|| BiasError::InvalidParameter {
        name: "noise",
        reason: "residual covariance with the bias random walk is not positive definite".into(),
    })?;
    let w = chol
        .l()
        .solve_lower_triangular(&DMatrix::identity(m, m))
        .ok_or_else(|| BiasError::InvalidParameter {
            name: "noise",
            reason: "singular Cholesky factor of the residual covariance".into(),
        })?;
    Ok(w)
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
        whitening,
        t_ref_ns,
        marginalised,
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
            whitening: &whitening,
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
            let why = if marginalised {
                "wrong densities, or biases that drift faster than the stated random walk"
            } else {
                "wrong densities, or biases that drift during the protocol: the model holds \
                 them constant"
            };
            reason.push_str(&format!(
                " WARNING: χ²/dof = {q:.2} for {dof_best} dof: the residuals exceed the stated \
                 noise ({why}), so the selection is unreliable."
            ));
        }
    }
    if marginalised {
        reason.push_str(&format!(
            " Bias random walk marginalised (σ_bg {:.2e} rad/s²/√Hz, σ_ba {:.2e} m/s³/√Hz); \
             biases at t_ref = {t_ref_ns} ns.",
            noise.gyro_random_walk, noise.acc_random_walk
        ));
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
        reference_time_ns: t_ref_ns,
        random_walk_marginalised: marginalised,
    })
}

#[cfg(test)]
mod tests {
    //! The problem's analytic Jacobian against Ridders' numeric one ([`crate::check_jacobian`],
    //! relative error ≤ 1e-8), for every candidate model, at a state away from the optimum (so
    //! that residuals, scales and misalignments are all non-zero).
    use super::*;
    use crate::checker::{CheckOptions, check_jacobian};
    use preint_lie::Manifold;
    use preint_sim::{MultiPoseStaticScene, SimConfig, scale_misalignment, simulate};

    /// The 5-pose protocol used by these tests: identity, ±90° about each axis, and two
    /// generic attitudes.
    fn five_poses() -> Vec<SO3> {
        let rx = |a: f64| SO3::exp(&Vector3::new(a, 0.0, 0.0));
        let ry = |a: f64| SO3::exp(&Vector3::new(0.0, a, 0.0));
        let rz = |a: f64| SO3::exp(&Vector3::new(0.0, 0.0, a));
        let h = std::f64::consts::FRAC_PI_2;
        vec![
            SO3::identity(),
            rx(h),
            rx(h).compose(&rz(h)),
            ry(-h).compose(&rz(0.7)),
            rz(-h).compose(&rx(1.1)),
        ]
    }

    fn data() -> (Vec<ImuSample>, ImuNoise) {
        let poses = five_poses();
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

    /// Both whitenings: block-diagonal (random walk off) and full (`L⁻¹`, EuRoC random walk).
    #[test]
    fn analytic_jacobians_match_ridders_for_every_model() {
        let (samples, noise) = data();
        for include_random_walk in [false, true] {
            let opts = MultiPoseOptions {
                include_random_walk,
                ..MultiPoseOptions::default()
            };
            let pr = prepare(&samples, &noise, &opts, 9.81).unwrap();
            assert_eq!(pr.marginalised, include_random_walk);
            check_problem_jacobians(&pr, &opts);
        }
    }

    fn check_problem_jacobians(pr: &Prepared, opts: &MultiPoseOptions) {
        assert_eq!(pr.intervals.len(), 5);
        for model in MultiPoseModel::ALL {
            let np = model.param_count();
            let problem = Problem {
                intervals: &pr.intervals,
                links: &pr.links,
                g: opts.gravity,
                model,
                whitening: &pr.whitening,
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

    /// [`wiener_cross_covariance`] against the definition `Σ_i Σ_j A_i B_jᵀ κ(t_i, t_j)`
    /// summed directly (O(n²)), for terms on both sides of `t_ref`, at `t_ref` and at equal
    /// times, in random order.
    #[test]
    fn wiener_cross_covariance_matches_the_double_sum() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let t_ref = 5_000_000_000i64;
        let mut terms = |n: usize| -> Vec<(i64, Matrix3<f64>)> {
            (0..n)
                .map(|i| {
                    let t = if i == 0 {
                        t_ref
                    } else if i == 1 {
                        t_ref + 1_000_000_000
                    } else {
                        rng.random_range(0..10_000_000_000i64)
                    };
                    (t, Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0)))
                })
                .collect()
        };
        let (a, b) = (terms(40), terms(25));
        let kappa = |s: i64, t: i64| {
            let (ds, dt) = (s - t_ref, t - t_ref);
            if (ds > 0 && dt > 0) || (ds < 0 && dt < 0) {
                ds.abs().min(dt.abs()) as f64 * 1e-9
            } else {
                0.0
            }
        };
        for (x, y) in [(&a, &b), (&a, &a), (&b, &a)] {
            let mut direct = Matrix3::zeros();
            for (ti, ci) in x.iter() {
                for (tj, cj) in y.iter() {
                    direct += ci * cj.transpose() * kappa(*ti, *tj);
                }
            }
            let fast = wiener_cross_covariance(x, y, t_ref);
            assert!(
                (fast - direct).amax() < 1e-12 * direct.amax(),
                "{fast} vs {direct}"
            );
        }
    }

    /// The mean of a walk over an interval centred on `t_ref` has variance `σ_b²·T/12`
    /// (the static problem's term, `static_bias` module docs); two interval means after
    /// `t_ref` covary by `σ_b²·(mid-time of the earlier − t_ref)`; opposite sides: 0.
    #[test]
    fn interval_mean_variances_are_the_closed_forms() {
        let dt = 5_000_000i64; // 200 Hz
        let mean = |from: i64, n: usize| -> Vec<(i64, Matrix3<f64>)> {
            (0..n)
                .map(|i| (from + i as i64 * dt, Matrix3::identity() / n as f64))
                .collect()
        };
        let t_ref = 50 * dt * 1000;
        // 2001 samples centred on t_ref: T = 2001·Δt.
        let c = mean(t_ref - 1000 * dt, 2001);
        let t = 2001.0 * dt as f64 * 1e-9;
        let v = wiener_cross_covariance(&c, &c, t_ref)[(0, 0)];
        assert!((v / (t / 12.0) - 1.0).abs() < 1e-5, "{v} vs {}", t / 12.0);
        let a = mean(t_ref + 400 * dt, 600);
        let b = mean(t_ref + 1500 * dt, 300);
        let ab = wiener_cross_covariance(&a, &b, t_ref);
        let mid_a = (400.0 + 299.5) * dt as f64 * 1e-9;
        assert!((ab - Matrix3::identity() * mid_a).amax() < 1e-12, "{ab}");
        let before = mean(t_ref - 900 * dt, 300);
        assert_eq!(
            wiener_cross_covariance(&a, &before, t_ref),
            Matrix3::zeros()
        );
    }

    /// The link drift coefficients are the derivative of the rotation preintegration with
    /// respect to a per-sample bias perturbation: checked with Ridders ([`check_jacobian`]) on
    /// `θ ↦ ΔR(b_g + w(θ))`, `w_i(θ) = θ₀ + θ₁τ_i + θ₂ sin(2πτ_i)` (τ ∈ [0, 1] along a
    /// rotating window), and `Σ_i C_i = ∂ΔR/∂b_g`.
    #[test]
    fn rotation_drift_coefficients_are_the_per_sample_bias_derivative() {
        let (samples, _) = data();
        let seg = &samples[350..800];
        let bg = Vector3::new(0.002, -0.001, 0.003);
        let (t0, t1) = (seg[0].t_ns, seg[seg.len() - 1].t_ns);
        let tau = |t: i64| (t - t0) as f64 / (t1 - t0) as f64;
        let basis = |t: i64| [1.0, tau(t), (2.0 * std::f64::consts::PI * tau(t)).sin()];
        let f = |th: &SVector<f64, 9>| {
            let shifted: Vec<ImuSample> = seg
                .iter()
                .map(|s| {
                    let b = basis(s.t_ns);
                    let w = (0..3).fold(Vector3::zeros(), |acc, k| {
                        acc + th.fixed_rows::<3>(3 * k).into_owned() * b[k]
                    });
                    ImuSample::new(s.t_ns, s.gyro - w, s.acc)
                })
                .collect();
            rotation_preintegration(&shifted, &bg, &Vector3::zeros()).0
        };
        let c = rotation_drift_coefficients(seg, &bg);
        let mut jac = DMatrix::zeros(3, 9);
        for (s, ci) in seg.iter().zip(&c) {
            for (k, bk) in basis(s.t_ns).iter().enumerate() {
                let mut blk = jac.view_mut((0, 3 * k), (3, 3));
                blk += ci * *bk;
            }
        }
        let rep = check_jacobian(f, &SVector::zeros(), &[jac], &CheckOptions::default()).unwrap();
        println!("drift coefficients: {:.2e}", rep.worst_rel_error);
        let (_, jb, _) = rotation_preintegration(seg, &bg, &Vector3::zeros());
        let sum: Matrix3<f64> = c.iter().sum();
        assert!((sum - jb).amax() < 1e-12 * jb.amax(), "{sum} vs {jb}");
    }

    /// The random-walk covariance `Σ_w` against Monte Carlo: noise-free `sim` data of a
    /// 5-pose protocol (S = I), plus bias random walks drawn here, one-sided from the first
    /// sample (`b_k = b_k−1 + σ_b√Δt z_k`, ARCHITECTURE.md; not the model's two-sided
    /// construction), 1500 draws; the raw residuals at the truth (true attitudes, `b̄` = the
    /// drawn walk at `t_ref`) through the nonlinear residual function. Every entry of the
    /// empirical covariance is within 5 of its sampling standard deviations
    /// `√((Σ_ij² + Σ_ii Σ_jj)/n)` of `Σ_w`, and every variance within 5·√(2/n) relative.
    #[test]
    fn random_walk_covariance_matches_monte_carlo() {
        use rand::{RngExt, SeedableRng};
        use rand_distr::StandardNormal;
        let poses = five_poses();
        let scene = MultiPoseStaticScene::new(poses.clone(), 3.0, 2.0, Vector3::zeros()).unwrap();
        let clean = simulate(&scene, 200.0, scene.duration_s(), &SimConfig::default(), 1)
            .unwrap()
            .samples;
        let noise = ImuNoise::euroc();
        let base = MultiPoseOptions {
            still: Some(StillOptions::from_noise(&noise, 200.0)),
            include_random_walk: false,
            ..MultiPoseOptions::default()
        };
        let pr0 = prepare(&clean, &noise, &base, 9.81).unwrap();
        let white = ImuNoise {
            gyro_random_walk: 0.0,
            acc_random_walk: 0.0,
            ..noise
        };
        let args = |nz: &ImuNoise| {
            residual_covariance(
                &clean,
                nz,
                &pr0.ivs,
                &pr0.intervals,
                &pr0.links,
                &pr0.bg0,
                pr0.t_ref_ns,
            )
        };
        let sigma_w = args(&noise) - args(&white);
        let m = sigma_w.nrows();
        let k_ref = clean.iter().position(|s| s.t_ns == pr0.t_ref_ns).unwrap();
        let dt = 0.005f64;
        let mut rng = rand::rngs::StdRng::seed_from_u64(99);
        let draws = 1500;
        let mut emp = DMatrix::<f64>::zeros(m, m);
        for _ in 0..draws {
            let (mut bg, mut ba) = (Vector3::zeros(), Vector3::zeros());
            let mut walk = Vec::with_capacity(clean.len());
            for k in 0..clean.len() {
                if k > 0 {
                    let z = |rng: &mut rand::rngs::StdRng| {
                        Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal))
                    };
                    bg += z(&mut rng) * (noise.gyro_random_walk * dt.sqrt());
                    ba += z(&mut rng) * (noise.acc_random_walk * dt.sqrt());
                }
                walk.push((bg, ba));
            }
            let data: Vec<ImuSample> = clean
                .iter()
                .zip(&walk)
                .map(|(s, (g, a))| ImuSample::new(s.t_ns, s.gyro + g, s.acc + a))
                .collect();
            let pr = prepare(&data, &noise, &base, 9.81).unwrap();
            assert_eq!(pr.ivs, pr0.ivs);
            assert_eq!(pr.t_ref_ns, pr0.t_ref_ns);
            let problem = Problem {
                intervals: &pr.intervals,
                links: &pr.links,
                g: base.gravity,
                model: MultiPoseModel::BiasOnly,
                whitening: &pr.whitening,
            };
            let mut p = DVector::zeros(6);
            p.fixed_rows_mut::<3>(0).copy_from(&walk[k_ref].0);
            p.fixed_rows_mut::<3>(3).copy_from(&walk[k_ref].1);
            let (e, _) = problem.eval_raw(&(p, poses.clone()), false);
            emp += &e * e.transpose();
        }
        emp /= draws as f64;
        let n = draws as f64;
        let (mut worst, mut worst_var) = (0.0f64, 0.0f64);
        for i in 0..m {
            for j in 0..m {
                let (sij, sii, sjj) = (sigma_w[(i, j)], sigma_w[(i, i)], sigma_w[(j, j)]);
                let sd = ((sij * sij + sii * sjj) / n).sqrt();
                worst = worst.max((emp[(i, j)] - sij).abs() / sd);
            }
            worst_var = worst_var.max((emp[(i, i)] / sigma_w[(i, i)] - 1.0).abs());
        }
        println!(
            "Σ_w vs Monte Carlo ({draws} draws, {m} residuals): worst entry {worst:.2} sd, worst \
             variance ratio error {:.1} %",
            100.0 * worst_var
        );
        assert!(worst <= 5.0, "{worst}");
        assert!(worst_var <= 5.0 * (2.0 / n).sqrt(), "{worst_var}");
    }
}
