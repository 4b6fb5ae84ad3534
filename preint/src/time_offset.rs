//! The time offset between the IMU clock and the keyframe (camera, motion-capture) clock:
//! derivatives of the preintegrated deltas with respect to it, the first-order correction for a
//! new offset estimate, and re-integration above a threshold.
//!
//! # Convention
//!
//! As in OpenVINS and VINS-Mono, the IMU clock reads `t_imu = t_cam + t_d` \[s\]: an event the
//! camera stamps `t` is stamped `t + t_d` by the IMU. A keyframe window `[t_i, t_j]` on the
//! keyframe clock is therefore the IMU window `[t_i + t_d, t_j + t_d]`, and a measurement
//! preintegrated with the offset estimate `t̂_d` is
//! `preintegrate(params, bias, samples, t_i + t̂_d, t_j + t̂_d)` ([`preintegrate_with_offset`]);
//! its `t_i_ns`, `t_j_ns` are on the IMU clock and its `delta_t` is the keyframes' `t_j − t_i`
//! whatever the offset.
//!
//! # Derivatives (chart of [`PreintegratedImu`], order [δφ, δv, δp])
//!
//! With `ω`, `a` the bias-corrected body rate [rad/s] and specific force [m/s²], moving the window
//! end `t_j` adds the end rate, `∂ΔR/∂t_j = ΔR [ω_j]×`, `∂Δv/∂t_j = ΔR a_j`, `∂Δp/∂t_j = Δv`;
//! moving the start `t_i` removes the first instant and re-expresses everything in the new
//! frame i (`ΔR ← Exp(−ω_i ε) ΔR`, `Δv ← Exp(−ω_i ε)(Δv − a_i ε)`,
//! `Δp ← Exp(−ω_i ε)(Δp − a_i Δt ε)`). Both ends move with `t_d`, so
//!
//! ```text
//! ∂φ/∂t_d  = ω_j − ΔRᵀ ω_i                     [rad/s]   (ΔR(t_d + ε) ≈ ΔR Exp(ε ∂φ/∂t_d))
//! ∂Δv/∂t_d = ΔR a_j − a_i − ω_i × Δv           [m/s²]
//! ∂Δp/∂t_d = Δv − a_i Δt − ω_i × Δp            [m/s]
//! ```
//!
//! `ω_i, a_i, ω_j, a_j` are the window's first and last samples, i.e. the boundary samples at the
//! keyframes, interpolated as the scheme interpolates them ([`preintegrate`](crate::preintegrate()): linear for
//! euler, midpoint and galilean, cubic Lagrange for hermite4). This is the exact derivative of the
//! continuous-time deltas of the interpolated signal; a scheme's discrete deltas follow it to
//! the scheme's order in the sample period (their derivative with respect to an end differs
//! by the local truncation error's rate of change; at a keyframe on a sample the discrete deltas
//! have one-sided derivatives that differ by as much), measured in `preint/tests/time_offset.rs`.
//! Measured: the closed form is the continuous-time derivative to 2e-10; a scheme's discrete
//! deltas follow it to 1e-8 for hermite4 at 200 Hz, 1e-5 for midpoint and 5e-3 for euler and
//! galilean. The result is [`PreintegratedImu::jac_td`], computed once per measurement from the
//! end samples (the engine keeps the first sample's specific force beside its rate; no
//! per-sample cost). It is zero at [`Level::Deltas`](crate::Level::Deltas), for hand-made
//! measurements, and with a `body_p_sensor` whose lever arm is removed in closed form
//! ([`SensorPose`](crate::SensorPose)): the body deltas then depend on the end rates' derivatives, which the
//! end samples do not give (a rotation-only `body_p_sensor` maps the column by
//! `diag(R_bs, R_bs, R_bs)`; GTSAM's per-sample centripetal model is covered, its samples being
//! the ones integrated).
//!
//! # Merge
//!
//! Shifting `t_d` shifts all three keyframes of consecutive windows `a = [t_i, t_k]`,
//! `b = [t_k, t_j]` together, so the merged derivative is the chain rule through the
//! composition: `J_td = A J_td,a + B J_td,b` with the `A`, `B` of [`crate::merge`](crate::merge()). The inner
//! keyframe's terms (`+ω_k`, `+ΔR_a a_k` from a's end, `−ω_k`, `−a_k` from b's start) cancel and
//! the result equals the closed form of the whole window. This holds only when both windows
//! were integrated with the same offset: windows of different sensors (offsets) would not move
//! their shared keyframe by the same amount.
//!
//! # First-order correction
//!
//! For `t_d = t̂_d + δt_d` the deltas are corrected with the column `J_td δt_d` added to the
//! bias correction of [`BiasCorrection`](crate::BiasCorrection) (`c = J_b δb + J_td δt_d`, applied additively
//! or on the group as the measurement's `bias_correction` says):
//! [`PreintegratedImu::corrected_with_time_offset`]. Its error against re-integration grows as
//! `δt_d²` (the end samples' rates of change: `ω̇`, `ȧ`); above
//! [`PreintParams::reintegrate_time_offset_threshold`](crate::PreintParams::reintegrate_time_offset_threshold)
//! [`measurement_for_time_offset`] re-integrates instead (the threshold and the study behind it:
//! [`crate::params::DEFAULT_REINTEGRATE_TIME_OFFSET`], 0.5 ms: on `aggressive` at 200 Hz with
//! EuRoC densities the correction's error reaches the noise's 1σ at 2.26 ms for midpoint and
//! hermite4; `docs/EVIDENCE.md`, "Time offset").
//!
//! # Factors
//!
//! `ImuFactor::evaluate_with_time_offset(&x_i, &x_j, &b_i, δt_d)` and
//! `CombinedImuFactor::evaluate_with_time_offset(&x_i, &x_j, &b_i, &b_j, δt_d)` return the
//! residual at the corrected deltas, every Jacobian block there, and the column `∂r/∂δt_d`:
//! component-wise `[−Jr⁻¹(r_φ) Eᵀ Jr(c_φ) j_φ, −∂Δv(b)/∂t_d, −∂Δp(b)/∂t_d]` (`E = Exp(r_φ)`,
//! the derivatives of the corrected deltas, through `Jl(c_φ)` for the group correction), mapped
//! to the Logmap chart as the gyro-bias columns are (`ΔR(b)ᵀ` moves with `δt_d`). At
//! `δt_d = 0` the residual and blocks are `evaluate`'s.
//!
//! ```
//! use preint::nalgebra::Vector3;
//! use preint::time_offset::preintegrate_with_offset;
//! use preint::{ImuBias, ImuFactor, ImuSample, NavState, PreintParams};
//! let s: Vec<ImuSample> = (0..601i64)
//!     .map(|k| {
//!         let t = k as f64 * 5e-3;
//!         ImuSample::new(k * 5_000_000, Vector3::new(0.0, 0.3, t.sin()), Vector3::new(t.cos(), 0.0, 9.81))
//!     })
//!     .collect();
//! let (p, b) = (PreintParams::default(), ImuBias::zero());
//! let keyframes = (1_000_000_000, 2_000_000_000); // camera clock [ns]
//! let m = preintegrate_with_offset(&p, &b, &s, keyframes, 3_000_000).unwrap(); // t̂_d = 3 ms
//! // The offset is 3.4 ms: the first-order correction against re-integration.
//! let exact = preintegrate_with_offset(&p, &b, &s, keyframes, 3_400_000).unwrap();
//! let mut c = m.clone();
//! (c.delta_r, c.delta_v, c.delta_p) = m.corrected_with_time_offset(&b, 4e-4);
//! assert!(exact.delta_error(&c).norm() < 1e-3 * exact.delta_error(&m).norm());
//! // A factor with t_d as a variable: the residual at δt_d and its column ∂r/∂δt_d.
//! let f = ImuFactor::new(m.clone()).unwrap();
//! let xi = NavState::identity();
//! let xj = f.predict(&xi, &b);
//! let (r, _jac, d_r_d_td) = f.evaluate_with_time_offset(&xi, &xj, &b, 0.0);
//! assert!(r.amax() < 1e-12 && d_r_d_td.norm() > 0.1);
//! ```

use crate::error::PreintError;
use crate::measurement::PreintegratedImu;
use crate::params::PreintParams;
use crate::sample::{ImuBias, ImuSample};
use nalgebra::Vector3;
use preint_lie::SO3;

pub use crate::preintegrator::time_offset_jacobian as jacobian;

/// The offset `td_s` \[s\] as integer nanoseconds (rounded to the nearest).
pub fn offset_ns(td_s: f64) -> i64 {
    (td_s * 1e9).round() as i64
}

/// The keyframe window `[t_i_ns, t_j_ns]` (keyframe clock) preintegrated with the offset
/// estimate `td_hat_ns` \[ns\]: [`preintegrate`](crate::preintegrate) over the IMU window
/// `[t_i + t̂_d, t_j + t̂_d]` (module docs). Errors as `preintegrate`'s (for the shifted times).
pub fn preintegrate_with_offset(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
    td_hat_ns: i64,
) -> Result<PreintegratedImu, PreintError> {
    crate::window::preintegrate(
        params,
        bias,
        samples,
        t_i_ns.saturating_add(td_hat_ns),
        t_j_ns.saturating_add(td_hat_ns),
    )
}

/// Result of [`measurement_for_time_offset`].
#[derive(Clone, Debug, PartialEq)]
pub struct TimeOffsetUpdate {
    /// The measurement for the new offset (deltas corrected or re-integrated; bias estimate
    /// unchanged).
    pub measurement: PreintegratedImu,
    /// True if the window was re-integrated, false for the first-order correction.
    pub reintegrated: bool,
}

/// The measurement of keyframe window `[t_i_ns, t_j_ns]` for a new offset `td_ns`, given `m`, the
/// same window preintegrated with `td_hat_ns` ([`preintegrate_with_offset`], same `params`,
/// bias and samples): if `|td − t̂d| ≤ params.reintegrate_time_offset_threshold`, `m` with its
/// deltas corrected to first order ([`PreintegratedImu::corrected_with_time_offset`] at
/// `m.bias_hat`; covariance and Jacobians kept, times moved by `td − t̂d`), otherwise the
/// window re-integrated with `td_ns`. Errors as [`preintegrate_with_offset`]'s.
pub fn measurement_for_time_offset(
    params: &PreintParams,
    samples: &[ImuSample],
    (t_i_ns, t_j_ns): (i64, i64),
    m: &PreintegratedImu,
    (td_hat_ns, td_ns): (i64, i64),
) -> Result<TimeOffsetUpdate, PreintError> {
    let d_ns = td_ns.saturating_sub(td_hat_ns);
    let dtd = d_ns as f64 * 1e-9;
    if dtd.abs() <= params.reintegrate_time_offset_threshold {
        let mut out = m.clone();
        (out.delta_r, out.delta_v, out.delta_p) = m.corrected_with_time_offset(&m.bias_hat, dtd);
        out.t_i_ns = m.t_i_ns.saturating_add(d_ns);
        out.t_j_ns = m.t_j_ns.saturating_add(d_ns);
        return Ok(TimeOffsetUpdate {
            measurement: out,
            reintegrated: false,
        });
    }
    let measurement =
        preintegrate_with_offset(params, &m.bias_hat, samples, (t_i_ns, t_j_ns), td_ns)?;
    Ok(TimeOffsetUpdate {
        measurement,
        reintegrated: true,
    })
}

impl PreintegratedImu {
    /// Deltas corrected to first order for a new bias estimate `bias` and a time-offset change
    /// `dtd_s` = `t_d − t̂_d` \[s\] (module docs): the bias correction of
    /// [`corrected`](Self::corrected) with `J_td δt_d` added to its tangent vector,
    /// `Δ ⊕ (J_b δb + J_td δt_d)` in the measurement's [`BiasCorrection`](crate::BiasCorrection). Equals `corrected`
    /// for `dtd_s = 0`. Returns `(ΔR, Δv [m/s], Δp [m])`.
    ///
    /// # Panics
    ///
    /// As [`corrected`](Self::corrected), if `bias` cannot be applied
    /// ([`check_bias`](Self::check_bias)).
    pub fn corrected_with_time_offset(
        &self,
        bias: &ImuBias,
        dtd_s: f64,
    ) -> (SO3, Vector3<f64>, Vector3<f64>) {
        self.assert_bias(bias);
        let (c, _) = crate::bias_correction::correct_with_time_offset(self, bias, dtd_s);
        (c.r, c.v, c.p)
    }
}
