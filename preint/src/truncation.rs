//! A window's own discretisation error, estimated from its samples, and a covariance that
//! knows it.
//!
//! # The estimate
//!
//! The deltas of a scheme of order `q` on samples `h` apart differ from the exact ones by its
//! truncation error `e = D_h ⊖ D ≈ C hᑫ`. A companion integration of the same window estimates
//! it ([`estimate`]), the one the scheme's registry row names
//! ([`SchemeInfo::truncation`](crate::SchemeInfo::truncation)):
//!
//! - [`TruncationCompanion::Hermite4Upsampled`] (**euler** and **galilean**, order 1 on smooth
//!   input, and **midpoint**, order 2): the 4th-order `hermite4` scheme on the same samples
//!   upsampled four times, `e ≈ D_h ⊖ D_fine`.
//!   Each inserted sample is the value of the degree-11 polynomial through the 12 nearest
//!   samples (centred on its interval): a smooth signal sampled a few times per period of its
//!   fastest component is interpolated to high order where a cubic, or Richardson's estimate
//!   on every other sample, is far from asymptotic (on `aggressive` at 20 Hz, 6.5 samples per
//!   period, the estimate's own error is 0.13σ of the window's noise, against 1.3σ for hermite4
//!   on the samples corrected by Richardson). The
//!   companion cuts the window itself, so a keyframe between samples is interpolated finely
//!   there and by a line in the scheme's window: the estimate includes the error of that line,
//!   as it should.
//! - [`TruncationCompanion::Richardson`] (**hermite4**): Richardson's estimate from the same
//!   scheme on every other sample: with `e_2h ≈ 2ᑫ e_h`, `D_h ⊖ D_2h ≈ e_h − e_2h`, so
//!   `e ≈ −(D_h ⊖ D_2h) / (2ᑫ − 1)` (`q = 4`: 15).
//!
//! The returned [`TruncationEstimate`] carries the companion's covariance: that of `hermite4`
//! on the samples themselves (the noise it responds to) for the upsampled companion, the
//! measurement's own for Richardson. The estimate costs two extra integrations of the window
//! (one of them on four times the samples) or one, on request (`integrate --truncation` on the
//! command line).
//!
//! `⊖` is the chart of [`PreintegratedImu`], order [δφ, δv, δp]. The estimate is as good as
//! the motion is smooth at the scale of the samples; the evidence suite measures it against the
//! true error on every scene and rate of `preint bench-steps`.
//!
//! # Weighting with it
//!
//! A factor at the true states sees `r = −(e + n)`: the deterministic truncation error plus the
//! noise. Weighting it by `Σ` alone makes the mean χ² `dof + eᵀΣ⁻¹e`, which for Euler at 20 Hz
//! is in the hundreds of thousands. The estimate is computed from the same noisy samples: with
//! `n_c` the companion's response to the noise, `ê = e + n − n_c` (plus the companion's own
//! error), so `r = −(ê + n_c)`: the residual is the estimated offset plus the companion's noise.
//! [`inflate`] therefore weights with `Σ_c + u uᵀ`, `Σ_c` the companion's covariance and `u`
//! the estimate as the factor's residual chart sees it ([`offset_in_chart`]): the direction of
//! the offset is left free (by the Sherman–Morrison identity the mean χ² is `dof` when the offset
//! is along `u`, and never more than `dof + 1` for an estimate along `e` of any size) and the
//! rest is weighted by the noise that is really there (the scheme's own `Σ` there leaves
//! 0.13–0.22 of χ²: its noise response differs from the companion's). Charting the estimate to
//! first order in the Logmap residual would leave several σ for Euler at 20 Hz
//! (`docs/EVIDENCE.md`).

use crate::choices::Level;
use crate::error::PreintError;
use crate::factor::ResidualMode;
use crate::measurement::PreintegratedImu;
use crate::params::PreintParams;
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::{Scheme, TruncationCompanion};
use crate::window::preintegrate;
use nalgebra::{SMatrix, SVector, Vector3};
use preint_lie::jl_inv;

/// The estimated truncation error of a window's deltas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruncationEstimate {
    /// `D_scheme ⊖ D_exact` estimated, order [δφ (rad), δv (m/s), δp (m)], the chart of
    /// [`PreintegratedImu`] (the same as [`PreintegratedImu::delta_error`]).
    pub error: SVector<f64, 9>,
    /// How it was estimated: `"hermite4 companion"` or `"richardson 2h"`.
    pub method: &'static str,
    /// The 9×9 covariance of the companion's deltas ([δφ, δv, δp]; for hermite4 the
    /// measurement's own): the noise a factor's residual keeps once the estimated offset is
    /// accounted for ([`inflate`]). Zero at `Level::Deltas`.
    pub companion_cov: SMatrix<f64, 9, 9>,
}

/// The truncation error of `m`, the window `[t_i_ns, t_j_ns]` of `samples` preintegrated with
/// `params` and `bias` (module docs). Errors as [`preintegrate`] (e.g. too few samples for the
/// companion: hermite4 on every other sample needs a window of ≥ 2 intervals).
pub fn estimate(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    m: &PreintegratedImu,
) -> Result<TruncationEstimate, PreintError> {
    let deltas = PreintParams {
        level: Level::Deltas,
        ..params.clone()
    };
    let (t_i, t_j) = (m.t_i_ns, m.t_j_ns);
    let info = params.scheme.info();
    match info.truncation {
        TruncationCompanion::Hermite4Upsampled => {
            let h4 = deltas.with_scheme(Scheme::Hermite4);
            // With covariance when the measurement has one: `inflate` weights with it.
            let level = match params.level {
                Level::Deltas => Level::Deltas,
                _ => Level::Covariance,
            };
            let with_cov = h4.clone().with_level(level);
            // On the samples as they are: the noise the companion responds to (and the
            // stream's checks, with errors naming its samples).
            let companion = preintegrate(&with_cov, bias, samples, t_i, t_j)?;
            let fine = upsampled(samples, t_i, t_j);
            let companion_fine = preintegrate(&h4, bias, &fine, t_i, t_j)?;
            Ok(TruncationEstimate {
                error: m.delta_error(&companion_fine),
                method: "hermite4 companion",
                companion_cov: companion.cov,
            })
        }
        TruncationCompanion::Richardson => Ok(TruncationEstimate {
            error: richardson(&deltas, bias, samples, m, info.order)?,
            method: "richardson 2h",
            companion_cov: m.cov,
        }),
    }
}

/// Richardson's estimate of the error of the window `m` of a scheme of order `q`:
/// `−(D_h ⊖ D_2h) / (2^q − 1)` (15 for hermite4), the coarse window on every other sample.
fn richardson(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    m: &PreintegratedImu,
    q: u32,
) -> Result<SVector<f64, 9>, PreintError> {
    let half = every_other(samples, m.t_i_ns, m.t_j_ns);
    let coarse = preintegrate(params, bias, &half, m.t_i_ns, m.t_j_ns)?;
    Ok(-m.delta_error(&coarse) / f64::from((1u32 << q) - 1))
}

/// Samples the companion inserts per interval.
const UPSAMPLE: i64 = 4;
/// Points of the interpolating polynomials.
const STENCIL: usize = 12;
/// Stream samples the estimate reads on each side of a window (beyond the samples at or next
/// to its keyframes) for centred interpolating polynomials: with fewer, at a stream's ends,
/// they are one-sided and the estimate less accurate.
pub const CONTEXT_SAMPLES: usize = STENCIL / 2 + 2;

/// The stream around `[t_i_ns, t_j_ns]` (from the interval before the one holding `t_i` to the
/// one after the one holding `t_j`) with `UPSAMPLE − 1` samples inserted in every interval,
/// each the value at its time of the degree-11 polynomial through the `STENCIL` nearest
/// samples (centred on the interval, one-sided at the stream's ends; module docs).
fn upsampled(samples: &[ImuSample], t_i_ns: i64, t_j_ns: i64) -> Vec<ImuSample> {
    let n = samples.len();
    let first = samples
        .partition_point(|s| s.t_ns <= t_i_ns)
        .saturating_sub(2);
    let last = (samples.partition_point(|s| s.t_ns < t_j_ns) + 1).min(n - 1);
    let mut out = Vec::with_capacity((last - first) * UPSAMPLE as usize + 1);
    for k in first..last {
        out.push(samples[k]);
        let lo = (k + 1)
            .saturating_sub(STENCIL / 2)
            .min(n.saturating_sub(STENCIL));
        let stencil = &samples[lo..(lo + STENCIL).min(n)];
        let dt = samples[k + 1].t_ns - samples[k].t_ns;
        for j in 1..UPSAMPLE {
            out.push(lagrange(stencil, samples[k].t_ns + dt * j / UPSAMPLE));
        }
    }
    out.push(samples[last]);
    out
}

/// The Lagrange polynomial through `stencil` (distinct times) at `t_ns`, both channels.
fn lagrange(stencil: &[ImuSample], t_ns: i64) -> ImuSample {
    let x = |s: &ImuSample| (s.t_ns - t_ns) as f64 * 1e-9;
    let (mut gyro, mut acc) = (Vector3::zeros(), Vector3::zeros());
    for (i, si) in stencil.iter().enumerate() {
        let w: f64 = (stencil.iter().enumerate())
            .filter(|(j, _)| *j != i)
            .map(|(_, sj)| x(sj) / (x(sj) - x(si)))
            .product();
        gyro += si.gyro * w;
        acc += si.acc * w;
    }
    ImuSample::new(t_ns, gyro, acc)
}

/// Every other sample of `samples`, keeping those at `t_i_ns` and `t_j_ns` (the window's edges
/// when they are samples) and the rhythm of the ones around them, so that the coarse window has
/// the same keyframes.
fn every_other(samples: &[ImuSample], t_i_ns: i64, t_j_ns: i64) -> Vec<ImuSample> {
    let anchor = samples.iter().position(|s| s.t_ns >= t_i_ns).unwrap_or(0);
    samples
        .iter()
        .enumerate()
        .filter(|(k, s)| (k + anchor) % 2 == 0 || s.t_ns == t_j_ns)
        .map(|(_, s)| *s)
        .collect()
}

/// `m` weighted with its estimated truncation error (module docs): its 9×9 covariance becomes
/// `Σ_c + u uᵀ`, with `Σ_c` the companion's covariance (`e.companion_cov`) and `u` the estimate
/// as a factor of `mode` sees it ([`offset_in_chart`]); the 9×9 block of its 15×15 covariance
/// changes by the same amount, `Σ_c − Σ + u uᵀ` (keeping what the bias random walk adds there).
pub fn inflate(
    m: &PreintegratedImu,
    e: &TruncationEstimate,
    mode: ResidualMode,
) -> PreintegratedImu {
    let u = offset_in_chart(m, e, mode);
    let mut out = m.clone();
    let change = e.companion_cov - m.cov + u * u.transpose();
    out.cov += change;
    out.cov15
        .fixed_view_mut::<9, 9>(0, 0)
        .zip_apply(&change, |x, y| *x += y);
    out
}

/// The estimate `ê` in the covariance's chart [δφ, δv, δp] such that the factor of `mode`,
/// whose weight is that covariance mapped linearly into its residual's chart, sees exactly the
/// residual the truncation error alone gives at the true states:
///
/// - [`ResidualMode::ComponentWise`]: `ê` itself (the component-wise residual is linear in
///   the deltas' error: `r = −ê` at the truth);
/// - [`ResidualMode::Logmap`]: with the exact deltas estimated as `ΔR_e = ΔR Exp(−ê_φ)`,
///   `Δv_e = Δv − ê_v`, `Δp_e = Δp − ê_p`, the residual at the truth is
///   `r_L = Log(D⁻¹ D_e) = [−ê_φ, −Jl(−ê_φ)⁻¹ ΔRᵀ ê_v, −Jl(−ê_φ)⁻¹ ΔRᵀ ê_p]`, and the weight is
///   `T cov Tᵀ` with `T = diag(I, ΔRᵀ, ΔRᵀ)` ([`ResidualMode`]), so
///   `u = −T⁻¹ r_L = [ê_φ, ΔR Jl(−ê_φ)⁻¹ ΔRᵀ ê_v, ΔR Jl(−ê_φ)⁻¹ ΔRᵀ ê_p]`. It differs from `ê` at
///   second order (`½ ê_φ × ê_v`), which for Euler at 20 Hz is several σ.
pub fn offset_in_chart(
    m: &PreintegratedImu,
    e: &TruncationEstimate,
    mode: ResidualMode,
) -> SVector<f64, 9> {
    match mode {
        ResidualMode::ComponentWise => e.error,
        ResidualMode::Logmap => {
            let phi: Vector3<f64> = e.error.fixed_rows::<3>(0).into_owned();
            let r = m.delta_r.matrix();
            let shear = r * jl_inv(&-phi) * r.transpose();
            let mut u = e.error;
            for k in [3, 6] {
                let x = shear * e.error.fixed_rows::<3>(k);
                u.fixed_rows_mut::<3>(k).copy_from(&x);
            }
            u
        }
    }
}
