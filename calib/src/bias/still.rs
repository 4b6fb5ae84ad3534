//! Still-interval detection by moving variance (the static detector of the multi-position
//! protocol, Tedaldi, Pretto, Menegatti 2014 / imu_tk).
//!
//! # Detector
//! For each sample k, over the centred window of `w = 2h + 1` samples (`h = round(window_s /
//! 2Δt)`, Δt the mean sample period), the mean per-axis variance
//!
//! ```text
//! V_ω(k) = ⅓ Σ_axes var(ω_m,k−h..k+h)     V_a(k) = ⅓ Σ_axes var(a_m,k−h..k+h)
//! ```
//!
//! (O(N) with prefix sums). Sample k is still when `V_ω ≤ gyro_var_max` **and**
//! `V_a ≤ acc_var_max`; samples closer than `h` to either end of the record are not
//! classified still. Runs of still samples lasting at least `min_duration_s` are the still
//! intervals. Because a window touching a motion has a large variance, intervals are trimmed
//! by about half a window at each side of a motion automatically.
//!
//! The per-axis variance of the vectors is used rather than the variance of their norms
//! `|ω|`, `|a|`: a slow rotation keeps `|a| ≈ |g|` and a constant-rate turn keeps `|ω|`
//! constant, but the former changes the direction of `a` (seen per axis). A rotation at an
//! exactly constant rate with negligible change of the gravity direction within one window is
//! not detected (no variance-based detector can).
//!
//! # Thresholds
//! At rest the variance is the white noise's, `σ²/Δt` per axis (σ the Kalibr density); the
//! default thresholds ([`StillOptions::from_noise`]) are `factor·σ²/Δt` with `factor = 4`:
//! with a 0.5 s window at 200 Hz the variance estimate of a still window has ~300 degrees of
//! freedom (relative std ≈ 8 %), so a still window exceeds 4× its expected value with
//! negligible probability, while any rotation faster than ≈ 1°/s tilts gravity enough to exceed
//! `4σ_a²/Δt` (EuRoC figures: 8e-4 (m/s²)² ↔ a change of ≈ 0.03 m/s² within the window).

use super::BiasError;
use super::stats::mean_period;
use super::validate::check_samples;
use preint::{ImuNoise, ImuSample};

/// Options of [`detect_still_intervals`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StillOptions {
    /// Length of the moving window \[s\] (default 0.5).
    pub window_s: f64,
    /// Threshold on the mean per-axis gyro variance `V_ω` [(rad/s)²].
    pub gyro_var_max: f64,
    /// Threshold on the mean per-axis accelerometer variance `V_a` [(m/s²)²].
    pub acc_var_max: f64,
    /// Minimum length of a still interval \[s\] (default 1.0).
    pub min_duration_s: f64,
}

impl StillOptions {
    /// Thresholds `factor·σ²·rate` from the noise densities with `factor = 4`, a 0.5 s window
    /// and a 1 s minimum length (module docs).
    pub fn from_noise(noise: &ImuNoise, rate_hz: f64) -> Self {
        Self::from_noise_factor(noise, rate_hz, 4.0)
    }
    /// Same with an explicit factor.
    pub fn from_noise_factor(noise: &ImuNoise, rate_hz: f64, factor: f64) -> Self {
        Self {
            window_s: 0.5,
            gyro_var_max: factor * noise.gyro_noise_density.powi(2) * rate_hz,
            acc_var_max: factor * noise.acc_noise_density.powi(2) * rate_hz,
            min_duration_s: 1.0,
        }
    }
}

/// A detected still interval: samples `start..end` (end exclusive) of the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StillInterval {
    /// First sample index.
    pub start: usize,
    /// One past the last sample index.
    pub end: usize,
    /// Timestamp of the first sample \[ns\].
    pub t_start_ns: i64,
    /// Timestamp of the last sample \[ns\].
    pub t_end_ns: i64,
}

impl StillInterval {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.end - self.start
    }
    /// `true` if it holds no sample.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
    /// Duration from the first to the last sample \[s\].
    pub fn duration_s(&self) -> f64 {
        (self.t_end_ns - self.t_start_ns) as f64 * 1e-9
    }
}

/// Moving variances `(V_ω, V_a)` per sample (module docs); `NaN` within `h` of the ends.
pub fn moving_variances(samples: &[ImuSample], window_s: f64) -> (Vec<f64>, Vec<f64>) {
    let n = samples.len();
    if n < 2 {
        return (vec![f64::NAN; n], vec![f64::NAN; n]);
    }
    let dt = mean_period(samples);
    let h = ((window_s / (2.0 * dt)).round() as usize).max(1);
    let w = 2 * h + 1;
    // Prefix sums of shifted values (sum, sum of squares) per channel.
    let (g0, a0) = (samples[0].gyro, samples[0].acc);
    let mut ps = vec![[0.0f64; 12]; n + 1];
    for (k, s) in samples.iter().enumerate() {
        let mut row = ps[k];
        for c in 0..3 {
            let dg = s.gyro[c] - g0[c];
            let da = s.acc[c] - a0[c];
            row[c] += dg;
            row[3 + c] += dg * dg;
            row[6 + c] += da;
            row[9 + c] += da * da;
        }
        ps[k + 1] = row;
    }
    let mut vg = vec![f64::NAN; n];
    let mut va = vec![f64::NAN; n];
    if w > n {
        return (vg, va);
    }
    let wf = w as f64;
    for k in h..n - h {
        let (lo, hi) = (&ps[k - h], &ps[k + h + 1]);
        let mut sg = 0.0;
        let mut sa = 0.0;
        for c in 0..3 {
            let s1 = hi[c] - lo[c];
            let s2 = hi[3 + c] - lo[3 + c];
            sg += ((s2 - s1 * s1 / wf) / (wf - 1.0)).max(0.0);
            let s1 = hi[6 + c] - lo[6 + c];
            let s2 = hi[9 + c] - lo[9 + c];
            sa += ((s2 - s1 * s1 / wf) / (wf - 1.0)).max(0.0);
        }
        vg[k] = sg / 3.0;
        va[k] = sa / 3.0;
    }
    (vg, va)
}

/// Detects still intervals (module docs). Errors: fewer than 3 samples, non-finite values,
/// non-increasing timestamps, non-positive or non-finite options.
pub fn detect_still_intervals(
    samples: &[ImuSample],
    opts: &StillOptions,
) -> Result<Vec<StillInterval>, BiasError> {
    check_samples(samples, 3)?;
    let opt_ok = [opts.window_s, opts.gyro_var_max, opts.acc_var_max]
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
        && opts.min_duration_s.is_finite()
        && opts.min_duration_s >= 0.0;
    if !opt_ok {
        return Err(BiasError::InvalidParameter {
            name: "StillOptions",
            reason: format!("window, thresholds must be finite and > 0, got {opts:?}"),
        });
    }
    let (vg, va) = moving_variances(samples, opts.window_s);
    let still: Vec<bool> = vg
        .iter()
        .zip(&va)
        .map(|(g, a)| *g <= opts.gyro_var_max && *a <= opts.acc_var_max)
        .collect();
    let mut out = Vec::new();
    let mut k = 0;
    let n = samples.len();
    while k < n {
        if !still[k] {
            k += 1;
            continue;
        }
        let s = k;
        while k < n && still[k] {
            k += 1;
        }
        let iv = StillInterval {
            start: s,
            end: k,
            t_start_ns: samples[s].t_ns,
            t_end_ns: samples[k - 1].t_ns,
        };
        if iv.duration_s() >= opts.min_duration_s {
            out.push(iv);
        }
    }
    Ok(out)
}
