//! What the readings show, sample by sample in fixed memory: flat tops at an axis' extremes
//! (saturation, clipping) and the fraction of time the accelerometer is steady.

use crate::error::Location;
use nalgebra::Vector3;

/// A flat top is a run of at least this many consecutive equal readings at the axis' largest
/// or smallest value over the recording. Noise makes an unclipped extreme a single sample
/// (EuRoC, KITTI and the ADIS16405 hour in `tests/data` have no run of two at any extreme);
/// a sensor driven past its range repeats its limit. An extreme counts as clipped when at
/// least half of its samples are in flat tops ([`FlatTop::clipped`]): a signal whose noise
/// is below its resolution visits its extreme level often, mostly for one or two samples.
pub const MIN_FLAT_RUN: u64 = 3;

/// The six axes in the order of [`AxisReport`]s: gyro x, y, z \[rad/s\], accelerometer x, y, z
/// \[m/s²\].
pub const AXES: [(&str, &str); 6] = [
    ("gyro x", "rad/s"),
    ("gyro y", "rad/s"),
    ("gyro z", "rad/s"),
    ("acc x", "m/s2"),
    ("acc y", "m/s2"),
    ("acc z", "m/s2"),
];

/// Runs of at least [`MIN_FLAT_RUN`] equal readings at one extreme.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlatTop {
    /// Samples at the extreme, in runs of any length.
    pub total: u64,
    /// Samples in runs of at least [`MIN_FLAT_RUN`].
    pub samples: u64,
    /// Number of runs.
    pub runs: u64,
    /// Longest run.
    pub longest: u64,
    /// The first sample of the first run: index and location.
    pub first: Option<(u64, Location)>,
}

/// One axis: its extremes and the flat tops at them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisReport {
    /// Name (`gyro x` … `acc z`).
    pub name: &'static str,
    /// Unit of `max` and `min` (`rad/s`, `m/s2`).
    pub unit: &'static str,
    /// Largest reading.
    pub max: f64,
    /// Smallest reading.
    pub min: f64,
    /// Flat tops at `max`.
    pub at_max: FlatTop,
    /// Flat tops at `min`.
    pub at_min: FlatTop,
}

impl FlatTop {
    /// Flat tops hold at least half of the samples at the extreme.
    pub fn clipped(&self) -> bool {
        self.runs > 0 && 2 * self.samples >= self.total
    }
}

impl AxisReport {
    /// Every reading is the same value (a stuck axis, or a signal without noise).
    pub fn constant(&self) -> bool {
        self.max == self.min
    }

    /// Fraction of `samples` in flat tops at either extreme.
    pub fn flat_fraction(&self, samples: u64) -> f64 {
        let n = if self.constant() {
            self.at_max.samples
        } else {
            self.at_max.samples + self.at_min.samples
        };
        n as f64 / samples.max(1) as f64
    }
}

/// Tracks one axis: the current extremes, their flat tops, and the current run.
#[derive(Clone, Copy, Debug)]
struct Axis {
    report: AxisReport,
    run_value: f64,
    run_start: (u64, Location),
    run_len: u64,
}

impl Axis {
    fn new(k: usize, v: f64, index: u64, at: Location) -> Self {
        Self {
            report: AxisReport {
                name: AXES[k].0,
                unit: AXES[k].1,
                max: v,
                min: v,
                at_max: FlatTop {
                    total: 1,
                    ..FlatTop::default()
                },
                at_min: FlatTop {
                    total: 1,
                    ..FlatTop::default()
                },
            },
            run_value: v,
            run_start: (index, at),
            run_len: 1,
        }
    }

    fn push(&mut self, v: f64, index: u64, at: Location) {
        if v == self.run_value {
            self.run_len += 1;
        } else {
            self.close_run();
            (self.run_value, self.run_start, self.run_len) = (v, (index, at), 1);
        }
        // The extremes only widen: a run at today's extreme is at the final one unless a
        // later reading passes it, which resets that extreme's flat tops.
        let r = &mut self.report;
        if v > r.max {
            (r.max, r.at_max) = (v, FlatTop::default());
        }
        if v < r.min {
            (r.min, r.at_min) = (v, FlatTop::default());
        }
        r.at_max.total += u64::from(v == r.max);
        r.at_min.total += u64::from(v == r.min);
    }

    fn close_run(&mut self) {
        if self.run_len < MIN_FLAT_RUN {
            return;
        }
        let r = &mut self.report;
        for (extreme, top) in [(r.max, &mut r.at_max), (r.min, &mut r.at_min)] {
            if self.run_value == extreme {
                top.samples += self.run_len;
                top.runs += 1;
                top.longest = top.longest.max(self.run_len);
                top.first.get_or_insert(self.run_start);
            }
        }
    }

    fn finish(mut self) -> AxisReport {
        self.close_run();
        self.report
    }
}

/// Flat tops of the six axes (finite samples only).
#[derive(Clone, Debug, Default)]
pub struct FlatTops {
    axes: Option<[Axis; 6]>,
}

impl FlatTops {
    /// Adds the readings of sample `index` at `at`.
    pub fn push(&mut self, gyro: &Vector3<f64>, acc: &Vector3<f64>, index: u64, at: Location) {
        let v = [gyro.x, gyro.y, gyro.z, acc.x, acc.y, acc.z];
        match &mut self.axes {
            Some(axes) => {
                for (a, x) in axes.iter_mut().zip(v) {
                    a.push(x, index, at);
                }
            }
            None => self.axes = Some(std::array::from_fn(|k| Axis::new(k, v[k], index, at))),
        }
    }

    /// The six axes, if any sample was pushed.
    pub fn finish(self) -> Option<[AxisReport; 6]> {
        self.axes.map(|a| a.map(Axis::finish))
    }
}

/// Gravity magnitude of the still criterion \[m/s²\] (as in [`crate::plausibility`]).
const G: f64 = 9.81;

/// Consecutive windows of `window` samples (the last one possibly shorter, but at least 5) in which the
/// accelerometer is steady, by the criterion of [`crate::plausibility::still_windows`]:
/// largest per-axis standard deviation below 0.2 m/s² and mean norm within 1 m/s² of 9.81.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Still {
    /// Samples per window (0.5 s at the nominal rate, at least 5).
    pub window: u64,
    /// Number of windows.
    pub windows: u64,
    /// Number of still windows.
    pub still: u64,
}

impl Still {
    /// Fraction of the windows that are still.
    pub fn fraction(&self) -> f64 {
        self.still as f64 / self.windows.max(1) as f64
    }
}

/// Accumulates [`Still`] one accelerometer reading at a time.
#[derive(Clone, Debug)]
pub struct StillWindows {
    out: Still,
    n: u64,
    mean: Vector3<f64>,
    m2: Vector3<f64>,
}

impl StillWindows {
    /// Windows of 0.5 s at the interval `dt_ns` (at least 5 samples; 5 when unknown).
    pub fn new(dt_ns: Option<i64>) -> Self {
        let window = dt_ns.map_or(5, |dt| ((0.5e9 / dt as f64).round() as u64).max(5));
        Self {
            out: Still {
                window,
                windows: 0,
                still: 0,
            },
            n: 0,
            mean: Vector3::zeros(),
            m2: Vector3::zeros(),
        }
    }

    /// Adds one accelerometer reading \[m/s²\] (Welford's update per axis).
    pub fn push(&mut self, acc: &Vector3<f64>) {
        self.n += 1;
        let d = acc - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d.component_mul(&(acc - self.mean));
        if self.n == self.out.window {
            self.close();
        }
    }

    fn close(&mut self) {
        let sd = (self.m2.max() / self.n as f64).sqrt();
        self.out.windows += 1;
        if sd < 0.2 && (self.mean.norm() - G).abs() < 1.0 {
            self.out.still += 1;
        }
        (self.n, self.mean, self.m2) = (0, Vector3::zeros(), Vector3::zeros());
    }

    /// The windows so far, the last partial one included if it holds at least 5 samples
    /// (fewer say nothing of the accelerometer's spread).
    pub fn finish(mut self) -> Still {
        if self.n >= 5 {
            self.close();
        }
        self.out
    }
}
