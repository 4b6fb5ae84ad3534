//! The overlapping Allan deviation (IEEE Std 952-1997, Annex C) and its confidence.
//!
//! # Allan deviation
//! For a rate signal `y_k` sampled every `Δt` (after removing its mean, which the Allan
//! variance ignores and which keeps the cumulative sums small), with the integral
//! `θ_k = Δt Σ_{i<k} y_i` (k = 0…N) and cluster time `τ = mΔt`, the overlapping Allan variance is
//!
//! `σ²(τ) = Σ_{k=0}^{N−2m} (θ_{k+2m} − 2θ_{k+m} + θ_k)² / (2τ²(N − 2m + 1))`,
//!
//! O(N) per τ. Cluster sizes `m` are log-spaced ([`log_spaced_cluster_sizes`]) up to `⌊N/2⌋`;
//! the fits only use points with at least 8 non-overlapping clusters (N/m ≥ 8).
//!
//! # Confidence
//! Each point carries its equivalent degrees of freedom ν (`σ̂² ~ σ²χ²_ν/ν`, [`super::edf`]:
//! Howe, Allan, Barnes 1981; Greenhall and Riley 2003) and the 1-σ error `σ̂/√(2ν)`. ν depends
//! on the noise, ≈ 1.5 r for white noise and ≈ 0.93 r for a random walk (`r = K − 2`,
//! K = N/m clusters), against the `K − 1` of K independent clusters (El-Sheimy, Hou, Niu 2008,
//! eq. 11): the overlapping estimator is better than that for white noise and a little worse
//! for a random walk, whose long clusters hold few independent pieces of data. The point's
//! noise is read from the curve's local slope s (least squares over the point and two
//! neighbours on either side): a share `(1 + 2s)/2` of σ̂² is random walk, the rest white
//! noise (clamped to [0, 1]), which is exact for a curve of white noise and a random walk,
//! whose slope runs from −½ to +½. The fits ([`super::fit`]) use ν under the fitted model.

use super::AllanError;
use super::edf::{NoiseLevels, edf};

/// One point of an Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AllanPoint {
    /// Cluster size m (samples).
    pub m: usize,
    /// Cluster time τ = mΔt \[s\].
    pub tau: f64,
    /// Overlapping Allan deviation σ(τ) [signal unit].
    pub adev: f64,
    /// 1-σ uncertainty of `adev`: `adev/√(2ν)` (see the module docs).
    pub adev_err: f64,
    /// Number of non-overlapping clusters N/m (as a real number).
    pub clusters: f64,
    /// Equivalent degrees of freedom ν of the estimate (`σ̂² ~ σ²χ²_ν/ν`) for the noise the
    /// curve's local slope shows (module docs).
    pub edf: f64,
}

/// Log-spaced cluster sizes `m = round(10^(k/per_decade))`, deduplicated, from 1 to
/// `max_m`. `per_decade` ≥ 1.
pub fn log_spaced_cluster_sizes(max_m: usize, per_decade: usize) -> Vec<usize> {
    let per = per_decade.max(1) as f64;
    let mut out: Vec<usize> = Vec::new();
    let mut k = 0.0;
    loop {
        let m = 10f64.powf(k / per).round() as usize;
        if m > max_m {
            break;
        }
        if out.last() != Some(&m) {
            out.push(m);
        }
        k += 1.0;
    }
    out
}

/// Overlapping Allan deviation of `data` (sample period `dt` \[s\]) at cluster sizes `ms`
/// (sizes with `2m > N` are skipped), with the EDF and error of every point (the local slopes
/// are taken over the points computed here). See the module docs for the formulas.
///
/// ```
/// use preint_calib::allan::allan_deviation;
/// use rand::{RngExt, SeedableRng};
/// use rand_distr::StandardNormal;
///
/// // White noise of density N = 0.01 unit/√Hz at 100 Hz: σ(τ) = N/√τ, so σ(1 s) = 0.01.
/// let (density, dt): (f64, f64) = (0.01, 0.01);
/// let mut rng = rand::rngs::StdRng::seed_from_u64(2);
/// let y: Vec<f64> = (0..20_000)
///     .map(|_| density / dt.sqrt() * rng.sample::<f64, _>(StandardNormal))
///     .collect();
/// let curve = allan_deviation(&y, dt, &[100]).unwrap();
/// let p = curve[0];
/// assert_eq!(p.tau, 1.0);
/// assert!((p.adev - density).abs() < 3.0 * p.adev_err);
/// ```
pub fn allan_deviation(data: &[f64], dt: f64, ms: &[usize]) -> Result<Vec<AllanPoint>, AllanError> {
    let n = data.len();
    if n < 8 {
        return Err(AllanError::TooFewSamples(n));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(AllanError::BadPeriod(dt));
    }
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(AllanError::NonFinite {
            channel: 0,
            index: i,
        });
    }
    let mean = data.iter().sum::<f64>() / n as f64;
    // θ in units of (signal · samples); Δt is applied once per τ.
    let mut theta = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    theta.push(0.0);
    for v in data {
        acc += v - mean;
        theta.push(acc);
    }
    let mut out = Vec::with_capacity(ms.len());
    for &m in ms {
        if m == 0 || 2 * m > n {
            continue;
        }
        let count = n - 2 * m + 1;
        let mut s = 0.0;
        for k in 0..count {
            let d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
            s += d * d;
        }
        let tau = m as f64 * dt;
        // (Δt·d)² / (2τ²) = d² / (2m²).
        let avar = s / (2.0 * (m * m) as f64 * count as f64);
        let adev = avar.sqrt();
        out.push(AllanPoint {
            m,
            tau,
            adev,
            adev_err: f64::NAN,
            clusters: n as f64 / m as f64,
            edf: f64::NAN,
        });
    }
    let slopes = local_slopes(&out);
    for (p, slope) in out.iter_mut().zip(slopes) {
        p.edf = edf(&slope_mix(p, slope), dt, n, p.m);
        p.adev_err = p.adev / (2.0 * p.edf).sqrt();
    }
    Ok(out)
}

/// The white-noise and random-walk levels whose Allan variances at the point's τ are σ̂² split
/// by the local slope s of log σ against log τ (module docs): the random walk's share is
/// `(1 + 2s)/2`, clamped to [0, 1] (white noise alone without a finite slope).
fn slope_mix(p: &AllanPoint, slope: f64) -> NoiseLevels {
    let walk = if slope.is_finite() {
        ((1.0 + 2.0 * slope) / 2.0).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s2 = p.adev * p.adev;
    NoiseLevels {
        white: (1.0 - walk) * s2 * p.tau,
        random_walk: walk * s2 * 3.0 / p.tau,
    }
}

/// Local log-log slopes of a curve: least-squares slopes of `ln σ` on `ln τ` over each point
/// and its two neighbours on either side (NaN for a single point).
pub(crate) fn local_slopes(pts: &[AllanPoint]) -> Vec<f64> {
    let lx: Vec<f64> = pts.iter().map(|p| p.tau.ln()).collect();
    let ly: Vec<f64> = pts.iter().map(|p| p.adev.max(1e-300).ln()).collect();
    (0..pts.len())
        .map(|i| {
            let a = i.saturating_sub(2);
            let b = (i + 2).min(pts.len() - 1);
            ls_slope(&lx[a..=b], &ly[a..=b])
        })
        .collect()
}

/// Unweighted least-squares slope of `y` on `x` (NaN for fewer than 2 distinct x).
pub(crate) fn ls_slope(x: &[f64], y: &[f64]) -> f64 {
    let k = x.len() as f64;
    let mx = x.iter().sum::<f64>() / k;
    let my = y.iter().sum::<f64>() / k;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
    }
    if sxx > 0.0 { sxy / sxx } else { f64::NAN }
}
