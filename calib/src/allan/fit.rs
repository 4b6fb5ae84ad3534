//! Noise-parameter fits to one channel's Allan deviation curve: white-noise density N, random
//! walk K and bias instability B (IEEE Std 952-1997, Annex C; the readings of allan_variance_ros
//! and kalibr_allan).
//!
//! # Model and regions
//! The model is `σ²(τ) = N²/τ + (2 ln2/π)B² + K²τ/3` (white noise, bias instability, rate
//! random walk). Allan variances of independent noises **add**, so every term alone lies
//! below the curve: `N²/τ ≤ σ²(τ)` and `K²τ/3 ≤ σ²(τ)` at every τ, within the curve's error.
//! Only reliable points (≥ 8 clusters) are used. Each point's error comes from its equivalent
//! degrees of freedom ν (`σ̂² ~ σ²χ²_ν/ν`; [`super::edf`], Greenhall and Riley 2003), which
//! depend on the noise: at 8 clusters 10 for white noise, 5.9 for a random walk.
//! - Local log-log slopes are least-squares slopes over ±2 neighbouring points.
//! - **Regions.** A point is a candidate for the slope −½ (white noise) region when its local
//!   slope is within ±0.15 of −½. Candidates form runs of consecutive points; a run is kept
//!   only if it has ≥ 3 points **and** its own least-squares slope (over the run's points only)
//!   is within ±0.15 of −½. The second test matters: a smoothed local slope passes through −½
//!   wherever the curve goes from flat to steeper than −½ (e.g. the ADIS16405 accelerometers at
//!   τ ≈ 0.8–1.6 s: a plateau then a drop of slope ≈ −1.2, a ≈ 1 Hz disturbance), which is not
//!   white noise. The same for +½ (random walk). Only where a line has its slope is the model
//!   held to the curve: elsewhere noises the model lacks may shape it.
//!
//! # Joint fit
//! - **N and K** (unit/√Hz and unit/s/√Hz; the lines `σ = N/√τ` read at τ = 1 s and
//!   `σ = K√(τ/3)` read at τ = 3 s): weighted least squares of `σ̂²(τ) = N²/τ + K²τ/3`, linear
//!   in N² and K², non-negative, on the union of the two regions, weights
//!   `1/Var σ̂² = ν/(2σ_m⁴)` at the model itself (iterated; weights at the measured points
//!   would favour the points that fall low). Both terms are fitted over the whole union: a line
//!   without a region of its own still takes its share at the end of the other's (the random
//!   walk at the long end of the white-noise region), and the model curve keeps it
//!   ([`NoiseFit::model_random_walk`]).
//! - **Errors.** The points share their data (neighbouring τ of 10 per decade correlate by
//!   0.9), so the covariance of `(N², K²)` is the sandwich `G Σ Gᵀ`, `G = (XᵀWX)⁻¹XᵀW`, with
//!   `Σ` the covariance of the points under the fitted model
//!   ([`super::edf::avar_covariance`]), and `σ_N = σ_{N²}/(2N)`. Measured on simulated white
//!   noise (N = 1e-3 u/√Hz, 100 Hz) plus a random walk, 40 seeds × 6 channels of ten minutes
//!   of white noise, an hour with K = 1e-4 and an hour with K = 3e-3
//!   (`calib/tests/allan_coverage.rs`): the pulls `(estimate − truth)/σ` have an RMS of
//!   0.93–1.04 and a mean within 0.13 of 0, and N and K lie within 3σ in ≥ 99 % of the
//!   channel-runs.
//! - **Why not generalised least squares** with the full `Σ` (the best linear unbiased
//!   estimator for a known `Σ`): with `Σ` from its own estimate it is more precise (N's spread
//!   0.65 and 0.28 % instead of 0.77 and 0.34 % on the first two cases) but biases K low by
//!   3.3 % on the hour with K = 1e-4 (a mean pull of −0.39 over 220 fits, 5 standard errors).
//! - **Caps.** Then `N ≤ min_τ σ̂(τ)√τ/√q(τ)` and `K ≤ min_τ σ̂(τ)√(3/τ)/√q(τ)` over the
//!   reliable points (for N those at τ ≥ 0.1 s, see "Sensor bandwidth" below), `q` the lower
//!   4σ quantile of `χ²_ν/ν` at the point's EDF ([`CAP_SIGMAS`]): no line lies above any
//!   point's upper 4σ confidence limit. A fit over a region where other noise already adds
//!   (σ√τ rising slowly: the ADIS16405 gyro x from 0.1 s, or the tail of a disturbance) sits
//!   above its best-determined points; the cap brings it to them. Why 4σ, not 3: a correct line
//!   lies above a given point's 3σ limit with probability 1.3e-3, and a line has 20–60 points;
//!   on the three simulated cases above, 3σ caps 5 of the 1180 fitted lines (one N 4 % low)
//!   and leaves 2 of the 120 runs not credible, 4σ caps none. Why χ² limits and not
//!   `σ̂(1 + kε)`: at few EDF the χ² distribution is skewed; a linear `σ̂(1 + 3ε)` at a point of
//!   8 clusters of a random walk would cap a correct line with probability 5 %, not 1.3e-3.
//! - **Bounds.** When a line has no region, its value is only an upper bound: the same cap
//!   alone, `min_τ σ̂(τ)√τ/√q(τ)` (resp. `min_τ σ̂(τ)√(3/τ)/√q(τ)`), the largest line the curve
//!   does not exclude at 4σ anywhere, flagged ([`NoiseFit::white_density_is_bound`],
//!   [`NoiseFit::random_walk_is_bound`]), with the τ of the minimum as its range and a NaN
//!   error. On the simulated hour with K = 1e-4, 20 of 240 channel-runs have no +½ region (their
//!   long-τ tail fell low), and 1 of those 20 bounds lies below the truth.
//! - **Sensor bandwidth.** The white-noise region, the cap and the bound of N use only points
//!   with τ ≥ [`WHITE_NOISE_MIN_TAU`] = 0.1 s (all reliable points when none reaches 0.1 s).
//!   An IMU filters before it samples (anti-alias and decimation filters; the ADIS16405 averages
//!   internally), and filtered white noise lies **below** the white-noise line: for a
//!   first-order low-pass of time constant T on white noise of density N,
//!   `σ²(τ) = (N²/τ)·[1 − (T/2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})]` (the first-order Gauss–Markov
//!   Allan variance, IEEE Std 952-1997 Annex C; El-Sheimy, Hou, Niu 2008, Table 1 with
//!   `q_c = N/T`), `≈ (N²/τ)(1 − 3T/2τ)` for τ ≫ T. At τ ~ T the deficit is tens of percent
//!   (ADIS16405 at 100 Hz: `σ√τ` = 0.032 deg/s/√Hz at τ = 0.01 s against 0.041 at 1 s), and the
//!   cap would take it for the white-noise level; at τ ≥ 0.1 s it is `3T/4τ` in σ (2 % for
//!   T = 2.7 ms, which reproduces the ADIS16405 curve at 0.01 s). With this floor a recording
//!   and its block means of length ≤ 0.1 s give the same N: the Allan variance of block means at
//!   τ a multiple of the block length is that of the raw data.
//!
//! # Goodness of fit
//! [`model_deviation`], [`super::ImuAllan::fit`]: the model curve `σ_m(τ) = √(N²/τ + K²τ/3)`
//! ([`model_adev`]: the fitted lines, and for a line that is only a bound the value the joint
//! fit gives it) against the measured one at the reliable points of the fitted (not bound) τ
//! ranges, each point as the standard normal deviate `z` of `σ̂²/σ_m²` under
//! `σ̂² ~ σ_m²χ²_ν/ν`, ν its EDF under the model ([`super::edf::normal_deviate`]), so that
//! `z ~ N(0, 1)` at every point of a correct model. The points share their data, so `Σz²` has
//! no χ² distribution; the fit is credible while `max |z| ≤` [`MAX_MODEL_Z`] = 5, the level a
//! normal deviate exceeds with probability 6e-7. Measured: max |z| = 3.38 / 2.98 / 2.73 over
//! the 40 seeds of the three simulated cases (all 120 runs credible); 3.97 on the real
//! ADIS16405 hour (tests/data/adis16405, 10 Hz block means); not credible on the same hour at
//! 100 Hz (12 at τ = 0.16 s: its accelerometer curves fall at −0.4 from 0.1 to 0.3 s, a region
//! of slope −½ within the tolerance but not white noise) and with a 1 Hz disturbance.
//!
//! # Bias instability
//! **B**: the minimum of σ(τ) over points with ≥ 8 clusters, divided by `√(2 ln2/π) ≈ 0.664`.
//! When the curve has no flat floor (e.g. white noise + random walk only) this is an upper
//! bound: for `σ² = N²/τ + K²τ/3` the minimum is `√(2NK/√3)` at `τ* = √3·N/K`.

use super::deviation::{local_slopes, ls_slope};
use super::edf::{NoiseLevels, avar_covariance, chi2_quantile_ratio, edf, normal_deviate};
use super::{AllanError, AllanPoint};
use nalgebra::DMatrix;

/// 2 ln2 / π: the bias-instability floor factor, `σ_floor = √(2 ln2/π)·B ≈ 0.664 B`.
pub const BIAS_INSTABILITY_FACTOR: f64 = 0.664_282_818_183_265_3;

/// Fitted noise parameters of one channel (units: the signal's unit `u`, e.g. rad/s or m/s²).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFit {
    /// White-noise density N [u/√Hz] (σ of the slope −½ line at τ = 1 s) of the joint fit,
    /// capped so that the line stays below every point's upper 4σ limit (module docs), or a
    /// bound (see `white_density_is_bound`).
    pub white_density: f64,
    /// Its 1-σ uncertainty, from the covariance of the joint fit under the points' model
    /// covariance (module docs, "Joint fit"); NaN when it is a bound.
    pub white_density_err: f64,
    /// τ range \[s\] of the points used for N (the τ of the point that sets the bound when a
    /// bound).
    pub white_tau_range: (f64, f64),
    /// `true` when no slope −½ region exists and N is only the upper bound
    /// `min_τ σ̂(τ)√τ/√q(τ)` (each point's upper 4σ limit) over the reliable points at
    /// τ ≥ [`WHITE_NOISE_MIN_TAU`] (module docs).
    pub white_density_is_bound: bool,
    /// Random walk K [u/s/√Hz] (σ of the slope +½ line at τ = 3 s), capped as N, or a bound
    /// (see `random_walk_is_bound`).
    pub random_walk: f64,
    /// 1-σ uncertainty of K, from the joint fit as for N (NaN when it is a bound).
    pub random_walk_err: f64,
    /// τ range \[s\] of the points used for K (the τ of the point that sets the bound when a
    /// bound).
    pub random_walk_tau_range: (f64, f64),
    /// `true` when no slope +½ region exists and K is only the upper bound
    /// `min_τ σ̂(τ)√(3/τ)/√q(τ)` over the reliable points (module docs).
    pub random_walk_is_bound: bool,
    /// Bias instability B \[u\] = min σ / 0.664 (an upper bound without a flat floor).
    pub bias_instability: f64,
    /// τ \[s\] of the minimum.
    pub bias_instability_tau: f64,
    /// N of the model curve ([`model_adev`]): `white_density` when fitted; when it is a bound,
    /// the value the joint fit gives the white-noise term over the random walk's region (at
    /// most the bound), 0 without any region.
    pub model_white_density: f64,
    /// K of the model curve, likewise: `random_walk` when fitted, else the joint fit's value
    /// over the white-noise region (at most the bound).
    pub model_random_walk: f64,
}

const MIN_CLUSTERS: f64 = 8.0;
/// Shortest τ \[s\] of the white-noise region, cap and bound (module docs, "Sensor bandwidth").
pub const WHITE_NOISE_MIN_TAU: f64 = 0.1;
const SLOPE_TOL: f64 = 0.15;
/// Minimum number of points of a slope region.
const MIN_RUN: usize = 3;
/// Largest credible `|z|` of the model curve against the measured one (module docs,
/// "Goodness of fit").
pub const MAX_MODEL_Z: f64 = 5.0;
/// The caps and bounds hold every line below each point's upper `k`-σ confidence limit, this
/// `k` (module docs).
pub const CAP_SIGMAS: f64 = 4.0;

/// Indices (into `pts`, all reliable) of the kept runs of slope `target` (module docs).
/// Only points with `τ ≥ min_tau` are candidates.
fn slope_region(pts: &[AllanPoint], slopes: &[f64], target: f64, min_tau: f64) -> Vec<usize> {
    let cand = |i: usize| {
        pts[i].clusters >= MIN_CLUSTERS
            && pts[i].tau >= min_tau
            && (slopes[i] - target).abs() <= SLOPE_TOL
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < pts.len() {
        if !cand(i) {
            i += 1;
            continue;
        }
        let start = i;
        while i < pts.len() && cand(i) {
            i += 1;
        }
        if i - start >= MIN_RUN {
            let x: Vec<f64> = pts[start..i].iter().map(|p| p.tau.ln()).collect();
            let y: Vec<f64> = pts[start..i].iter().map(|p| p.adev.ln()).collect();
            if (ls_slope(&x, &y) - target).abs() <= SLOPE_TOL {
                out.extend(start..i);
            }
        }
    }
    out
}

/// Samples (or blocks) behind a point: `n = clusters·m`.
fn samples(p: &AllanPoint) -> usize {
    (p.clusters * p.m as f64).round() as usize
}

/// The sample period of the series behind a point: `τ/m`.
fn period(p: &AllanPoint) -> f64 {
    p.tau / p.m as f64
}

/// The model `σ² = n2/τ + k2·τ/3` as [`NoiseLevels`] (white noise of unit density when both
/// are zero, which fixes the EDF only).
fn levels(n2: f64, k2: f64) -> NoiseLevels {
    if n2 > 0.0 || k2 > 0.0 {
        NoiseLevels {
            white: n2,
            random_walk: k2,
        }
    } else {
        NoiseLevels::white(1.0)
    }
}

/// The EDF of a point under the model `σ² = n2/τ + k2·τ/3` ([`edf`]).
fn model_edf(p: &AllanPoint, n2: f64, k2: f64) -> f64 {
    edf(&levels(n2, k2), period(p), samples(p), p.m)
}

/// `min_τ σ(τ)·g(τ)/√q(τ)` over the reliable points and its τ, `q` the lower `k`-σ quantile of
/// `χ²_ν/ν` ([`chi2_quantile_ratio`]) at the point's EDF: the largest `c` of a line
/// `σ = c/g(τ)` that stays below every point's upper `k`-σ confidence limit (module docs).
fn line_cap(reliable: &[&AllanPoint], g: impl Fn(f64) -> f64, k: f64) -> (f64, f64) {
    reliable
        .iter()
        .map(|p| {
            let q = chi2_quantile_ratio(-k, p.edf);
            let c = if q > 0.0 {
                p.adev * g(p.tau) / q.sqrt()
            } else {
                f64::INFINITY
            };
            (c, p.tau)
        })
        .fold(
            (f64::INFINITY, f64::NAN),
            |a, b| if b.0 < a.0 { b } else { a },
        )
}

/// The joint fit of the two lines, `σ²(τ) = n2/τ + k2·τ/3`, and the covariance of `(n2, k2)`.
struct LinesFit {
    n2: f64,
    k2: f64,
    cov: [[f64; 2]; 2],
}

/// Weighted least squares of `σ²(τ) = n2/τ + k2·τ/3` on the points `idx` (module docs, "Joint
/// fit"), non-negative, weights `1/Var σ̂² = ν/(2σ_m⁴)` at the model itself (iterated from
/// the measured σ̂); the covariance of `(n2, k2)` by the sandwich `G Σ Gᵀ`,
/// `G = (XᵀWX)⁻¹XᵀW`, with `Σ` the model covariance of the points ([`avar_covariance`]).
fn fit_lines(pts: &[AllanPoint], idx: &[usize]) -> LinesFit {
    let (mut n2, mut k2) = (0.0, 0.0);
    let mut cov = [[f64::NAN; 2]; 2];
    if idx.is_empty() {
        return LinesFit { n2, k2, cov };
    }
    let row = |i: usize| [1.0 / pts[i].tau, pts[i].tau / 3.0];
    let weight = |i: usize, n2: f64, k2: f64| {
        let p = &pts[i];
        let (m2, nu) = if n2 > 0.0 || k2 > 0.0 {
            (n2 / p.tau + k2 * p.tau / 3.0, model_edf(p, n2, k2))
        } else {
            (p.adev * p.adev, p.edf)
        };
        nu / (2.0 * m2 * m2).max(1e-300)
    };
    for _ in 0..FIT_ITERATIONS {
        let (mut h, mut b) = ([[0.0; 2]; 2], [0.0; 2]);
        for &i in idx {
            let (x, w, y) = (row(i), weight(i, n2, k2), pts[i].adev.powi(2));
            for r in 0..2 {
                b[r] += w * x[r] * y;
                for c in 0..2 {
                    h[r][c] += w * x[r] * x[c];
                }
            }
        }
        (n2, k2) = solve_nonnegative(h, b);
    }
    let x = DMatrix::from_fn(idx.len(), 2, |r, c| row(idx[r])[c]);
    let xtw = DMatrix::from_fn(2, idx.len(), |c, r| x[(r, c)] * weight(idx[r], n2, k2));
    let Some(hinv) = (&xtw * &x).try_inverse() else {
        return LinesFit { n2, k2, cov };
    };
    let g = hinv * xtw;
    let (lv, p0) = (levels(n2, k2), &pts[idx[0]]);
    let sigma = DMatrix::from_fn(idx.len(), idx.len(), |r, c| {
        avar_covariance(&lv, period(p0), samples(p0), pts[idx[r]].m, pts[idx[c]].m)
    });
    let c = &g * sigma * g.transpose();
    cov = [[c[(0, 0)], c[(0, 1)]], [c[(1, 0)], c[(1, 1)]]];
    LinesFit { n2, k2, cov }
}

/// Rounds of reweighting in [`fit_lines`] (the first with weights at the measured points).
const FIT_ITERATIONS: usize = 6;

/// The non-negative solution of the 2×2 normal equations `h·θ = b`: the unconstrained one, or,
/// when a component is negative, the other alone.
fn solve_nonnegative(h: [[f64; 2]; 2], b: [f64; 2]) -> (f64, f64) {
    let one = |a: f64, b: f64| if a > 0.0 { (b / a).max(0.0) } else { 0.0 };
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    let n = (h[1][1] * b[0] - h[0][1] * b[1]) / det;
    let k = (h[0][0] * b[1] - h[1][0] * b[0]) / det;
    if det > 0.0 && n >= 0.0 && k >= 0.0 {
        (n, k)
    } else if det > 0.0 && n < 0.0 {
        (0.0, one(h[1][1], b[1]))
    } else {
        (one(h[0][0], b[0]), 0.0)
    }
}

/// Fits N, K and B to one channel's curve (see the module docs). `channel` only labels errors.
/// Errors: no point with ≥ 8 clusters ([`AllanError::NoWhiteNoiseRegion`]); a curve that is 0
/// at every reliable τ, readings that never change ([`AllanError::NoNoise`]).
///
/// ```
/// use preint_calib::allan::{allan_deviation, fit_noise, log_spaced_cluster_sizes};
/// use rand::{RngExt, SeedableRng};
/// use rand_distr::StandardNormal;
///
/// // 200 s of white noise of density N = 0.01 unit/√Hz at 100 Hz (per-sample σ = N/√Δt).
/// let (density, dt): (f64, f64) = (0.01, 0.01);
/// let mut rng = rand::rngs::StdRng::seed_from_u64(1);
/// let y: Vec<f64> = (0..20_000)
///     .map(|_| density / dt.sqrt() * rng.sample::<f64, _>(StandardNormal))
///     .collect();
/// let curve = allan_deviation(&y, dt, &log_spaced_cluster_sizes(y.len() / 2, 10)).unwrap();
/// let fit = fit_noise(&curve, 0).unwrap();
/// assert!(!fit.white_density_is_bound);
/// assert!((fit.white_density - density).abs() < 3.0 * fit.white_density_err);
/// ```
pub fn fit_noise(pts: &[AllanPoint], channel: usize) -> Result<NoiseFit, AllanError> {
    let reliable: Vec<&AllanPoint> = pts.iter().filter(|p| p.clusters >= MIN_CLUSTERS).collect();
    if reliable.is_empty() {
        return Err(AllanError::NoWhiteNoiseRegion(channel));
    }
    if reliable.iter().all(|p| p.adev == 0.0) {
        return Err(AllanError::NoNoise(channel));
    }
    // The white-noise floor: 0.1 s, or the longest reliable τ when shorter (module docs).
    let tau_w = reliable
        .iter()
        .map(|p| p.tau)
        .fold(0.0, f64::max)
        .min(WHITE_NOISE_MIN_TAU);
    let reliable_w: Vec<&AllanPoint> = reliable
        .iter()
        .copied()
        .filter(|p| p.tau >= tau_w)
        .collect();
    let slopes = local_slopes(pts);
    let white = slope_region(pts, &slopes, -0.5, tau_w);
    let rw = slope_region(pts, &slopes, 0.5, 0.0);
    let mut idx: Vec<usize> = white.iter().chain(&rw).copied().collect();
    idx.sort_unstable();
    idx.dedup();
    let lines = fit_lines(pts, &idx);
    let n = read_line(&reliable_w, &white, pts, &lines, true, |t: f64| t.sqrt());
    let kk = read_line(&reliable, &rw, pts, &lines, false, |t: f64| {
        (3.0 / t).sqrt()
    });
    let minp = reliable
        .iter()
        .min_by(|a, b| a.adev.total_cmp(&b.adev))
        .copied()
        .unwrap_or(&pts[0]);
    Ok(NoiseFit {
        white_density: n.value,
        white_density_err: n.err,
        white_tau_range: n.tau_range,
        white_density_is_bound: n.is_bound,
        random_walk: kk.value,
        random_walk_err: kk.err,
        random_walk_tau_range: kk.tau_range,
        random_walk_is_bound: kk.is_bound,
        bias_instability: minp.adev / BIAS_INSTABILITY_FACTOR,
        bias_instability_tau: minp.tau,
        model_white_density: model_line(&n, lines.n2),
        model_random_walk: model_line(&kk, lines.k2),
    })
}

/// A line's coefficient in the model curve: the fitted value, or for a bound the joint fit's
/// value over the other line's region, at most the bound (module docs).
fn model_line(line: &LineParameter, c2: f64) -> f64 {
    if line.is_bound {
        c2.sqrt().min(line.value)
    } else {
        line.value
    }
}

/// One parameter read from its line `σ = c/g(τ)`.
struct LineParameter {
    value: f64,
    err: f64,
    tau_range: (f64, f64),
    is_bound: bool,
}

/// The coefficient `c` of a line `σ = c/g(τ)` (module docs): when the line has a slope region,
/// `√c2` of the joint fit capped by [`line_cap`] at [`CAP_SIGMAS`], its error `σ_{c2}/(2√c2)`
/// and the region's τ range; otherwise the bound, [`line_cap`] alone, at the τ of the point
/// that sets it, NaN error.
fn read_line(
    reliable: &[&AllanPoint],
    region: &[usize],
    pts: &[AllanPoint],
    lines: &LinesFit,
    white: bool,
    g: impl Fn(f64) -> f64,
) -> LineParameter {
    if region.is_empty() {
        let (b, t) = line_cap(reliable, g, CAP_SIGMAS);
        return LineParameter {
            value: b,
            err: f64::NAN,
            tau_range: (t, t),
            is_bound: true,
        };
    }
    let (c2, var) = if white {
        (lines.n2, lines.cov[0][0])
    } else {
        (lines.k2, lines.cov[1][1])
    };
    let cap = line_cap(reliable, g, CAP_SIGMAS);
    let c = c2.sqrt().min(cap.0);
    // δc = δ(c²)/(2c); at c = 0 the c whose square is one σ of c².
    let sd = var.max(0.0).sqrt();
    let err = if c2 > 0.0 {
        sd / (2.0 * c2.sqrt())
    } else {
        sd.sqrt()
    };
    LineParameter {
        value: c,
        err,
        tau_range: (pts[region[0]].tau, pts[region[region.len() - 1]].tau),
        is_bound: false,
    }
}

/// The model curve of a fit: `σ_m(τ) = √(N²/τ + K²τ/3)` with [`NoiseFit::model_white_density`]
/// and [`NoiseFit::model_random_walk`] (the fitted lines; for a line that is only a bound, the
/// value the joint fit gives it, not the bound; bias instability left out, as a Kalibr
/// `imu.yaml` does).
pub fn model_adev(fit: &NoiseFit, tau: f64) -> f64 {
    let (n2, k2) = model_levels(fit);
    (n2 / tau + k2 * tau / 3.0).sqrt()
}

/// `(N², K²)` of the model curve of a fit.
fn model_levels(fit: &NoiseFit) -> (f64, f64) {
    (
        fit.model_white_density.powi(2),
        fit.model_random_walk.powi(2),
    )
}

/// How far the model curve ([`model_adev`]) is from the measured one where it was fitted: at
/// the reliable points (≥ 8 clusters) of the white-noise and random-walk τ ranges that are
/// fits, not bounds, `z(τ)` = the standard normal deviate of `σ̂²/σ_m²` under
/// `σ̂² ~ σ_m²χ²_ν/ν`, ν the point's EDF under the model (module docs, "Goodness of fit";
/// `≈ (σ̂ − σ_m)/(σ_m ε)` with `ε = 1/√(2ν)` for many EDF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelDeviation {
    /// `Σ z²` over those points.
    pub sum_z2: f64,
    /// Their number.
    pub points: usize,
    /// The largest `|z|` (0 without points).
    pub max_abs_z: f64,
    /// Its τ \[s\] (NaN without points).
    pub tau_at_max: f64,
    /// `z` there (its sign: positive when the curve lies above the model).
    pub z_at_max: f64,
    /// Whether that point lies in the white-noise line's τ range (else the random walk's).
    pub in_white_range: bool,
}

/// The [`ModelDeviation`] of one channel's fit.
pub fn model_deviation(pts: &[AllanPoint], fit: &NoiseFit) -> ModelDeviation {
    let within = |r: (f64, f64), t: f64| t >= r.0 * (1.0 - 1e-9) && t <= r.1 * (1.0 + 1e-9);
    let mut d = ModelDeviation {
        sum_z2: 0.0,
        points: 0,
        max_abs_z: 0.0,
        tau_at_max: f64::NAN,
        z_at_max: 0.0,
        in_white_range: true,
    };
    for p in pts.iter().filter(|p| p.clusters >= MIN_CLUSTERS) {
        let white = !fit.white_density_is_bound && within(fit.white_tau_range, p.tau);
        let fitted =
            white || (!fit.random_walk_is_bound && within(fit.random_walk_tau_range, p.tau));
        let m = model_adev(fit, p.tau);
        if !fitted || m.is_nan() || m <= 0.0 {
            continue;
        }
        let (n2, k2) = model_levels(fit);
        let nu = model_edf(p, n2, k2);
        let z = normal_deviate((p.adev / m).powi(2), nu);
        d.sum_z2 += z * z;
        d.points += 1;
        if z.abs() > d.max_abs_z {
            d.max_abs_z = z.abs();
            d.tau_at_max = p.tau;
            d.z_at_max = z;
            d.in_white_range = white;
        }
    }
    d
}
