//! The alternative readings of a source's units (module docs, "Passed or inconclusive"),
//! check 5 on each, and the verdict's reasons.

use super::scale::{
    DECISIVE_RATIO, MIN_PAIRS, MISFIT_REFUSED_RAD, TiltPair, median_misfit, median_turn, tilt_pairs,
};
use super::{MIN_STILL_WINDOWS, StillGyro, UnitVerdict};
use crate::units::{GyroUnit, TimeUnit, Units};
use preint::ImuSample;

/// Intervals \[ns\] at which an IMU may sample (1 Hz to 50 kHz): an alternative time unit
/// that gives another interval is excluded.
const IMU_INTERVAL_NS: std::ops::RangeInclusive<f64> = 20_000.0..=1e9;

/// Smallest median turn of the gravity direction between the pairs \[rad\] (2°) for check 5
/// to exclude an alternative (module docs).
const MIN_TURN_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// A reading of the source other than as read: the true timestamps are `time` times those
/// read, the true rates `gyro` times those read; the units they correspond to, when the
/// units read are known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Alternative {
    pub(crate) time: f64,
    pub(crate) gyro: f64,
    time_unit: Option<TimeUnit>,
    gyro_unit: Option<GyroUnit>,
}

impl Alternative {
    /// The scale of the gyro's integral under this reading.
    fn scale(&self) -> f64 {
        self.time * self.gyro
    }

    /// What this reading changes, e.g. `timestamps in s, gyro in deg/s`.
    fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.time != 1.0 {
            parts.push(match self.time_unit {
                Some(u) => format!("timestamps in {u}"),
                None => format!("timestamps ×{:e}", self.time),
            });
        }
        if self.gyro != 1.0 {
            parts.push(match self.gyro_unit {
                Some(u) => format!("gyro in {u}"),
                None => format!("gyro ×{}", scale_name(self.gyro)),
            });
        }
        parts.join(", ")
    }

    /// The flags that read the source this way.
    fn fix(&self) -> String {
        let mut parts = Vec::new();
        if self.time != 1.0 {
            parts.push(match self.time_unit {
                Some(u) => format!("the timestamps look like {u}: set --time-unit {u}"),
                None => format!(
                    "the timestamps look {:e} times too {}: set --time-unit",
                    self.time.max(1.0 / self.time),
                    if self.time > 1.0 { "small" } else { "large" }
                ),
            });
        }
        if self.gyro != 1.0 {
            parts.push(if self.gyro < 1.0 {
                "the gyro looks like deg/s: set --gyro-unit deg/s".to_string()
            } else {
                "the gyro looks like rad/s, not deg/s: set --gyro-unit rad/s".to_string()
            });
        }
        parts.join("; ")
    }
}

fn scale_name(s: f64) -> &'static str {
    if s < 1.0 { "π/180" } else { "180/π" }
}

/// Factors from the values as read to the true ones, with the unit they stand for (`None`
/// when the units read are unknown).
type Factors<U> = Vec<(f64, Option<U>)>;

/// The time factors and units other than as read, and the gyro factors and units.
fn options(read_as: Option<Units>) -> (Factors<TimeUnit>, Factors<GyroUnit>) {
    let deg = std::f64::consts::PI / 180.0;
    match read_as {
        Some(u) => {
            let times = [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us, TimeUnit::Ns]
                .into_iter()
                .filter(|&v| v != u.time)
                .map(|v| {
                    let e = v.to_ns_exponent() - u.time.to_ns_exponent();
                    (10f64.powi(e), Some(v))
                })
                .collect();
            let other = match u.gyro {
                GyroUnit::RadPerS => GyroUnit::DegPerS,
                GyroUnit::DegPerS => GyroUnit::RadPerS,
            };
            let g = other.to_rad_per_s() / u.gyro.to_rad_per_s();
            (times, vec![(g, Some(other))])
        }
        None => (
            [-9, -6, -3, 3, 6, 9]
                .map(|e| (10f64.powi(e), None))
                .to_vec(),
            vec![(deg, None), (1.0 / deg, None)],
        ),
    }
}

/// Every alternative reading of `read_as` (`None`: unknown units) whose interval, from the
/// median `dt_ns` as read, is an IMU's.
pub(crate) fn candidates(read_as: Option<Units>, dt_ns: f64) -> Vec<Alternative> {
    let (times, gyros) = options(read_as);
    let times: Factors<TimeUnit> = std::iter::once((1.0, None))
        .chain(
            times
                .into_iter()
                .filter(|(k, _)| IMU_INTERVAL_NS.contains(&(dt_ns * k))),
        )
        .collect();
    let mut out = Vec::new();
    for &(time, time_unit) in &times {
        for &(gyro, gyro_unit) in std::iter::once(&(1.0, None)).chain(&gyros) {
            if time != 1.0 || gyro != 1.0 {
                out.push(Alternative {
                    time,
                    gyro,
                    time_unit,
                    gyro_unit,
                });
            }
        }
    }
    out
}

/// The time units under which the median interval `dt_ns`, refused as read, is an IMU's:
/// `; as us it is 5 ms (200 Hz)` (empty when the units read are unknown or none fits).
pub(crate) fn interval_hint(read_as: Option<Units>, dt_ns: f64) -> String {
    let Some(u) = read_as else {
        return String::new();
    };
    let fits: Vec<String> = options(Some(u))
        .0
        .into_iter()
        .filter(|(k, _)| IMU_INTERVAL_NS.contains(&(dt_ns * k)))
        .filter_map(|(k, v)| {
            let dt = dt_ns * k;
            Some(format!(
                "as {} it is {} s ({:.4} Hz)",
                v?,
                dt * 1e-9,
                1e9 / dt
            ))
        })
        .collect();
    if fits.is_empty() {
        String::new()
    } else {
        format!("; read as {}: {}", u.time, fits.join(", "))
    }
}

/// Check 5 on the pairs found with the interval as read: the misfit as read and each
/// alternative's.
#[derive(Clone, Debug)]
struct AsRead {
    pairs: usize,
    turn: f64,
    misfit: f64,
    alternatives: Vec<(Alternative, f64)>,
}

/// Check 5 over every candidate reading.
#[derive(Clone, Debug)]
pub(crate) struct Fit {
    /// On the pairs of the interval as read; `None` with fewer than [`MIN_PAIRS`].
    as_read: Option<AsRead>,
    /// Pairs found with the interval as read.
    pairs: usize,
    /// The best alternative that explains the data where the reading as read does not:
    /// (alternative, its misfit, the misfit as read, pairs) \[rad\].
    better: Option<(Alternative, f64, f64, usize)>,
}

impl Fit {
    /// Fits every candidate: on the pairs of the interval as read, and each alternative time
    /// unit on the pairs of its own interval.
    pub(crate) fn of(samples: &[ImuSample], dt: f64, candidates: &[Alternative]) -> Self {
        let mut better: Option<(Alternative, f64, f64, usize)> = None;
        let mut consider = |pairs: &[TiltPair], alts: &mut dyn Iterator<Item = &Alternative>| {
            let one = median_misfit(pairs, 1.0);
            let mut scored = Vec::new();
            for a in alts {
                let m = median_misfit(pairs, a.scale());
                if one > MISFIT_REFUSED_RAD
                    && m < one / DECISIVE_RATIO
                    && better.is_none_or(|b| m / one < b.1 / b.2)
                {
                    better = Some((*a, m, one, pairs.len()));
                }
                scored.push((*a, m));
            }
            (one, scored)
        };
        let p1 = tilt_pairs(samples, dt);
        let as_read = (p1.len() >= MIN_PAIRS).then(|| {
            let (misfit, alternatives) = consider(&p1, &mut candidates.iter());
            AsRead {
                pairs: p1.len(),
                turn: median_turn(&p1),
                misfit,
                alternatives,
            }
        });
        let mut times: Vec<f64> = candidates.iter().map(|a| a.time).collect();
        times.dedup();
        for k in times.into_iter().filter(|&k| k != 1.0) {
            let pk = tilt_pairs(samples, dt * k);
            if pk.len() >= MIN_PAIRS {
                consider(&pk, &mut candidates.iter().filter(|a| a.time == k));
            }
        }
        Self {
            as_read,
            pairs: p1.len(),
            better,
        }
    }

    /// The error message when an alternative explains the turning of gravity and the
    /// reading as read does not.
    pub(crate) fn refusal(&self) -> Option<String> {
        let (a, m, one, pairs) = self.better?;
        Some(format!(
            "the gyro does not explain how the accelerometer's gravity direction turns: over \
             {pairs} pairs of quasi-static moments 1 s apart it misses by {:.1}° (median) as \
             read, by {:.1}° with the {}; {} (or --no-unit-check)",
            one.to_degrees(),
            m.to_degrees(),
            a.describe(),
            a.fix()
        ))
    }

    /// Whether check 5 excludes `a`: gravity turns by at least 2° and 3 times the misfit as
    /// read, which is below 10°, and `a` misses by at least 3 times as much.
    pub(crate) fn excludes(&self, a: &Alternative) -> bool {
        let Some(r) = &self.as_read else {
            return false;
        };
        r.misfit < MISFIT_REFUSED_RAD
            && r.turn >= MIN_TURN_RAD.max(DECISIVE_RATIO * r.misfit)
            && (r.alternatives.iter()).any(|(b, m)| b == a && *m >= DECISIVE_RATIO * r.misfit)
    }

    /// Why check 5 did not exclude what is left.
    fn status(&self) -> String {
        match &self.as_read {
            None => format!(
                "too few quasi-static moments to compare the gyro with the turning of gravity \
                 ({} pairs 1 s apart, {MIN_PAIRS} needed)",
                self.pairs
            ),
            Some(r) if r.misfit >= MISFIT_REFUSED_RAD => format!(
                "no scale of the gyro's integral explains how the gravity direction turns \
                 between quasi-static moments (the gyro as read missing by {:.1}° over {} pairs, \
                 gravity turning by {:.1}°: the accelerometer does not see gravity alone there)",
                r.misfit.to_degrees(),
                r.pairs,
                r.turn.to_degrees()
            ),
            Some(r) => format!(
                "the gravity direction turns too little between quasi-static moments to tell \
                 the scales of the gyro's integral apart (median {:.1}° over {} pairs 1 s \
                 apart, the gyro as read missing by {:.1}°)",
                r.turn.to_degrees(),
                r.pairs,
                r.misfit.to_degrees()
            ),
        }
    }
}

/// The verdict once the alternatives `open` are all that no check excluded.
pub(crate) fn verdict(
    open: &[&Alternative],
    read_as: Option<Units>,
    dt_ns: f64,
    still: &StillGyro,
    fit: &Fit,
) -> UnitVerdict {
    let mut why = Vec::new();
    let mut times: Vec<&Alternative> = open.iter().copied().filter(|a| a.time != 1.0).collect();
    times.dedup_by(|a, b| a.time == b.time);
    if !times.is_empty() {
        let read = read_as.map_or(String::new(), |u| format!(" (read as {})", u.time));
        let other: Vec<String> = times
            .iter()
            .map(|a| {
                let dt = dt_ns * a.time;
                let unit = a
                    .time_unit
                    .map_or(format!("×{:e}", a.time), |u| format!("in {u}"));
                format!("{unit} {} s ({:.4} Hz)", dt * 1e-9, 1e9 / dt)
            })
            .collect();
        why.push(format!(
            "time unit: the median interval of {} s{read} would be {}, also an IMU's rate, and \
             {}",
            dt_ns * 1e-9,
            other.join(" or "),
            fit.status()
        ));
    }
    if open.iter().any(|a| a.gyro != 1.0) {
        let (read, other) = match read_as.map(|u| u.gyro) {
            Some(GyroUnit::RadPerS) => ("rad/s", "deg/s"),
            Some(GyroUnit::DegPerS) => ("deg/s", "rad/s"),
            None => ("the gyro's unit", "its scale by π/180 or 180/π"),
        };
        let still = match still.across {
            None => "no still part".to_string(),
            Some(_) if still.windows < MIN_STILL_WINDOWS => format!(
                "{} still 0.5 s window{} ({MIN_STILL_WINDOWS} needed)",
                still.windows,
                if still.windows == 1 { "" } else { "s" }
            ),
            Some(w) => format!(
                "the still gyro's {w:.4} rad/s across the vertical would be a plausible bias \
                 in {other} too"
            ),
        };
        why.push(format!(
            "gyro unit: {read} not told from {other}: {still}, and {}",
            fit.status()
        ));
    }
    if why.is_empty() {
        UnitVerdict::Passed
    } else {
        UnitVerdict::Inconclusive(why)
    }
}
