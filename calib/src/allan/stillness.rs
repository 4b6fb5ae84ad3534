//! Is a recording static? A streamed check for the Allan analysis, in constant memory.
//!
//! The Allan variance describes the sensor's noise only when the input is constant: on a
//! moving recording it describes the motion. [`StillnessMonitor`] cuts the stream into
//! consecutive windows of [`StillnessOptions::window_s`] = 1 s (at least 5 samples) and keeps
//! only the running sums of the current window and the summary of the previous one:
//! - **Still window.** A window is still when, on each of the six axes, its mean differs from
//!   the previous window's by at most `max_z` = 10 standard errors,
//!   `|m_k − m_{k−1}| ≤ z·√(s_k²/n_k + s_{k−1}²/n_{k−1})` (`s` the sample standard deviation,
//!   at least 1e-4 rad/s resp. 1e-3 m/s² so that a quantised, constant reading is not infinitely
//!   sharp). At rest, the difference of consecutive 1 s means has the rms `√2·σ(1 s)` (the Allan
//!   deviation's definition), which exceeds `√2·s/√n` only by the noise's correlation: measured
//!   on the static ADIS16405 hour the ratio is 1.3 (gyro) to 2 (accelerometer, a ≈ 1 Hz
//!   disturbance), the largest z over 3600 windows 7.3. Any rotation or acceleration changes a
//!   1 s mean by far more (EuRoC V1_01: median z 13, 67 % of the windows moving).
//! - **Tilt.** The gravity direction (the accelerometer's window mean) may not turn by more
//!   than `max_tilt_deg` = 2° from the first window's: a sensor set down in another attitude
//!   moves the gravity components, a step that dominates the accelerometers' Allan deviation at
//!   long τ, while only one or two windows show the motion. (The static ADIS16405 hour: 0.41°,
//!   its temperature drift.)
//! - **Verdict** ([`Stillness::verdict`]): static when at least `min_still_fraction` = 90 % of
//!   the compared windows are still and the tilt stays within `max_tilt_deg`.
//!
//! Rotation at a constant rate about the vertical (a turntable) keeps every window mean
//! constant and passes; it adds a constant to the gyro, which the Allan variance ignores.

use super::AllanError;
use preint::ImuSample;

/// Thresholds of [`StillnessMonitor`] (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StillnessOptions {
    /// Window length \[s\] (1).
    pub window_s: f64,
    /// Largest difference of consecutive window means, in standard errors (10).
    pub max_z: f64,
    /// Smallest fraction of still windows of a static recording (0.9).
    pub min_still_fraction: f64,
    /// Largest turn of the gravity direction from the first window's \[deg\] (2).
    pub max_tilt_deg: f64,
}

impl Default for StillnessOptions {
    fn default() -> Self {
        Self {
            window_s: 1.0,
            max_z: 10.0,
            min_still_fraction: 0.9,
            max_tilt_deg: 2.0,
        }
    }
}

/// Smallest per-sample standard deviation used in the z test: gyro \[rad/s\], accelerometer
/// \[m/s²\] (module docs).
const SD_FLOOR: [f64; 6] = [1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3];

/// Running sums of the current window (values relative to its first sample).
#[derive(Clone, Copy, Debug, Default)]
struct Window {
    t_start_ns: i64,
    n: usize,
    reference: [f64; 6],
    s1: [f64; 6],
    s2: [f64; 6],
}

/// Mean and variance of a closed window.
#[derive(Clone, Copy, Debug)]
struct Summary {
    n: f64,
    mean: [f64; 6],
    var: [f64; 6],
}

impl Window {
    fn summary(&self) -> Summary {
        let n = self.n as f64;
        Summary {
            n,
            mean: std::array::from_fn(|c| self.reference[c] + self.s1[c] / n),
            var: std::array::from_fn(|c| {
                ((self.s2[c] - self.s1[c] * self.s1[c] / n) / (n - 1.0))
                    .max(SD_FLOOR[c] * SD_FLOOR[c])
            }),
        }
    }
}

/// What [`StillnessMonitor`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stillness {
    /// Windows compared with their predecessor.
    pub windows: u64,
    /// Of those, the still ones.
    pub still_windows: u64,
    /// Start of the first moving window, seconds from the first sample.
    pub first_motion_s: Option<f64>,
    /// Largest turn of the gravity direction from the first window's \[deg\].
    pub max_tilt_deg: f64,
    /// When it was reached, seconds from the first sample.
    pub max_tilt_at_s: f64,
}

impl Stillness {
    /// Fraction of the compared windows that are still (1 when none was compared).
    pub fn still_fraction(&self) -> f64 {
        if self.windows == 0 {
            1.0
        } else {
            self.still_windows as f64 / self.windows as f64
        }
    }

    /// `Ok` for a static recording, otherwise [`AllanError::NotStatic`] saying why (module
    /// docs).
    pub fn verdict(&self, opts: &StillnessOptions) -> Result<(), AllanError> {
        let frac = self.still_fraction();
        if frac >= opts.min_still_fraction && self.max_tilt_deg <= opts.max_tilt_deg {
            return Ok(());
        }
        let motion = self.first_motion_s.map_or(String::new(), |t| {
            format!(", the first moving one at {t:.1} s")
        });
        Err(AllanError::NotStatic(format!(
            "the recording is not static: {:.1} % of its {} windows of {} s are still (a static \
             recording needs {:.0} %; a window is still when its mean readings agree with the \
             previous window's within {} standard errors on every axis){motion}; the gravity \
             direction turns by up to {:.2}° (at {:.1} s; at most {}° at rest). The Allan \
             deviation of a moving recording describes the motion, not the sensor's noise: \
             record the sensor at rest, or keep only its still part",
            100.0 * frac,
            self.windows,
            opts.window_s,
            100.0 * opts.min_still_fraction,
            opts.max_z,
            self.max_tilt_deg,
            self.max_tilt_at_s,
            opts.max_tilt_deg
        )))
    }
}

/// Streamed stillness check (module docs): push every sample, then [`StillnessMonitor::finish`].
///
/// ```
/// use nalgebra::Vector3;
/// use preint::ImuSample;
/// use preint_calib::allan::{StillnessMonitor, StillnessOptions};
///
/// // 20 s at 100 Hz at rest, then 10 s turning about x at 0.5 rad/s (gravity tilts).
/// let mut m = StillnessMonitor::new(StillnessOptions::default());
/// for k in 0..3000i64 {
///     let t = k as f64 * 0.01;
///     let wiggle = 1e-3 * ((k * 7919 % 13) as f64 - 6.0); // deterministic "noise"
///     let angle = if t < 20.0 { 0.0 } else { 0.5 * (t - 20.0) };
///     let acc = Vector3::new(0.0, 9.81 * angle.sin(), 9.81 * angle.cos()).add_scalar(wiggle);
///     let w = if t < 20.0 { 0.0 } else { 0.5 };
///     m.push(&ImuSample { t_ns: k * 10_000_000, gyro: Vector3::new(w + wiggle, wiggle, 0.0), acc });
/// }
/// let s = m.finish();
/// assert_eq!(s.windows, 28); // 29 closed windows, each compared with its predecessor
/// assert_eq!(s.still_windows, 19);
/// assert_eq!(s.first_motion_s, Some(20.0));
/// assert!(s.verdict(&StillnessOptions::default()).is_err());
/// ```
#[derive(Clone, Debug)]
pub struct StillnessMonitor {
    opts: StillnessOptions,
    window_ns: i64,
    t0_ns: Option<i64>,
    cur: Window,
    prev: Option<Summary>,
    first_up: Option<[f64; 3]>,
    result: Stillness,
}

impl StillnessMonitor {
    /// A monitor with thresholds `opts`.
    pub fn new(opts: StillnessOptions) -> Self {
        Self {
            opts,
            window_ns: (opts.window_s * 1e9).round() as i64,
            t0_ns: None,
            cur: Window::default(),
            prev: None,
            first_up: None,
            result: Stillness {
                windows: 0,
                still_windows: 0,
                first_motion_s: None,
                max_tilt_deg: 0.0,
                max_tilt_at_s: 0.0,
            },
        }
    }

    /// Adds the next sample (time-ordered; values finite).
    pub fn push(&mut self, s: &ImuSample) {
        let t0 = *self.t0_ns.get_or_insert(s.t_ns);
        if self.cur.n >= 5 && s.t_ns - self.cur.t_start_ns >= self.window_ns {
            self.close(t0);
        }
        let v = [s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z];
        let w = &mut self.cur;
        if w.n == 0 {
            w.t_start_ns = s.t_ns;
            w.reference = v;
        }
        w.n += 1;
        for (c, x) in v.iter().enumerate() {
            let d = x - w.reference[c];
            w.s1[c] += d;
            w.s2[c] += d * d;
        }
    }

    /// Closes the current window: compares it with the previous one and measures the tilt.
    fn close(&mut self, t0_ns: i64) {
        let sum = self.cur.summary();
        let t_s = (self.cur.t_start_ns - t0_ns) as f64 * 1e-9;
        if let Some(p) = &self.prev {
            let still = (0..6).all(|c| {
                let se = (sum.var[c] / sum.n + p.var[c] / p.n).sqrt();
                (sum.mean[c] - p.mean[c]).abs() <= self.opts.max_z * se
            });
            self.result.windows += 1;
            if still {
                self.result.still_windows += 1;
            } else if self.result.first_motion_s.is_none() {
                self.result.first_motion_s = Some(t_s);
            }
        }
        let a = [sum.mean[3], sum.mean[4], sum.mean[5]];
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        if norm > 0.0 {
            let up = a.map(|x| x / norm);
            let first = *self.first_up.get_or_insert(up);
            let cos = (up[0] * first[0] + up[1] * first[1] + up[2] * first[2]).clamp(-1.0, 1.0);
            let tilt = cos.acos().to_degrees();
            if tilt > self.result.max_tilt_deg {
                self.result.max_tilt_deg = tilt;
                self.result.max_tilt_at_s = t_s;
            }
        }
        self.prev = Some(sum);
        self.cur = Window::default();
    }

    /// The result over the closed windows (a last, shorter window is left out).
    pub fn finish(self) -> Stillness {
        self.result
    }
}
