//! Visual-inertial initialisation: gravity, scale, keyframe velocities and the IMU biases from
//! a short window of keyframe poses known up to scale (a monocular front end) or metric, with
//! their joint covariance and a verdict on whether they are known well enough to start a
//! visual-inertial estimator.
//!
//! # Method
//! 1. A linear start ([`linear`]: VINS-Mono's alignment, Qin et al., T-RO 2018, sec. V-B):
//!    gyroscope bias from the rotations, then velocities, gravity and scale by linear least
//!    squares, gravity refined on its sphere.
//! 2. The maximum-a-posteriori refinement on the preintegrated factors (ORB-SLAM3's
//!    inertial-only optimisation, Campos et al., T-RO 2021, sec. V-A): the known-pose problem
//!    ([`crate::bias::known_poses`]) with the scale as one more unknown (`p = s·p̃ + R̃ p_bs`),
//!    a Gaussian prior on the biases ([`BiasPrior`]), gravity as a 2-DoF direction, each window
//!    weighted by its preintegration covariance and the keyframes' pose noise.
//! 3. The verdict ([`Readiness`]): ready when the scale's relative σ and the gravity
//!    direction's σ are under their limits, the σ being those the fit's own χ²/dof supports
//!    (multiplied by `√(χ²/dof)` when that exceeds 1).
//!
//! The poses may be those of a camera or lidar: [`InitOptions::body_p_sensor`] gives the IMU's
//! pose in that frame (as `calibrate --estimate extrinsic-rotation,lever-arm` estimates it);
//! the lever arm is metric, the poses' positions are in their own unit.

pub mod linear;
mod profile;

use crate::Fit;
use crate::bias::known_poses::extras::Param;
use crate::bias::{BiasError, BiasPrior, KnownPose, KnownPoseCalibration, KnownPoseOptions};
use linear::LinearStart;
use nalgebra::{DMatrix, DVector, SMatrix, SVector, Vector3};
use preint::{ImuBias, ImuSample, PreintParams, SensorPose};
use profile::Profile as Scaled;

/// Whether the poses' positions are metric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaleMode {
    /// Known up to scale (a monocular front end): the scale is estimated.
    Unknown,
    /// Metric: the scale is 1.
    Known,
}

/// When an initialisation is ready (module docs, step 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readiness {
    /// Largest relative σ of the scale (default 0.01).
    pub max_scale_rel_std: f64,
    /// Largest σ of the gravity direction \[rad\] (default 0.01, 0.57°).
    pub max_gravity_std_rad: f64,
}

impl Default for Readiness {
    fn default() -> Self {
        Self {
            max_scale_rel_std: 0.01,
            max_gravity_std_rad: 0.01,
        }
    }
}

/// Options of [`initialise`].
#[derive(Clone, Debug, PartialEq)]
pub struct InitOptions {
    /// Preintegration parameters (noise densities, scheme; `gravity` gives |g| and the start
    /// of nothing else: the direction comes from the linear start).
    pub params: PreintParams,
    /// Whether the scale is estimated.
    pub scale: ScaleMode,
    /// σ of each keyframe attitude \[rad\] (default 0).
    pub pose_rot_std: f64,
    /// σ of each keyframe position per axis \[unit of the poses\] (default 0).
    pub pose_pos_std: f64,
    /// The IMU's pose in the frame of the poses (`R_bs`, `p_bs` \[m\]); `None`: the poses are
    /// the IMU's.
    pub body_p_sensor: Option<SensorPose>,
    /// The prior on the biases (default zero mean, σ_g 0.05 rad/s, σ_a 0.2 m/s²: a consumer
    /// MEMS IMU's turn-on bias).
    pub bias_prior: BiasPrior,
    /// The readiness limits.
    pub readiness: Readiness,
}

impl InitOptions {
    /// Defaults around the given preintegration parameters, scale unknown.
    pub fn new(params: PreintParams) -> Self {
        Self {
            params,
            scale: ScaleMode::Unknown,
            pose_rot_std: 0.0,
            pose_pos_std: 0.0,
            body_p_sensor: None,
            bias_prior: BiasPrior {
                mean: ImuBias::zero(),
                gyro_std: 0.05,
                acc_std: 0.2,
            },
            readiness: Readiness::default(),
        }
    }
}

/// The order of [`Initialisation::covariance`]: scale, gravity \[m/s², world\], b_g \[rad/s\],
/// b_a \[m/s²\].
pub const COVARIANCE_ORDER: [&str; 10] = [
    "s", "g.x", "g.y", "g.z", "b_g.x", "b_g.y", "b_g.z", "b_a.x", "b_a.y", "b_a.z",
];

/// The result of [`initialise`]. Every `_std` is the predicted σ times
/// [`Initialisation::std_factor`].
#[derive(Clone, Debug)]
pub struct Initialisation {
    /// Scale \[m per unit of the poses\] (1 when known).
    pub scale: f64,
    /// Its σ \[m per unit\] (0 when known).
    pub scale_std: f64,
    /// Gravity \[m/s², world frame of the poses\] (magnitude |params.gravity|).
    pub gravity: Vector3<f64>,
    /// σ of each component \[m/s²\].
    pub gravity_std: Vector3<f64>,
    /// σ of the gravity direction \[rad\] (the larger of its two tangent σ).
    pub gravity_dir_std_rad: f64,
    /// Biases \[rad/s, m/s²\], in the IMU frame.
    pub bias: ImuBias,
    /// σ of b_g \[rad/s\].
    pub gyro_bias_std: Vector3<f64>,
    /// σ of b_a \[m/s²\].
    pub acc_bias_std: Vector3<f64>,
    /// Keyframe times \[ns\] and the IMU's velocity there \[m/s, world\].
    pub velocities: Vec<(i64, Vector3<f64>)>,
    /// σ of each velocity \[m/s\].
    pub velocity_std: Vec<Vector3<f64>>,
    /// Predicted joint covariance in [`COVARIANCE_ORDER`] (not multiplied by `std_factor`;
    /// the scale's rows are zero when it is known).
    pub covariance: SMatrix<f64, 10, 10>,
    /// `max(1, √(χ²/dof))`: the factor the printed σ carry.
    pub std_factor: f64,
    /// The refinement's goodness of fit.
    pub fit: Fit,
    /// The linear start.
    pub linear: LinearStart,
    /// Whether the estimate is good enough to start from ([`Readiness`]).
    pub ready: bool,
    /// Why, in words: "scale σ 12.0 % (limit 1.0 %): not ready; move more …".
    pub reason: String,
    /// Keyframes used.
    pub keyframes: usize,
    /// The window's length \[s\].
    pub window_s: f64,
}

/// Gravity, scale, velocities and biases from keyframe `poses` (at least 3, strictly
/// increasing times inside the samples' span) and the samples (module docs). A window that
/// is not ready is a result with `ready: false`, not an error; errors are bad input.
pub fn initialise(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &InitOptions,
) -> Result<Initialisation, BiasError> {
    crate::bias::validate::check_samples(samples, 2)?;
    opts.params.validate()?;
    crate::bias::known_poses::check_poses(samples, poses)?;
    crate::bias::validate::check_positive(
        "readiness.max_scale_rel_std",
        opts.readiness.max_scale_rel_std,
    )?;
    crate::bias::validate::check_positive(
        "readiness.max_gravity_std_rad",
        opts.readiness.max_gravity_std_rad,
    )?;
    let x_bs = opts
        .body_p_sensor
        .unwrap_or_else(crate::bias::known_poses::extras::identity_pose);
    let known = match opts.scale {
        ScaleMode::Known => Some(1.0),
        ScaleMode::Unknown => None,
    };
    let lin = linear::linear_start(samples, poses, &opts.params, &x_bs, known)?;
    let start_scale = if lin.scale.is_finite() && lin.scale > 0.0 {
        lin.scale
    } else {
        1.0
    };
    let kp = KnownPoseOptions {
        params: PreintParams {
            gravity: lin.gravity,
            ..opts.params.clone()
        },
        pose_rot_std: opts.pose_rot_std,
        pose_pos_std: opts.pose_pos_std,
        initial_bias: ImuBias::new(lin.gyro_bias, opts.bias_prior.mean.acc),
        initial_extrinsic: opts.body_p_sensor,
        initial_scale: start_scale,
        estimate_scale: known.is_none(),
        bias_prior: Some(opts.bias_prior),
        ..KnownPoseOptions::new(opts.params.clone())
    };
    let c = crate::bias::calibrate_known_poses(samples, poses, &kp)?;
    let scaled = match known {
        Some(_) => Scaled {
            scale_std: 0.0,
            sensitivity: DVector::zeros(9 + 3 * poses.len()),
            scale: 1.0,
            at: c,
        },
        None => {
            let s = scale_of(&c);
            let mut warm = kp;
            warm.initial_bias = c.bias;
            warm.params.gravity = c.gravity;
            profile::minimise(samples, poses, warm, s)?
        }
    };
    Ok(result(scaled, lin, poses, opts))
}

/// The scale and its relative σ of a solve that estimated it (the profile's start).
fn scale_of(c: &KnownPoseCalibration) -> (f64, f64) {
    let e = c.parameters.iter().find(|p| p.param == Param::Scale);
    let s = if c.scale > 0.0 { c.scale } else { 1.0 };
    (s, e.map_or(0.05, |e| e.std / s))
}

/// The initialisation from the scale's profile (or the one solve at a known scale).
fn result(
    p: Scaled,
    linear: LinearStart,
    poses: &[KnownPose],
    opts: &InitOptions,
) -> Initialisation {
    let c = &p.at;
    let fit = c.fit();
    let std_factor = fit.scale().max(1.0);
    let covariance = joint_covariance(&p);
    let sd = |k: usize| covariance[(k, k)].max(0.0).sqrt() * std_factor;
    let gcov = covariance.fixed_view::<3, 3>(1, 1).into_owned();
    let gravity_dir_std_rad =
        gcov.symmetric_eigenvalues().max().max(0.0).sqrt() / c.gravity.norm() * std_factor;
    let scale_std = sd(0);
    let window_s = preint::dt_seconds(poses[0].t_ns, poses[poses.len() - 1].t_ns);
    let (ready, mut reason) = verdict(p.scale, scale_std, gravity_dir_std_rad, &fit, opts);
    reason.push_str(&drift_note(opts, window_s, sd(7).max(sd(8)).max(sd(9))));
    let velocity_std = c
        .velocity_std
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let sens = p.sensitivity.fixed_rows::<3>(9 + 3 * k) * p.scale_std;
            (s.component_mul(s) + sens.component_mul(&sens)).map(f64::sqrt) * std_factor
        })
        .collect();
    Initialisation {
        scale: p.scale,
        scale_std,
        gravity: c.gravity,
        gravity_std: Vector3::new(sd(1), sd(2), sd(3)),
        gravity_dir_std_rad,
        bias: c.bias,
        gyro_bias_std: Vector3::new(sd(4), sd(5), sd(6)),
        acc_bias_std: Vector3::new(sd(7), sd(8), sd(9)),
        velocities: poses
            .iter()
            .zip(&c.velocities)
            .map(|(p, v)| (p.t_ns, *v))
            .collect(),
        velocity_std,
        covariance,
        std_factor,
        fit,
        linear,
        ready,
        reason,
        keyframes: poses.len(),
        window_s,
    }
}

/// The covariance of `[s, g, b_g, b_a]`: the conditional one at the scale (from the solver's
/// state covariance `[b_g, b_a, v, δg]`) plus the scale's, carried by the sensitivity
/// ([`profile`]).
fn joint_covariance(p: &Scaled) -> SMatrix<f64, 10, 10> {
    let c = &p.at;
    let n = c.state_covariance.nrows();
    let mut j = DMatrix::zeros(10, n);
    j.view_mut((1, n - 2), (3, 2))
        .copy_from(&c.gravity_jacobian);
    for k in 0..6 {
        j[(4 + k, k)] = 1.0;
    }
    let cond = &j * &c.state_covariance * j.transpose();
    let mut d = SVector::<f64, 10>::zeros();
    d[0] = 1.0;
    d.rows_mut(1, 9).copy_from(&p.sensitivity.rows(0, 9));
    let spread = if p.scale_std.is_finite() {
        d * d.transpose() * p.scale_std.powi(2)
    } else {
        SMatrix::from_element(f64::INFINITY)
    };
    SMatrix::from_fn(|r, k| cond[(r, k)]) + spread
}

/// A note when the accelerometer bias's random walk over the window, `σ_ba √T`, exceeds the
/// bias's own σ: the problem holds the bias constant, so its σ (and those correlated with it)
/// do not carry the drift ([`crate::bias::known_poses`], "Limits").
fn drift_note(opts: &InitOptions, window_s: f64, acc_bias_std: f64) -> String {
    let rw = opts.params.acc_bias_rw_cov.diagonal().max().max(0.0).sqrt();
    let drift = rw * window_s.sqrt();
    if drift > acc_bias_std {
        format!(
            "; note: the accelerometer bias's random walk moves it by ≈ {drift:.3} m/s² over \
             the {window_s:.1} s window, more than its σ {acc_bias_std:.3} m/s², which holds it \
             constant: a shorter window models it better"
        )
    } else {
        String::new()
    }
}

/// Ready when the scale's relative σ and the gravity direction's σ are within the limits; the
/// reason says which is not, and how far.
fn verdict(
    scale: f64,
    scale_std: f64,
    gravity_std: f64,
    fit: &Fit,
    opts: &InitOptions,
) -> (bool, String) {
    let lim = &opts.readiness;
    let rel = scale_std / scale.abs();
    let mut short = Vec::new();
    let within = |v: f64, limit: f64| v.partial_cmp(&limit).is_some_and(|o| o.is_le());
    if opts.scale == ScaleMode::Unknown && !within(rel, lim.max_scale_rel_std) {
        short.push(format!(
            "scale σ {:.1} % (limit {:.1} %)",
            100.0 * rel,
            100.0 * lim.max_scale_rel_std
        ));
    }
    if !within(gravity_std, lim.max_gravity_std_rad) {
        short.push(format!(
            "gravity direction σ {:.2}° (limit {:.2}°)",
            gravity_std.to_degrees(),
            lim.max_gravity_std_rad.to_degrees()
        ));
    }
    let fit_note = if fit.credible {
        String::new()
    } else {
        format!(
            "; the fit is not credible (χ²/dof {:.2}): σ multiplied by √(χ²/dof), check the \
             noise densities, the pose noise and the extrinsics",
            fit.chi2_dof
        )
    };
    if short.is_empty() {
        let scale = if opts.scale == ScaleMode::Unknown {
            format!("scale σ {:.2} %, ", 100.0 * rel)
        } else {
            String::new()
        };
        let text = format!(
            "ready: {scale}gravity direction σ {:.2}°{fit_note}",
            gravity_std.to_degrees()
        );
        (true, text)
    } else {
        let text = format!(
            "{}: not ready; move more (accelerate along changing directions and rotate: the \
             scale and gravity are seen through acceleration) or use a longer window{fit_note}",
            short.join(", ")
        );
        (false, text)
    }
}
