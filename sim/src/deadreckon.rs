//! Dead reckoning: full navigation state (R, v, p) integrated from IMU samples, with two time rules and three attitude representations.
//!
//! Bias-corrected inputs: `ω_k = ω_m,k − b_g`, world acceleration `a_k = R_k (a_m,k − b_a) + g`
//! (`g` = world gravity, default `(0, 0, −9.81)`). Interval `k` is `[t_k, t_k+1]`,
//! `Δt = (t_k+1 − t_k)·1e-9` s.
//!
//! **Rules**
//! - [`Rule::Euler`] (sample k held over interval k):
//!   `R_k+1 = R_k ⊞ ω_k Δt`, `p_k+1 = p_k + v_k Δt + ½ a_k Δt²`, `v_k+1 = v_k + a_k Δt`.
//! - [`Rule::Midpoint`]: `ω̄ = ½(ω_k + ω_k+1)`, `R_k+1 = R_k ⊞ ω̄ Δt`,
//!   `ā = ½[(R_k (a_m,k − b_a) + g) + (R_k+1 (a_m,k+1 − b_a) + g)]`,
//!   `p_k+1 = p_k + v_k Δt + ½ ā Δt²`, `v_k+1 = v_k + ā Δt` (the notes' midpoint method, with
//!   the accelerometer bias where the notes misprint the gyro bias).
//!
//! **Attitude update `R ⊞ θ` (θ = body rotation vector over the step)**
//! - [`Attitude::Quaternion`]: the notes' first-order `q ← q ⊗ [1, ½θ]`, then `q ← q/‖q‖`
//!   (rotation angle `2 atan(‖θ‖/2) = ‖θ‖ − ‖θ‖³/12 + …`: local error O(Δt³)).
//! - [`Attitude::Matrix`]: exact `R ← R·Exp(θ)` (Rodrigues, [`preint_lie::SO3::exp`]).
//! - [`Attitude::EulerZyx`]: ZYX angles Θ = (roll φ, pitch θ, yaw ψ), `R = Rz(ψ)Ry(θ)Rx(φ)`,
//!   `Θ̇ = E(φ, θ) ω_b` ([`crate::scene::body_rate_to_euler_rate`], singular at θ = ±90°).
//!   Euler rule: `Θ ← Θ + E(Θ) ω_k Δt`; midpoint rule (explicit midpoint, second order):
//!   `Θ_½ = Θ + ½ E(Θ) ω̄ Δt`, `Θ ← Θ + E(Θ_½) ω̄ Δt`. Near gimbal lock `E` blows up and the
//!   angles may jump, become huge or NaN; that is a *result* (this code never panics).
//!   [`euler_zyx_angles`] returns the raw (unwrapped) angle states. See
//!   [`crate::scenes::GimbalLockScene`] for how it fails, measured.
//!
//! Orders on smooth motion, noise-free (`tests/deadreckon.rs`, `seed-ellipse`): the Euler rule
//! is first order in Δt (global error ∝ Δt), the midpoint rule second order (∝ Δt²) with any
//! of the three attitude updates. Quaternion and matrix differ by O(Δt²) under *both* rules
//! (the quaternion update's `2 atan(|θ|/2) = |θ| − |θ|³/12 + …` is an O(Δt³) local
//! difference on the same θ), measured 4.00× smaller per rate doubling.

use crate::scene::{body_rate_to_euler_rate, rot_zyx};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use preint::{ImuBias, ImuSample, NavState};
use preint_lie::SO3;

/// Time-discretisation rule (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Rule {
    /// Sample k held constant over `[t_k, t_k+1]` (first order).
    Euler,
    /// Mean of the endpoint rates and of the endpoint world accelerations (second order).
    Midpoint,
}

/// How the attitude is stored and updated (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Attitude {
    /// Unit quaternion with the first-order update `q ⊗ [1, ½θ]` and normalisation.
    Quaternion,
    /// Rotation matrix with the exact `Exp`.
    Matrix,
    /// ZYX Euler angles with the body-rate→Euler-rate matrix `E(φ, θ)`.
    EulerZyx,
}

/// Internal attitude state in the chosen representation.
#[derive(Clone, Copy, Debug)]
enum AttState {
    Quat(nalgebra::Quaternion<f64>),
    Mat(SO3),
    Euler(Vector3<f64>),
}

impl AttState {
    fn new(kind: Attitude, r: &SO3) -> Self {
        match kind {
            Attitude::Quaternion => AttState::Quat(*r.to_quaternion().quaternion()),
            Attitude::Matrix => AttState::Mat(*r),
            Attitude::EulerZyx => AttState::Euler(euler_zyx_of(r)),
        }
    }

    /// Body→world rotation matrix (may hold NaN for a diverged Euler-angle state).
    fn rotation(&self) -> SO3 {
        match self {
            AttState::Quat(q) => SO3::from_quaternion(&UnitQuaternion::new_unchecked(*q)),
            AttState::Mat(r) => *r,
            AttState::Euler(e) => rot_zyx(e),
        }
    }

    /// `self ⊞ θ` with the Euler-rule update, or for Euler angles the explicit midpoint when
    /// `midpoint` is set.
    fn step(&self, theta: &Vector3<f64>, midpoint: bool) -> Self {
        match self {
            AttState::Quat(q) => {
                let dq =
                    nalgebra::Quaternion::new(1.0, 0.5 * theta.x, 0.5 * theta.y, 0.5 * theta.z);
                let qn = q * dq;
                AttState::Quat(qn / qn.norm())
            }
            AttState::Mat(r) => AttState::Mat(*r * SO3::exp(theta)),
            AttState::Euler(e) => AttState::Euler(euler_zyx_step(e, theta, midpoint)),
        }
    }
}

/// One ZYX Euler-angle attitude step `Θ ⊞ θ` (θ = body rotation vector over the step \[rad\],
/// i.e. `ω Δt`): `Θ + E(Θ) θ` (Euler rule), or the explicit midpoint
/// `Θ_½ = Θ + ½ E(Θ) θ`, `Θ + E(Θ_½) θ` when `midpoint` is set, with `E` =
/// [`body_rate_to_euler_rate`]. Near pitch ±90° the increment is huge or non-finite; nothing
/// here panics.
fn euler_zyx_step(e: &Vector3<f64>, theta: &Vector3<f64>, midpoint: bool) -> Vector3<f64> {
    let rate_at = |x: &Vector3<f64>| body_rate_to_euler_rate(x) * theta;
    let inc = if midpoint {
        let half = e + 0.5 * rate_at(e);
        rate_at(&half)
    } else {
        rate_at(e)
    };
    e + inc
}

/// The raw ZYX Euler-angle states `Θ_k = (roll, pitch, yaw)` \[rad\] that
/// [`dead_reckon`] with [`Attitude::EulerZyx`] integrates (attitude only: the update uses only
/// the gyro), started from `initial` at `samples[0].t_ns`, with gyro bias `gyro_bias`
/// \[rad/s\] removed. `out[k]` is the state at `samples[k].t_ns`; `out[0] == initial`. The
/// angles are *not* wrapped, so a run that meets the gimbal-lock singularity shows it as huge
/// or non-finite angles. `rot_zyx(out[k])` equals the attitude `dead_reckon` returns for
/// [`Attitude::EulerZyx`] (started from `euler_zyx_of(R_0)`).
pub fn euler_zyx_angles(
    samples: &[ImuSample],
    initial: &Vector3<f64>,
    gyro_bias: &Vector3<f64>,
    rule: Rule,
) -> Vec<Vector3<f64>> {
    let mut out = Vec::with_capacity(samples.len());
    if samples.is_empty() {
        return out;
    }
    let mut e = *initial;
    out.push(e);
    for w in samples.windows(2) {
        let dt = preint::dt_seconds(w[0].t_ns, w[1].t_ns);
        e = match rule {
            Rule::Euler => euler_zyx_step(&e, &((w[0].gyro - gyro_bias) * dt), false),
            Rule::Midpoint => {
                let w_bar = 0.5 * (w[0].gyro + w[1].gyro) - gyro_bias;
                euler_zyx_step(&e, &(w_bar * dt), true)
            }
        };
        out.push(e);
    }
    out
}

/// ZYX Euler angles `(roll, pitch, yaw)` of `R = Rz(yaw)·Ry(pitch)·Rx(roll)`, pitch in
/// [−π/2, π/2]: `pitch = asin(−R₂₀)`, `roll = atan2(R₂₁, R₂₂)`, `yaw = atan2(R₁₀, R₀₀)`
/// (at exact gimbal lock roll and yaw are not unique; this returns one valid pair).
pub fn euler_zyx_of(r: &SO3) -> Vector3<f64> {
    let m: &Matrix3<f64> = r.matrix();
    let pitch = (-m[(2, 0)]).clamp(-1.0, 1.0).asin();
    Vector3::new(
        m[(2, 1)].atan2(m[(2, 2)]),
        pitch,
        m[(1, 0)].atan2(m[(0, 0)]),
    )
}

/// Integrates the navigation state through `samples` from `initial` (the state at
/// `samples[0].t_ns`), correcting the readings with the constant `bias` and using world
/// `gravity` [m/s²]. Returns one [`NavState`] per sample (`out[k]` at `samples[k].t_ns`;
/// `out[0] == initial` up to the representation round trip; empty input gives an empty
/// output). The attitude of a diverged [`Attitude::EulerZyx`] run may be non-finite.
pub fn dead_reckon(
    samples: &[ImuSample],
    initial: &NavState,
    bias: &ImuBias,
    gravity: &Vector3<f64>,
    rule: Rule,
    attitude: Attitude,
) -> Vec<NavState> {
    let mut out = Vec::with_capacity(samples.len());
    if samples.is_empty() {
        return out;
    }
    let mut att = AttState::new(attitude, &initial.r);
    let (mut p, mut v) = (initial.p, initial.v);
    out.push(NavState::new(att.rotation(), p, v));
    for w in samples.windows(2) {
        let (s0, s1) = (&w[0], &w[1]);
        let dt = preint::dt_seconds(s0.t_ns, s1.t_ns);
        let r0 = att.rotation();
        let a0 = r0 * (s0.acc - bias.acc) + gravity;
        let (att1, a) = match rule {
            Rule::Euler => (att.step(&((s0.gyro - bias.gyro) * dt), false), a0),
            Rule::Midpoint => {
                let w_bar = 0.5 * (s0.gyro + s1.gyro) - bias.gyro;
                let att1 = att.step(&(w_bar * dt), true);
                let a1 = att1.rotation() * (s1.acc - bias.acc) + gravity;
                (att1, 0.5 * (a0 + a1))
            }
        };
        p += v * dt + a * (0.5 * dt * dt);
        v += a * dt;
        att = att1;
        out.push(NavState::new(att.rotation(), p, v));
    }
    out
}

/// Rotation error angle `‖Log(Aᵀ B)‖` \[rad\] between two attitudes, or `+∞` if either matrix
/// has a non-finite entry (a diverged Euler-angle integration).
pub fn rotation_error(a: &SO3, b: &SO3) -> f64 {
    let finite = |r: &SO3| r.matrix().iter().all(|x| x.is_finite());
    if !finite(a) || !finite(b) {
        return f64::INFINITY;
    }
    (a.inverse() * *b).log().norm()
}
