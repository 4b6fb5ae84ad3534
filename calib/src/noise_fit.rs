//! Maximum-likelihood IMU noise densities and ground-truth errors from the residuals of IMU
//! factors at known states.
//!
//! Each window `w` (a 9-dof `ImuFactor` between two ground-truth states) has a residual
//! `r_w ∈ ℝ⁹` whose covariance is linear in the squared parameters
//! `θ = [N_g², N_a², K_g², K_a², σ_R², σ_p², σ_v², σ_bg², σ_ba²]` ([`Param`]):
//!
//! `Σ_w(θ) = Σ_k θ_k A_{w,k}`,
//!
//! with `A_{w,N_g}`, `A_{w,N_a}` the preintegration covariance at unit white-noise density
//! (the noise enters as `σ²/h` per sample, so the covariance is linear in `σ²`), `A_{w,K_g}`,
//! `A_{w,K_a}` the deltas' block of the combined covariance at unit bias random walk (the factor
//! holds the bias constant while the true bias drifts), `A_{w,R|p|v} = J_i P J_iᵀ + J_j P J_jᵀ`
//! with `P` the unit diagonal of that block of the `NavState` tangent, and
//! `A_{w,bg|ba} = J_b P J_bᵀ` through the bias Jacobian.
//!
//! With `r_w ~ N(0, Σ_w(θ))` independent, the log-likelihood is
//! `ℓ(θ) = −½ Σ_w [log det Σ_w + r_wᵀ Σ_w⁻¹ r_w]`, its gradient
//! `g_k = ½ Σ_w [r_wᵀ Σ_w⁻¹ A_k Σ_w⁻¹ r_w − tr(Σ_w⁻¹ A_k)]` and the Fisher information
//! `F_kl = ½ Σ_w tr(Σ_w⁻¹ A_k Σ_w⁻¹ A_l)` (Gaussian ML with a parameter-dependent covariance:
//! S. M. Kay, *Fundamentals of Statistical Signal Processing*, vol. I: Estimation Theory,
//! Prentice Hall 1993, §3.9 (eq. 3.31) and §7.8). Fisher scoring `θ ← θ + F⁻¹ g` keeps
//! `θ ≥ 0`: a parameter on the bound 0 whose gradient points below it is held there for the
//! step (projected Fisher scoring), and a step that lowers `ℓ` is halved. The standard deviation
//! of `θ_k` is `√(F⁻¹)_kk` (the Cramér–Rao bound, attained asymptotically by the MLE) for
//! independent windows, and the sandwich covariance of [`sandwich`] when windows share data
//! (several lengths cut from one recording); that of a density `N = √θ` is `σ_θ / (2N)`.
//!
//! A parameter is withheld ([`Withheld`]) when it was held at a given value, when it sits on the
//! bound 0 (its `2σ` upper bound is reported instead) or when its `σ` exceeds its value (the
//! windows cannot separate it from the others). Windows of several lengths separate the white
//! noise (`∝ T` in rotation), the random walk (`∝ T³`) and the ground truth's error
//! (independent of `T`).
//!
//! The ground truth's world frame need not be aligned with gravity (a motion-capture frame is
//! levelled to a fraction of a degree): with [`NoiseFitOptions::fit_gravity`] the residual's
//! mean `G_w δg` is fitted too, `G_w = ∂r_w/∂g` the residual's (exactly linear) dependence on the
//! world gravity vector ([`gravity`]). The correction is kept only when the Bayesian
//! information criterion supports its three parameters (`2Δℓ > 3 ln n`, `n` the residual
//! components; G. Schwarz, *Ann. Statist.* 6(2), 1978); otherwise the fit without it stands and
//! the correction is reported as not supported.

use nalgebra::{DMatrix, DVector, SMatrix, SVector};

pub mod gravity;
pub mod sandwich;
pub use gravity::GravityEstimate;

/// Number of parameters.
pub const PARAMS: usize = 9;

/// The parameters, in the order of `θ` (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// Gyroscope white-noise density `N_g` [rad/s/√Hz].
    GyroNoiseDensity,
    /// Accelerometer white-noise density `N_a` [m/s²/√Hz].
    AccNoiseDensity,
    /// Gyroscope bias random walk `K_g` [rad/s²/√Hz].
    GyroRandomWalk,
    /// Accelerometer bias random walk `K_a` [m/s³/√Hz].
    AccRandomWalk,
    /// Ground-truth attitude error `σ_R` \[rad\].
    RotStd,
    /// Ground-truth position error `σ_p` \[m\].
    PosStd,
    /// Ground-truth velocity error `σ_v` [m/s].
    VelStd,
    /// Ground-truth gyroscope-bias error `σ_bg` [rad/s].
    BiasGyroStd,
    /// Ground-truth accelerometer-bias error `σ_ba` [m/s²].
    BiasAccStd,
}

impl Param {
    /// All nine, in the order of `θ`.
    pub const ALL: [Param; PARAMS] = [
        Param::GyroNoiseDensity,
        Param::AccNoiseDensity,
        Param::GyroRandomWalk,
        Param::AccRandomWalk,
        Param::RotStd,
        Param::PosStd,
        Param::VelStd,
        Param::BiasGyroStd,
        Param::BiasAccStd,
    ];

    /// The unit of the parameter (of `√θ_k`).
    pub fn unit(self) -> &'static str {
        match self {
            Param::GyroNoiseDensity => "rad/s/√Hz",
            Param::AccNoiseDensity => "m/s²/√Hz",
            Param::GyroRandomWalk => "rad/s²/√Hz",
            Param::AccRandomWalk => "m/s³/√Hz",
            Param::RotStd => "rad",
            Param::PosStd => "m",
            Param::VelStd => "m/s",
            Param::BiasGyroStd => "rad/s",
            Param::BiasAccStd => "m/s²",
        }
    }
}

/// One window: its residual and the basis of its covariance, `Σ(θ) = Σ_k θ_k basis[k]`.
#[derive(Clone, Debug)]
pub struct NoiseWindow {
    /// The window's length \[s\] (groups the χ² per length).
    pub length_s: f64,
    /// The residual `r` (order [r_φ, r_v, r_p]).
    pub r: SVector<f64, 9>,
    /// `A_k`, in the order of [`Param::ALL`].
    pub basis: [SMatrix<f64, 9, 9>; PARAMS],
    /// `G = ∂r/∂g`, the residual's Jacobian with respect to the world gravity vector
    /// \[(rad, m/s, m) per m/s²\] (zero when the mean is not fitted).
    pub gravity_jacobian: SMatrix<f64, 9, 3>,
    /// The stretch of the recording the window lies in: windows of one block may share data,
    /// windows of different blocks do not ([`sandwich`]; one block per window when the windows
    /// are independent).
    pub block: usize,
}

/// Why a parameter has no fitted value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Withheld {
    /// Held at the given value.
    Held,
    /// On the bound 0; the data put it below `upper` (2σ) [unit of the parameter].
    AtBound {
        /// The 2σ upper bound of `√θ`.
        upper: f64,
    },
    /// Its σ exceeds its value: the windows do not separate it from the others.
    NotSeparable,
}

impl Withheld {
    /// One line: why the parameter is not reported.
    pub fn reason(&self, unit: &str) -> String {
        match self {
            Withheld::Held => "held at the given value".into(),
            Withheld::AtBound { upper } => {
                format!("at the bound 0: no evidence for it, below {upper:.2e} {unit} (2σ)")
            }
            Withheld::NotSeparable => {
                "not separable: its σ exceeds its value (the windows cannot tell it from the \
                 others)"
                    .into()
            }
        }
    }
}

/// One parameter's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamEstimate {
    /// Which parameter.
    pub param: Param,
    /// `√θ` [unit of the parameter] (the held value when held).
    pub value: f64,
    /// Its σ, `σ_θ / (2√θ)` (infinite when unknown; 0 when held).
    pub std: f64,
    /// `θ` and its σ `√(F⁻¹)_kk`.
    pub theta: (f64, f64),
    /// `None`: fitted and reported.
    pub withheld: Option<Withheld>,
}

/// χ² of the windows of one length.
#[derive(Clone, Debug, PartialEq)]
pub struct LengthChi2 {
    /// The length \[s\].
    pub length_s: f64,
    /// Windows of that length.
    pub count: usize,
    /// Mean `χ²/dof` at the start values (NaN when `Σ` was not positive definite there).
    pub before: f64,
    /// Mean `χ²/dof` at the estimate.
    pub after: f64,
    /// Sum of the χ² at the estimate.
    pub chi2_after: f64,
}

/// The estimate.
#[derive(Clone, Debug)]
pub struct NoiseFit {
    /// One per parameter, in the order of [`Param::ALL`].
    pub params: Vec<ParamEstimate>,
    /// Fisher-scoring iterations.
    pub iterations: usize,
    /// `ℓ(θ)` at the estimate.
    pub log_likelihood: f64,
    /// Per window length, in increasing length.
    pub per_length: Vec<LengthChi2>,
    /// The world gravity correction, when [`NoiseFitOptions::fit_gravity`] asked for it.
    pub gravity: Option<GravityEstimate>,
}

/// Why the estimator cannot answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NoiseFitError {
    /// Too few windows.
    #[error(
        "{windows} windows for {free} free parameters: give a longer recording or more window lengths"
    )]
    TooFewWindows {
        /// Windows given.
        windows: usize,
        /// Parameters to fit.
        free: usize,
    },
    /// A start value or held value is negative or not finite.
    #[error("parameter {0:?}: the start or held value must be finite and ≥ 0")]
    BadValue(Param),
    /// `Σ_w(θ)` is not positive definite.
    #[error(
        "the covariance of window {0} is not positive definite at the start: give non-zero start values"
    )]
    Singular(usize),
}

struct Eval {
    ll: f64,
    grad: SVector<f64, PARAMS>,
    fisher: SMatrix<f64, PARAMS, PARAMS>,
}

/// `Σ_w(θ) = Σ_k θ_k A_{w,k}`, the covariance of the window's residual at `θ`.
pub fn covariance(w: &NoiseWindow, theta: &SVector<f64, PARAMS>) -> SMatrix<f64, 9, 9> {
    sigma(w, theta)
}

/// `θ` of the estimate (0 for a parameter withheld on its bound), in the order of
/// [`Param::ALL`].
pub fn theta_of(fit: &NoiseFit) -> SVector<f64, PARAMS> {
    SVector::from_fn(|k, _| fit.params[k].theta.0)
}

fn sigma(w: &NoiseWindow, theta: &SVector<f64, PARAMS>) -> SMatrix<f64, 9, 9> {
    (0..PARAMS).fold(SMatrix::zeros(), |s, k| s + w.basis[k] * theta[k])
}

/// `ℓ`, `g` and `F` at `θ` for the residuals `res` (one per window); the index of the first
/// window whose `Σ_w` is not positive definite otherwise.
fn evaluate(
    windows: &[NoiseWindow],
    res: &[SVector<f64, 9>],
    theta: &SVector<f64, PARAMS>,
) -> Result<Eval, usize> {
    let mut e = Eval {
        ll: 0.0,
        grad: SVector::zeros(),
        fisher: SMatrix::zeros(),
    };
    for (i, (w, r)) in windows.iter().zip(res).enumerate() {
        let chol = sigma(w, theta).cholesky().ok_or(i)?;
        let logdet: f64 = 2.0 * chol.l_dirty().diagonal().map(f64::ln).sum();
        let u = chol.solve(r);
        e.ll -= 0.5 * (logdet + r.dot(&u));
        let b: Vec<SMatrix<f64, 9, 9>> = w.basis.iter().map(|a| chol.solve(a)).collect();
        for k in 0..PARAMS {
            e.grad[k] += 0.5 * (u.dot(&(w.basis[k] * u)) - b[k].trace());
            for l in k..PARAMS {
                let f = 0.5 * b[k].component_mul(&b[l].transpose()).sum();
                e.fisher[(k, l)] += f;
                if l != k {
                    e.fisher[(l, k)] += f;
                }
            }
        }
    }
    Ok(e)
}

/// `F_ss⁻¹` on the index set `s` (infinite diagonal where it is singular).
fn inverse_on(f: &SMatrix<f64, PARAMS, PARAMS>, s: &[usize]) -> DMatrix<f64> {
    let n = s.len();
    let d: Vec<f64> = s.iter().map(|&k| f[(k, k)].max(0.0).sqrt()).collect();
    let m = DMatrix::from_fn(n, n, |i, j| f[(s[i], s[j])] / (d[i] * d[j]));
    match (d.iter().all(|x| *x > 0.0), m.clone().cholesky()) {
        (true, Some(c)) if c.l_dirty().diagonal().min() > 1e-7 => {
            DMatrix::from_fn(n, n, |i, j| c.inverse()[(i, j)] / (d[i] * d[j]))
        }
        _ => DMatrix::from_element(n, n, f64::INFINITY),
    }
}

/// The projected Fisher-scoring step on the free set: `F_ff⁻¹ g_f`, parameters on the bound
/// with a gradient pointing below it left out.
fn step(e: &Eval, theta: &SVector<f64, PARAMS>, free: &[usize]) -> SVector<f64, PARAMS> {
    let active: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&k| theta[k] > 0.0 || e.grad[k] > 0.0)
        .collect();
    let mut out = SVector::zeros();
    if active.is_empty() {
        return out;
    }
    let n = active.len();
    let d: Vec<f64> = active
        .iter()
        .map(|&k| e.fisher[(k, k)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let m = DMatrix::from_fn(n, n, |i, j| {
        e.fisher[(active[i], active[j])] / (d[i] * d[j])
    });
    let g = DVector::from_fn(n, |i, _| e.grad[active[i]] / d[i]);
    let x = m
        .svd(true, true)
        .solve(&g, 1e-10)
        .unwrap_or_else(|_| DVector::zeros(n));
    for (i, &k) in active.iter().enumerate() {
        out[k] = x[i] / d[i];
    }
    out
}

/// The moment start of a free parameter with no start value: the residual energy
/// `Σ_w ‖r_w‖²` shared equally among the `n_free` free parameters, `θ_k = E / (n_free Σ_w tr A_k)`.
fn moment_start(windows: &[NoiseWindow], k: usize, n_free: usize) -> f64 {
    let energy: f64 = windows.iter().map(|w| w.r.norm_squared()).sum();
    let trace: f64 = windows.iter().map(|w| w.basis[k].trace()).sum();
    if trace > 0.0 {
        energy / (n_free as f64 * trace)
    } else {
        0.0
    }
}

/// The options of [`fit`].
#[derive(Clone, Copy, Debug)]
pub struct NoiseFitOptions {
    /// Start values of `√θ` (0: the moment start for a free parameter).
    pub start: [f64; PARAMS],
    /// Held values of `√θ` (`Some`: not fitted).
    pub held: [Option<f64>; PARAMS],
    /// Most Fisher-scoring iterations.
    pub max_iterations: usize,
    /// Fit the world gravity correction (module docs; needs each window's
    /// [`NoiseWindow::gravity_jacobian`]).
    pub fit_gravity: bool,
}

impl Default for NoiseFitOptions {
    fn default() -> Self {
        Self {
            start: [0.0; PARAMS],
            held: [None; PARAMS],
            max_iterations: 100,
            fit_gravity: false,
        }
    }
}

/// The maximum-likelihood estimate of `θ` from `windows` (module docs), and of the world
/// gravity correction when `opts.fit_gravity`.
pub fn fit(windows: &[NoiseWindow], opts: &NoiseFitOptions) -> Result<NoiseFit, NoiseFitError> {
    let plain = fit_with(windows, opts, false)?;
    if !opts.fit_gravity {
        return Ok(plain);
    }
    let with = fit_with(windows, opts, true)?;
    Ok(gravity::select(plain, with, 9 * windows.len()))
}

fn fit_with(
    windows: &[NoiseWindow],
    opts: &NoiseFitOptions,
    fit_gravity: bool,
) -> Result<NoiseFit, NoiseFitError> {
    let free: Vec<usize> = (0..PARAMS).filter(|&k| opts.held[k].is_none()).collect();
    if windows.len() * 9 < 2 * free.len().max(1) || windows.len() < 2 {
        return Err(NoiseFitError::TooFewWindows {
            windows: windows.len(),
            free: free.len(),
        });
    }
    let mut theta = SVector::<f64, PARAMS>::zeros();
    for k in 0..PARAMS {
        let v = opts.held[k].unwrap_or(opts.start[k]);
        if !(v.is_finite() && v >= 0.0) {
            return Err(NoiseFitError::BadValue(Param::ALL[k]));
        }
        theta[k] = v * v;
    }
    let raw: Vec<SVector<f64, 9>> = windows.iter().map(|w| w.r).collect();
    let before = evaluate(windows, &raw, &theta).ok().map(|_| theta);
    for &k in &free {
        if theta[k] == 0.0 {
            theta[k] = moment_start(windows, k, free.len());
        }
    }
    let mut dg = SVector::<f64, 3>::zeros();
    let mut res = raw.clone();
    let mut e = evaluate(windows, &res, &theta).map_err(NoiseFitError::Singular)?;
    let mut iterations = 0;
    while iterations < opts.max_iterations {
        iterations += 1;
        if fit_gravity {
            // Block coordinate ascent: the mean at θ is a generalised least-squares solve.
            dg = gravity::correction(windows, &theta).0;
            res = gravity::shifted(windows, &dg);
            e = evaluate(windows, &res, &theta).map_err(NoiseFitError::Singular)?;
        }
        let d = step(&e, &theta, &free);
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let t = (theta + d * alpha).map(|x| x.max(0.0));
            if let Ok(n) = evaluate(windows, &res, &t)
                && n.ll >= e.ll - 1e-12 * e.ll.abs()
            {
                accepted = Some((t, n));
                break;
            }
            alpha *= 0.5;
        }
        let Some((t, n)) = accepted else { break };
        let gain = n.ll - e.ll;
        let moved = (t - theta).abs().max() / theta.abs().max().max(f64::MIN_POSITIVE);
        theta = t;
        e = n;
        if gain.abs() < 1e-10 * e.ll.abs().max(1.0) && moved < 1e-6 {
            break;
        }
    }
    let j = sandwich::shared(windows).then(|| sandwich::score_variance(windows, &res, &theta));
    let gravity = fit_gravity.then(|| {
        let info_inv = gravity::correction(windows, &theta).1;
        GravityEstimate {
            correction: dg,
            cov: match &j {
                Some((_, jg)) => info_inv * jg * info_inv,
                None => info_inv,
            },
            lr: 0.0,
            penalty: 0.0,
            supported: true,
        }
    });
    Ok(NoiseFit {
        params: estimates(&e, &theta, &free, (opts, j.map(|j| j.0).as_ref())),
        iterations,
        log_likelihood: e.ll,
        per_length: per_length(windows, (&raw, before.as_ref()), (&res, &theta)),
        gravity,
    })
}

/// The covariance of `θ_s`: `F_ss⁻¹`, or the sandwich with the score variance `j` when the
/// windows share data ([`sandwich`]).
fn param_cov(e: &Eval, j: Option<&SMatrix<f64, PARAMS, PARAMS>>, s: &[usize]) -> DMatrix<f64> {
    let h_inv = inverse_on(&e.fisher, s);
    match j {
        Some(j) => sandwich::on(&h_inv, j, s),
        None => h_inv,
    }
}

fn estimates(
    e: &Eval,
    theta: &SVector<f64, PARAMS>,
    free: &[usize],
    (opts, j): (&NoiseFitOptions, Option<&SMatrix<f64, PARAMS, PARAMS>>),
) -> Vec<ParamEstimate> {
    let interior: Vec<usize> = free.iter().copied().filter(|&k| theta[k] > 0.0).collect();
    let cov = param_cov(e, j, &interior);
    Param::ALL
        .iter()
        .enumerate()
        .map(|(k, &param)| {
            if let Some(v) = opts.held[k] {
                return ParamEstimate {
                    param,
                    value: v,
                    std: 0.0,
                    theta: (v * v, 0.0),
                    withheld: Some(Withheld::Held),
                };
            }
            if let Some(i) = interior.iter().position(|&j| j == k) {
                let st = cov[(i, i)].max(0.0).sqrt();
                let value = theta[k].sqrt();
                let std = st / (2.0 * value);
                let separable = std <= value;
                let withheld = (!separable).then_some(Withheld::NotSeparable);
                return ParamEstimate {
                    param,
                    value,
                    std,
                    theta: (theta[k], st),
                    withheld,
                };
            }
            let mut with: Vec<usize> = interior.clone();
            with.push(k);
            let st = param_cov(e, j, &with)[(with.len() - 1, with.len() - 1)]
                .max(0.0)
                .sqrt();
            ParamEstimate {
                param,
                value: 0.0,
                std: f64::INFINITY,
                theta: (0.0, st),
                withheld: Some(Withheld::AtBound {
                    upper: (2.0 * st).sqrt(),
                }),
            }
        })
        .collect()
}

/// `rᵀ Σ(θ)⁻¹ r` of one window at the given gravity (NaN when `Σ` is not positive definite).
pub fn chi2(w: &NoiseWindow, theta: &SVector<f64, PARAMS>) -> f64 {
    chi2_of(w, &w.r, theta)
}

/// `rᵀ Σ(θ)⁻¹ r` of one window at the world gravity corrected by `dg` \[m/s²\].
pub fn chi2_corrected(w: &NoiseWindow, theta: &SVector<f64, PARAMS>, dg: &SVector<f64, 3>) -> f64 {
    chi2_of(w, &(w.r + w.gravity_jacobian * dg), theta)
}

fn chi2_of(w: &NoiseWindow, r: &SVector<f64, 9>, theta: &SVector<f64, PARAMS>) -> f64 {
    sigma(w, theta)
        .cholesky()
        .map_or(f64::NAN, |c| r.dot(&c.solve(r)))
}

type Residuals<'a> = &'a [SVector<f64, 9>];

fn per_length(
    windows: &[NoiseWindow],
    (raw, before): (Residuals, Option<&SVector<f64, PARAMS>>),
    (res, after): (Residuals, &SVector<f64, PARAMS>),
) -> Vec<LengthChi2> {
    let mut lengths: Vec<f64> = windows.iter().map(|w| w.length_s).collect();
    lengths.sort_by(f64::total_cmp);
    lengths.dedup();
    lengths
        .into_iter()
        .map(|l| {
            let of: Vec<usize> = (0..windows.len())
                .filter(|&i| windows[i].length_s == l)
                .collect();
            let n = of.len() as f64;
            let sum = |r: Residuals, t: &SVector<f64, PARAMS>| {
                of.iter()
                    .map(|&i| chi2_of(&windows[i], &r[i], t))
                    .sum::<f64>()
            };
            let chi2_after = sum(res, after);
            LengthChi2 {
                length_s: l,
                count: of.len(),
                before: before.map_or(f64::NAN, |t| sum(raw, t) / (9.0 * n)),
                after: chi2_after / (9.0 * n),
                chi2_after,
            }
        })
        .collect()
}

#[cfg(test)]
#[path = "noise_fit_tests.rs"]
mod tests;
