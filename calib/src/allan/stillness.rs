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
//! - **Bias random walk is not tilt.** Over hours the accelerometer bias walks (4 h at
//!   0.003 m/s³/√Hz: 0.36 m/s² per axis, 2° of apparent tilt). Two readings of the tilt tell
//!   a turn of the sensor from it:
//!   - the turn across the *moving* windows (`step_tilt_deg`: the changes of the gravity
//!     direction, a unit vector, summed as vectors over the transitions that fail the z test):
//!     a sensor set down in another attitude turns there, a bias walk (within the z test at
//!     every transition) does not, and the noise of a few moving windows adds only as a
//!     random walk (0.3° over 360 of them at 0.002 m/s²/√Hz);
//!   - the slow turn from the first window counts when its part across gravity,
//!     `|a₀|·sin(tilt)`, exceeds [`BIAS_WALK_RATIO`] = 8 times the largest change of the mean's
//!     norm `max_k ||a_k| − |a₀||`: a bias walk moves the mean along gravity as much as
//!     across it, turning the sensor moves it only across (the norm stays |g|). For an
//!     isotropic random walk the largest 2-axis excursion exceeds 8 times the largest 1-axis
//!     one in 5 of 100 000 walks (20 000 simulated walks of 2 000 steps: 0.0016 above 4,
//!     1e-3 above 6, 5e-5 above 8).
//! - **Verdict** ([`Stillness::verdict`]): static when at least `min_still_fraction` = 90 % of
//!   the compared windows are still and the tilt stays within `max_tilt_deg` (or is explained
//!   by the bias walk). A recording of fewer than two windows cannot be judged
//!   ([`AllanError::TooShort`]).
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

/// A turn of the gravity direction beyond `max_tilt_deg` counts as tilt only when its part
/// across gravity exceeds this many times the largest change of the accelerometer mean's norm
/// (module docs).
pub const BIAS_WALK_RATIO: f64 = 8.0;

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
    /// Largest change of the accelerometer window mean's norm from the first window's
    /// \[m/s²\]: the part of a bias walk along gravity.
    pub max_norm_change_ms2: f64,
    /// The first window's accelerometer mean norm \[m/s²\] (0 before a window closed).
    pub first_norm_ms2: f64,
    /// Turn of the gravity direction across the moving windows \[deg\]: the norm of the
    /// changes of its unit vector summed over the transitions that are not still (module docs).
    pub step_tilt_deg: f64,
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

    /// Whether the largest turn of the gravity direction is explained by the accelerometer
    /// bias walk rather than a turn of the sensor (module docs, [`BIAS_WALK_RATIO`]).
    pub fn tilt_is_bias_walk(&self) -> bool {
        let across = self.first_norm_ms2 * self.max_tilt_deg.to_radians().sin();
        across <= BIAS_WALK_RATIO * self.max_norm_change_ms2
    }

    /// Whether the gravity direction turned beyond `opts.max_tilt_deg` by a turn of the
    /// sensor, across the moving windows or slowly beyond what the bias walk explains.
    pub fn tilted(&self, opts: &StillnessOptions) -> bool {
        self.step_tilt_deg > opts.max_tilt_deg
            || (self.max_tilt_deg > opts.max_tilt_deg && !self.tilt_is_bias_walk())
    }

    /// `Ok` for a static recording, otherwise [`AllanError::NotStatic`] saying why (module
    /// docs), or [`AllanError::TooShort`] for fewer than two windows.
    pub fn verdict(&self, opts: &StillnessOptions) -> Result<(), AllanError> {
        if self.windows == 0 {
            return Err(AllanError::TooShort(format!(
                "too short to judge whether it is static: stillness compares consecutive \
                 windows of {} s, and the recording has fewer than two",
                opts.window_s
            )));
        }
        let frac = self.still_fraction();
        let still_enough = frac >= opts.min_still_fraction;
        let tilted = self.tilted(opts);
        if still_enough && !tilted {
            return Ok(());
        }
        let motion = self.first_motion_s.map_or(String::new(), |t| {
            format!(", the first moving one at {t:.1} s")
        });
        let windows = format!(
            "{:.1} % of its {} windows of {} s are still (a static recording needs {:.0} %; a \
             window is still when its mean readings agree with the previous window's within {} \
             standard errors on every axis){motion}",
            100.0 * frac,
            self.windows,
            opts.window_s,
            100.0 * opts.min_still_fraction,
            opts.max_z,
        );
        let tilt = format!(
            "the gravity direction turns by up to {:.2}° (at {:.1} s; at most {}° at rest), \
             {:.2}° of it across the moving windows, {:.3} m/s² across gravity while the norm \
             changes by at most {:.3} m/s² (a bias walk moves both alike)",
            self.max_tilt_deg,
            self.max_tilt_at_s,
            opts.max_tilt_deg,
            self.step_tilt_deg,
            self.first_norm_ms2 * self.max_tilt_deg.to_radians().sin(),
            self.max_norm_change_ms2,
        );
        let why = match (still_enough, tilted) {
            (false, true) => format!("{windows}, and {tilt}"),
            (false, false) => windows,
            _ => format!("it turned: {tilt}, although {windows}"),
        };
        Err(AllanError::NotStatic(format!(
            "the recording is not static: {why}. The Allan deviation of a moving recording \
             describes the motion, not the sensor's noise: record the sensor at rest, or keep \
             only its still part"
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
    /// Sum of the changes of the gravity direction over the moving transitions.
    step_turn: [f64; 3],
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
            step_turn: [0.0; 3],
            result: Stillness {
                windows: 0,
                still_windows: 0,
                first_motion_s: None,
                max_tilt_deg: 0.0,
                max_tilt_at_s: 0.0,
                max_norm_change_ms2: 0.0,
                first_norm_ms2: 0.0,
                step_tilt_deg: 0.0,
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
            } else {
                self.result.first_motion_s.get_or_insert(t_s);
                let (a, b) = (unit(&acc_mean(&p.mean)), unit(&acc_mean(&sum.mean)));
                for c in 0..3 {
                    self.step_turn[c] += b[c] - a[c];
                }
                let n = self.step_turn.iter().map(|x| x * x).sum::<f64>().sqrt();
                self.result.step_tilt_deg = (2.0 * (0.5 * n).min(1.0).asin()).to_degrees();
            }
        }
        let a = acc_mean(&sum.mean);
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        if norm > 0.0 && norm.is_finite() {
            let up = a.map(|x| x / norm);
            if self.first_up.is_none() {
                self.result.first_norm_ms2 = norm;
            }
            let change = (norm - self.result.first_norm_ms2).abs();
            self.result.max_norm_change_ms2 = self.result.max_norm_change_ms2.max(change);
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

/// The accelerometer part of a window mean.
fn acc_mean(mean: &[f64; 6]) -> [f64; 3] {
    [mean[3], mean[4], mean[5]]
}

/// `a` normalised (zero when `a` is zero or not finite).
fn unit(a: &[f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if n > 0.0 && n.is_finite() {
        a.map(|x| x / n)
    } else {
        [0.0; 3]
    }
}
