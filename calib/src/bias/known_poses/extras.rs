//! Calibration parameters estimated beside the biases from known poses: the time offset
//! ([`preint::time_offset`]) and the IMU intrinsics ([`preint::intrinsics`]); their
//! linearisation point, the columns they add to each window's residual, and the test of
//! whether the motion excites them.
//!
//! # Parameters
//!
//! [`Estimate`] names groups; [`parameters`] expands them into scalars ([`Param`]):
//! - `time-offset`: `t_d` \[s\], `t_imu = t_keyframe + t_d` ([`preint::time_offset`]);
//! - `gyro-intrinsics`: the 6 free entries of `T_w` and, in the `kalibr` model, the 3 angles of
//!   `R_IMUtoGYRO` (together a full 3×3 gyroscope matrix); dimensionless and rad;
//! - `g-sensitivity`: the 9 entries of `T_g` \[(rad/s)/(m/s²)\];
//! - `accel-intrinsics`: the 6 free entries of `T_a` and, in the `rpng` model, the 3 angles of
//!   `R_IMUtoACC`;
//! - `extrinsic-rotation`: `R_bs`, the IMU's attitude in the frame of the poses, as a right
//!   perturbation `R_bs·Exp(δθ)` \[rad\] ([`super::extrinsic`]);
//! - `lever-arm`: `p_bs`, the IMU's origin in the frame of the poses \[m\].
//!
//! As in OpenVINS, one of the two sensor rotations stays fixed (identity by default): the IMU
//! frame is defined by that sensor's axes, and the known poses fix it against the world.
//!
//! # Linearisation
//!
//! A window is preintegrated at the current estimate `(θ̂, t̂_d)` and corrected to first order,
//! `Δ(θ̂ ⊞ δθ, t̂_d + δt_d) ≈ Δ ⊕ (J_θ δθ + J_td δt_d)`, exactly as for the biases (Forster et
//! al., T-RO 2017, eq. 44); the state carries `e = (δt_d, δθ)`, which is folded into the
//! linearisation point and reset at each re-linearisation.
//!
//! # Excitation
//!
//! A parameter is *excited* when its standard deviation is below a limit
//! ([`ExcitationLimits`]): above it, applying the estimate would not be worth its uncertainty,
//! and the estimate is withheld (the parameter is held at its initial value and the problem
//! solved again without it). A parameter the motion does not move at all (e.g. the gyroscope's
//! x scale on a rotation about z only) has an infinite standard deviation. Those are withheld
//! together; of the others, the one furthest over its limit (in σ / limit) is withheld alone
//! and the problem solved again, since a parameter correlated with it may then pass.

use crate::bias::BiasError;
use crate::gauss_newton::Solution;
use nalgebra::{DMatrix, DVector, SVector, Vector3};
use preint::intrinsics::{AppliedIntrinsics, ImuIntrinsics, IntrinsicsModel};
use preint::{ImuBias, ImuSample, PreintError, PreintParams, PreintegratedImu, SensorPose};
use preint_lie::SO3;

/// The identity transform: the poses are the IMU's.
pub(crate) fn identity_pose() -> SensorPose {
    SensorPose::new(SO3::identity(), Vector3::zeros())
}

/// Which calibration parameters [`super::calibrate_known_poses`] estimates beside the biases
/// (module docs). All false by default: biases, velocities and gravity only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Estimate {
    /// The time offset `t_d` \[s\].
    pub time_offset: bool,
    /// `T_w` and, in the `kalibr` model, `R_IMUtoGYRO`.
    pub gyro_intrinsics: bool,
    /// `T_g`.
    pub g_sensitivity: bool,
    /// `T_a` and, in the `rpng` model, `R_IMUtoACC`.
    pub accel_intrinsics: bool,
    /// `R_bs`, the IMU's attitude in the frame of the poses ([`super::extrinsic`]).
    pub extrinsic_rotation: bool,
    /// `p_bs`, the IMU's origin in the frame of the poses \[m\] ([`super::extrinsic`]).
    pub lever_arm: bool,
}

impl Estimate {
    /// The names [`Estimate::parse`] accepts.
    pub const NAMES: [&'static str; 6] = [
        "time-offset",
        "gyro-intrinsics",
        "g-sensitivity",
        "accel-intrinsics",
        "extrinsic-rotation",
        "lever-arm",
    ];

    /// Parses a comma-separated list of [`Estimate::NAMES`] (e.g.
    /// `time-offset,gyro-intrinsics`); the error names the unknown entry.
    pub fn parse(list: &str) -> Result<Self, String> {
        let mut e = Estimate::default();
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            match name {
                "time-offset" => e.time_offset = true,
                "gyro-intrinsics" => e.gyro_intrinsics = true,
                "g-sensitivity" => e.g_sensitivity = true,
                "accel-intrinsics" => e.accel_intrinsics = true,
                "extrinsic-rotation" => e.extrinsic_rotation = true,
                "lever-arm" => e.lever_arm = true,
                _ => {
                    return Err(format!(
                        "unknown parameter `{name}` (expected some of {})",
                        Self::NAMES.join(", ")
                    ));
                }
            }
        }
        Ok(e)
    }

    /// True when any parameter is asked for.
    pub fn any(&self) -> bool {
        self.time_offset
            || self.gyro_intrinsics
            || self.g_sensitivity
            || self.accel_intrinsics
            || self.extrinsic()
    }

    /// True when a part of the extrinsic transform is asked for.
    pub fn extrinsic(&self) -> bool {
        self.extrinsic_rotation || self.lever_arm
    }
}

/// One estimated scalar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// The time offset `t_d` \[s\].
    TimeOffset,
    /// Column `i` of the intrinsics' parameters ([`preint::intrinsics`], 24 columns).
    Intrinsic(usize),
    /// Component `i` of the right perturbation of `R_bs` \[rad\] ([`super::extrinsic`]).
    ExtrinsicRotation(usize),
    /// Component `i` of the lever arm `p_bs` \[m, frame of the poses\].
    LeverArm(usize),
    /// The scale `s` of the poses' positions \[m per unit of the poses\]
    /// ([`super::KnownPoseOptions::estimate_scale`]): the IMU positions are `s·p̃ + R̃ p_bs`.
    Scale,
}

impl Param {
    /// A readable name: `t_d`, `T_w[1,0]`, `R_IMUtoGYRO.θy`, `T_g[2,0]`, ….
    pub fn name(self, model: IntrinsicsModel) -> String {
        let entry = |i: usize| model.free_entries()[i];
        match self {
            Param::TimeOffset => "t_d".into(),
            Param::Intrinsic(i) if i < 6 => format!("T_w[{},{}]", entry(i).0, entry(i).1),
            Param::Intrinsic(i) if i < 12 => {
                format!("T_a[{},{}]", entry(i - 6).0, entry(i - 6).1)
            }
            Param::Intrinsic(i) if i < 15 => {
                let r = match model {
                    IntrinsicsModel::Kalibr => "R_IMUtoGYRO",
                    IntrinsicsModel::Rpng => "R_IMUtoACC",
                };
                format!("{r}.θ{}", ["x", "y", "z"][i - 12])
            }
            Param::Intrinsic(i) => format!("T_g[{},{}]", (i - 15) % 3, (i - 15) / 3),
            Param::ExtrinsicRotation(i) => format!("R_bs.θ{}", ["x", "y", "z"][i]),
            Param::LeverArm(i) => format!("p_bs.{}", ["x", "y", "z"][i]),
            Param::Scale => "s".into(),
        }
    }

    /// Its unit.
    pub fn unit(self) -> &'static str {
        match self {
            Param::TimeOffset => "s",
            Param::Intrinsic(i) if i < 12 => "1",
            Param::Intrinsic(i) if i < 15 => "rad",
            Param::Intrinsic(_) => "(rad/s)/(m/s²)",
            Param::ExtrinsicRotation(_) => "rad",
            Param::LeverArm(_) => "m",
            Param::Scale => "m/unit",
        }
    }

    /// The limit of its standard deviation in `limits` (none for the scale: whether it is
    /// known well enough is the initialisation's readiness verdict, [`crate::init`]).
    pub fn limit(self, limits: &ExcitationLimits) -> f64 {
        match self {
            Param::Scale => f64::INFINITY,
            Param::TimeOffset => limits.time_offset_s,
            Param::Intrinsic(i) if i < 15 => limits.scale_misalignment,
            Param::Intrinsic(_) => limits.g_sensitivity,
            Param::ExtrinsicRotation(_) => limits.extrinsic_rotation_rad,
            Param::LeverArm(_) => limits.lever_arm_m,
        }
    }
}

/// The standard deviation above which a parameter counts as not excited (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExcitationLimits {
    /// Time offset \[s\] (default 1e-3: 1 ms).
    pub time_offset_s: f64,
    /// Entries of `T_w`, `T_a` (dimensionless) and sensor-axis angles \[rad\] (default 1e-3:
    /// 0.1 % scale, 1 mrad).
    pub scale_misalignment: f64,
    /// Entries of `T_g` \[(rad/s)/(m/s²)\] (default 1e-4, ≈ 0.06 °/s per g).
    pub g_sensitivity: f64,
    /// Components of the extrinsic rotation \[rad\] (default 5e-3: 0.29°).
    pub extrinsic_rotation_rad: f64,
    /// Components of the lever arm \[m\] (default 0.01).
    pub lever_arm_m: f64,
}

impl Default for ExcitationLimits {
    fn default() -> Self {
        Self {
            time_offset_s: 1e-3,
            scale_misalignment: 1e-3,
            g_sensitivity: 1e-4,
            extrinsic_rotation_rad: 5e-3,
            lever_arm_m: 0.01,
        }
    }
}

/// The scalars of `e` for intrinsics of `model`, in the state's order (module docs).
pub fn parameters(e: &Estimate, model: IntrinsicsModel) -> Vec<Param> {
    let mut out = Vec::new();
    if e.time_offset {
        out.push(Param::TimeOffset);
    }
    if e.gyro_intrinsics {
        out.extend((0..6).map(Param::Intrinsic));
        if model == IntrinsicsModel::Kalibr {
            out.extend((12..15).map(Param::Intrinsic));
        }
    }
    if e.g_sensitivity {
        out.extend((15..24).map(Param::Intrinsic));
    }
    if e.accel_intrinsics {
        out.extend((6..12).map(Param::Intrinsic));
        if model == IntrinsicsModel::Rpng {
            out.extend((12..15).map(Param::Intrinsic));
        }
    }
    if e.extrinsic_rotation {
        out.extend((0..3).map(Param::ExtrinsicRotation));
    }
    if e.lever_arm {
        out.extend((0..3).map(Param::LeverArm));
    }
    out
}

/// An estimated parameter with its standard deviation; `excited: false` means the estimate is
/// withheld: `value` is the initial value and `std` the deviation the data would have given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParameterEstimate {
    /// Which parameter.
    pub param: Param,
    /// Its value: `t_d` \[s\], the intrinsics' entry, the lever arm's component \[m\], or the
    /// angle \[rad\] of the estimated rotation relative to the initial one (the rotation itself
    /// is in the result's intrinsics or extrinsic).
    pub value: f64,
    /// Its standard deviation (same unit; `+∞` when the motion does not move it at all).
    pub std: f64,
    /// Whether it passed the excitation limit (module docs).
    pub excited: bool,
}

/// The linearisation point of the calibration parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Calibration {
    pub(crate) intrinsics: ImuIntrinsics,
    pub(crate) td_s: f64,
    /// The pose of the IMU in the frame of the poses (`R_bs`, `p_bs`).
    pub(crate) extrinsic: SensorPose,
    /// The scale of the poses' positions \[m per unit\] (1 for metric poses).
    pub(crate) scale: f64,
}

impl Calibration {
    /// The initial calibration of `opts`.
    pub(crate) fn initial(opts: &super::KnownPoseOptions) -> Self {
        Self {
            intrinsics: opts.initial_intrinsics,
            td_s: opts.initial_time_offset_s,
            extrinsic: opts.initial_extrinsic.unwrap_or_else(identity_pose),
            scale: opts.initial_scale,
        }
    }

    /// The preintegration parameters with these intrinsics applied (with their Jacobians when
    /// `jacobians`).
    pub(crate) fn params(&self, base: &PreintParams, jacobians: bool) -> PreintParams {
        PreintParams {
            intrinsics: Some(AppliedIntrinsics {
                model: self.intrinsics,
                jacobians,
            }),
            ..base.clone()
        }
    }

    /// The offset in integer nanoseconds (the windows' shift).
    pub(crate) fn td_ns(&self) -> i64 {
        preint::time_offset::offset_ns(self.td_s)
    }

    /// Moved by the state's correction `e` of the scalars `params`.
    pub(crate) fn moved(&self, params: &[Param], e: &[f64]) -> Calibration {
        let mut delta = SVector::<f64, { ImuIntrinsics::PARAMS }>::zeros();
        let mut td = self.td_s;
        let mut scale = self.scale;
        for (p, v) in params.iter().zip(e) {
            match p {
                Param::TimeOffset => td += v,
                Param::Intrinsic(i) => delta[*i] = *v,
                Param::Scale => scale += v,
                Param::ExtrinsicRotation(_) | Param::LeverArm(_) => {}
            }
        }
        Calibration {
            intrinsics: self.intrinsics.perturbed(&delta),
            td_s: td,
            extrinsic: super::extrinsic::moved(
                &self.extrinsic,
                &super::extrinsic::correction(params, e),
            ),
            scale,
        }
    }

    /// The estimate's value of `p` (module docs of [`ParameterEstimate::value`]): the angle
    /// entries are those of `Log(R_initialᵀ R)`.
    pub(crate) fn value(&self, p: Param, initial: &Calibration) -> f64 {
        let x = &self.intrinsics;
        let initial_x = &initial.intrinsics;
        match p {
            Param::ExtrinsicRotation(i) => {
                self.extrinsic.rotation.minus(&initial.extrinsic.rotation)[i]
            }
            Param::LeverArm(i) => self.extrinsic.translation[i],
            Param::Scale => self.scale,
            Param::TimeOffset => self.td_s,
            Param::Intrinsic(i) if i < 12 => x.params()[i],
            Param::Intrinsic(i) if i < 15 => {
                let (r0, r) = match x.model {
                    IntrinsicsModel::Kalibr => (initial_x.r_imu_to_gyro, x.r_imu_to_gyro),
                    IntrinsicsModel::Rpng => (initial_x.r_imu_to_acc, x.r_imu_to_acc),
                };
                let d = preint_lie::SO3::from_matrix(&(r0.transpose() * r)).log();
                d[i - 12]
            }
            Param::Intrinsic(i) => x.params()[i],
        }
    }
}

/// The window `[t_i_ns, t_j_ns]` (keyframe clock) preintegrated at the calibration `c` and
/// bias `bias`, and the 9 × `params.len()` Jacobian of its `[δφ, δv, δp]` with respect to the
/// scalars `params` (module docs).
pub(crate) fn window(
    base: &PreintParams,
    c: &Calibration,
    params: &[Param],
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
) -> Result<(PreintegratedImu, DMatrix<f64>), PreintError> {
    let td = c.td_ns();
    let (ti, tj) = (t_i_ns.saturating_add(td), t_j_ns.saturating_add(td));
    let intrinsic = params.iter().any(|p| matches!(p, Param::Intrinsic(_)));
    let (pim, jac) = if intrinsic {
        let (m, j) = preint::preintegrate_with_intrinsic_jacobian(
            &c.params(base, true),
            bias,
            samples,
            ti,
            tj,
        )?;
        (m, Some(j))
    } else {
        let m = preint::preintegrate(&c.params(base, false), bias, samples, ti, tj)?;
        (m, None)
    };
    let mut out = DMatrix::zeros(9, params.len());
    for (k, p) in params.iter().enumerate() {
        match (p, &jac) {
            (Param::TimeOffset, _) => out.column_mut(k).copy_from(&pim.jac_td),
            (Param::Intrinsic(i), Some(j)) => out.column_mut(k).copy_from(&j.column(*i)),
            // `jac` is present whenever an intrinsic parameter is asked for; the extrinsic
            // transform and the scale move the poses, not the deltas ([`super::extrinsic`]).
            (Param::Intrinsic(_), None)
            | (Param::ExtrinsicRotation(_), _)
            | (Param::LeverArm(_), _)
            | (Param::Scale, _) => {}
        }
    }
    Ok((pim, out))
}

/// A fit of the excited parameters and every asked-for parameter's estimate.
pub(crate) struct Excited<T> {
    pub(crate) fit: T,
    pub(crate) parameters: Vec<ParameterEstimate>,
}

/// Fits the parameters `asked` with `fit` (which returns its fit, the calibration it reached
/// and the standard deviations of the parameters it was given) and, while some are over their
/// limit, withholds those with an infinite σ or else the one furthest over (in σ / limit), and
/// fits again (module docs).
pub(crate) fn fit_excited<T>(
    asked: &[Param],
    initial: &Calibration,
    limits: &ExcitationLimits,
    mut fit: impl FnMut(&[Param]) -> Result<(T, Calibration, Vec<f64>), BiasError>,
) -> Result<Excited<T>, BiasError> {
    let mut active = asked.to_vec();
    let mut withheld: Vec<(Param, f64)> = Vec::new();
    loop {
        let (f, calib, stds) = fit(&active)?;
        let excited = |k: usize| stds[k] <= active[k].limit(limits);
        if (0..active.len()).all(excited) {
            let mut parameters: Vec<ParameterEstimate> = active
                .iter()
                .zip(&stds)
                .map(|(p, std)| (*p, calib.value(*p, initial), *std, true))
                .chain(
                    withheld
                        .iter()
                        .map(|(p, std)| (*p, initial.value(*p, initial), *std, false)),
                )
                .map(|(param, value, std, excited)| ParameterEstimate {
                    param,
                    value,
                    std,
                    excited,
                })
                .collect();
            parameters.sort_by_key(|e| asked.iter().position(|p| *p == e.param));
            return Ok(Excited { fit: f, parameters });
        }
        // Parameters the motion does not move at all go together; of the others the weakest
        // alone, because withholding it may make the rest excited.
        let ratio = |k: usize| stds[k] / active[k].limit(limits);
        let drop: Vec<usize> = if stds.iter().any(|s| !s.is_finite()) {
            (0..active.len())
                .filter(|&k| !stds[k].is_finite())
                .collect()
        } else {
            (0..active.len())
                .max_by(|&a, &b| ratio(a).total_cmp(&ratio(b)))
                .into_iter()
                .collect()
        };
        withheld.extend(drop.iter().map(|&k| (active[k], stds[k])));
        active = (0..active.len())
            .filter(|k| !drop.contains(k))
            .map(|k| active[k])
            .collect();
    }
}

/// The windows between consecutive keyframe `times` preintegrated at `lin` with their
/// calibration Jacobians ([`window`]).
pub(crate) fn windows(
    base: &PreintParams,
    (bias, calib): &(ImuBias, Calibration),
    params: &[Param],
    samples: &[ImuSample],
    times: impl Iterator<Item = (i64, i64)>,
) -> Result<(Vec<PreintegratedImu>, Vec<DMatrix<f64>>), PreintError> {
    let (mut pims, mut jacs) = (Vec::new(), Vec::new());
    for t in times {
        let (pim, j) = window(base, calib, params, bias, samples, t)?;
        pims.push(pim);
        jacs.push(j);
    }
    Ok((pims, jacs))
}

/// A converged fit: the last solve, the bias and calibration it reached.
pub(crate) struct Relinearised<X> {
    pub(crate) sol: Solution<X>,
    pub(crate) bias: ImuBias,
    pub(crate) calib: Calibration,
    pub(crate) iterations: u64,
    pub(crate) solves: usize,
}

/// The state's vector part and where the calibration corrections `e` start in it.
pub(crate) struct Layout<X> {
    /// The vector of a state.
    pub(crate) vec: fn(&X) -> &DVector<f64>,
    /// The same, to write.
    pub(crate) vec_mut: fn(&mut X) -> &mut DVector<f64>,
    /// Index of `e` in it.
    pub(crate) eo: usize,
    /// The bias of a state, given the linearisation point's (for the entries it does not hold).
    pub(crate) bias: fn(&DVector<f64>, &ImuBias) -> ImuBias,
}

/// Solves at the linearisation point (`solve`), folds the state's `e` into the calibration,
/// resets it, and solves again until the bias moves by less than 1e-6 and every parameter by
/// less than 1e-3 of its excitation limit, or `opts.max_relinearizations` (module docs).
pub(crate) fn relinearise<X: Clone + preint_lie::Manifold>(
    opts: &super::KnownPoseOptions,
    active: &[Param],
    mut x: X,
    layout: &Layout<X>,
    mut solve: impl FnMut(&(ImuBias, Calibration), X) -> Result<Solution<X>, BiasError>,
) -> Result<Relinearised<X>, BiasError> {
    let mut lin = (opts.initial_bias, Calibration::initial(opts));
    let (mut iterations, mut solves) = (0, 0);
    loop {
        let sol = solve(&lin, x)?;
        solves += 1;
        iterations += sol.iterations;
        let p = (layout.vec)(&sol.estimate);
        let b = (layout.bias)(p, &lin.0);
        let e: Vec<f64> = p.rows(layout.eo, active.len()).iter().copied().collect();
        let moved = (b.gyro - lin.0.gyro).norm() + (b.acc - lin.0.acc).norm();
        let moved_e = active
            .iter()
            .zip(&e)
            .map(|(q, v)| v.abs() / q.limit(&opts.excitation))
            .fold(0.0, f64::max);
        lin = (b, lin.1.moved(active, &e));
        x = sol.estimate.clone();
        (layout.vec_mut)(&mut x)
            .rows_mut(layout.eo, active.len())
            .fill(0.0);
        if (moved < 1e-6 && moved_e < 1e-3) || solves > opts.max_relinearizations {
            return Ok(Relinearised {
                sol,
                bias: b,
                calib: lin.1,
                iterations,
                solves,
            });
        }
    }
}
