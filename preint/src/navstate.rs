//! Navigation state `(R, p, v)` (its frames and tangent order: [`NavState`]) and its prediction
//! from a preintegrated measurement.

use crate::choices::CoriolisMode;
use crate::earth::{Transport, centrifugal};
use crate::error::PreintError;
use crate::measurement::PreintegratedImu;
use crate::sample::ImuBias;
use nalgebra::{SVector, Vector3};
use preint_lie::SO3;

/// A 9-vector in the [`NavState`] tangent order [δφ, δp, δv] (rad, m, m/s).
pub type NavTangent = SVector<f64, 9>;

/// Navigation state: attitude `r` (body → world), position `p` [m, world], velocity
/// `v` [m/s, world]. The tangent order [δφ, δp, δv] and the perturbations are below.
///
/// Frames: `R` rotates body → world (`x_w = R x_b`); `p` \[m\] and `v` [m/s] are the body origin's
/// position and velocity in the world frame (z up; gravity is carried by the
/// [`PreintegratedImu`], default `(0, 0, −9.81)` m/s²).
///
/// **Tangent space and perturbation** (used by [`NavState::retract`], [`NavState::local`], the
/// [`preint_lie::Manifold`] impl and every Jacobian of [`ImuFactor`](crate::ImuFactor)): a 9-vector in the order
/// **[δφ, δp, δv]** (rad, m, m/s) with
///
/// ```text
/// R ← R·Exp(δφ)      (right, body-frame rotation perturbation)
/// p ← p + R·δp       (body-frame position perturbation)
/// v ← v + δv         (world-frame velocity perturbation)
/// ```
///
/// This is Forster et al. 2017 (T-RO), Sec. VI-B, and to first order GTSAM's: its `Pose3`
/// retract perturbs `[dw, dt]` with `dt` in the body frame, and its `ImuFactor` velocity
/// variable is a world-frame vector. The order [δφ, δp, δv] is that of GTSAM's `NavState`
/// (pose first, then velocity); it is **not** the preintegration order [δφ, δv, δp] of
/// residuals and covariances — the factor exposes named blocks so the two cannot be confused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NavState {
    /// Attitude, rotation body → world.
    pub r: SO3,
    /// Position of the body origin in the world frame \[m\].
    pub p: Vector3<f64>,
    /// Velocity of the body origin in the world frame [m/s].
    pub v: Vector3<f64>,
}

impl Default for NavState {
    fn default() -> Self {
        Self::identity()
    }
}

impl NavState {
    /// A state from its attitude (body → world), world position \[m\] and world velocity [m/s].
    pub fn new(r: SO3, p: Vector3<f64>, v: Vector3<f64>) -> Self {
        Self { r, p, v }
    }

    /// Identity attitude, zero position and velocity.
    pub fn identity() -> Self {
        Self {
            r: SO3::identity(),
            p: Vector3::zeros(),
            v: Vector3::zeros(),
        }
    }

    /// `self ⊕ d` for `d = [δφ, δp, δv]`: `(R·Exp(δφ), p + R·δp, v + δv)` ([`NavState`]).
    pub fn retract(&self, d: &NavTangent) -> Self {
        let dphi = d.fixed_rows::<3>(0).into_owned();
        let dp = d.fixed_rows::<3>(3).into_owned();
        let dv = d.fixed_rows::<3>(6).into_owned();
        Self {
            r: self.r.plus(&dphi),
            p: self.p + self.r.act(&dp),
            v: self.v + dv,
        }
    }

    /// `other ⊖ self` = `[Log(Rᵀ R_o), Rᵀ(p_o − p), v_o − v]`, the inverse of
    /// [`retract`](Self::retract): `self.retract(&self.local(&o)) == o`.
    pub fn local(&self, other: &Self) -> NavTangent {
        let mut out = NavTangent::zeros();
        out.fixed_rows_mut::<3>(0)
            .copy_from(&other.r.minus(&self.r));
        out.fixed_rows_mut::<3>(3)
            .copy_from(&self.r.inverse().act(&(other.p - self.p)));
        out.fixed_rows_mut::<3>(6).copy_from(&(other.v - self.v));
        out
    }

    /// True if every entry of `R`, `p` and `v` is finite.
    pub fn is_finite(&self) -> bool {
        self.r.matrix().iter().all(|x| x.is_finite())
            && self.p.iter().all(|x| x.is_finite())
            && self.v.iter().all(|x| x.is_finite())
    }
}

impl preint_lie::Manifold for NavState {
    fn dim(&self) -> usize {
        9
    }
    /// [`NavState::retract`]; `delta = [δφ, δp, δv]`.
    fn retract(&self, delta: &[f64]) -> Self {
        NavState::retract(self, &NavTangent::from_column_slice(delta))
    }
    /// [`NavState::local`].
    fn local(&self, other: &Self, out: &mut [f64]) {
        out.copy_from_slice(NavState::local(self, other).as_slice());
    }
}

/// Predicts the state at keyframe j from the state at i and a bias estimate (Forster et al.
/// 2017, eq. 33, with the bias-corrected deltas of eq. 44, see [`PreintegratedImu::corrected`]):
///
/// ```text
/// R_j = R_i ΔR(b)
/// v_j = v_i + g Δt + R_i Δv(b)
/// p_j = p_i + v_i Δt + ½ g Δt² + R_i Δp(b)
/// ```
///
/// `g = pim.gravity` [m/s², world], `Δt = pim.delta_t` \[s\]. `bias` is the bias at keyframe i
/// (order [b_g, b_a]); the correction is first order in `bias − pim.bias_hat`.
///
/// With `pim.omega_coriolis` set, the navigation frame rotates and the prediction follows
/// `pim.coriolis` ([`crate::earth`] for the equations of each mode).
///
/// # Panics
///
/// If `bias` cannot be applied to `pim`
/// ([`PreintegratedImu::check_bias`]: a [`Level::Deltas`](crate::Level::Deltas) measurement,
/// which has no bias Jacobians, and `bias ≠ pim.bias_hat`); [`try_predict`] returns the error
/// instead.
pub fn predict(pim: &PreintegratedImu, state_i: &NavState, bias: &ImuBias) -> NavState {
    pim.assert_bias(bias);
    predict_checked(pim, state_i, bias)
}

/// [`predict`], or [`PreintError::NoBiasJacobians`] when `bias` cannot be applied to `pim`
/// ([`PreintegratedImu::check_bias`]). Equal to [`predict`] to the bit otherwise.
pub fn try_predict(
    pim: &PreintegratedImu,
    state_i: &NavState,
    bias: &ImuBias,
) -> Result<NavState, PreintError> {
    pim.check_bias(bias)?;
    Ok(predict_checked(pim, state_i, bias))
}

/// [`predict`] for a bias [`PreintegratedImu::check_bias`] accepts.
fn predict_checked(pim: &PreintegratedImu, state_i: &NavState, bias: &ImuBias) -> NavState {
    if let Some(w) = &pim.omega_coriolis {
        return predict_rotating(pim, state_i, bias, w, pim.coriolis);
    }
    let c = crate::bias_correction::correct(pim, bias);
    let (dr, dv, dp) = (c.r, c.v, c.p);
    let dt = pim.delta_t;
    let g = pim.gravity;
    NavState {
        r: state_i.r.compose(&dr),
        v: state_i.v + g * dt + state_i.r.act(&dv),
        p: state_i.p + state_i.v * dt + g * (0.5 * dt * dt) + state_i.r.act(&dp),
    }
}

/// `state_i` propagated by the bias-corrected deltas `(ΔR, Δv, Δp)` over `T = pim.delta_t`
/// with the Earth rate `omega` [rad/s, navigation frame] in mode `mode` ([`crate::earth`]).
pub(crate) fn predict_rotating(
    pim: &PreintegratedImu,
    s: &NavState,
    bias: &ImuBias,
    omega: &Vector3<f64>,
    mode: CoriolisMode,
) -> NavState {
    let c = crate::bias_correction::correct(pim, bias);
    let (dr, dv, dp) = (c.r, c.v, c.p);
    let t = pim.delta_t;
    let g = pim.gravity;
    match mode {
        CoriolisMode::Exact => {
            let tr = Transport::new(omega, t, &g);
            let vbar = s.v + omega.cross(&s.p);
            let p = tr.a.act(&(s.p + vbar * t + s.r.act(&dp))) + tr.pg;
            let vbar_j = tr.a.act(&(vbar + s.r.act(&dv))) + tr.vg;
            NavState {
                r: tr.a.compose(&s.r).compose(&dr),
                p,
                v: vbar_j - omega.cross(&p),
            }
        }
        CoriolisMode::FirstOrder | CoriolisMode::SecondOrder => {
            let c = centrifugal(omega, &s.p, mode);
            let wv = omega.cross(&s.v);
            let xi_r = dr.log() - s.r.inverse().act(omega) * t;
            NavState {
                r: s.r.compose(&SO3::exp(&xi_r)),
                p: s.p + s.v * t + g * (0.5 * t * t) + s.r.act(&dp)
                    - wv * (t * t)
                    - c * (0.5 * t * t),
                v: s.v + g * t + s.r.act(&dv) - wv * (2.0 * t) - c * t,
            }
        }
    }
}
