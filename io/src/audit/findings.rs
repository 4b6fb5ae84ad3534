//! The verdict of an audit: one [`Finding`] per problem (or fact), each naming counts and the
//! first indices and lines.

use super::intervals::{Event, EventList, GAP_FACTOR, LONG_GAP_NS, Timing};
use super::spikes::SPIKE_SIGMAS;
use super::{AXES, Audit, AxisReport, BadRow, MIN_FLAT_RUN};
use crate::error::Location;
use std::fmt::Write as _;

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// The data breaks an assumption of every computation (order, finiteness, units,
    /// saturation, a gap the integrator refuses): results from it would be wrong.
    Defect,
    /// Worth knowing before trusting results: dropped samples, jitter, drift, a constant axis.
    Warning,
    /// A measurement: rate, span, still fraction, units that pass.
    Info,
}

impl std::fmt::Display for Severity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Severity::Defect => "defect",
            Severity::Warning => "warning",
            Severity::Info => "info",
        })
    }
}

/// One finding.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    /// How bad it is.
    pub severity: Severity,
    /// What it is about: `rate`, `gaps`, `long_gaps`, `duplicates`, `out_of_order`,
    /// `bad_rows`, `stopped`, `non_finite`, `impossible`, `spikes`, `clipping`,
    /// `constant_axis`, `units`, `still`, `jitter`, `drift`, `empty`, `too_short`, `stamps`
    /// (split streams).
    pub kind: &'static str,
    /// What was found, with counts and the first indices and lines.
    pub message: String,
}

impl Finding {
    /// A finding of `kind` with `message`.
    pub fn new(severity: Severity, kind: &'static str, message: String) -> Self {
        Self {
            severity,
            kind,
            message,
        }
    }
}

/// Events named in a message (the rest are counted).
const NAMED: usize = 3;

/// Fewest samples an audit judges: a Δt histogram, a median interval, a jitter and a drift of
/// fewer than 99 intervals say little.
pub const MIN_JUDGED_SAMPLES: u64 = 100;

/// Shortest span an audit judges \[s\]: two of the 0.5 s still windows, and the unit checks'
/// pairs of quasi-static moments are 1 s apart. (The unit checks say on their own when they
/// need more: a still part of 2 s.)
pub const MIN_JUDGED_SPAN_S: f64 = 1.0;

/// The overall verdict of an audit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// No defect, and long enough to judge.
    Clean,
    /// At least one defect.
    Defects,
    /// No defect, but too short to judge (a `too_short` finding).
    TooShort,
}

impl Verdict {
    /// The verdict of `findings`: defects first, then too short, else clean.
    pub fn of(findings: &[Finding]) -> Self {
        if findings.iter().any(|f| f.severity == Severity::Defect) {
            Verdict::Defects
        } else if findings.iter().any(|f| f.kind == "too_short") {
            Verdict::TooShort
        } else {
            Verdict::Clean
        }
    }

    /// `clean`, `defects` or `too_short`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Clean => "clean",
            Verdict::Defects => "defects",
            Verdict::TooShort => "too_short",
        }
    }
}

/// A `too_short` warning when `t` has fewer than [`MIN_JUDGED_SAMPLES`] samples or spans less
/// than [`MIN_JUDGED_SPAN_S`] (and any sample at all); `label` prefixes the message.
pub(crate) fn too_short(t: &Timing, label: &str, f: &mut Vec<Finding>) {
    let span = t.span_s().unwrap_or(0.0);
    if t.samples == 0 || (t.samples >= MIN_JUDGED_SAMPLES && span >= MIN_JUDGED_SPAN_S) {
        return;
    }
    f.push(Finding::new(
        Severity::Warning,
        "too_short",
        format!(
            "{label}too short to judge: {} over {span:.3} s; an audit needs at least \
             {MIN_JUDGED_SAMPLES} samples over {MIN_JUDGED_SPAN_S} s (the rate, the still \
             windows and the unit checks rest on too few intervals otherwise)",
            count(t.samples, "sample", "samples")
        ),
    ));
}

/// Jitter (robust sd of Δt, as a fraction of the median interval) above which a warning is
/// given: sensor-clocked stamps jitter by far less (EuRoC: 0; KITTI's 0.4 % passes).
pub const JITTER_WARNING: f64 = 0.01;
/// Rate drift between the first and the last tenth above which a warning is given \[ppm\]:
/// a sensor's crystal clock is typically within ±100 ppm over its temperature range.
pub const DRIFT_WARNING_PPM: f64 = 1000.0;

/// `", +N more"` when a list of `count` names only `named`.
fn more(count: u64, named: usize) -> String {
    if count > named as u64 {
        format!(", +{} more", count - named as u64)
    } else {
        String::new()
    }
}

/// `"1 gap"`, `"2 gaps"`.
fn count(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

fn list_events<T>(l: &EventList<T>, one: impl Fn(&T) -> String) -> String {
    let names: Vec<String> = l.first.iter().take(NAMED).map(one).collect();
    format!("{}{}", names.join("; "), more(l.count, names.len()))
}

/// The findings of `a`, defects first.
pub(crate) fn of_audit(a: &Audit) -> Vec<Finding> {
    let mut f = Vec::new();
    if a.timing.samples == 0 {
        f.push(Finding::new(
            Severity::Defect,
            "empty",
            "no samples".to_string(),
        ));
    }
    reading(&a.bad_rows, &a.stopped, &a.non_finite, "", &mut f);
    impossible_and_spikes(a, &mut f);
    too_short(&a.timing, "", &mut f);
    timing(&a.timing, "", &mut f);
    if a.identical_duplicates > 0
        && let Some(d) = f.iter_mut().find(|x| x.kind == "duplicates")
    {
        let _ = write!(
            d.message,
            " ({} of them repeat the readings too: rows written twice)",
            a.identical_duplicates
        );
    }
    if let Some(axes) = &a.axes {
        for ax in axes {
            axis(ax, a.timing.samples, &mut f);
        }
    }
    units(a, &mut f);
    if a.still.windows > 0 {
        f.push(Finding::new(
            Severity::Info,
            "still",
            format!(
                "still (accelerometer steady) in {:.1} % of {} of {} samples",
                100.0 * a.still.fraction(),
                count(a.still.windows, "window", "windows"),
                a.still.window
            ),
        ));
    }
    f.sort_by_key(|x| x.severity);
    f
}

/// Findings about readings no IMU produces: beyond any IMU's range (a defect) and
/// single-sample spikes (a warning).
fn impossible_and_spikes(a: &Audit, f: &mut Vec<Finding>) {
    let l = &a.impossible;
    if l.count > 0 {
        f.push(Finding::new(
            Severity::Defect,
            "impossible",
            format!(
                "{} beyond any IMU's range (corrupt rows): {}",
                count(l.count, "sample", "samples"),
                list_events(l, |e| format!("index {} ({}): {}", e.index, e.at, e.what))
            ),
        ));
    }
    let s = &a.spikes;
    if s.count > 0 {
        let names = list_events(s, |e| {
            format!(
                "index {} ({}) {} = {} {}, {:.0} σ from both neighbours",
                e.index, e.at, AXES[e.axis].0, e.value, AXES[e.axis].1, e.sigmas
            )
        });
        f.push(Finding::new(
            Severity::Warning,
            "spikes",
            format!(
                "{} (a reading ≥ {SPIKE_SIGMAS} robust σ of the axis' sample-to-sample change \
                 from both neighbours, which agree): {names}",
                count(s.count, "single-sample spike", "single-sample spikes"),
            ),
        ));
    }
}

/// Findings about reading: bad rows, an early stop, non-finite readings; `label` prefixes the
/// messages.
pub(crate) fn reading(
    bad_rows: &EventList<BadRow>,
    stopped: &Option<String>,
    non_finite: &EventList<(u64, Location)>,
    label: &str,
    f: &mut Vec<Finding>,
) {
    if bad_rows.count > 0 {
        f.push(Finding::new(
            Severity::Defect,
            "bad_rows",
            format!(
                "{label}{} could not be read: {}",
                count(bad_rows.count, "row", "rows"),
                list_events(bad_rows, |r| r.message.clone())
            ),
        ));
    }
    if let Some(e) = stopped {
        f.push(Finding::new(
            Severity::Defect,
            "stopped",
            format!("{label}reading stopped early: {e}"),
        ));
    }
    if non_finite.count > 0 {
        f.push(Finding::new(
            Severity::Defect,
            "non_finite",
            format!(
                "{label}{} with a non-finite reading: {}",
                count(non_finite.count, "sample", "samples"),
                list_events(non_finite, |(i, at)| format!("index {i} ({at})"))
            ),
        ));
    }
}

/// The timing findings; `label` prefixes the messages (`gyro: ` for a split channel).
pub(crate) fn timing(t: &Timing, label: &str, f: &mut Vec<Finding>) {
    let d = &t.duplicates;
    if d.count > 0 {
        let msg = list_events(d, |e| {
            format!(
                "index {} ({}) repeats t = {} ns of {}",
                e.index, e.at, e.t_ns, e.prev_at
            )
        });
        let what = count(d.count, "duplicate timestamp", "duplicate timestamps");
        let m = format!("{label}{what}: {msg}");
        f.push(Finding::new(Severity::Defect, "duplicates", m));
    }
    let o = &t.out_of_order;
    if o.count > 0 {
        let msg = list_events(o, |e| {
            format!(
                "index {} ({}) t = {} ns, {} ns before {}",
                e.index,
                e.at,
                e.t_ns,
                e.dt_ns().unsigned_abs(),
                e.prev_at
            )
        });
        let what = count(o.count, "sample goes", "samples go");
        let m = format!("{label}{what} back in time: {msg}");
        f.push(Finding::new(Severity::Defect, "out_of_order", m));
    }
    let gap = |e: &Event| {
        format!(
            "{:.6} s before index {} ({}, t = {} ns)",
            e.dt_ns() as f64 * 1e-9,
            e.index,
            e.at,
            e.t_ns
        )
    };
    if t.long_gaps.count > 0 {
        let m = format!(
            "{label}{} longer than {} s (the integrator refuses windows across them): {}",
            count(t.long_gaps.count, "gap", "gaps"),
            LONG_GAP_NS as f64 * 1e-9,
            list_events(&t.long_gaps, gap)
        );
        f.push(Finding::new(Severity::Defect, "long_gaps", m));
    }
    if let (Some(largest), true) = (&t.largest_gap, t.gaps.count > 0) {
        let mut m = format!(
            "{label}{} (Δt > {GAP_FACTOR} × the {} ns reference interval; {} missing)",
            count(t.gaps.count, "gap", "gaps"),
            t.reference_ns.unwrap_or(0),
            count(t.missing_samples, "sample", "samples")
        );
        if t.gaps.count == 1 {
            let _ = write!(m, ": {}", gap(largest));
        } else {
            let _ = write!(
                m,
                ", largest {}; first {}",
                gap(largest),
                list_events(&t.gaps, gap)
            );
        }
        f.push(Finding::new(Severity::Warning, "gaps", m));
    }
    rate(t, label, f);
}

fn rate(t: &Timing, label: &str, f: &mut Vec<Finding>) {
    let (Some(median), Some(rate)) = (t.median_ns, t.rate_hz()) else {
        let why = match t.reference_ns {
            _ if t.samples < 2 => return,
            None => "no two samples have different stamps".to_string(),
            Some(r) => format!(
                "the median interval is more than 5 % away from the reference {r} ns (the rate \
                 changes during the recording)"
            ),
        };
        f.push(Finding::new(
            Severity::Warning,
            "rate",
            format!("{label}no nominal rate: {why}"),
        ));
        return;
    };
    let mut m = format!(
        "{label}{} samples over {:.3} s; nominal rate {rate:.4} Hz (median Δt {median:.0} ns, \
         mean {:.1} ns)",
        t.samples,
        t.span_s().unwrap_or(0.0),
        t.mean_ns.unwrap_or(f64::NAN)
    );
    if let Some(sd) = t.sd_ns {
        let _ = write!(m, "; jitter sd {sd:.1} ns");
    }
    if let Some(r) = t.robust_sd_ns {
        let _ = write!(m, ", robust sd {r:.1} ns");
    }
    if let Some(p) = t.drift_ppm() {
        let _ = write!(m, "; drift {p:+.1} ppm (last vs first tenth)");
    }
    f.push(Finding::new(Severity::Info, "rate", m));
    let jitter = match t.robust_sd_ns {
        Some(j) if j > JITTER_WARNING * median => format!(
            "robust sd of Δt {j:.0} ns is more than {} % of the {median:.0} ns interval",
            JITTER_WARNING * 100.0
        ),
        None => "more than half of the intervals are over 5 % away from the median".to_string(),
        Some(_) => String::new(),
    };
    if !jitter.is_empty() {
        let m = format!(
            "{label}jittery stamps: {jitter} (host receive times rather than sensor times?)"
        );
        f.push(Finding::new(Severity::Warning, "jitter", m));
    }
    if let Some(p) = t.drift_ppm().filter(|p| p.abs() > DRIFT_WARNING_PPM) {
        let (a, b) = t.tenth_rates_hz.unwrap_or_default();
        let m = format!(
            "{label}the rate drifts by {p:+.0} ppm: {a:.4} Hz over the first tenth, {b:.4} Hz \
             over the last"
        );
        f.push(Finding::new(Severity::Warning, "drift", m));
    }
}

fn axis(ax: &AxisReport, samples: u64, f: &mut Vec<Finding>) {
    if ax.constant() && samples > 1 {
        let m = format!(
            "{} reads the constant {} {}: a stuck axis, or a signal without noise",
            ax.name, ax.max, ax.unit
        );
        f.push(Finding::new(Severity::Warning, "constant_axis", m));
        return;
    }
    let side = |what: &str, v: f64, t: &super::FlatTop| {
        let (i, at) = t.first.filter(|_| t.clipped())?;
        Some(format!(
            "at its {what} {v} {}: {} of its {} samples in {} runs of ≥ {MIN_FLAT_RUN} equal \
             readings (longest {}), first at index {i} ({at})",
            ax.unit, t.samples, t.total, t.runs, t.longest
        ))
    };
    let sides: Vec<String> = [
        side("maximum", ax.max, &ax.at_max),
        side("minimum", ax.min, &ax.at_min),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !sides.is_empty() {
        let m = format!(
            "{} is clipped ({:.3} % of samples in flat tops) {}: saturated beyond the sensor's \
             range, or limited when written",
            ax.name,
            100.0 * ax.flat_fraction(samples),
            sides.join("; ")
        );
        f.push(Finding::new(Severity::Defect, "clipping", m));
    }
}

fn units(a: &Audit, f: &mut Vec<Finding>) {
    let Some(u) = &a.units else { return };
    let scale = match &u.gyro_scale {
        Some(s) => {
            let [d, one, r] = s.median_error.map(f64::to_degrees);
            format!(
                "gravity direction vs gyro over {} quasi-static pairs misses by {one:.1}° as \
                 read, {d:.1}° scaled by π/180, {r:.1}° by 180/π",
                s.pairs
            )
        }
        None => "too few quasi-static moments to compare the gyro with gravity".to_string(),
    };
    axes_finding(u, f);
    let facts = format!(
        "median |a| {:.3} m/s², median |ω| {:.4} rad/s over the first {} samples; {scale}",
        u.gravity_median_m_s2, u.gyro_median_rad_s, u.samples
    );
    match (&u.error, u.verdict.as_ref().and_then(|v| v.why())) {
        (Some(e), _) => f.push(Finding::new(
            Severity::Defect,
            "units",
            format!("{e} ({facts})"),
        )),
        (None, Some(why)) => f.push(Finding::new(
            Severity::Warning,
            "units",
            format!("unit check inconclusive: {why} ({facts})"),
        )),
        (None, None) => f.push(Finding::new(
            Severity::Info,
            "units",
            format!("units plausible: {facts}"),
        )),
    }
}

/// Whether the gyro's axes are the accelerometer's (check 7 of the unit checks): a defect
/// when another axis map explains the turning of gravity far better (the unit check's error
/// then says the same), otherwise what the check could tell.
fn axes_finding(u: &crate::audit::UnitCheck, f: &mut Vec<Finding>) {
    use crate::plausibility::axes::AxisVerdict;
    let (severity, m) = match u.gyro_axes.as_ref().map(|a| (a, a.verdict())) {
        Some((_, AxisVerdict::Mismatch(m))) => (Severity::Defect, m),
        Some((a, AxisVerdict::Agree)) => (
            Severity::Info,
            format!(
                "gyro axes agree with the accelerometer's: over {} pairs of quasi-static moments \
                 (gravity turning {:.0}° median) the gyro as read leaves {:.0} % of the turn \
                 unexplained, every other axis map at least {:.0} %",
                a.pairs,
                a.median_turn_rad.to_degrees(),
                100.0 * a.identity,
                100.0 * a.best_other.1
            ),
        ),
        Some((_, AxisVerdict::CannotTell(m))) => (Severity::Info, format!("axis check: {m}")),
        None => (
            Severity::Info,
            "axis check: too few pairs of quasi-static moments between which gravity turns to \
             compare the gyro's axes with the accelerometer's"
                .to_string(),
        ),
    };
    f.push(Finding::new(severity, "gyro axes", m));
}
