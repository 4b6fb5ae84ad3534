//! Biases, velocities and the gravity direction from segments with known poses (motion
//! capture or a VIO front end): the inertial-only initialisation of ORB-SLAM3 (Campos et al.,
//! ICRA 2020; T-RO 2021) and VINS-Mono's gyro-bias estimation (Qin et al., T-RO 2018), with
//! preintegration factors.
//!
//! # Model
//! Poses `(R̃_k, p̃_k)` (R_wb body → world, p \[m\] in the world) are measured at times
//! `t_0 < … < t_P−1`; for each consecutive pair the samples are preintegrated
//! ([`preint::preintegrate`]) at the current bias estimate `b̂`. Unknowns: `b = [b_g, b_a]`
//! (constant over the segment), the velocities `v_k` \[m/s, world\] at the pose times, and the
//! gravity direction `g = R_wg·g₀`, `g₀ = (0, 0, −|g|)`, with a 2-DoF tangent ([`gravity`]),
//! so the problem has no gauge freedom. The residual of each pair is the preintegration
//! factor's `[r_φ, r_v, r_p]` (Forster et al., T-RO 2017, eqs. 44–45; [`residuals`]), whitened
//! by its covariance, which includes the noise of the known poses with the correlation between
//! factors that share a pose ([`pose_noise`]).
//!
//! On request ([`KnownPoseOptions::estimate`], [`extras`]) the time offset `t_d` between the
//! IMU and pose clocks, the gyroscope intrinsics, its g-sensitivity and the accelerometer
//! intrinsics ([`preint::intrinsics`]) are estimated too, each through the first-order
//! correction of the windows' deltas (their Jacobians `J_td`, `J_θ`), with a standard deviation,
//! and withheld when the motion does not excite them ([`extras::ExcitationLimits`]).
//!
//! The poses may be those of another frame rigidly attached to the IMU (a camera, a lidar, a
//! motion-capture body): [`KnownPoseOptions::initial_extrinsic`] gives the IMU's pose in it,
//! and `estimate` can ask for its rotation and lever arm ([`extrinsic`]), started at the
//! hand-eye rotation when not given.
//!
//! When the fit is not credible ([`crate::fit`]), [`conventions`] tries the usual convention
//! errors of a pose file (quaternion order, inverse rotation or pose, world z down, poses of
//! another frame) and names the one that explains the misfit.
//!
//! Because the corrections are first order, the problem is re-linearised: after a solve the
//! windows are re-integrated at the new bias and calibration and the problem solved again,
//! until the bias moves by less than 1e-6 and every calibration parameter by less than 1e-3 of
//! its excitation limit (or `max_relinearizations`).
//!
//! Limits: the biases are constant over the segment (over T seconds a random walk of density
//! σ_b moves them by ≈ σ_b√T, e.g. 0.013 m/s² in 20 s for EuRoC's σ_ba: keep segments short or
//! expect that much model error); dense linear algebra, O(P³) per iteration.

pub mod attitudes;
pub mod conventions;
pub mod extras;
pub mod extrinsic;
pub mod gravity;
pub mod pose_noise;
pub mod residuals;
#[cfg(test)]
mod test_data;

use super::BiasError;
use super::validate::{check_gravity, check_non_negative, check_positive, check_samples};
use crate::gauss_newton::{GaussNewton, Solution, StopReason, solve};
pub use attitudes::{KnownAttitude, KnownAttitudeCalibration, calibrate_known_attitudes};
use extras::{
    Calibration, Estimate, ExcitationLimits, Layout, Param, ParameterEstimate, Relinearised,
    fit_excited, parameters, relinearise,
};
use extrinsic::{ExtrinsicEstimate, ExtrinsicStart};
use gravity::GravityDir;
use nalgebra::{DMatrix, DVector, Vector3};
use pose_noise::{Whitening, residual_covariance};
use preint::intrinsics::ImuIntrinsics;
use preint::{ImuBias, ImuSample, PreintParams, SensorPose, dt_seconds};
use preint_lie::SO3;
use residuals::Problem;

/// A known pose: time \[ns\], attitude R_wb (body → world) and position p \[m, world\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownPose {
    /// Time \[ns\].
    pub t_ns: i64,
    /// Attitude R_wb.
    pub r: SO3,
    /// Position \[m\].
    pub p: Vector3<f64>,
}

/// Options of [`calibrate_known_poses`].
#[derive(Clone, Debug, PartialEq)]
pub struct KnownPoseOptions {
    /// Preintegration parameters (noise densities, scheme; its `gravity` gives the initial
    /// gravity vector and its magnitude |g|).
    pub params: PreintParams,
    /// Standard deviation σ_R \[rad\] of each known attitude, `R̃ = R·Exp(n_R)`,
    /// `n_R ~ N(0, σ_R² I)` (default 0: exact attitudes).
    pub pose_rot_std: f64,
    /// Standard deviation σ_p \[m\] of each known position per world axis (default 0).
    pub pose_pos_std: f64,
    /// Initial bias (default zero).
    pub initial_bias: ImuBias,
    /// Maximum number of re-linearisations (default 8).
    pub max_relinearizations: usize,
    /// Gauss-Newton iterations per solve (default 50).
    pub max_iters: u64,
    /// Calibration parameters estimated beside the biases (default none).
    pub estimate: Estimate,
    /// Intrinsics applied to the samples, and the initial value of those estimated (default
    /// identity, `kalibr` model; its model decides which sensor rotation is estimated).
    pub initial_intrinsics: ImuIntrinsics,
    /// Time offset `t_d` \[s\] (`t_imu = t_pose + t_d`) applied to the windows, and the initial
    /// value when estimated (default 0).
    pub initial_time_offset_s: f64,
    /// Standard deviations above which a parameter counts as not excited.
    pub excitation: ExcitationLimits,
    /// The IMU's pose in the frame of the poses (`R_bs`, `p_bs`; [`extrinsic`]), applied to
    /// the poses and the initial value of what `estimate` asks of it. `None` (default): the
    /// poses are the IMU's, or, when the rotation is estimated, it starts at the hand-eye
    /// rotation. Exclusive with `params.body_p_sensor`.
    pub initial_extrinsic: Option<SensorPose>,
    /// The scale of the poses' positions \[m per unit\]: applied to them (`s·p̃`), and the
    /// initial value when estimated (default 1: metric poses). `pose_pos_std` is in the
    /// poses' unit.
    pub initial_scale: f64,
    /// Estimate the scale too (poses known up to scale, a monocular front end; default
    /// false). Its estimate is [`KnownPoseCalibration::parameters`]' [`Param::Scale`] entry,
    /// never withheld ([`crate::init`] decides whether it is known well enough).
    pub estimate_scale: bool,
    /// A Gaussian prior on the biases (default none: the data alone).
    pub bias_prior: Option<BiasPrior>,
}

/// A Gaussian prior on the biases, `b_g ~ N(μ_g, σ_g² I)`, `b_a ~ N(μ_a, σ_a² I)`: the
/// maximum-a-posteriori form of the inertial-only optimisation (Campos et al., T-RO 2021,
/// sec. V-A), which keeps a short window's accelerometer bias from trading against gravity and
/// scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasPrior {
    /// The prior mean μ.
    pub mean: ImuBias,
    /// σ_g \[rad/s\].
    pub gyro_std: f64,
    /// σ_a \[m/s²\].
    pub acc_std: f64,
}

impl KnownPoseOptions {
    /// Defaults around the given preintegration parameters.
    pub fn new(params: PreintParams) -> Self {
        Self {
            params,
            pose_rot_std: 0.0,
            pose_pos_std: 0.0,
            initial_bias: ImuBias::zero(),
            max_relinearizations: 8,
            max_iters: 50,
            estimate: Estimate::default(),
            initial_intrinsics: ImuIntrinsics::default(),
            initial_time_offset_s: 0.0,
            excitation: ExcitationLimits::default(),
            initial_extrinsic: None,
            initial_scale: 1.0,
            estimate_scale: false,
            bias_prior: None,
        }
    }
}

/// Result of [`calibrate_known_poses`]. Standard deviations come from the solver covariance
/// of the whitened problem (predicted from the noise densities and the pose noise, not
/// rescaled by the residuals); compare [`KnownPoseCalibration::chi2_per_dof`] with 1.
#[derive(Clone, Debug)]
pub struct KnownPoseCalibration {
    /// Bias estimate \[b_g rad/s, b_a m/s²\], in the IMU frame of the intrinsics (the biases
    /// the preintegrator subtracts from intrinsics-corrected samples; OpenVINS' sensor-frame
    /// biases are `intrinsics.bias_from_imu(&bias)`).
    pub bias: ImuBias,
    /// Standard deviation of b_g \[rad/s\].
    pub gyro_bias_std: Vector3<f64>,
    /// Standard deviation of b_a \[m/s²\].
    pub acc_bias_std: Vector3<f64>,
    /// Gravity vector in the world frame \[m/s²\] (magnitude fixed to |params.gravity|).
    pub gravity: Vector3<f64>,
    /// Standard deviation of each component of `gravity` \[m/s²\] (the component along gravity
    /// has ≈ 0: only the direction is estimated).
    pub gravity_std: Vector3<f64>,
    /// Angle between the estimated gravity and the initial one \[rad\].
    pub gravity_tilt: f64,
    /// Velocities at the pose times \[m/s, world\].
    pub velocities: Vec<Vector3<f64>>,
    /// Their standard deviations \[m/s\].
    pub velocity_std: Vec<Vector3<f64>>,
    /// χ² of the whitened residuals.
    pub chi2: f64,
    /// Degrees of freedom: residuals − unknowns = `9(P − 1) (+ 6 with a bias prior) − (3P + 8
    /// + m)`, `m` the excited calibration parameters.
    pub dof: usize,
    /// Total Gauss-Newton iterations.
    pub iterations: u64,
    /// Number of solves (re-linearisations + 1).
    pub solves: usize,
    /// Why the last solve stopped.
    pub stop: StopReason,
    /// The intrinsics: the estimated ones where [`KnownPoseCalibration::parameters`] says
    /// excited, the initial ones elsewhere.
    pub intrinsics: ImuIntrinsics,
    /// The time offset \[s\] (estimated, or the initial one).
    pub time_offset_s: f64,
    /// Every parameter asked for, with its standard deviation and excitation, in the order of
    /// [`extras::parameters`].
    pub parameters: Vec<ParameterEstimate>,
    /// Joint covariance of `[b_g, b_a, e]`, `e` the excited entries of
    /// [`KnownPoseCalibration::parameters`] in their order (angles as right perturbations of
    /// the estimated rotation): what propagates the calibration's own uncertainty into a
    /// window it is applied to, `Σ + J Σ_c Jᵀ` with `J = [J_b, J_e]`.
    pub covariance: DMatrix<f64>,
    /// The IMU's pose in the frame of the poses, when estimated or given.
    pub extrinsic: Option<ExtrinsicEstimate>,
    /// The scale of the poses' positions \[m per unit\] (estimated, or the initial one).
    pub scale: f64,
    /// The solver's covariance of the whole state, in the order `[b_g, b_a, v_0, …, v_P−1,
    /// e, δg]` (`e` as in [`KnownPoseCalibration::covariance`], `δg` the 2-DoF gravity
    /// tangent of [`gravity`]).
    pub state_covariance: DMatrix<f64>,
    /// `∂g/∂δg` \[m/s² per rad\], 3×2: the gravity vector's columns of the state covariance.
    pub gravity_jacobian: nalgebra::Matrix3x2<f64>,
}

impl KnownPoseCalibration {
    /// `χ²/dof` (≈ 1 when the noise densities and pose noise are right; NaN for dof = 0).
    pub fn chi2_per_dof(&self) -> f64 {
        per_dof(self.chi2, self.dof)
    }

    /// The goodness of fit: `chi2` against `χ²_dof` ([`crate::fit`]).
    pub fn fit(&self) -> crate::Fit {
        crate::Fit::new(self.chi2, self.dof)
    }
}

/// `χ² / dof`, NaN for dof = 0.
fn per_dof(chi2: f64, dof: usize) -> f64 {
    if dof == 0 {
        f64::NAN
    } else {
        chi2 / dof as f64
    }
}

/// The state `([b_g, b_a, v_0, …, v_P−1], R_wg)`.
type State = (DVector<f64>, GravityDir);

/// Estimates `b_g`, `b_a`, the velocities at the pose times and the gravity direction from
/// IMU samples and known (optionally noisy) poses (module docs).
///
/// `poses`: at least 3, strictly increasing times inside the sample span. Errors are typed
/// ([`BiasError`]); no panics on bad input.
///
/// ```
/// use nalgebra::Vector3;
/// use preint::{ImuBias, ImuNoise, PreintParams};
/// use preint_calib::bias::{KnownPose, KnownPoseOptions, calibrate_known_poses};
/// use preint_sim::{EulerScene, SimConfig, simulate};
///
/// // 2 s of an aggressive motion at 200 Hz, exact poses every 0.25 s.
/// let noise = ImuNoise::euroc();
/// let (b_g, b_a) = (Vector3::new(0.004, -0.003, 0.006), Vector3::new(0.08, -0.05, 0.12));
/// let cfg = SimConfig {
///     noise,
///     initial_bias: ImuBias::new(b_g, b_a),
///     bias_random_walk: false,
///     ..SimConfig::default()
/// };
/// let rec = simulate(&EulerScene::aggressive(), 200.0, 2.0, &cfg, 3).unwrap();
/// let poses: Vec<KnownPose> = rec
///     .truth
///     .iter()
///     .step_by(50)
///     .map(|s| KnownPose { t_ns: s.t_ns, r: s.rotation(), p: s.p })
///     .collect();
/// let opts = KnownPoseOptions::new(PreintParams::from_noise(&noise));
/// let cal = calibrate_known_poses(&rec.samples, &poses, &opts).unwrap();
/// for k in 0..3 {
///     assert!((cal.bias.gyro[k] - b_g[k]).abs() < 4.0 * cal.gyro_bias_std[k]);
///     assert!((cal.bias.acc[k] - b_a[k]).abs() < 4.0 * cal.acc_bias_std[k]);
/// }
/// assert!(cal.gravity_tilt < 0.01);
/// ```
pub fn calibrate_known_poses(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
) -> Result<KnownPoseCalibration, BiasError> {
    check_samples(samples, 2)?;
    opts.params.validate()?;
    check_poses(samples, poses)?;
    check_non_negative("pose_rot_std", opts.pose_rot_std)?;
    check_non_negative("pose_pos_std", opts.pose_pos_std)?;
    check_calibration_options(opts)?;
    check_extrinsic_options(opts)?;
    check_scale_options(opts)?;
    let gnorm = check_gravity("params.gravity", &opts.params.gravity)?;
    let g0 = Vector3::new(0.0, 0.0, -gnorm);
    let (opts, start) = &extrinsic_start(samples, poses, opts);
    let mut asked = parameters(&opts.estimate, opts.initial_intrinsics.model);
    if opts.estimate_scale {
        asked.push(Param::Scale);
    }
    let eo = 6 + 3 * poses.len();
    let out = fit_excited(
        &asked,
        &Calibration::initial(opts),
        &opts.excitation,
        |active| {
            let f = fit(samples, poses, opts, &g0, active)?;
            let stds = f.sol.std_devs();
            let calib = f.calib;
            Ok((f, calib, (0..active.len()).map(|k| stds[eo + k]).collect()))
        },
    )?;
    let extrinsic = start.map(|s| (s, extrinsic::rotation_rms(poses)));
    Ok(calibration(
        out.fit,
        (&g0, &opts.params.gravity),
        poses.len(),
        out.parameters,
        extrinsic,
    ))
}

/// The options with the extrinsic start of [`extrinsic`] ("Start"): the given transform, or,
/// when the rotation is estimated without one, the hand-eye rotation (the identity when the
/// motion cannot give it); `None` when the poses are the IMU's.
fn extrinsic_start(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
) -> (KnownPoseOptions, Option<ExtrinsicStart>) {
    if opts.initial_extrinsic.is_some() {
        return (opts.clone(), Some(ExtrinsicStart::Given));
    }
    if !opts.estimate.extrinsic() {
        return (opts.clone(), None);
    }
    let mut o = opts.clone();
    let mut start = ExtrinsicStart::Identity;
    if opts.estimate.extrinsic_rotation {
        let atts: Vec<(i64, SO3)> = poses.iter().map(|p| (p.t_ns, p.r)).collect();
        if let Some(x) = conventions::hand_eye_rotation(samples, &atts, opts) {
            o.initial_extrinsic = Some(SensorPose::new(x, Vector3::zeros()));
            start = ExtrinsicStart::HandEye;
        }
    }
    (o, Some(start))
}

/// The extrinsic options are consistent: one way of giving the IMU's pose, and a valid one.
fn check_extrinsic_options(opts: &KnownPoseOptions) -> Result<(), BiasError> {
    if (opts.estimate.extrinsic() || opts.initial_extrinsic.is_some())
        && opts.params.body_p_sensor.is_some()
    {
        return Err(BiasError::InvalidParameter {
            name: "params.body_p_sensor",
            reason: "the IMU's pose in the frame of the poses is given or estimated through                      initial_extrinsic (applied to the poses); params.body_p_sensor would apply                      it a second time"
                .into(),
        });
    }
    if let Some(x) = &opts.initial_extrinsic
        && !x.is_valid()
    {
        return Err(BiasError::InvalidParameter {
            name: "initial_extrinsic",
            reason: "not a rigid transform (non-finite, or the rotation is not orthonormal)".into(),
        });
    }
    for (name, v) in [
        (
            "excitation.extrinsic_rotation_rad",
            opts.excitation.extrinsic_rotation_rad,
        ),
        ("excitation.lever_arm_m", opts.excitation.lever_arm_m),
    ] {
        check_positive(name, v)?;
    }
    Ok(())
}

/// The scale is positive and finite, and the bias prior's deviations positive.
fn check_scale_options(opts: &KnownPoseOptions) -> Result<(), BiasError> {
    check_positive("initial_scale", opts.initial_scale)?;
    if let Some(b) = &opts.bias_prior {
        check_positive("bias_prior.gyro_std", b.gyro_std)?;
        check_positive("bias_prior.acc_std", b.acc_std)?;
        let mean = b.mean.gyro.iter().chain(b.mean.acc.iter());
        if mean.clone().any(|v| !v.is_finite()) {
            return Err(BiasError::InvalidParameter {
                name: "bias_prior.mean",
                reason: "non-finite".into(),
            });
        }
    }
    Ok(())
}

/// The initial calibration is valid: intrinsics invertible, time offset finite, and the
/// excitation limits positive.
pub(super) fn check_calibration_options(opts: &KnownPoseOptions) -> Result<(), BiasError> {
    opts.initial_intrinsics.validate()?;
    if !opts.initial_time_offset_s.is_finite() {
        return Err(BiasError::InvalidParameter {
            name: "initial_time_offset_s",
            reason: format!("{} is not finite", opts.initial_time_offset_s),
        });
    }
    let l = &opts.excitation;
    for (name, v) in [
        ("excitation.time_offset_s", l.time_offset_s),
        ("excitation.scale_misalignment", l.scale_misalignment),
        ("excitation.g_sensitivity", l.g_sensitivity),
    ] {
        check_positive(name, v)?;
    }
    Ok(())
}

type Fit = Relinearised<State>;

/// The re-linearised fit of the parameters `active` (module docs).
fn fit(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
    g0: &Vector3<f64>,
    active: &[Param],
) -> Result<Fit, BiasError> {
    let layout = Layout {
        vec: |x: &State| &x.0,
        vec_mut: |x: &mut State| &mut x.0,
        eo: 6 + 3 * poses.len(),
        bias: |p, _| {
            ImuBias::new(
                Vector3::new(p[0], p[1], p[2]),
                Vector3::new(p[3], p[4], p[5]),
            )
        },
    };
    let start = Calibration::initial(opts);
    let imu = extrinsic::imu_poses(poses, &start.extrinsic, start.scale);
    let x = initial_state(&imu, opts, g0, active.len());
    relinearise(opts, active, x, &layout, |lin, x| {
        solve_linearised(samples, poses, opts, lin, active, g0, x)
    })
}

/// At least 3 poses, at strictly increasing times within the samples' span, finite.
pub(crate) fn check_poses(samples: &[ImuSample], poses: &[KnownPose]) -> Result<(), BiasError> {
    if poses.len() < 3 {
        return Err(BiasError::TooFew {
            what: "poses",
            found: poses.len(),
            needed: 3,
        });
    }
    for (i, w) in poses.windows(2).enumerate() {
        if w[1].t_ns <= w[0].t_ns {
            return Err(BiasError::InvalidParameter {
                name: "poses",
                reason: format!(
                    "pose {} time {} ns is not after the previous",
                    i + 1,
                    w[1].t_ns
                ),
            });
        }
    }
    let (t0, t1) = (samples[0].t_ns, samples[samples.len() - 1].t_ns);
    if poses[0].t_ns < t0 || poses[poses.len() - 1].t_ns > t1 {
        return Err(BiasError::InvalidParameter {
            name: "poses",
            reason: format!("pose times must lie within the samples' span [{t0}, {t1}] ns"),
        });
    }
    if poses
        .iter()
        .any(|p| !(p.p.iter().all(|v| v.is_finite()) && p.r.matrix().iter().all(|v| v.is_finite())))
    {
        return Err(BiasError::InvalidParameter {
            name: "poses",
            reason: "non-finite position or attitude".into(),
        });
    }
    Ok(())
}

/// The initial state: the initial bias, velocities by central differences of the positions
/// (one-sided at the ends), no calibration correction, gravity along `params.gravity`.
fn initial_state(
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
    g0: &Vector3<f64>,
    extras: usize,
) -> State {
    let n = poses.len();
    let mut p0 = DVector::zeros(6 + 3 * n + extras);
    p0.fixed_rows_mut::<3>(0).copy_from(&opts.initial_bias.gyro);
    p0.fixed_rows_mut::<3>(3).copy_from(&opts.initial_bias.acc);
    for k in 0..n {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let dt = dt_seconds(poses[a].t_ns, poses[b].t_ns);
        p0.fixed_rows_mut::<3>(6 + 3 * k)
            .copy_from(&((poses[b].p - poses[a].p) / dt));
    }
    (p0, GravityDir::aligned_with(g0, &opts.params.gravity))
}

/// One solve at the linearisation point `(b̂, calibration)`: the windows preintegrated there
/// with their calibration Jacobians, weighted by their covariance with the pose noise, solved
/// from `x`.
fn solve_linearised(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: &KnownPoseOptions,
    lin: &(ImuBias, Calibration),
    active: &[Param],
    g0: &Vector3<f64>,
    x: State,
) -> Result<Solution<State>, BiasError> {
    let times = poses.windows(2).map(|w| (w[0].t_ns, w[1].t_ns));
    let (pims, extras) = extras::windows(&opts.params, lin, active, samples, times)?;
    let (x_bs, scale) = (lin.1.extrinsic, lin.1.scale);
    let (diag, sub) = residual_covariance(
        &pims,
        &extrinsic::imu_poses(poses, &x_bs, scale),
        (opts.pose_rot_std, opts.pose_pos_std * scale),
        &extrinsic::lever_in_imu(&x_bs),
    );
    let white = Whitening::new(&diag, &sub).ok_or_else(|| BiasError::InvalidParameter {
        name: "params",
        reason: "the residual covariance (preintegration + pose noise) is not positive \
                 definite: give non-zero noise densities"
            .into(),
    })?;
    let problem = Problem {
        poses,
        active,
        extrinsic: x_bs,
        pims: &pims,
        extras: &extras,
        g0: *g0,
        white: &white,
        scale,
        prior: opts.bias_prior,
    };
    Ok(solve(problem, x, GaussNewton::default(), opts.max_iters)?)
}

/// The result of the last solve: estimates and marginal standard deviations (and the extrinsic
/// estimate, when the poses are of another frame: where it started and how much they rotate).
fn calibration(
    fit: Fit,
    (g0, g_init): (&Vector3<f64>, &Vector3<f64>),
    n: usize,
    parameters: Vec<ParameterEstimate>,
    extrinsic: Option<(ExtrinsicStart, Vector3<f64>)>,
) -> KnownPoseCalibration {
    let sol = fit.sol;
    let (p, rwg) = &sol.estimate;
    let np = p.len();
    let eo = 6 + 3 * n;
    let idx: Vec<usize> = (0..6).chain(eo..np).collect();
    let covariance = DMatrix::from_fn(idx.len(), idx.len(), |i, j| {
        sol.covariance[(idx[i], idx[j])]
    });
    let active: Vec<Param> = parameters
        .iter()
        .filter(|e| e.excited)
        .map(|e| e.param)
        .collect();
    let extrinsic = extrinsic
        .map(|s| extrinsic::estimate(fit.calib.extrinsic, &sol.covariance, eo, &active, s));
    let (gravity, gd) = rwg.gravity(g0);
    let gcov = gd * sol.marginal_covariance::<2>(np) * gd.transpose();
    let cosang = (gravity.dot(g_init) / (gravity.norm() * g_init.norm())).clamp(-1.0, 1.0);
    KnownPoseCalibration {
        bias: fit.bias,
        gyro_bias_std: sol.marginal_std::<3>(0),
        acc_bias_std: sol.marginal_std::<3>(3),
        gravity,
        gravity_std: gcov.diagonal().map(|v| v.max(0.0).sqrt()),
        gravity_tilt: cosang.acos(),
        velocities: (0..n)
            .map(|k| Vector3::new(p[6 + 3 * k], p[7 + 3 * k], p[8 + 3 * k]))
            .collect(),
        velocity_std: (0..n).map(|k| sol.marginal_std::<3>(6 + 3 * k)).collect(),
        chi2: 2.0 * sol.cost,
        dof: sol.residual_count.saturating_sub(sol.rank),
        iterations: fit.iterations,
        solves: fit.solves,
        stop: sol.stop,
        intrinsics: fit.calib.intrinsics,
        time_offset_s: fit.calib.td_s,
        parameters,
        covariance,
        extrinsic,
        scale: fit.calib.scale,
        state_covariance: sol.covariance.clone(),
        gravity_jacobian: gd,
    }
}
