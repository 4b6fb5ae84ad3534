//! Are these readings plausible for an IMU on Earth in the units they were read as? Checks
//! that catch data in g, deg/s or the wrong time unit before it gives a confident wrong answer,
//! and say when they cannot tell.
//!
//! [`check_units_read_as`] runs, in order (each failure is an [`IoError::Units`] naming the
//! flag that fixes it):
//! 1. **Time unit.** The median sample interval must lie in [20 µs, 10 s] (50 kHz to 0.1 Hz):
//!    milliseconds read as nanoseconds give ≈ 5 ns, microseconds ≈ 5 µs.
//! 2. **Accelerometer unit.** The median accelerometer norm must lie in [4, 20] m/s² (specific
//!    force near the Earth's surface; data in g reads ≈ 1).
//! 3. **Gyroscope, moving.** The median gyro norm must stay below 20 rad/s (data in deg/s of a
//!    moving IMU reads tens to hundreds).
//!    A gyro that reads exactly zero on every sample (≥ 100) while the accelerometer varies is
//!    no gyroscope (an accelerometer-only topic, a wrong column): no real gyro is noise-free.
//!    (Noise-free simulated data at rest, with a constant accelerometer, passes.)
//! 4. **Gyroscope, still.** Over the windows where the accelerometer is steady
//!    ([`still_windows`], whose two halves also agree within 0.1 m/s²: decided from the
//!    accelerometer only, so the gyro's unit does not matter), the gyro's mean reading across
//!    the gravity direction must stay below
//!    [`MAX_STILL_GYRO_RAD_S`] = 0.1 rad/s (median over at least 4 windows), and below
//!    [`MAX_STEADY_TURN_RAD_S`] = 1 rad/s over any number of them. A steady accelerometer
//!    means the body turns at most about the vertical (any turn about a horizontal axis tilts
//!    gravity in the body frame), so what the gyro reads across the vertical is its bias:
//!    MEMS gyro biases are a few mrad/s to a few tens of mrad/s, while a bias in deg/s read as
//!    rad/s is 57× larger (0.4 deg/s → 0.4 "rad/s"). A turn at 1 rad/s about a horizontal
//!    axis tilts gravity by 29° in a 0.5 s window, which no steady accelerometer shows, so
//!    one window is enough at that level. Steady turning about the vertical (a turntable)
//!    passes.
//! 5. **Gyroscope and timestamps against gravity.** On moving data, the gyro's integral must
//!    explain how the gravity direction seen by the accelerometer turns between quasi-static
//!    moments 1 s apart ([`scale`]). A gyro misread by π/180 and timestamps misread by a
//!    power of 1000 both scale that integral; each alternative reading of the source's units
//!    (the other gyro unit, the other time units whose interval is an IMU's, below) is fitted
//!    on windows sized for its own interval. If the reading as read misses by more than 10°
//!    (median) while an alternative misses by less than a third of that, the data is refused
//!    with the flags of the alternative (`--gyro-unit`, `--time-unit`). The accelerometer sees
//!    gravity only where the sensor is not accelerating; where no scale explains the data (a
//!    multirotor's accelerometer follows its thrust axis), the misfits are all small or all
//!    large, and the check is silent.
//!
//! 7. **Gyroscope axes against the accelerometer's.** Between quasi-static moments where
//!    gravity turns, the gyro's rotation must turn the accelerometer's gravity direction as
//!    it does; if another of the 48 signed permutations of the gyro's axes explains the turns
//!    far better (an axis inverted, two swapped, a left-handed frame), the data is refused
//!    naming that map ([`axes`]). Motion that does not turn gravity about every axis cannot
//!    tell, and the check is silent.
//!
//! # Passed or inconclusive
//! Passing checks 1–5 does not always confirm the units: a still recording at 10 Hz in
//! seconds would pass as 10 kHz in milliseconds too. So the checks also ask, for each
//! alternative reading of the units declared ([`crate::Units`]: the other gyro unit, each
//! other time unit), whether something excludes it:
//! - a time unit whose interval would not be an IMU's: outside [20 µs, 1 s] (50 kHz to 1 Hz;
//!   200 Hz in ns would be 0.2 Hz in µs or 200 kHz in ms, so it is decided by its rate alone);
//! - a gyro unit under which the still gyro would break check 4 or the moving one check 3
//!   (data declared deg/s whose bias would exceed 0.1 rad/s as rad/s);
//! - a gyro in deg/s read as rad/s, by check 4 having its 4 still windows. This takes the
//!   gyro's bias to be a MEMS gyro's, 0.1 °/s or more: a better gyro's bias in deg/s read
//!   as rad/s stays under 0.1 "rad/s" and passes unnoticed;
//! - either, by check 5 on at least 10 pairs whose gravity direction turns by at least 2°
//!   and 3 times the misfit as read (median): the reading as read misses by less than 10°
//!   and the alternative by at least 3 times as much. (On a still recording the misfits
//!   measure the gyro's bias drift, which shorter timestamps always shrink; they say
//!   nothing of the units there.)
//!
//! The accelerometer's unit is always decided (g and m/s² differ by 9.8, the band of check 2
//! by 5). When every alternative is excluded the verdict is [`UnitVerdict::Passed`];
//! otherwise [`UnitVerdict::Inconclusive`] says, per unit left open, what is missing (a still
//! part, quasi-static moments, enough turning of gravity). A recording too short for the
//! still windows (2 s) and the pairs is inconclusive in the gyro, whatever its rate.
//!
//! Beside the unit checks, [`limits`] refuses single readings beyond any IMU's range.

pub mod axes;
pub mod limits;
pub mod scale;

mod alternatives;

use crate::error::IoError;
use crate::units::Units;
use nalgebra::Vector3;
use preint::ImuSample;
pub use scale::{GYRO_SCALES, GyroScaleFit, gyro_scale_fit};

/// Largest median gyro norm \[rad/s\] accepted while the accelerometer shows the sensor still
/// (over at least [`MIN_STILL_WINDOWS`] windows).
pub const MAX_STILL_GYRO_RAD_S: f64 = 0.1;

/// Largest gyro norm across the vertical \[rad/s\] accepted over any still window (module
/// docs, check 4).
pub const MAX_STEADY_TURN_RAD_S: f64 = 1.0;

/// Gravity magnitude used to recognise still and quasi-static windows \[m/s²\].
const G: f64 = 9.81;

/// Median sample interval accepted as read \[ns\]: 20 µs to 10 s.
const INTERVAL_NS: std::ops::RangeInclusive<f64> = 20_000.0..=1e10;

/// What the unit checks established about samples that passed them (a failure is an error).
#[derive(Clone, Debug, PartialEq)]
pub enum UnitVerdict {
    /// Every alternative reading of the time and gyro units was excluded (module docs).
    Passed,
    /// Nothing contradicts the units as read, but some alternative could not be excluded: one
    /// reason per unit left open, saying what was missing.
    Inconclusive(Vec<String>),
}

impl UnitVerdict {
    /// Whether every alternative was excluded.
    pub fn passed(&self) -> bool {
        matches!(self, UnitVerdict::Passed)
    }

    /// `passed` or `inconclusive`.
    pub fn name(&self) -> &'static str {
        match self {
            UnitVerdict::Passed => "passed",
            UnitVerdict::Inconclusive(_) => "inconclusive",
        }
    }

    /// Why the checks could not decide (reasons joined by `; `), or `None` when they passed.
    pub fn why(&self) -> Option<String> {
        match self {
            UnitVerdict::Passed => None,
            UnitVerdict::Inconclusive(r) => Some(r.join("; ")),
        }
    }
}

/// [`check_units_read_as`] for samples whose source units are not known: every other time
/// unit and both gyro scales (π/180, 180/π) are the alternatives.
pub fn check_units(samples: &[ImuSample], source_name: &str) -> Result<UnitVerdict, IoError> {
    check_units_read_as(samples, source_name, None)
}

/// Runs the checks of the module docs on `samples` (time-ordered, distinct stamps), read from
/// `source_name` in the units `read_as` (`None`: unknown). An error names the source and
/// the flag that fixes it; a pass says whether the units were confirmed.
pub fn check_units_read_as(
    samples: &[ImuSample],
    source_name: &str,
    read_as: Option<Units>,
) -> Result<UnitVerdict, IoError> {
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    match samples.len() {
        0 => {
            return Err(IoError::Empty {
                source_name: source_name.to_string(),
            });
        }
        1 => {
            return Ok(UnitVerdict::Inconclusive(vec![
                "one sample: no interval to judge the time unit by, and no stillness or motion \
                 to judge the gyro's"
                    .into(),
            ]));
        }
        _ => {}
    }
    let dt_ns = median_interval_ns(samples);
    if !INTERVAL_NS.contains(&dt_ns) {
        return Err(units(format!(
            "the median sample interval is {dt_ns} ns ({:.4e} Hz); expected 20 µs to 10 s. If the \
             timestamps are not in the unit they were read as, set --time-unit (s, ms, us, ns){}",
            1e9 / dt_ns,
            alternatives::interval_hint(read_as, dt_ns)
        )));
    }
    check_si_units(samples, source_name)?;
    let dt = dt_ns * 1e-9;
    let still = StillGyro::of(samples, dt);
    if let Some(msg) = still.refusal(read_as) {
        return Err(units(msg));
    }
    let gyro_median = median(samples.iter().map(|s| s.gyro.norm()).collect());
    let candidates = alternatives::candidates(read_as, dt_ns);
    let fit = alternatives::Fit::of(samples, dt, &candidates);
    if let Some(msg) = fit.refusal() {
        return Err(units(msg));
    }
    if let Some(axes::AxisVerdict::Mismatch(msg)) =
        axes::gyro_axes_fit(samples, dt).map(|f| f.verdict())
    {
        return Err(units(format!(
            "{msg}: fix the gyro's column order (--columns) or its signs, or --no-unit-check"
        )));
    }
    let open: Vec<&alternatives::Alternative> = candidates
        .iter()
        .filter(|a| !fit.excludes(a) && !still.excludes(a.gyro) && gyro_median * a.gyro <= 20.0)
        .collect();
    Ok(alternatives::verdict(&open, read_as, dt_ns, &still, &fit))
}

/// Median interval between consecutive samples \[ns\].
pub fn median_interval_ns(samples: &[ImuSample]) -> f64 {
    let mut d: Vec<i64> = samples.windows(2).map(|w| w[1].t_ns - w[0].t_ns).collect();
    let mid = d.len() / 2;
    *d.select_nth_unstable(mid).1 as f64
}

/// Checks that IMU samples look like SI units for an IMU near the Earth's surface: the median
/// accelerometer norm must lie in [4, 20] m/s² (data in g reads ≈ 1) and the median gyro norm
/// below 20 rad/s (data in deg/s of a moving IMU reads tens to hundreds).
pub fn check_si_units(samples: &[ImuSample], source_name: &str) -> Result<(), IoError> {
    if samples.is_empty() {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    }
    let acc = median(samples.iter().map(|s| s.acc.norm()).collect());
    let gyro = median(samples.iter().map(|s| s.gyro.norm()).collect());
    let units = |msg: String| IoError::Units {
        source_name: source_name.to_string(),
        msg,
    };
    if let Some(msg) = accel_norm_verdict(acc).or_else(|| gyro_norm_verdict(gyro)) {
        return Err(units(msg));
    }
    let first_acc = samples[0].acc;
    if samples.len() >= MIN_SAMPLES_FOR_ZERO_GYRO
        && samples.iter().all(|s| s.gyro == Vector3::zeros())
        && samples.iter().any(|s| s.acc != first_acc)
    {
        return Err(units(format!(
            "the gyro reads exactly 0 on all {} samples while the accelerometer varies: this \
             is not a gyroscope channel (an accelerometer-only topic, or the wrong --columns?)",
            samples.len()
        )));
    }
    Ok(())
}

/// The error message if a median accelerometer norm `acc` (as read) is not in [4, 20] m/s².
pub fn accel_norm_verdict(acc: f64) -> Option<String> {
    (!(4.0..=20.0).contains(&acc)).then(|| {
        format!(
            "median accelerometer norm is {acc:.4}; expected about 9.81 m/s² (specific force). \
             If the data is in g, set --accel-unit g"
        )
    })
}

/// The error message if a median gyro norm `gyro` (as read) exceeds 20 rad/s.
pub fn gyro_norm_verdict(gyro: f64) -> Option<String> {
    (gyro > 20.0).then(|| {
        format!(
            "median gyro norm is {gyro:.2}; expected rad/s. If the data is in deg/s, set \
             --gyro-unit deg/s"
        )
    })
}

/// Fewest samples for the zero-gyro check of [`check_si_units`] (and of a split recording's
/// gyro channel in the audit).
pub const MIN_SAMPLES_FOR_ZERO_GYRO: usize = 100;

fn median(mut v: Vec<f64>) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Mean and largest per-axis standard deviation of the accelerometer over `w`.
fn acc_stats(w: &[ImuSample]) -> (Vector3<f64>, f64) {
    let n = w.len() as f64;
    let mean = w.iter().map(|s| s.acc).sum::<Vector3<f64>>() / n;
    let var = w
        .iter()
        .map(|s| (s.acc - mean).component_mul(&(s.acc - mean)))
        .sum::<Vector3<f64>>()
        / n;
    (mean, var.max().sqrt())
}

/// Non-overlapping windows of about `seconds` (at least 5 samples) over `samples` sampled
/// every `dt` s.
fn windows(samples: &[ImuSample], dt: f64, seconds: f64) -> std::slice::Chunks<'_, ImuSample> {
    let n = ((seconds / dt).round() as usize).max(5);
    samples.chunks(n)
}

/// The windows of 0.5 s in which the sensor is still by its accelerometer: largest per-axis
/// standard deviation below 0.2 m/s² (a still MEMS accelerometer shows 0.01–0.05 m/s² per
/// sample at 100–200 Hz; any tilt of a few degrees or a push moves it by more) and mean norm
/// within 1 m/s² of g.
pub fn still_windows(samples: &[ImuSample], dt: f64) -> Vec<&[ImuSample]> {
    windows(samples, dt, 0.5)
        .filter(|w| {
            let (mean, sd) = acc_stats(w);
            sd < 0.2 && (mean.norm() - G).abs() < 1.0
        })
        .collect()
}

/// Fewest still windows (2 s) for the 0.1 rad/s bound across the vertical: a few windows of a
/// moving recording can look steady while it turns slowly.
pub const MIN_STILL_WINDOWS: usize = 4;

/// Largest difference \[m/s²\] between the accelerometer's means over the two halves of a
/// still window for check 4: a turn about a horizontal axis at ω tilts gravity by ω·0.25 s
/// between the halves' centres, so 0.1 m/s² bounds ω at 0.04 rad/s, below the 0.1 rad/s the
/// check allows. (A window's standard deviation below 0.2 m/s² alone admits a slow rocking
/// at 0.14 rad/s.)
const MAX_HALVES_DIFFERENCE_M_S2: f64 = 0.1;

/// Whether the accelerometer's means over the two halves of `w` agree (see
/// [`MAX_HALVES_DIFFERENCE_M_S2`]).
fn halves_agree(w: &[ImuSample]) -> bool {
    let (a, b) = w.split_at(w.len() / 2);
    let mean = |x: &[ImuSample]| x.iter().map(|s| s.acc).sum::<Vector3<f64>>() / x.len() as f64;
    (mean(a) - mean(b)).norm() < MAX_HALVES_DIFFERENCE_M_S2
}

/// The gyro across the vertical over the still windows (module docs, check 4).
#[derive(Clone, Copy, Debug)]
pub(crate) struct StillGyro {
    /// Number of still 0.5 s windows.
    pub(crate) windows: usize,
    /// Median over them of the gyro's mean reading across the gravity direction (the part
    /// perpendicular to the accelerometer's mean) \[rad/s, as read\]; `None` without any.
    pub(crate) across: Option<f64>,
}

impl StillGyro {
    fn of(samples: &[ImuSample], dt: f64) -> Self {
        let still = still_windows(samples, dt);
        let across: Vec<f64> = still
            .iter()
            .filter(|w| halves_agree(w))
            .map(|w| {
                let n = w.len() as f64;
                let gyro = w.iter().map(|s| s.gyro).sum::<Vector3<f64>>() / n;
                let up = (w.iter().map(|s| s.acc).sum::<Vector3<f64>>() / n).normalize();
                (gyro - up * gyro.dot(&up)).norm()
            })
            .collect();
        Self {
            windows: across.len(),
            across: (!across.is_empty()).then(|| median(across)),
        }
    }

    /// Whether check 4 excludes the gyro scaled by `gyro` (module docs): it would break
    /// check 4, or it is smaller than as read and check 4 had its windows.
    fn excludes(&self, gyro: f64) -> bool {
        (gyro < 1.0 && self.windows >= MIN_STILL_WINDOWS) || self.breaks(gyro)
    }

    /// Whether the gyro scaled by `gyro` would break check 4.
    fn breaks(&self, gyro: f64) -> bool {
        self.across.is_some_and(|w| {
            let w = w * gyro;
            w > MAX_STEADY_TURN_RAD_S
                || (self.windows >= MIN_STILL_WINDOWS && w > MAX_STILL_GYRO_RAD_S)
        })
    }

    /// The error message if the gyro as read breaks check 4.
    fn refusal(&self, read_as: Option<Units>) -> Option<String> {
        let w = self.across.filter(|_| self.breaks(1.0))?;
        let bound = if self.windows >= MIN_STILL_WINDOWS {
            format!("above {MAX_STILL_GYRO_RAD_S} rad/s for a MEMS bias")
        } else {
            format!(
                "above {MAX_STEADY_TURN_RAD_S} rad/s, which would tilt gravity by {:.0}° in each \
                 0.5 s window",
                (0.5 * w).to_degrees()
            )
        };
        let fix = match read_as.map(|u| u.gyro) {
            Some(crate::GyroUnit::DegPerS) => "it was read as deg/s already".to_string(),
            _ => "is it in deg/s (--gyro-unit deg/s)?".to_string(),
        };
        Some(format!(
            "while the accelerometer is steady (no turn about a horizontal axis; {} still 0.5 s \
             window{}), the gyro reads {w:.3} rad/s across the vertical (median), {bound}: \
             {fix} If this gyro's bias really is that large, pass --no-unit-check",
            self.windows,
            if self.windows == 1 { "" } else { "s" }
        ))
    }
}
