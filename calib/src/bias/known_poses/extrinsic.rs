//! The IMU's pose in the frame of the known poses (a camera, a lidar, a motion-capture body):
//! the extrinsic rotation `R_bs` and the lever arm `p_bs`, the transform `--body-p-sensor`
//! takes (GTSAM's `body_P_sensor`, the poses being the body's; Kalibr's `T_cam_imu`).
//!
//! # Model
//! The poses `(R̃_k, p̃_k)` are of a frame b rigidly attached to the IMU s. The IMU's pose is
//!
//! ```text
//! R_s,k = R̃_k R_bs,      p_s,k = p̃_k + R̃_k p_bs
//! ```
//!
//! and the residuals of [`super::residuals`] are those of the IMU poses; velocities are the
//! IMU's. The state carries the corrections `R_bs·Exp(δθ)` and `p_bs + δp` beside the other
//! calibration parameters ([`super::extras`]), folded into the linearisation point at each
//! re-linearisation.
//!
//! # Jacobians
//! A right perturbation of `R_bs` is the same right perturbation of every IMU attitude, and
//! leaves the IMU positions unchanged. With `M = R_s,iᵀR_s,j`,
//! `y_v = R_s,iᵀ(v_j − v_i − gΔt)` and `y_p = R_s,iᵀ(p_s,j − p_s,i − v_iΔt − ½gΔt²)`:
//!
//! ```text
//! ∂r_φ/∂δθ = Jr⁻¹(r_φ)(I − Mᵀ),   ∂r_v/∂δθ = [y_v]×,   ∂r_p/∂δθ = [y_p]×,
//! ∂r_p/∂δp = R_s,iᵀ(R̃_j − R̃_i)
//! ```
//!
//! (at a correction `δθ ≠ 0` within a solve the rotation columns are multiplied by `Jr(δθ)`).
//! The lever arm is seen only through the change of attitude between poses: a motion without
//! rotation about an axis leaves the lever arm along that axis unobservable, and its σ grows as
//! the rotation shrinks. [`ExtrinsicEstimate::rotation_rms_rad_s`] says how much the poses
//! rotate about each of their axes.
//!
//! # Pose noise
//! The attitude noise of the poses, `R̃ = R·Exp(n_R)`, is the IMU attitude noise
//! `n_s = R_bsᵀn_R` (isotropic as before) and moves the IMU position by `−R̃[p_bs]×R_bs n_s`:
//! with `q = R_bsᵀp_bs` it adds `[q]×` to the position rows of pose i's Jacobian and
//! `−M[q]×` to those of pose j ([`super::pose_noise`]).
//!
//! # Start
//! Without a given initial transform the rotation starts at the hand-eye rotation of the gyro
//! and the poses ([`super::conventions::hand_eye_rotation`]: the Kabsch solution on the
//! rotation vectors of the windows), so no initial guess is needed; the lever arm starts at
//! zero (the residuals are linear in it).

use super::KnownPose;
use super::extras::Param;
use nalgebra::{DVector, Matrix3, Matrix6, SMatrix, Vector3};
use preint::SensorPose;
use preint_lie::{hat, jr, jr_inv};

/// Where the extrinsic estimate started (module docs, "Start").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtrinsicStart {
    /// The given initial transform ([`super::KnownPoseOptions::initial_extrinsic`]).
    Given,
    /// The hand-eye rotation, lever arm zero.
    HandEye,
    /// The identity: the motion does not rotate about two independent axes, so the hand-eye
    /// rotation does not exist.
    Identity,
}

/// The estimated pose of the IMU in the frame of the poses (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtrinsicEstimate {
    /// `R_bs` (IMU → pose frame) and `p_bs` \[m, pose frame\]: estimated where excited, the
    /// start elsewhere.
    pub body_p_sensor: SensorPose,
    /// Covariance of `[δθ (rad, right perturbation of R_bs), δp (m, pose frame)]`; the rows and
    /// columns of a withheld or unasked component are NaN.
    pub covariance: Matrix6<f64>,
    /// Whether every component of the rotation was asked for and excited.
    pub rotation_excited: bool,
    /// Whether every component of the lever arm was asked for and excited.
    pub lever_arm_excited: bool,
    /// Where the estimate started.
    pub start: ExtrinsicStart,
    /// RMS angular rate of the poses about each of their axes \[rad/s\] (the lever arm along
    /// an axis needs rotation about the other two).
    pub rotation_rms_rad_s: Vector3<f64>,
}

impl ExtrinsicEstimate {
    /// Standard deviations of `[δθ, δp]` (NaN where withheld).
    pub fn std(&self) -> [f64; 6] {
        std::array::from_fn(|k| self.covariance[(k, k)].sqrt())
    }
}

/// The IMU's pose from the pose `p` of the frame b (module docs).
pub(crate) fn imu_pose(p: &KnownPose, x: &SensorPose) -> KnownPose {
    KnownPose {
        t_ns: p.t_ns,
        r: p.r.compose(&x.rotation),
        p: p.p + p.r.act(&x.translation),
    }
}

/// The IMU's poses from the poses of the frame b, their positions scaled by `scale` \[m per
/// unit\] (1 for metric poses; [`super::KnownPoseOptions::estimate_scale`]).
pub(crate) fn imu_poses(poses: &[KnownPose], x: &SensorPose, scale: f64) -> Vec<KnownPose> {
    poses
        .iter()
        .map(|p| imu_pose(&scaled(p, scale), x))
        .collect()
}

/// The pose with its position scaled by `s`.
pub(crate) fn scaled(p: &KnownPose, s: f64) -> KnownPose {
    KnownPose { p: p.p * s, ..*p }
}

/// The state's correction `(δθ, δp)` of the extrinsic transform: the entries of `e` (in the
/// order of `active`) that are extrinsic, zero elsewhere.
pub(crate) fn correction(active: &[Param], e: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
    let (mut dth, mut dp) = (Vector3::zeros(), Vector3::zeros());
    for (p, v) in active.iter().zip(e) {
        match p {
            Param::ExtrinsicRotation(i) => dth[*i] = *v,
            Param::LeverArm(i) => dp[*i] = *v,
            Param::TimeOffset | Param::Intrinsic(_) | Param::Scale => {}
        }
    }
    (dth, dp)
}

/// The transform at the linearisation point `x` moved by the correction `(δθ, δp)`.
pub(crate) fn moved(x: &SensorPose, (dth, dp): &(Vector3<f64>, Vector3<f64>)) -> SensorPose {
    SensorPose::new(x.rotation.plus(dth), x.translation + dp)
}

/// One window's quantities the extrinsic columns need (module docs, "Jacobians").
pub(crate) struct WindowTerms<'a> {
    /// The given poses i and j (frame b).
    pub(crate) given: (&'a KnownPose, &'a KnownPose),
    /// `R_s,iᵀ`.
    pub(crate) rit: Matrix3<f64>,
    /// `M = R_s,iᵀR_s,j`.
    pub(crate) m: Matrix3<f64>,
    /// `r_φ`.
    pub(crate) rphi: Vector3<f64>,
    /// `y_v`, `y_p` (the velocity and position residuals before the deltas are subtracted).
    pub(crate) y: (Vector3<f64>, Vector3<f64>),
}

/// The 9×3 Jacobians of `[r_φ, r_v, r_p]` with respect to the state's `δθ` and `δp` (module
/// docs), `dth` the current rotation correction.
pub(crate) fn jacobians(
    w: &WindowTerms,
    dth: &Vector3<f64>,
) -> (SMatrix<f64, 9, 3>, SMatrix<f64, 9, 3>) {
    let mut d_rot = SMatrix::<f64, 9, 3>::zeros();
    d_rot
        .fixed_rows_mut::<3>(0)
        .copy_from(&(jr_inv(&w.rphi) * (Matrix3::identity() - w.m.transpose())));
    d_rot.fixed_rows_mut::<3>(3).copy_from(&hat(&w.y.0));
    d_rot.fixed_rows_mut::<3>(6).copy_from(&hat(&w.y.1));
    let d_rot = d_rot * jr(dth);
    let mut d_p = SMatrix::<f64, 9, 3>::zeros();
    let (gi, gj) = w.given;
    d_p.fixed_rows_mut::<3>(6)
        .copy_from(&(w.rit * (gj.r.matrix() - gi.r.matrix())));
    (d_rot, d_p)
}

/// RMS angular rate of the poses about each of their axes \[rad/s\].
pub(crate) fn rotation_rms(poses: &[KnownPose]) -> Vector3<f64> {
    let mut sum = Vector3::zeros();
    let mut t = 0.0;
    for w in poses.windows(2) {
        let dt = preint::dt_seconds(w[0].t_ns, w[1].t_ns);
        let rate = w[0].r.inverse().compose(&w[1].r).log() / dt;
        sum += rate.component_mul(&rate) * dt;
        t += dt;
    }
    (sum / t).map(f64::sqrt)
}

/// The extrinsic estimate from the solution: `x` the converged transform, `cov` the solver
/// covariance, `eo` where `e` starts in the state vector, `active` its parameters.
pub(crate) fn estimate(
    x: SensorPose,
    cov: &nalgebra::DMatrix<f64>,
    eo: usize,
    active: &[Param],
    (start, rms): (ExtrinsicStart, Vector3<f64>),
) -> ExtrinsicEstimate {
    let slot = |p: &Param| match p {
        Param::ExtrinsicRotation(i) => Some(*i),
        Param::LeverArm(i) => Some(3 + *i),
        Param::TimeOffset | Param::Intrinsic(_) | Param::Scale => None,
    };
    let mut covariance = Matrix6::from_element(f64::NAN);
    let idx: Vec<(usize, usize)> = active
        .iter()
        .enumerate()
        .filter_map(|(k, p)| slot(p).map(|s| (s, eo + k)))
        .collect();
    for &(a, ka) in &idx {
        for &(b, kb) in &idx {
            covariance[(a, b)] = cov[(ka, kb)];
        }
    }
    let all = |mut range: std::ops::Range<usize>| range.all(|s| idx.iter().any(|(a, _)| *a == s));
    ExtrinsicEstimate {
        body_p_sensor: x,
        covariance,
        rotation_excited: all(0..3),
        lever_arm_excited: all(3..6),
        start,
        rotation_rms_rad_s: rms,
    }
}

/// The extrinsic corrections of a state vector `p` (`e` from `eo`, in the order of `active`).
pub(crate) fn state_correction(
    p: &DVector<f64>,
    eo: usize,
    active: &[Param],
) -> (Vector3<f64>, Vector3<f64>) {
    let e: Vec<f64> = p.rows(eo, active.len()).iter().copied().collect();
    correction(active, &e)
}

/// The lever arm in the IMU frame, `q = R_bsᵀp_bs` (module docs, "Pose noise").
pub(crate) fn lever_in_imu(x: &SensorPose) -> Vector3<f64> {
    x.rotation.inverse().act(&x.translation)
}
