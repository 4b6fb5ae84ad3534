//! `preint audit`: what is wrong with a recording, found in one streaming pass in bounded
//! memory, before anything is computed from it.
//!
//! The [`Auditor`] takes the samples as the source gives them, before the reader's order and
//! finiteness checks ([`crate::ImuReader::into_unvalidated`]), so it sees duplicate and
//! out-of-order stamps and reports every one (count, first indices and lines) instead of
//! stopping at the first. Rows the reader cannot parse are counted and listed too. Memory is
//! fixed: histograms, counters, the first [`AuditOptions::max_listed`] defects of each kind,
//! and a prefix of [`AuditOptions::prefix_samples`] samples for the reference interval and the
//! unit checks.
//!
//! It measures:
//! - **timing** ([`Timing`]): sample count, span, nominal rate (1 / median Δt), mean Δt, drift
//!   (rate over the first vs the last tenth, ppm), Δt histogram in multiples of the reference
//!   interval, jitter (standard deviation of the regular intervals, and 1.4826 × MAD), gaps
//!   (Δt > [`GAP_FACTOR`] × reference; those above [`LONG_GAP_NS`] are defects), duplicates
//!   and out-of-order samples;
//! - **readings**: non-finite samples, readings beyond any IMU's range
//!   ([`crate::plausibility::limits`]: a corrupt row), single-sample spikes ([`Spike`]: a
//!   reading far from both neighbours while they agree), flat tops at an axis' extremes
//!   ([`FlatTop`]: saturation/clipping), constant axes, the fraction of 0.5 s windows in which
//!   the accelerometer is still ([`Still`]);
//! - **units** ([`UnitCheck`]): [`crate::plausibility::check_units_read_as`] in the units
//!   the source was read in ([`AuditOptions::read_as`]) and the gyro-scale fit on the prefix,
//!   the median gravity magnitude and gyro norm; checks that cannot decide are a warning.
//!
//! A recording with fewer than [`MIN_JUDGED_SAMPLES`] samples or shorter than
//! [`MIN_JUDGED_SPAN_S`] is too short to judge: its verdict is [`Verdict::TooShort`], not
//! clean (its rate, stillness and units rest on too few intervals).
//!
//! Split recordings (separate gyro and accelerometer streams) are audited by
//! [`audit_channels`]: each channel's timing, and how the accelerometer stamps sit between the
//! gyro stamps.
//!
//! The result is an [`Audit`] with a list of [`Finding`]s (defect, warning, info);
//! [`Audit::is_clean`] says whether there is no defect, [`Audit::verdict`] whether the
//! recording is clean, has defects, or is too short to judge.
//!
//! Indices are 0-based positions among the samples the source yields (rows that cannot be
//! parsed take no index); locations are 1-based lines (messages for containers).

mod axes;
mod channels;
mod findings;
mod intervals;
mod spikes;

pub use axes::{AXES, AxisReport, FlatTop, MIN_FLAT_RUN, Still};
pub use channels::{ChannelAudit, Offsets, SplitAudit, audit_channels};
pub use findings::{
    DRIFT_WARNING_PPM, Finding, JITTER_WARNING, MIN_JUDGED_SAMPLES, MIN_JUDGED_SPAN_S, Severity,
    Verdict,
};
pub use intervals::{
    Event, EventList, GAP_FACTOR, HISTOGRAM_EDGES, LONG_GAP_NS, Step, Timing, TimingStats,
    reference_interval,
};
pub use spikes::{SPIKE_SIGMAS, Spike};

use crate::error::{IoError, Location};
use crate::plausibility::limits::impossible;
use crate::plausibility::{
    GyroScaleFit, UnitVerdict, check_units_read_as, gyro_scale_fit, median_interval_ns,
};
use crate::reader::{ImuReader, Located};
use crate::units::Units;
use axes::{FlatTops, StillWindows};
use preint::ImuSample;
use spikes::Spikes;

/// How much an audit keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AuditOptions {
    /// Samples kept from the start for the reference interval and the unit checks (default
    /// 32 768: 164 s at 200 Hz, 2.4 MB).
    pub prefix_samples: usize,
    /// Events of each kind listed (the rest are counted; default 20).
    pub max_listed: usize,
    /// IMU intrinsics applied to the samples of the unit checks (a calibration file's
    /// [`preint::intrinsics::ImuIntrinsics::correction`]); timing, clipping, non-finite
    /// readings and stillness are audited on the raw readings, where the sensor produced them.
    /// Default `None`.
    pub correction: Option<preint::intrinsics::Correction>,
    /// The units the source was read in, whose alternatives the unit checks weigh
    /// ([`check_units_read_as`]; `None`: unknown). [`audit_reader`] sets them.
    pub read_as: Option<Units>,
}

impl Default for AuditOptions {
    fn default() -> Self {
        Self {
            prefix_samples: 1 << 15,
            max_listed: 20,
            correction: None,
            read_as: None,
        }
    }
}

/// A row the source could not turn into a sample: where, and the reader's message.
#[derive(Clone, Debug, PartialEq)]
pub struct BadRow {
    /// Where it is.
    pub at: Location,
    /// The reader's error message (with file and line).
    pub message: String,
}

/// Reading errors of a stream: rows that could not be read, and the error that ended reading.
#[derive(Clone, Debug, Default)]
pub(crate) struct ErrorLog {
    bad_rows: EventList<BadRow>,
    last_at: Option<Location>,
    stopped: Option<String>,
}

impl ErrorLog {
    /// Adds an error; returns whether reading can go on (see [`super::Auditor::push_error`]).
    pub(crate) fn push(&mut self, e: &IoError, limit: usize) -> bool {
        if let IoError::Parse { at, .. } = e
            && self.last_at != Some(*at)
        {
            self.last_at = Some(*at);
            let row = BadRow {
                at: *at,
                message: e.to_string(),
            };
            self.bad_rows.push(row, limit);
            return true;
        }
        self.stopped = Some(e.to_string());
        false
    }
}

/// The unit checks on the prefix (finite samples, sorted by time, one per stamp).
#[derive(Clone, Debug, PartialEq)]
pub struct UnitCheck {
    /// Samples checked.
    pub samples: usize,
    /// Median accelerometer norm \[m/s²\] (≈ 9.81 when the unit is right), of the corrected
    /// samples when [`AuditOptions::correction`] is given.
    pub gravity_median_m_s2: f64,
    /// The same median of the raw readings.
    pub raw_gravity_median_m_s2: f64,
    /// Median gyro norm \[rad/s\].
    pub gyro_median_rad_s: f64,
    /// How well the gyro scaled by π/180, 1 and 180/π explains the turning of gravity
    /// ([`crate::plausibility::gyro_scale_fit`]); `None` with fewer than 10 quasi-static pairs.
    pub gyro_scale: Option<GyroScaleFit>,
    /// Whether the gyro's axes are the accelerometer's
    /// ([`crate::plausibility::axes::gyro_axes_fit`]); `None` with fewer than 10 pairs of
    /// quasi-static moments between which gravity turns.
    pub gyro_axes: Option<crate::plausibility::axes::AxisFit>,
    /// The message of [`crate::plausibility::check_units_read_as`] when it refuses the data.
    pub error: Option<String>,
    /// Its verdict when it does not (passed or inconclusive).
    pub verdict: Option<UnitVerdict>,
}

/// A reading beyond any IMU's range ([`crate::plausibility::limits`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Impossible {
    /// 0-based sample index.
    pub index: u64,
    /// Where it is in the source.
    pub at: Location,
    /// What it reads, and the limit.
    pub what: String,
}

/// Everything an audit found (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Audit {
    /// The source's name.
    pub source: String,
    /// Timing of the stamps.
    pub timing: Timing,
    /// Rows that could not be read.
    pub bad_rows: EventList<BadRow>,
    /// The error that ended reading early, if any.
    pub stopped: Option<String>,
    /// Samples with a non-finite reading.
    pub non_finite: EventList<(u64, Location)>,
    /// Samples with a reading beyond any IMU's range.
    pub impossible: EventList<Impossible>,
    /// Single-sample spikes.
    pub spikes: EventList<Spike>,
    /// Duplicates whose readings are also the same as the sample they repeat.
    pub identical_duplicates: u64,
    /// Extremes and flat tops of the six axes (finite samples), if there were any.
    pub axes: Option<[AxisReport; 6]>,
    /// Still windows.
    pub still: Still,
    /// Unit checks, when the prefix has two samples with different stamps.
    pub units: Option<UnitCheck>,
    /// The verdict: defects first, then warnings, then information.
    pub findings: Vec<Finding>,
}

impl Audit {
    /// No defect was found.
    pub fn is_clean(&self) -> bool {
        self.defects().next().is_none()
    }

    /// Clean, defects, or too short to judge (see the module docs).
    pub fn verdict(&self) -> Verdict {
        Verdict::of(&self.findings)
    }

    /// The defects.
    pub fn defects(&self) -> impl Iterator<Item = &Finding> {
        self.findings
            .iter()
            .filter(|f| f.severity == Severity::Defect)
    }

    /// Number of findings of `severity`.
    pub fn count(&self, severity: Severity) -> usize {
        self.findings
            .iter()
            .filter(|f| f.severity == severity)
            .count()
    }
}

/// The streaming part of an [`Auditor`], once the reference interval is known.
struct Streaming {
    timing: TimingStats,
    tops: FlatTops,
    still: StillWindows,
    spikes: Spikes,
    non_finite: EventList<(u64, Location)>,
    impossible: EventList<Impossible>,
    identical: u64,
    latest: Option<ImuSample>,
    limit: usize,
}

impl Streaming {
    fn push(&mut self, index: u64, s: &Located) {
        let x = &s.sample;
        match self.timing.push(index, s.at, x.t_ns) {
            Step::Duplicate if self.latest.is_some_and(|l| l == *x) => self.identical += 1,
            Step::First | Step::Regular | Step::Gap => self.latest = Some(*x),
            _ => {}
        }
        if !(x.gyro.iter().chain(x.acc.iter())).all(|v| v.is_finite()) {
            self.non_finite.push((index, s.at), self.limit);
            self.spikes.gap();
            return;
        }
        if let Some(what) = impossible(x) {
            let e = Impossible {
                index,
                at: s.at,
                what,
            };
            self.impossible.push(e, self.limit);
            self.spikes.gap();
            return;
        }
        self.tops.push(&x.gyro, &x.acc, index, s.at);
        self.still.push(&x.acc);
        self.spikes.push(index, s.at, readings(x));
    }
}

/// Audits a stream sample by sample (see the module docs): [`Auditor::push`] each sample,
/// [`Auditor::push_error`] each error, then [`Auditor::finish`].
pub struct Auditor {
    source: String,
    opts: AuditOptions,
    samples: u64,
    prefix: Vec<Located>,
    streaming: Option<Streaming>,
    units: Option<UnitCheck>,
    errors: ErrorLog,
}

impl Auditor {
    /// An audit of the source named `source`.
    pub fn new(source: &str, opts: AuditOptions) -> Self {
        Self {
            source: source.to_string(),
            opts,
            samples: 0,
            prefix: Vec::with_capacity(opts.prefix_samples.min(1 << 20)),
            streaming: None,
            units: None,
            errors: ErrorLog::default(),
        }
    }

    /// Adds the next sample.
    pub fn push(&mut self, s: &Located) {
        let index = self.samples;
        self.samples += 1;
        match &mut self.streaming {
            Some(st) => st.push(index, s),
            None => {
                self.prefix.push(*s);
                if self.prefix.len() >= self.opts.prefix_samples {
                    self.start_streaming();
                }
            }
        }
    }

    /// Adds an error of the source; returns whether reading can go on. A malformed row
    /// ([`IoError::Parse`] at a new location) is counted and reading goes on; any other error
    /// ends the audit's reading and is reported.
    pub fn push_error(&mut self, e: &IoError) -> bool {
        self.errors.push(e, self.opts.max_listed)
    }

    /// Computes the reference interval and the unit checks from the prefix, then replays it.
    fn start_streaming(&mut self) {
        let prefix = std::mem::take(&mut self.prefix);
        let reference = reference_interval(prefix.iter().map(|s| s.sample.t_ns));
        self.units = unit_check(&prefix, &self.opts);
        let limit = self.opts.max_listed;
        let judged: Vec<[f64; 6]> = (prefix.iter().map(|l| &l.sample))
            .filter(|s| judged(s))
            .map(readings)
            .collect();
        let mut st = Streaming {
            timing: TimingStats::new(reference, limit),
            tops: FlatTops::default(),
            still: StillWindows::new(reference),
            spikes: Spikes::new(&judged, limit),
            non_finite: EventList::default(),
            impossible: EventList::default(),
            identical: 0,
            latest: None,
            limit,
        };
        for (k, s) in prefix.iter().enumerate() {
            st.push(k as u64, s);
        }
        self.streaming = Some(st);
    }

    /// The audit of everything pushed, with its findings.
    pub fn finish(mut self) -> Audit {
        if self.streaming.is_none() {
            self.start_streaming();
        }
        let st = self.streaming.take().expect("started above");
        let mut audit = Audit {
            source: self.source,
            timing: st.timing.finish(),
            bad_rows: self.errors.bad_rows,
            stopped: self.errors.stopped,
            non_finite: st.non_finite,
            impossible: st.impossible,
            spikes: st.spikes.found,
            identical_duplicates: st.identical,
            axes: st.tops.finish(),
            still: st.still.finish(),
            units: self.units,
            findings: Vec::new(),
        };
        audit.findings = findings::of_audit(&audit);
        audit
    }
}

/// The six readings of `s`: gyro x, y, z, accelerometer x, y, z.
fn readings(s: &ImuSample) -> [f64; 6] {
    [s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z]
}

/// Whether the readings of `s` are judged by the unit checks, the spikes and the axes: finite
/// and within any IMU's range.
fn judged(s: &ImuSample) -> bool {
    (s.gyro.iter().chain(s.acc.iter())).all(|v| v.is_finite()) && impossible(s).is_none()
}

/// The unit checks of the module docs on `prefix`, corrected by the options' correction, in
/// the units the source was read in.
fn unit_check(prefix: &[Located], opts: &AuditOptions) -> Option<UnitCheck> {
    let mut v: Vec<ImuSample> = prefix.iter().map(|l| l.sample).filter(judged).collect();
    v.sort_by_key(|s| s.t_ns);
    v.dedup_by_key(|s| s.t_ns);
    if v.len() < 2 {
        return None;
    }
    let raw: Vec<f64> = v.iter().map(|s| s.acc.norm()).collect();
    if let Some(c) = &opts.correction {
        v.iter_mut().for_each(|s| *s = c.apply(s));
    }
    let med = |mut x: Vec<f64>| {
        let mid = x.len() / 2;
        *x.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let (verdict, error) = match check_units_read_as(&v, "", opts.read_as) {
        Ok(verdict) => (Some(verdict), None),
        Err(IoError::Units { msg, .. }) => (None, Some(msg)),
        Err(other) => (None, Some(other.to_string())),
    };
    Some(UnitCheck {
        samples: v.len(),
        gravity_median_m_s2: med(v.iter().map(|s| s.acc.norm()).collect()),
        raw_gravity_median_m_s2: med(raw),
        gyro_median_rad_s: med(v.iter().map(|s| s.gyro.norm()).collect()),
        gyro_scale: gyro_scale_fit(&v, median_interval_ns(&v) * 1e-9),
        gyro_axes: crate::plausibility::axes::gyro_axes_fit(&v, median_interval_ns(&v) * 1e-9),
        error,
        verdict,
    })
}

/// Audits every item of `samples` from the source named `source` (see the module docs).
pub fn audit_stream(
    samples: impl Iterator<Item = Result<Located, IoError>>,
    source: &str,
    opts: AuditOptions,
) -> Audit {
    let mut a = Auditor::new(source, opts);
    for item in samples {
        match item {
            Ok(s) => a.push(&s),
            Err(e) => {
                if !a.push_error(&e) {
                    break;
                }
            }
        }
    }
    a.finish()
}

/// Audits the samples of `reader` as its source gives them, without its order and
/// finiteness checks; the unit checks weigh the alternatives of the units it reads in (unless
/// the options give others).
pub fn audit_reader(reader: ImuReader, opts: AuditOptions) -> Audit {
    let (samples, info, _) = reader.into_unvalidated();
    let opts = AuditOptions {
        read_as: opts.read_as.or(Some(info.units)),
        ..opts
    };
    audit_stream(samples, &info.source_name, opts)
}
