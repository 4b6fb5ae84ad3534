//! Audit of a split recording: a gyro stream and an accelerometer stream with their own
//! stamps (RealSense: 200 Hz and 63 Hz). Each channel gets the timing audit of a single stream;
//! between them, the audit measures where each accelerometer stamp sits relative to the
//! nearest gyro stamp (a merge interpolates one channel onto the other's stamps) and how many
//! samples of either channel lie outside the other's span (a merge cannot use them). Each
//! channel's units are checked on its own (the median norm of its first readings).
//!
//! Both streams are read once, side by side in stamp order, in bounded memory.

use super::findings::{self, Finding, Severity};
use super::intervals::{EventList, Timing, TimingStats, reference_interval};
use super::{AuditOptions, BadRow, ErrorLog};
use crate::channel::{ChannelSample, ChannelStream, Sensor};
use crate::error::Location;

/// The audit of one channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelAudit {
    /// Which sensor.
    pub sensor: Sensor,
    /// Timing of its stamps.
    pub timing: Timing,
    /// Rows that could not be read.
    pub bad_rows: EventList<BadRow>,
    /// The error that ended reading early, if any.
    pub stopped: Option<String>,
    /// Readings that are not finite.
    pub non_finite: EventList<(u64, Location)>,
    /// Median norm of the readings over the first [`AuditOptions::prefix_samples`] (rad/s or
    /// m/s² as read), `None` without finite readings.
    pub median_norm: Option<f64>,
    /// Whether every reading of that prefix is exactly zero.
    pub all_zero: bool,
}

/// Accelerometer stamps against gyro stamps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Offsets {
    /// Accelerometer samples between two gyro stamps.
    pub count: u64,
    /// Mean of (accelerometer stamp − nearest gyro stamp) \[ns\].
    pub mean_ns: f64,
    /// Its standard deviation \[ns\].
    pub sd_ns: f64,
    /// Its smallest value \[ns\].
    pub min_ns: i64,
    /// Its largest value \[ns\].
    pub max_ns: i64,
    /// Accelerometer samples stamped exactly at a gyro stamp.
    pub coincident: u64,
    /// Accelerometer samples before the first gyro stamp.
    pub accel_before: u64,
    /// Accelerometer samples after the last gyro stamp.
    pub accel_after: u64,
    /// Gyro samples before the first accelerometer stamp.
    pub gyro_before: u64,
    /// Gyro samples after the last accelerometer stamp.
    pub gyro_after: u64,
    m2: f64,
}

impl Offsets {
    /// Adds the accelerometer stamp `t` between gyro stamps `prev` and `next`.
    fn push(&mut self, t: i64, prev: Option<i64>, next: Option<i64>) {
        let d = match (prev, next) {
            (None, None) => return,
            (None, Some(_)) => return self.accel_before += 1,
            (Some(_), None) => return self.accel_after += 1,
            (Some(p), Some(n)) if t.abs_diff(p) <= n.abs_diff(t) => t.saturating_sub(p),
            (Some(_), Some(n)) => t.saturating_sub(n),
        };
        if self.count == 0 {
            (self.min_ns, self.max_ns) = (d, d);
        }
        self.count += 1;
        self.coincident += u64::from(d == 0);
        (self.min_ns, self.max_ns) = (self.min_ns.min(d), self.max_ns.max(d));
        let delta = d as f64 - self.mean_ns;
        self.mean_ns += delta / self.count as f64;
        self.m2 += delta * (d as f64 - self.mean_ns);
        self.sd_ns = (self.m2 / self.count as f64).sqrt();
    }
}

/// The audit of a split recording.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitAudit {
    /// The recording's name.
    pub source: String,
    /// The gyro channel.
    pub gyro: ChannelAudit,
    /// The accelerometer channel.
    pub accel: ChannelAudit,
    /// Accelerometer stamps against gyro stamps.
    pub offsets: Offsets,
    /// The verdict: defects first.
    pub findings: Vec<Finding>,
}

impl SplitAudit {
    /// No defect was found.
    pub fn is_clean(&self) -> bool {
        self.findings.iter().all(|f| f.severity != Severity::Defect)
    }

    /// Clean, defects, or too short to judge.
    pub fn verdict(&self) -> findings::Verdict {
        findings::Verdict::of(&self.findings)
    }
}

/// One channel being audited: a prefix for the reference interval, then streaming.
struct ChannelAuditor {
    sensor: Sensor,
    opts: AuditOptions,
    samples: u64,
    prefix: Vec<(i64, Location)>,
    timing: Option<TimingStats>,
    errors: ErrorLog,
    non_finite: EventList<(u64, Location)>,
    /// Norms of the first `opts.prefix_samples` finite readings.
    norms: Vec<f64>,
}

impl ChannelAuditor {
    fn new(sensor: Sensor, opts: AuditOptions) -> Self {
        Self {
            sensor,
            opts,
            samples: 0,
            prefix: Vec::new(),
            timing: None,
            errors: ErrorLog::default(),
            non_finite: EventList::default(),
            norms: Vec::new(),
        }
    }

    fn push(&mut self, s: &ChannelSample) {
        let index = self.samples;
        self.samples += 1;
        if !s.value.iter().all(|v| v.is_finite()) {
            self.non_finite.push((index, s.at), self.opts.max_listed);
        } else if self.norms.len() < self.opts.prefix_samples {
            self.norms.push(s.value.norm());
        }
        match &mut self.timing {
            Some(t) => {
                t.push(index, s.at, s.t_ns);
            }
            None => {
                self.prefix.push((s.t_ns, s.at));
                if self.prefix.len() >= self.opts.prefix_samples {
                    self.start();
                }
            }
        }
    }

    fn start(&mut self) {
        let prefix = std::mem::take(&mut self.prefix);
        let reference = reference_interval(prefix.iter().map(|p| p.0));
        let mut t = TimingStats::new(reference, self.opts.max_listed);
        for (k, (ts, at)) in prefix.into_iter().enumerate() {
            t.push(k as u64, at, ts);
        }
        self.timing = Some(t);
    }

    /// The next sample's stamp from `it`, counting errors; `None` at the end or when an error
    /// ends reading.
    fn next(&mut self, it: &mut ChannelStream) -> Option<ChannelSample> {
        loop {
            match it.next()? {
                Ok(s) => {
                    self.push(&s);
                    return Some(s);
                }
                Err(e) => {
                    if !self.errors.push(&e, self.opts.max_listed) {
                        return None;
                    }
                }
            }
        }
    }

    fn finish(mut self) -> ChannelAudit {
        if self.timing.is_none() {
            self.start();
        }
        let all_zero = !self.norms.is_empty() && self.norms.iter().all(|&n| n == 0.0);
        let median_norm = (!self.norms.is_empty()).then(|| {
            let mid = self.norms.len() / 2;
            *self.norms.select_nth_unstable_by(mid, f64::total_cmp).1
        });
        ChannelAudit {
            median_norm,
            all_zero,
            sensor: self.sensor,
            timing: self.timing.take().expect("started above").finish(),
            bad_rows: self.errors.bad_rows,
            stopped: self.errors.stopped,
            non_finite: self.non_finite,
        }
    }
}

/// Audits a split recording named `source`: both channels, read side by side (see the module
/// docs).
pub fn audit_channels(
    mut gyro: ChannelStream,
    mut accel: ChannelStream,
    source: &str,
    opts: AuditOptions,
) -> SplitAudit {
    let mut g = ChannelAuditor::new(Sensor::Gyro, opts);
    let mut a = ChannelAuditor::new(Sensor::Accel, opts);
    let mut off = Offsets::default();
    let (mut g_prev, mut g_next, mut g_done) = (None::<i64>, None::<i64>, false);
    let mut last_accel = None;
    while let Some(s) = a.next(&mut accel) {
        let t = s.t_ns;
        last_accel = Some(last_accel.map_or(t, |l: i64| l.max(t)));
        loop {
            if g_next.is_none() && !g_done {
                g_next = g.next(&mut gyro).map(|x| x.t_ns);
                g_done = g_next.is_none();
            }
            match g_next {
                Some(x) if x < t => {
                    off.gyro_before += u64::from(a.samples == 1);
                    (g_prev, g_next) = (Some(g_prev.map_or(x, |p| p.max(x))), None);
                }
                _ => break,
            }
        }
        off.push(t, g_prev, g_next);
    }
    let after = |x: i64| last_accel.is_some_and(|l| x > l);
    off.gyro_after += g_next.map_or(0, |x| u64::from(after(x)));
    while !g_done {
        match g.next(&mut gyro) {
            Some(x) => off.gyro_after += u64::from(after(x.t_ns)),
            None => g_done = true,
        }
    }
    let (gyro, accel) = (g.finish(), a.finish());
    let findings = split_findings(&gyro, &accel, &off);
    SplitAudit {
        source: source.to_string(),
        gyro,
        accel,
        offsets: off,
        findings,
    }
}

/// The unit checks one channel allows on its own (those of
/// [`crate::plausibility::check_si_units`]): an accelerometer's median norm in [4, 20] m/s²,
/// a gyro's below 20 rad/s and not identically zero.
fn channel_units(c: &ChannelAudit) -> Option<String> {
    use crate::plausibility::{MIN_SAMPLES_FOR_ZERO_GYRO, accel_norm_verdict, gyro_norm_verdict};
    let norm = c.median_norm?;
    match c.sensor {
        Sensor::Accel => accel_norm_verdict(norm),
        Sensor::Gyro => gyro_norm_verdict(norm).or_else(|| {
            (c.all_zero && c.timing.samples >= MIN_SAMPLES_FOR_ZERO_GYRO as u64).then(|| {
                "the gyro reads exactly 0 on every sample checked: is this a gyroscope channel?"
                    .to_string()
            })
        }),
    }
}

fn split_findings(g: &ChannelAudit, a: &ChannelAudit, off: &Offsets) -> Vec<Finding> {
    let mut f = Vec::new();
    for c in [g, a] {
        let label = format!("{}: ", c.sensor);
        if c.timing.samples == 0 {
            let m = format!("{label}no samples");
            f.push(Finding::new(Severity::Defect, "empty", m));
        }
        findings::reading(&c.bad_rows, &c.stopped, &c.non_finite, &label, &mut f);
        findings::too_short(&c.timing, &label, &mut f);
        findings::timing(&c.timing, &label, &mut f);
        if let Some(m) = channel_units(c) {
            f.push(Finding::new(
                Severity::Defect,
                "units",
                format!("{label}{m}"),
            ));
        }
    }
    if off.count > 0 {
        let m = format!(
            "accel stamps against the nearest gyro stamp: mean {:.0} ns, sd {:.0} ns, from {} to \
             {} ns; {} of {} coincide",
            off.mean_ns, off.sd_ns, off.min_ns, off.max_ns, off.coincident, off.count
        );
        f.push(Finding::new(Severity::Info, "stamps", m));
    }
    let outside = [
        (
            off.accel_before + off.accel_after,
            a.timing.samples,
            "accel",
            "gyro",
        ),
        (
            off.gyro_before + off.gyro_after,
            g.timing.samples,
            "gyro",
            "accel",
        ),
    ];
    for (n, total, this, other) in outside {
        if n == 0 {
            continue;
        }
        let severity = if n as f64 > 0.01 * total as f64 {
            Severity::Warning
        } else {
            Severity::Info
        };
        let m = format!(
            "{n} of {total} {this} samples lie outside the {other} stream's span (a merge \
             cannot use them)"
        );
        f.push(Finding::new(severity, "stamps", m));
    }
    f.sort_by_key(|x| x.severity);
    f
}
