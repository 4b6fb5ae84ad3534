//! The merge model: cubic Hermite resampling of the accelerometer onto the gyro stamps, its
//! noise weights, and the effective accelerometer noise of the merged stream.
//!
//! Equation numbers refer to `docs/SPLIT_STREAMS.md`.

use preint::ImuNoise;

/// Weights of the accelerometer samples `a_{j−1}, a_j, a_{j+1}, a_{j+2}` (times `t_{j−1} <
/// t_j ≤ t < t_{j+1} < t_{j+2}` \[ns\]) in the cubic Hermite value at `t` with finite-difference
/// tangents `m_j = (a_{j+1} − a_{j−1})/(t_{j+1} − t_{j−1})` (eq. 1; Catmull–Rom for uniform
/// stamps). With `h = t_{j+1} − t_j`, `λ = (t − t_j)/h` and the Hermite basis `h00 = 2λ³ − 3λ²
/// + 1`, `h10 = λ³ − 2λ² + λ`, `h01 = −2λ³ + 3λ²`, `h11 = λ³ − λ²`:
///
/// ```text
/// w_{j−1} = −h·h10/D_j,  w_j = h00 − h·h11/D_{j+1},  w_{j+1} = h01 + h·h10/D_j,  w_{j+2} = h·h11/D_{j+1}
/// ```
///
/// (`D_j = t_{j+1} − t_{j−1}`, `D_{j+1} = t_{j+2} − t_j`); they sum to 1.
#[inline]
pub fn hermite_weights(t: [i64; 4], at: i64) -> [f64; 4] {
    let h = (t[2] - t[1]) as f64;
    let l = (at - t[1]) as f64 / h;
    let (l2, l3) = (l * l, l * l * l);
    let h00 = 2.0 * l3 - 3.0 * l2 + 1.0;
    let h10 = l3 - 2.0 * l2 + l;
    let h01 = -2.0 * l3 + 3.0 * l2;
    let h11 = l3 - l2;
    let g0 = h / (t[2] - t[0]) as f64;
    let g1 = h / (t[3] - t[1]) as f64;
    [-g0 * h10, h00 - g1 * h11, h01 + g0 * h10, g1 * h11]
}

/// Counts and statistics of one merge, from which [`effective_noise`] follows. Available
/// from [`crate::split::MergeHandle::report`] while and after the merged stream is read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MergeReport {
    /// Gyro samples read.
    pub gyro_samples: u64,
    /// Accelerometer samples read.
    pub accel_samples: u64,
    /// IMU samples produced (one per gyro sample inside the accelerometer span).
    pub merged: u64,
    /// Gyro samples dropped because fewer than two accelerometer samples are at or before them.
    pub dropped_before: u64,
    /// Gyro samples dropped because fewer than two accelerometer samples follow them.
    pub dropped_after: u64,
    /// Time of the first and last merged sample \[ns\] (0 when none).
    pub merged_span_ns: (i64, i64),
    /// Time of the first and last accelerometer sample read \[ns\].
    pub accel_span_ns: (i64, i64),
    /// Time of the first and last gyro sample read \[ns\].
    pub gyro_span_ns: (i64, i64),
    /// `Σ_j W_j²/c_j` \[s\] over the accelerometer samples (eq. 4): `W_j` \[s\] the weight of
    /// sample `j` in the trapezoidal integral of the merged accelerometer over the merged
    /// span, `c_j` \[s\] its own time cell.
    pub white_weight_sq: f64,
    /// Number of accelerometer third differences in [`MergeReport::third_diff_sq_sum`].
    pub third_diffs: u64,
    /// `Σ |Δ³a_j|²` [m²/s⁴] over consecutive accelerometer quadruples (all three axes), for
    /// the interpolation-error term (eq. 6).
    pub third_diff_sq_sum: f64,
}

impl MergeReport {
    /// Mean gyro rate \[Hz\] from the stamps read (0 with fewer than two).
    pub fn gyro_rate_hz(&self) -> f64 {
        rate(self.gyro_samples, self.gyro_span_ns)
    }

    /// Mean accelerometer rate \[Hz\] from the stamps read (0 with fewer than two).
    pub fn accel_rate_hz(&self) -> f64 {
        rate(self.accel_samples, self.accel_span_ns)
    }

    /// Length of the merged span \[s\].
    pub fn merged_span_s(&self) -> f64 {
        (self.merged_span_ns.1 - self.merged_span_ns.0) as f64 * 1e-9
    }

    /// `ρ` (eq. 4): the variance of the integrated accelerometer white noise of the merged
    /// stream over its span, divided by what density `σ_a` gives (`σ_a² T`). `1.0` when the
    /// span is empty. Close to 1 (slightly below, eq. 5) when the accelerometer is slower
    /// than the gyro; above 1 when it is faster (samples between gyro stamps are skipped).
    pub fn white_ratio(&self) -> f64 {
        let t = self.merged_span_s();
        if t > 0.0 && self.white_weight_sq > 0.0 {
            self.white_weight_sq / t
        } else {
            1.0
        }
    }

    /// When the merge shortened the recording to the accelerometer's span (at either end, more
    /// gyro samples dropped than fall within `EDGE_ACCEL_INTERVALS` accelerometer intervals,
    /// the end the cubic interpolation needs): what was dropped, for a warning.
    pub fn shortening(&self) -> Option<String> {
        let (fg, fa) = (self.gyro_rate_hz(), self.accel_rate_hz());
        let edge = if fg > 0.0 && fa > 0.0 {
            (EDGE_ACCEL_INTERVALS * fg / fa).ceil() as u64
        } else {
            0
        };
        if self.dropped_before <= edge && self.dropped_after <= edge {
            return None;
        }
        let span = |s: (i64, i64)| (s.1 - s.0) as f64 * 1e-9;
        Some(format!(
            "the split streams overlap over {:.3} s only: the accelerometer runs from {} to {} \
             ns, so {} gyro samples before and {} after it are dropped (of {} over {:.3} s); the \
             result is that of the overlap",
            span(self.merged_span_ns),
            self.accel_span_ns.0,
            self.accel_span_ns.1,
            self.dropped_before,
            self.dropped_after,
            self.gyro_samples,
            span(self.gyro_span_ns),
        ))
    }

    /// One line for the notes of a source.
    pub fn describe(&self) -> String {
        format!(
            "split streams: accelerometer ({} samples, {:.3} Hz) resampled onto {} of {} gyro \
             stamps ({:.3} Hz) by cubic Hermite interpolation; {} gyro samples dropped before \
             and {} after the accelerometer span; white-noise ratio ρ = {:.4}",
            self.accel_samples,
            self.accel_rate_hz(),
            self.merged,
            self.gyro_samples,
            self.gyro_rate_hz(),
            self.dropped_before,
            self.dropped_after,
            self.white_ratio()
        )
    }
}

/// Accelerometer intervals at each end of a merge whose gyro samples may be dropped without it
/// being a shortening of the recording: the cubic needs two accelerometer samples on each side
/// of a gyro stamp, and the streams' first and last stamps need not coincide.
pub const EDGE_ACCEL_INTERVALS: f64 = 3.0;

fn rate(n: u64, span: (i64, i64)) -> f64 {
    let s = (span.1 - span.0) as f64 * 1e-9;
    if n >= 2 && s > 0.0 {
        (n - 1) as f64 / s
    } else {
        0.0
    }
}

/// `E_λ[(λ(1−λ)(1−2λ))²]` for `λ` uniform on [0, 1): `1/210` (eq. 6).
const CURVATURE_SHAPE_MS: f64 = 1.0 / 210.0;

/// Accelerometer interpolation-error density `q_int` [m²/s³ per axis] (eq. 6): the mean
/// square of the cubic interpolation error `e = (h³/6) λ(1−λ)(1−2λ) a⃛` from the
/// accelerometer's third differences with their white-noise part (`20 σ_a²/h_a` per axis,
/// eq. 7) removed, as a white density at the gyro cell `h_g`. Zero when the noise explains the
/// third differences.
pub fn interpolation_psd(report: &MergeReport, acc_noise_density: f64) -> f64 {
    let (fa, fg) = (report.accel_rate_hz(), report.gyro_rate_hz());
    if report.third_diffs == 0 || fa <= 0.0 || fg <= 0.0 {
        return 0.0;
    }
    let per_axis = report.third_diff_sq_sum / (3.0 * report.third_diffs as f64);
    let noise = 20.0 * acc_noise_density.powi(2) * fa;
    let signal = (per_axis - noise).max(0.0);
    signal / 36.0 * CURVATURE_SHAPE_MS / fg
}

/// The noise densities to preintegrate the merged stream with (eqs. 4–8): gyro densities
/// unchanged (the samples are at the gyro stamps), the accelerometer density
/// `σ_a,eff = √(ρ σ_a² + q_int)` with `ρ` = [`MergeReport::white_ratio`] and `q_int` =
/// [`interpolation_psd`], random walks unchanged (the bias moves in time, not in samples),
/// `update_rate_hz` the gyro rate.
pub fn effective_noise(noise: &ImuNoise, report: &MergeReport) -> ImuNoise {
    let rho = report.white_ratio();
    let q = interpolation_psd(report, noise.acc_noise_density);
    let mut out = *noise;
    out.acc_noise_density = (rho * noise.acc_noise_density.powi(2) + q).sqrt();
    let fg = report.gyro_rate_hz();
    if fg > 0.0 {
        out.update_rate_hz = fg;
    }
    out
}

/// `ρ` (eq. 4) for uniform streams at `gyro_rate_hz` and `accel_rate_hz` over windows of
/// `window_s` seconds, averaged over `phases` phases of the accelerometer grid against the
/// window start: the same weights as a merge, on the stamps alone. For
/// `accel_rate_hz ≤ gyro_rate_hz` it is `1 − κ h_a/T` to first order (eq. 5). `None` unless
/// the rates and the window are finite and positive, `phases ≥ 1`, and the window holds at
/// most [`MAX_RATE_WINDOW_SAMPLES`] gyro samples.
pub fn white_ratio_for_rates(
    gyro_rate_hz: f64,
    accel_rate_hz: f64,
    window_s: f64,
    phases: u32,
) -> Option<f64> {
    let ok = |x: f64| x.is_finite() && x > 0.0;
    let n_g = (window_s * gyro_rate_hz).round();
    let valid = ok(gyro_rate_hz)
        && ok(accel_rate_hz)
        && ok(window_s)
        && phases >= 1
        && (1.0..=MAX_RATE_WINDOW_SAMPLES as f64).contains(&n_g)
        && gyro_rate_hz <= 1e9
        && accel_rate_hz <= 1e9;
    if !valid {
        return None;
    }
    let (hg, ha, n_g) = (1e9 / gyro_rate_hz, 1e9 / accel_rate_hz, n_g as i64);
    let mut sum = 0.0;
    for p in 0..phases {
        let off = ha * f64::from(p) / f64::from(phases);
        let acc_t = |j: i64| (j as f64 * ha + off).round() as i64;
        let mut acc = WeightAccumulator::default();
        let mut j = 1i64;
        for k in 0..=n_g {
            let t = 3 * ha as i64 + (k as f64 * hg).round() as i64;
            while acc_t(j + 1) <= t {
                j += 1;
            }
            let ts = [acc_t(j - 1), acc_t(j), acc_t(j + 1), acc_t(j + 2)];
            for (i, &tt) in ts.iter().enumerate() {
                acc.see_accel(j - 1 + i as i64, tt);
            }
            acc.add_gyro(t, j - 1, &hermite_weights(ts, t));
        }
        let span = n_g as f64 * hg * 1e-9;
        sum += acc.finish(acc_t) / span;
    }
    Some(sum / f64::from(phases))
}

/// Most gyro samples in a window of [`white_ratio_for_rates`] (10⁷).
pub const MAX_RATE_WINDOW_SAMPLES: u64 = 10_000_000;

/// The densities for uniform streams at `gyro_rate_hz` and `accel_rate_hz` and windows of
/// `window_s` seconds, before any data is read: eq. 8 with `ρ` from
/// [`white_ratio_for_rates`] (16 phases) and no interpolation term. `None` for invalid rates
/// or window (see [`white_ratio_for_rates`]).
pub fn effective_noise_for_rates(
    noise: &ImuNoise,
    gyro_rate_hz: f64,
    accel_rate_hz: f64,
    window_s: f64,
) -> Option<ImuNoise> {
    let rho = white_ratio_for_rates(gyro_rate_hz, accel_rate_hz, window_s, 16)?;
    let mut out = *noise;
    out.acc_noise_density = noise.acc_noise_density * rho.sqrt();
    out.update_rate_hz = gyro_rate_hz;
    Some(out)
}

/// Accumulates `W_j` (eq. 3) while samples are merged and `Σ W_j²/c_j` as accelerometer
/// samples leave the merge window. Holds the open samples only (at most eight).
#[derive(Clone, Debug, Default)]
pub struct WeightAccumulator {
    /// `(index, W_j [s])` of the accelerometer samples still receiving weight, increasing.
    open: Vec<(i64, f64)>,
    /// The previous merged sample: its time \[ns\], first accelerometer index and weights.
    prev: Option<(i64, i64, [f64; 4])>,
    /// Stamps \[ns\] of recently seen accelerometer samples, by index (for their cells).
    stamps: Vec<(i64, i64)>,
    /// `Σ W_j²/c_j` \[s\] of the closed samples.
    pub sum: f64,
}

impl WeightAccumulator {
    /// Notes the stamp of accelerometer sample `index` (called in index order, repeats allowed).
    pub fn see_accel(&mut self, index: i64, t_ns: i64) {
        if self.stamps.last().is_none_or(|&(i, _)| i < index) {
            self.stamps.push((index, t_ns));
            if self.stamps.len() > 12 {
                self.stamps.remove(0);
            }
        }
    }

    /// Adds the merged sample at `t_ns` whose value has weights `w` on accelerometer samples
    /// `first..first + 4`: the trapezoid over the interval from the previous merged sample
    /// gives each end half the interval (eq. 3).
    pub fn add_gyro(&mut self, t_ns: i64, first: i64, w: &[f64; 4]) {
        if let Some((tp, fp, wp)) = self.prev {
            let half = (t_ns - tp) as f64 * 1e-9 * 0.5;
            self.add(fp, &wp, half);
            self.add(first, w, half);
        }
        self.prev = Some((t_ns, first, *w));
        // Samples before `first` get no more weight: later intervals start at this sample.
        let (open, stamps) = (&mut self.open, &self.stamps);
        while open.first().is_some_and(|&(i, _)| i < first) {
            let (i, wj) = open.remove(0);
            self.sum += wj * wj / cell(stamps, i);
        }
    }

    fn add(&mut self, first: i64, w: &[f64; 4], scale: f64) {
        for (k, &wk) in w.iter().enumerate() {
            let idx = first + k as i64;
            match self.open.iter_mut().find(|(i, _)| *i == idx) {
                Some(slot) => slot.1 += wk * scale,
                None => {
                    let pos = self.open.partition_point(|&(i, _)| i < idx);
                    self.open.insert(pos, (idx, wk * scale));
                }
            }
        }
    }

    /// Closes every open sample, with `stamp(index)` giving stamps not seen; returns `Σ W_j²/c_j`.
    pub fn finish(mut self, stamp: impl Fn(i64) -> i64) -> f64 {
        for &(i, wj) in &self.open {
            for k in [i - 1, i, i + 1] {
                if !self.stamps.iter().any(|&(s, _)| s == k) {
                    self.stamps.push((k, stamp(k)));
                }
            }
            self.sum += wj * wj / cell(&self.stamps, i);
        }
        self.open.clear();
        self.sum
    }

    /// Closes every open sample using only the stamps seen (the end of a recording: a
    /// missing neighbour gives the one-sided cell).
    pub fn finish_seen(mut self) -> f64 {
        for &(i, wj) in &self.open {
            self.sum += wj * wj / cell(&self.stamps, i);
        }
        self.open.clear();
        self.sum
    }
}

/// The time cell \[s\] of accelerometer sample `i`: half the distance between its neighbours,
/// or the one interval at an end (the `Centered` rule of `preint::CellRule`).
fn cell(stamps: &[(i64, i64)], i: i64) -> f64 {
    let at = |k: i64| stamps.iter().find(|&&(s, _)| s == k).map(|&(_, t)| t);
    let t = at(i).unwrap_or(0);
    let left = at(i - 1).map_or(0.0, |p| (t - p) as f64 * 1e-9);
    let right = at(i + 1).map_or(0.0, |n| (n - t) as f64 * 1e-9);
    preint::CellRule::Centered.cell_s(left, right)
}
