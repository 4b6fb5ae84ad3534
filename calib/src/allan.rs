//! Overlapping Allan deviation and IMU noise-parameter fits (IEEE Std 952-1997, Annex C;
//! readings as in allan_variance_ros and kalibr_allan).
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
//! Each point carries `σ/√(2(N/m − 1))`, the 1-σ error of an Allan deviation estimated from
//! `K = N/m` independent clusters (IEEE 952 Annex C; El-Sheimy, Hou, Niu 2008, eq. 11). This is
//! the non-overlapping figure: the overlapping estimator is somewhat better, so the band is
//! conservative.
//!
//! # Fits (per channel)
//! The model is `σ²(τ) = N²/τ + (2 ln2/π)B² + K²τ/3` (white noise, bias instability, rate
//! random walk). Allan variances of independent noises **add**, so every term alone lies
//! below the curve: `N²/τ ≤ σ²(τ)` and `K²τ/3 ≤ σ²(τ)` at every τ. The fits enforce this.
//! Only reliable points (≥ 8 clusters) are used; below that the estimate has too few degrees
//! of freedom for its error `ε(τ) = adev_err/adev` to mean anything (with 2–3 clusters σ can be
//! off by a factor of several).
//! - Local log-log slopes are least-squares slopes over ±2 neighbouring points.
//! - **Regions.** A point is a candidate for the slope −½ (white noise) region when its local
//!   slope is within ±0.15 of −½. Candidates form runs of consecutive points; a run is kept
//!   only if it has ≥ 3 points **and** its own least-squares slope (over the run's points only)
//!   is within ±0.15 of −½. The second test matters: a smoothed local slope passes through −½
//!   wherever the curve goes from flat to steeper than −½ (e.g. the ADIS16405 accelerometers at
//!   τ ≈ 0.8–1.6 s: a plateau then a drop of slope ≈ −1.2, a ≈ 1 Hz disturbance), which is not
//!   white noise. The same for +½ (random walk).
//! - **N** (white-noise density, unit/√Hz): the slope −½ line `σ = N/√τ` fitted (weighted mean
//!   of `σ²τ`, weights = clusters) over the kept runs, read at τ = 1 s.
//! - **K** (random walk, unit/s/√Hz): the slope +½ line `σ = K√(τ/3)` fitted the same way,
//!   read at τ = 3 s.
//! - Each line is fitted after subtracting the other fitted term (two passes), which removes most
//!   of the bias from the crossover region where both terms matter.
//! - **Caps.** Then `N ≤ min_τ σ(τ)√τ·(1 + kε(τ))` and `K ≤ min_τ σ(τ)√(3/τ)·(1 + kε(τ))`
//!   over the reliable points, `k = 3` ([`CAP_SIGMAS`]): the line never exceeds the measured
//!   curve by more than 3 of its statistical errors anywhere. A weighted mean over a region
//!   where other noise already adds (σ√τ rising slowly) sits above the lowest points; the cap
//!   brings it to them. Why not `k = 2`: the long-τ points of a random-walk curve are few and
//!   strongly correlated, so the whole tail of a correct curve often sits ≈ 2ε low together; on
//!   `sim` data (10 h, 24 channels) `k = 2` pulled one K 13 % low, `k = 3` none.
//! - **Bounds.** When no run of the right slope exists, the value is only the upper bound
//!   `min_τ σ(τ)√τ` (resp. `min_τ σ(τ)√(3/τ)`, usually at the longest reliable τ): the line
//!   touching the measured curve at its lowest point, flagged
//!   ([`NoiseFit::white_density_is_bound`], [`NoiseFit::random_walk_is_bound`]), with the τ of
//!   the minimum as its range and a NaN error.
//! - Errors of fitted N and K: the relative error of the best-determined point of the fitted
//!   region, `1/√(2(K_max − 1))` (neighbouring τ share data, so the region is hardly better than
//!   that point).
//! - **B** (bias instability): the minimum of σ(τ) over points with ≥ 8 clusters, divided by
//!   `√(2 ln2/π) ≈ 0.664`. When the curve has no flat floor (e.g. white noise + random walk only)
//!   this is an upper bound: for `σ² = N²/τ + K²τ/3` the minimum is `√(2NK/√3)` at
//!   `τ* = √3·N/K`.

use preint::ImuSample;
use preint::noise::ImuNoise;

/// 2 ln2 / π: the bias-instability floor factor, `σ_floor = √(2 ln2/π)·B ≈ 0.664 B`.
pub const BIAS_INSTABILITY_FACTOR: f64 = 0.664_282_818_183_265_3;

/// Errors of the Allan analysis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AllanError {
    /// Not enough samples to form clusters.
    #[error("{0} samples: need at least 8 for an Allan deviation")]
    TooFewSamples(usize),
    /// The sample period is not positive and finite.
    #[error("invalid sample period {0} s")]
    BadPeriod(f64),
    /// A sample is NaN or infinite.
    #[error("channel {channel}: non-finite sample at index {index}")]
    NonFinite {
        /// Channel index.
        channel: usize,
        /// Sample index.
        index: usize,
    },
    /// Timestamps are not strictly increasing or not uniform.
    #[error("timestamps: {0}")]
    Timestamps(String),
    /// The curve has no reliable point (≥ 8 clusters): nothing can be read from it. (A curve
    /// without a slope −½ region gives an upper bound on N instead, see [`NoiseFit`].)
    #[error("channel {0}: no point with at least 8 clusters, white-noise density not fitted")]
    NoWhiteNoiseRegion(usize),
    /// Channels have different lengths.
    #[error("channel lengths differ ({0} vs {1})")]
    LengthMismatch(usize, usize),
}

/// One point of an Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AllanPoint {
    /// Cluster size m (samples).
    pub m: usize,
    /// Cluster time τ = mΔt \[s\].
    pub tau: f64,
    /// Overlapping Allan deviation σ(τ) [signal unit].
    pub adev: f64,
    /// 1-σ uncertainty of `adev`: `adev/√(2(N/m − 1))` (see the module docs).
    pub adev_err: f64,
    /// Number of non-overlapping clusters N/m (as a real number).
    pub clusters: f64,
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
/// (sizes with `2m > N` are skipped). See the module docs for the formula.
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
        let clusters = n as f64 / m as f64;
        out.push(AllanPoint {
            m,
            tau,
            adev,
            adev_err: adev / (2.0 * (clusters - 1.0)).sqrt(),
            clusters,
        });
    }
    Ok(out)
}

/// Fitted noise parameters of one channel (units: the signal's unit `u`, e.g. rad/s or m/s²).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFit {
    /// White-noise density N [u/√Hz] (σ of the slope −½ line at τ = 1 s), capped so that the
    /// line stays below the curve (module docs), or a bound (see `white_density_is_bound`).
    pub white_density: f64,
    /// Its 1-σ uncertainty: that of the best-determined point used, `N/√(2(K_max − 1))`
    /// (K = clusters); NaN when it is a bound.
    pub white_density_err: f64,
    /// τ range \[s\] of the points used for N (the τ of the minimum of `σ√τ` when a bound).
    pub white_tau_range: (f64, f64),
    /// `true` when no slope −½ region exists and N is only the upper bound `min_τ σ(τ)√τ`
    /// over the reliable points (module docs).
    pub white_density_is_bound: bool,
    /// Random walk K [u/s/√Hz] (σ of the slope +½ line at τ = 3 s), capped as N, or a bound
    /// (see `random_walk_is_bound`).
    pub random_walk: f64,
    /// 1-σ uncertainty of K, from the best-determined point used as for N (NaN when it is a
    /// bound).
    pub random_walk_err: f64,
    /// τ range \[s\] of the points used for K (the single longest τ when it is a bound).
    pub random_walk_tau_range: (f64, f64),
    /// `true` when no slope +½ region exists and K is only the upper bound `min_τ σ(τ)√(3/τ)`
    /// over the reliable points (module docs; usually at the longest reliable τ).
    pub random_walk_is_bound: bool,
    /// Bias instability B \[u\] = min σ / 0.664 (an upper bound without a flat floor).
    pub bias_instability: f64,
    /// τ \[s\] of the minimum.
    pub bias_instability_tau: f64,
}

const MIN_CLUSTERS: f64 = 8.0;
const SLOPE_TOL: f64 = 0.15;
/// Minimum number of points of a slope region.
const MIN_RUN: usize = 3;
/// Allowance `k` of the caps and bounds, in units of a point's relative error ε (module docs).
pub const CAP_SIGMAS: f64 = 3.0;

fn local_slopes(pts: &[AllanPoint]) -> Vec<f64> {
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
fn ls_slope(x: &[f64], y: &[f64]) -> f64 {
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

/// Indices (into `pts`, all reliable) of the kept runs of slope `target` (module docs).
fn slope_region(pts: &[AllanPoint], slopes: &[f64], target: f64) -> Vec<usize> {
    let cand =
        |i: usize| pts[i].clusters >= MIN_CLUSTERS && (slopes[i] - target).abs() <= SLOPE_TOL;
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

/// `min_τ σ(τ)·g(τ)·(1 + k·ε(τ))` over the reliable points and its τ: the largest `c` of a
/// line `σ = c/g(τ)` that stays below the curve within `k` errors (module docs: `k =`
/// [`CAP_SIGMAS`] for the caps, 0 for the bounds).
fn line_cap(reliable: &[&AllanPoint], g: impl Fn(f64) -> f64, k: f64) -> (f64, f64) {
    reliable
        .iter()
        .map(|p| {
            let eps = p.adev_err / p.adev.max(1e-300);
            (p.adev * g(p.tau) * (1.0 + k * eps), p.tau)
        })
        .fold(
            (f64::INFINITY, f64::NAN),
            |a, b| if b.0 < a.0 { b } else { a },
        )
}

/// Weighted mean of `vals` (value, weight = 2(K−1), the inverse relative variance of σ) and
/// the relative 1-σ error of the square root of that mean: `1/√max w`, the error of the
/// best-determined point used. Neighbouring τ of an overlapping Allan curve share their data
/// and are strongly correlated, so combining them gains little over their best point;
/// `1/√Σw` (independent points) was optimistic by 2–3× against the spread over seeds
/// (`tests/allan.rs` checks the ratio).
fn weighted(vals: &[(f64, f64)]) -> (f64, f64) {
    let sw: f64 = vals.iter().map(|v| v.1).sum();
    let wmax = vals.iter().map(|v| v.1).fold(0.0, f64::max);
    let mean = vals.iter().map(|v| v.0 * v.1).sum::<f64>() / sw;
    (mean, (1.0 / wmax).sqrt())
}

/// Fits N, K and B to one channel's curve (see the module docs). `channel` only labels errors.
/// Error: no point with ≥ 8 clusters ([`AllanError::NoWhiteNoiseRegion`]).
pub fn fit_noise(pts: &[AllanPoint], channel: usize) -> Result<NoiseFit, AllanError> {
    let reliable: Vec<&AllanPoint> = pts.iter().filter(|p| p.clusters >= MIN_CLUSTERS).collect();
    if reliable.is_empty() {
        return Err(AllanError::NoWhiteNoiseRegion(channel));
    }
    let slopes = local_slopes(pts);
    let white = slope_region(pts, &slopes, -0.5);
    let rw = slope_region(pts, &slopes, 0.5);
    // Weight of a point: 2(K−1) = inverse relative variance of σ (so of σ², up to 4).
    let wgt = |p: &AllanPoint| 2.0 * (p.clusters - 1.0);
    let (mut n2, mut k2) = (0.0, 0.0);
    let (mut n_rel, mut k_rel) = (f64::NAN, f64::NAN);
    for _pass in 0..2 {
        if !white.is_empty() {
            let v: Vec<(f64, f64)> = white
                .iter()
                .map(|&i| {
                    let p = &pts[i];
                    let s2 = (p.adev * p.adev - k2 * p.tau / 3.0).max(0.0);
                    (s2 * p.tau, wgt(p))
                })
                .collect();
            (n2, n_rel) = weighted(&v);
        }
        if !rw.is_empty() {
            let v: Vec<(f64, f64)> = rw
                .iter()
                .map(|&i| {
                    let p = &pts[i];
                    let s2 = (p.adev * p.adev - n2 / p.tau).max(0.0);
                    (3.0 * s2 / p.tau, wgt(p))
                })
                .collect();
            (k2, k_rel) = weighted(&v);
        }
    }
    let minp = reliable
        .iter()
        .min_by(|a, b| a.adev.total_cmp(&b.adev))
        .copied()
        .unwrap_or(&pts[0]);
    let range = |idx: &[usize]| (pts[idx[0]].tau, pts[idx[idx.len() - 1]].tau);
    let g_white = |t: f64| t.sqrt();
    let g_rw = |t: f64| (3.0 / t).sqrt();
    let (n, n_err, n_range, n_bound) = if white.is_empty() {
        let (b, t) = line_cap(&reliable, g_white, 0.0);
        (b, f64::NAN, (t, t), true)
    } else {
        let n = n2.sqrt().min(line_cap(&reliable, g_white, CAP_SIGMAS).0);
        (n, n * n_rel, range(&white), false)
    };
    let (k, k_err, k_range, k_bound) = if rw.is_empty() {
        let (b, t) = line_cap(&reliable, g_rw, 0.0);
        (b, f64::NAN, (t, t), true)
    } else {
        let k = k2.sqrt().min(line_cap(&reliable, g_rw, CAP_SIGMAS).0);
        (k, k * k_rel, range(&rw), false)
    };
    Ok(NoiseFit {
        white_density: n,
        white_density_err: n_err,
        white_tau_range: n_range,
        white_density_is_bound: n_bound,
        random_walk: k,
        random_walk_err: k_err,
        random_walk_tau_range: k_range,
        random_walk_is_bound: k_bound,
        bias_instability: minp.adev / BIAS_INSTABILITY_FACTOR,
        bias_instability_tau: minp.tau,
    })
}

/// Allan analysis of a six-axis IMU record.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuAllan {
    /// Sample period Δt \[s\].
    pub dt: f64,
    /// Curves, channel order `[ω_x, ω_y, ω_z, a_x, a_y, a_z]`.
    pub curves: [Vec<AllanPoint>; 6],
    /// Fits, same order (gyro in rad/s units, accelerometer in m/s² units).
    pub fits: [NoiseFit; 6],
}

impl ImuAllan {
    /// Analyses six channels `[ω_x, ω_y, ω_z, a_x, a_y, a_z]` sampled every `dt` \[s\], with
    /// `per_decade` log-spaced τ per decade (10 is typical).
    pub fn from_channels(
        channels: [&[f64]; 6],
        dt: f64,
        per_decade: usize,
    ) -> Result<Self, AllanError> {
        let n = channels[0].len();
        for c in &channels {
            if c.len() != n {
                return Err(AllanError::LengthMismatch(n, c.len()));
            }
        }
        let ms = log_spaced_cluster_sizes(n / 2, per_decade);
        let mut curves: [Vec<AllanPoint>; 6] = Default::default();
        for (i, c) in channels.iter().enumerate() {
            curves[i] = allan_deviation(c, dt, &ms).map_err(|e| match e {
                AllanError::NonFinite { index, .. } => AllanError::NonFinite { channel: i, index },
                e => e,
            })?;
        }
        let fits = [
            fit_noise(&curves[0], 0)?,
            fit_noise(&curves[1], 1)?,
            fit_noise(&curves[2], 2)?,
            fit_noise(&curves[3], 3)?,
            fit_noise(&curves[4], 4)?,
            fit_noise(&curves[5], 5)?,
        ];
        Ok(Self { dt, curves, fits })
    }

    /// Analyses IMU samples; the period is `(t_last − t_first)/(N − 1)` and every interval must
    /// lie within ±10 % of it (no gaps or reordering).
    pub fn from_samples(samples: &[ImuSample], per_decade: usize) -> Result<Self, AllanError> {
        if samples.len() < 8 {
            return Err(AllanError::TooFewSamples(samples.len()));
        }
        let n = samples.len();
        let span = samples[n - 1].t_ns - samples[0].t_ns;
        let dt = span as f64 * 1e-9 / (n - 1) as f64;
        for (i, w) in samples.windows(2).enumerate() {
            let d = (w[1].t_ns - w[0].t_ns) as f64 * 1e-9;
            if !(d > 0.0 && (d - dt).abs() <= 0.1 * dt) {
                return Err(AllanError::Timestamps(format!(
                    "interval {i} is {d} s, mean period {dt} s (gap or reordering)"
                )));
            }
        }
        let ch: Vec<Vec<f64>> = (0..6)
            .map(|c| {
                samples
                    .iter()
                    .map(|s| if c < 3 { s.gyro[c] } else { s.acc[c - 3] })
                    .collect()
            })
            .collect();
        Self::from_channels(
            [&ch[0], &ch[1], &ch[2], &ch[3], &ch[4], &ch[5]],
            dt,
            per_decade,
        )
    }

    /// Kalibr noise parameters, aggregated over the three axes of each sensor by the **maximum**
    /// (conservative: a VIO back end fed a too-small noise becomes overconfident). Densities
    /// and random walks that are only upper bounds are used as they are (conservative too). `update_rate = 1/Δt`.
    pub fn to_imu_noise(&self) -> ImuNoise {
        let max = |r: std::ops::Range<usize>, f: fn(&NoiseFit) -> f64| {
            self.fits[r].iter().map(f).fold(0.0, f64::max)
        };
        ImuNoise {
            gyro_noise_density: max(0..3, |f| f.white_density),
            gyro_random_walk: max(0..3, |f| f.random_walk),
            acc_noise_density: max(3..6, |f| f.white_density),
            acc_random_walk: max(3..6, |f| f.random_walk),
            update_rate_hz: 1.0 / self.dt,
        }
    }

    /// Kalibr `imu.yaml` text of [`ImuAllan::to_imu_noise`] (via `preint::io`).
    pub fn kalibr_yaml(&self) -> String {
        preint::io::kalibr_yaml_string(&self.to_imu_noise())
    }
}
