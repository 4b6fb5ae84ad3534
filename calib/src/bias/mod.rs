//! Bias estimation problems ("model no more than the data supports").
//!
//! - [`still`]: still-interval detection by moving variance (multi-position protocol).
//! - [`static_bias`]: one static attitude → gyro bias and gravity direction (roll, pitch); the
//!   accelerometer bias is reported unobservable unless a prior is given.
//! - [`multipose`]: several static attitudes linked by gyro preintegration (Tedaldi et al. 2014,
//!   imu_tk) → gyro and accelerometer bias, attitude of each still interval, optional scale
//!   factors and misalignments (accelerometer lower-triangular, gyro full), the model chosen
//!   by BIC among the identifiable, converged candidates; the bias random walk is
//!   marginalised (its covariance, which correlates intervals and links, whitens the stacked
//!   residual), so the biases are those at a reference time and no parameter is added.
//! - [`known_poses`]: segments with known, optionally noisy poses → biases, velocities and
//!   gravity direction from preintegration factors (ORB-SLAM3 inertial-only initialisation,
//!   VINS-Mono gyro bias), the pose noise propagated into every residual block with the
//!   correlation between factors that share a pose.
//!
//! Conventions (`docs/ARCHITECTURE.md`): world z up, gravity `g = (0, 0, −9.81)` m/s² by
//! default; the accelerometer measures specific force `a_m = R_wbᵀ(a_w − g) + b_a + n_a` (so at
//! rest `a_m = R_wbᵀ(−g) + b_a`, +9.81 on the up axis; [`multipose`] adds `S_a`, `S_g`); gyro
//! `ω_m = ω_b + b_g + n_g`; rotation perturbations on the right `R ← R·Exp(δφ)`; bias order
//! **[b_g, b_a]**; integer-ns time.
//! Noise figures are Kalibr densities ([`preint::ImuNoise`]): a mean of white noise of density σ
//! over `T` seconds has standard deviation `σ/√T`.
//!
//! Every estimate comes with a standard deviation from the solver covariance `(JᵀJ)⁻¹` of the
//! whitened problem, i.e. predicted from the noise densities (not rescaled by the residuals),
//! so it is wrong if the densities are; each result also reports `chi2` so that this can be
//! checked (`chi2/dof ≈ 1` when the densities are right).

pub mod known_poses;
pub mod multipose;
pub mod static_bias;
pub mod still;

use crate::gauss_newton::GnError;
use nalgebra::{Matrix2x3, Vector3};
use preint::{ImuNoise, ImuSample, PreintError};
use preint_lie::SO3;

/// Errors of the bias-estimation problems. Each names the input at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BiasError {
    /// Not enough samples (or still intervals, poses) for the problem.
    #[error("too few {what}: {found}, need at least {needed}")]
    TooFew {
        /// What is counted (`"samples"`, `"still intervals"`, `"poses"`).
        what: &'static str,
        /// How many were given / found.
        found: usize,
        /// How many are needed.
        needed: usize,
    },
    /// A sample holds NaN or ∞.
    #[error("sample {index} (t = {t_ns} ns): non-finite value")]
    NonFinite {
        /// Sample index.
        index: usize,
        /// Its timestamp \[ns\].
        t_ns: i64,
    },
    /// Timestamps are not strictly increasing.
    #[error("sample {index} (t = {t_ns} ns): timestamp not after the previous one")]
    NotIncreasing {
        /// Sample index.
        index: usize,
        /// Its timestamp \[ns\].
        t_ns: i64,
    },
    /// A noise density or option is out of its domain.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The preintegration of a window failed.
    #[error("preintegration: {0}")]
    Preint(#[from] PreintError),
    /// The Gauss-Newton solver failed.
    #[error("solver: {0}")]
    Solver(#[from] GnError),
}

/// Checks finite values and strictly increasing timestamps; needs at least `min` samples.
pub(crate) fn check_samples(samples: &[ImuSample], min: usize) -> Result<(), BiasError> {
    if samples.len() < min {
        return Err(BiasError::TooFew {
            what: "samples",
            found: samples.len(),
            needed: min,
        });
    }
    for (i, s) in samples.iter().enumerate() {
        if !(s.gyro.iter().all(|v| v.is_finite()) && s.acc.iter().all(|v| v.is_finite())) {
            return Err(BiasError::NonFinite {
                index: i,
                t_ns: s.t_ns,
            });
        }
        if i > 0 && s.t_ns <= samples[i - 1].t_ns {
            return Err(BiasError::NotIncreasing {
                index: i,
                t_ns: s.t_ns,
            });
        }
    }
    Ok(())
}

/// Checks that the white-noise densities are finite and > 0 and the random walks finite ≥ 0.
pub(crate) fn check_noise(noise: &ImuNoise) -> Result<(), BiasError> {
    let pos = [
        ("gyro_noise_density", noise.gyro_noise_density),
        ("acc_noise_density", noise.acc_noise_density),
    ];
    for (name, v) in pos {
        if !(v.is_finite() && v > 0.0) {
            return Err(BiasError::InvalidParameter {
                name,
                reason: format!("must be finite and > 0, got {v}"),
            });
        }
    }
    let nonneg = [
        ("gyro_random_walk", noise.gyro_random_walk),
        ("acc_random_walk", noise.acc_random_walk),
    ];
    for (name, v) in nonneg {
        if !(v.is_finite() && v >= 0.0) {
            return Err(BiasError::InvalidParameter {
                name,
                reason: format!("must be finite and ≥ 0, got {v}"),
            });
        }
    }
    Ok(())
}

pub(crate) fn check_gravity(g: &Vector3<f64>) -> Result<f64, BiasError> {
    let n = g.norm();
    if !(n.is_finite() && n > 0.0) {
        return Err(BiasError::InvalidParameter {
            name: "gravity",
            reason: format!("must be finite and non-zero, got {g:?}"),
        });
    }
    Ok(n)
}

/// Sufficient statistics of a run of samples: per-axis means and sample variances of ω and a,
/// the count N and the mean sample period (`(t_last − t_first)/(N − 1)`) \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentStats {
    /// Number of samples N.
    pub count: usize,
    /// Mean sample period Δt \[s\].
    pub dt: f64,
    /// Mean gyro reading ω̄ [rad/s].
    pub gyro_mean: Vector3<f64>,
    /// Sample variance of the gyro readings per axis [(rad/s)²].
    pub gyro_var: Vector3<f64>,
    /// Mean specific force f̄ [m/s²].
    pub acc_mean: Vector3<f64>,
    /// Sample variance of the accelerometer readings per axis [(m/s²)²].
    pub acc_var: Vector3<f64>,
}

impl SegmentStats {
    /// Statistics of `samples` (≥ 2 samples, increasing timestamps, not re-checked). Sums
    /// are shifted by the first sample for accuracy.
    pub fn of(samples: &[ImuSample]) -> Self {
        let n = samples.len();
        let (g0, a0) = (samples[0].gyro, samples[0].acc);
        let (mut sg, mut sg2, mut sa, mut sa2) = (
            Vector3::zeros(),
            Vector3::zeros(),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        for s in samples {
            let dg = s.gyro - g0;
            let da = s.acc - a0;
            sg += dg;
            sg2 += dg.component_mul(&dg);
            sa += da;
            sa2 += da.component_mul(&da);
        }
        let nf = n as f64;
        let var = |s: Vector3<f64>, s2: Vector3<f64>| {
            if n > 1 {
                (s2 - s.component_mul(&s) / nf) / (nf - 1.0)
            } else {
                Vector3::zeros()
            }
        };
        let dt = if n > 1 {
            (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (nf - 1.0)
        } else {
            0.0
        };
        Self {
            count: n,
            dt,
            gyro_mean: g0 + sg / nf,
            gyro_var: var(sg, sg2),
            acc_mean: a0 + sa / nf,
            acc_var: var(sa, sa2),
        }
    }

    /// Effective averaging time `T = N·Δt` \[s\]: the mean of N samples of white noise of
    /// density σ has standard deviation `σ/√T` (per-sample std `σ/√Δt`).
    pub fn averaging_time(&self) -> f64 {
        self.count as f64 * self.dt
    }
}

/// Roll and pitch \[rad\] (Z-Y-X Euler angles, `R_wb = Rz(yaw)·Ry(pitch)·Rx(roll)`) of the body
/// "up" unit vector `u = R_wbᵀ·ẑ`: `u = (−sin p, sin r cos p, cos r cos p)`, so
/// `roll = atan2(u_y, u_z)`, `pitch = atan2(−u_x, √(u_y² + u_z²))`. Also returns
/// `∂(roll, pitch)/∂u` (2×3).
pub fn roll_pitch_of_up(u: &Vector3<f64>) -> (f64, f64, Matrix2x3<f64>) {
    let u = u / u.norm();
    let ryz2 = u.y * u.y + u.z * u.z;
    let ryz = ryz2.sqrt();
    let roll = u.y.atan2(u.z);
    let pitch = (-u.x).atan2(ryz);
    let mut j = Matrix2x3::zeros();
    if ryz2 > 0.0 {
        j[(0, 1)] = u.z / ryz2;
        j[(0, 2)] = -u.y / ryz2;
        j[(1, 0)] = -ryz;
        j[(1, 1)] = u.x * u.y / ryz;
        j[(1, 2)] = u.x * u.z / ryz;
    }
    (roll, pitch, j)
}

/// The zero-yaw attitude `R_wb = Ry(pitch)·Rx(roll)` \[rad\].
pub fn attitude_from_roll_pitch(roll: f64, pitch: f64) -> SO3 {
    SO3::exp(&Vector3::new(0.0, pitch, 0.0)).compose(&SO3::exp(&Vector3::new(roll, 0.0, 0.0)))
}

/// A rotation `R` with `Rᵀ·up_w = u_b` (both unit vectors): the minimal rotation taking
/// `u_b` to `up_w`; for the default z-up world, the zero-yaw attitude of
/// [`roll_pitch_of_up`]`(u_b)`.
pub(crate) fn attitude_from_up(u_b: &Vector3<f64>, up_w: &Vector3<f64>) -> SO3 {
    let u = u_b.normalize();
    let w = up_w.normalize();
    if (w - Vector3::z()).norm() < 1e-12 {
        let (r, p, _) = roll_pitch_of_up(&u);
        return attitude_from_roll_pitch(r, p);
    }
    let axis = u.cross(&w);
    let s = axis.norm();
    let c = u.dot(&w);
    if s < 1e-12 {
        if c > 0.0 {
            return SO3::identity();
        }
        // Antiparallel: half turn about any axis perpendicular to u.
        let perp = if u.x.abs() < 0.9 {
            u.cross(&Vector3::x())
        } else {
            u.cross(&Vector3::y())
        };
        return SO3::exp(&(perp.normalize() * std::f64::consts::PI));
    }
    // R u = w with R = Exp(axis·θ).
    SO3::exp(&(axis / s * s.atan2(c)))
}

pub use known_poses::{KnownPose, KnownPoseCalibration, KnownPoseOptions, calibrate_known_poses};
pub use multipose::{
    ModelFit, MultiPoseCalibration, MultiPoseModel, MultiPoseOptions, calibrate_multi_pose,
};
pub use static_bias::{AccBiasPrior, StaticCalibration, StaticOptions, calibrate_static};
pub use still::{StillInterval, StillOptions, detect_still_intervals};
