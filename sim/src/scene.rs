//! The [`Scene`] trait, the exact kinematic state it returns, and the registry of named scenes.
//!
//! Frames: world `w` is z-up; body `b` is the IMU frame. `r_wb` maps body vectors into the
//! world (`x_w = R_wb x_b`). Every scene gives analytic derivatives (no finite differences):
//! `v = ṗ`, `a = p̈`, `Ṙ_wb = R_wb [ω_b]×`, `ω̇_b = d/dt ω_b`.

use crate::scenes::{
    EulerScene, GimbalLockScene, MultiPoseStaticScene, SeedEllipseScene, SpinScene, StaticScene,
};
use nalgebra::Vector3;
use preint::ImuSample;
use preint_lie::SO3;

/// The exact kinematic state of the body at one instant (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneState {
    /// Position of the body in the world frame \[m\].
    pub p: Vector3<f64>,
    /// Velocity in the world frame, `ṗ` [m/s].
    pub v: Vector3<f64>,
    /// Kinematic acceleration in the world frame, `p̈` [m/s²] (gravity not included).
    pub a: Vector3<f64>,
    /// Attitude, body→world (`x_w = R_wb x_b`).
    pub r_wb: SO3,
    /// Angular velocity of the body w.r.t. the world, in the body frame [rad/s]:
    /// `Ṙ_wb = R_wb [ω_b]×`.
    pub omega_b: Vector3<f64>,
    /// Its time derivative `ω̇_b` [rad/s²], body frame.
    pub omega_dot_b: Vector3<f64>,
}

impl SceneState {
    /// What an ideal IMU (no bias, noise or scale error) reads in this state at `t_ns`: gyro
    /// `ω_b` [rad/s], accelerometer the specific force `R_wbᵀ(a − g)` [m/s²] for the world
    /// gravity `gravity` (e.g. `(0, 0, −9.81)`), both in the body frame.
    pub fn ideal_sample(&self, t_ns: i64, gravity: &Vector3<f64>) -> ImuSample {
        ImuSample::new(
            t_ns,
            self.omega_b,
            self.r_wb.inverse().act(&(self.a - gravity)),
        )
    }
}

impl SceneState {
    /// The state of a sensor mounted at `pose` in the body (sensor → body rotation `R`,
    /// sensor origin `r` \[m\] in body coordinates), by rigid-body kinematics: position
    /// `p + R_wb r`, velocity `v + R_wb (ω_b × r)`, acceleration
    /// `a + R_wb (ω̇_b × r + ω_b × (ω_b × r))`, attitude `R_wb R`, rate `Rᵀ ω_b` and its
    /// derivative `Rᵀ ω̇_b`.
    pub fn at_sensor(&self, pose: &preint::SensorPose) -> SceneState {
        let (w, wd, r) = (self.omega_b, self.omega_dot_b, pose.translation);
        let rt = pose.rotation.inverse();
        SceneState {
            p: self.p + self.r_wb.act(&r),
            v: self.v + self.r_wb.act(&w.cross(&r)),
            a: self.a + self.r_wb.act(&(wd.cross(&r) + w.cross(&w.cross(&r)))),
            r_wb: self.r_wb.compose(&pose.rotation),
            omega_b: rt.act(&w),
            omega_dot_b: rt.act(&wd),
        }
    }

    /// What an ideal IMU mounted at `pose` in the body reads in this state at `t_ns`: the body
    /// rate in sensor axes and the specific force of the sensor's point,
    /// `f_s = Rᵀ (R_wbᵀ(a − g) + ω̇_b × r + ω_b × (ω_b × r))` (the ideal sample of
    /// [`SceneState::at_sensor`]).
    pub fn sensor_sample(
        &self,
        t_ns: i64,
        gravity: &Vector3<f64>,
        pose: &preint::SensorPose,
    ) -> ImuSample {
        self.at_sensor(pose).ideal_sample(t_ns, gravity)
    }
}

/// A trajectory with analytic derivatives, defined for every `t_s` (seconds from the scene
/// start, which is timestamp 0 ns; see [`t_s`]).
pub trait Scene {
    /// The scene's registry name (one of [`SCENE_NAMES`] for the built-in scenes).
    fn name(&self) -> &str;
    /// The exact state at time `t_s` \[s\].
    fn state(&self, t_s: f64) -> SceneState;
}

/// Scene time \[s\] of an integer-nanosecond timestamp, relative to the scene start at 0 ns:
/// `t_s = ns · 1e-9`.
#[inline]
pub fn t_s(ns: i64) -> f64 {
    ns as f64 * 1e-9
}

/// Names of the built-in scenes, in the order they are documented.
pub const SCENE_NAMES: &[&str] = &[
    "seed-ellipse",
    "static",
    "multi-pose-static",
    "gimbal-lock",
    "spin",
    "aggressive",
];

/// The built-in scene called `name` (see [`SCENE_NAMES`]) with its default parameters, or
/// `None` for an unknown name.
///
/// - `seed-ellipse`: [`SeedEllipseScene`]
/// - `static`: [`StaticScene::default`]
/// - `multi-pose-static`: [`MultiPoseStaticScene::default`]
/// - `gimbal-lock`: [`GimbalLockScene`]
/// - `spin`: [`SpinScene::default`]
/// - `aggressive`: [`EulerScene::aggressive`]
pub fn scene_by_name(name: &str) -> Option<Box<dyn Scene + Send + Sync>> {
    let s: Box<dyn Scene + Send + Sync> = match name {
        "seed-ellipse" => Box::new(SeedEllipseScene),
        "static" => Box::new(StaticScene::default()),
        "multi-pose-static" => Box::new(MultiPoseStaticScene::default()),
        "gimbal-lock" => Box::new(GimbalLockScene),
        "spin" => Box::new(SpinScene::default()),
        "aggressive" => Box::new(EulerScene::aggressive()),
        _ => return None,
    };
    Some(s)
}

/// Rotation matrix of ZYX Euler angles `(roll φ, pitch θ, yaw ψ)`:
/// `R_wb = Rz(ψ)·Ry(θ)·Rx(φ)` (body→world).
pub fn rot_zyx(euler: &Vector3<f64>) -> SO3 {
    let (sr, cr) = euler.x.sin_cos();
    let (sp, cp) = euler.y.sin_cos();
    let (sy, cy) = euler.z.sin_cos();
    SO3::from_matrix_unchecked(nalgebra::Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    ))
}

/// Euler-rate→body-rate matrix `W(φ, θ)` of ZYX angles (the notes' eq. 31):
/// `ω_b = W [φ̇, θ̇, ψ̇]ᵀ` with
/// `W = [[1, 0, −sin θ], [0, cos φ, sin φ cos θ], [0, −sin φ, cos φ cos θ]]`.
/// Regular everywhere; its inverse [`body_rate_to_euler_rate`] is singular at `θ = ±90°`.
pub fn euler_rate_to_body_rate(euler: &Vector3<f64>) -> nalgebra::Matrix3<f64> {
    let (sr, cr) = euler.x.sin_cos();
    let (sp, cp) = euler.y.sin_cos();
    nalgebra::Matrix3::new(1.0, 0.0, -sp, 0.0, cr, sr * cp, 0.0, -sr, cr * cp)
}

/// Body-rate→Euler-rate matrix `E(φ, θ) = W⁻¹` of ZYX angles (the notes' section 4):
/// `[φ̇, θ̇, ψ̇]ᵀ = E ω_b` with
/// `E = [[1, sin φ tan θ, cos φ tan θ], [0, cos φ, −sin φ], [0, sin φ / cos θ, cos φ / cos θ]]`.
/// Singular at pitch `θ = ±90°` (gimbal lock): entries become huge or infinite there; this
/// function never panics.
pub fn body_rate_to_euler_rate(euler: &Vector3<f64>) -> nalgebra::Matrix3<f64> {
    let (sr, cr) = euler.x.sin_cos();
    let (sp, cp) = euler.y.sin_cos();
    let tp = sp / cp;
    nalgebra::Matrix3::new(1.0, sr * tp, cr * tp, 0.0, cr, -sr, 0.0, sr / cp, cr / cp)
}

/// Body rate and its derivative from ZYX Euler angles Θ = (φ, θ, ψ), rates Θ̇ and
/// accelerations Θ̈: `ω_b = W(Θ) Θ̇`, `ω̇_b = W(Θ) Θ̈ + Ẇ(Θ, Θ̇) Θ̇` with
/// `Ẇ = [[0, 0, −cos θ θ̇], [0, −sin φ φ̇, cos φ cos θ φ̇ − sin φ sin θ θ̇],
///       [0, −cos φ φ̇, −sin φ cos θ φ̇ − cos φ sin θ θ̇]]`.
pub fn euler_zyx_body_rates(
    euler: &Vector3<f64>,
    euler_rate: &Vector3<f64>,
    euler_acc: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let w = euler_rate_to_body_rate(euler);
    let (sr, cr) = euler.x.sin_cos();
    let (sp, cp) = euler.y.sin_cos();
    let (dr, dp) = (euler_rate.x, euler_rate.y);
    let w_dot = nalgebra::Matrix3::new(
        0.0,
        0.0,
        -cp * dp,
        0.0,
        -sr * dr,
        cr * cp * dr - sr * sp * dp,
        0.0,
        -cr * dr,
        -sr * cp * dr - cr * sp * dp,
    );
    (w * euler_rate, w * euler_acc + w_dot * euler_rate)
}

/// Convenience used by [`EulerScene`]-based scenes: the full state from position derivatives
/// and ZYX Euler angles with their first two derivatives.
pub(crate) fn state_from_euler(p: [Vector3<f64>; 3], euler: [Vector3<f64>; 3]) -> SceneState {
    let (omega_b, omega_dot_b) = euler_zyx_body_rates(&euler[0], &euler[1], &euler[2]);
    SceneState {
        p: p[0],
        v: p[1],
        a: p[2],
        r_wb: rot_zyx(&euler[0]),
        omega_b,
        omega_dot_b,
    }
}
