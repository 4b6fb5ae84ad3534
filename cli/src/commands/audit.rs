//! `preint audit`: what is wrong with a recording, in one streaming pass in bounded memory
//! ([`preint_io::audit`]): rate and its drift, Δt histogram and jitter, gaps, duplicate and
//! out-of-order samples (with their indices and lines), unreadable rows, non-finite readings,
//! flat tops at an axis' extremes (saturation/clipping), unit plausibility and the fraction of
//! time the sensor is still.
//!
//! Exit status 0 with a verdict; with `--strict`, exit 2 when a defect is found (the defects
//! are printed on stderr, each naming counts, indices and lines). With `--no-unit-check` a
//! unit problem is a warning instead of a defect.
//!
//! # JSON (`--json`)
//! - `imu`, `input` (`format`, `read_as`, `notes`): the recording and how it was read.
//! - `clean` (no defect), `defects`, `warnings`: counts; `findings`: `[{severity` (`defect`,
//!   `warning`, `info`), `kind`, `message}]`, defects first. Kinds: `empty`, `bad_rows`,
//!   `stopped`, `non_finite`, `duplicates`, `out_of_order`, `long_gaps`, `gaps`, `rate`,
//!   `jitter`, `drift`, `clipping`, `constant_axis`, `units`, `still`.
//! - `samples`; `t_first_ns`, `t_last_ns` (largest stamp), `span_s`.
//! - `rate`: `nominal_hz` (1 / median Δt), `median_interval_ns`, `resolution_ns` (of the
//!   median), `mean_interval_ns` (positive intervals), `reference_interval_ns` (median of the
//!   first 32 768 samples: the unit of the histogram and the gap threshold), `first_tenth_hz`,
//!   `last_tenth_hz`, `drift_ppm` (last vs first tenth).
//! - `jitter`: `sd_ns` (standard deviation of Δt, gaps left out), `robust_sd_ns`
//!   (1.4826 × MAD).
//! - `histogram`: `[{from, to, count}]`, Δt in multiples of the reference interval, bins
//!   `(from, to]` (`to` null for the last, unbounded one).
//! - `gaps` (Δt > 1.5 × reference): `count`, `missing_samples`, `largest`, `first`, and
//!   `long` (`count`, `first`: gaps above 0.25 s). `duplicates` (`count`, `identical`,
//!   `first`), `out_of_order` (`count`, `first`). An event is `{index` (0-based sample),
//!   `at` (`line N` or `message N`), `line` (null for containers), `t_ns`, `dt_ns` (from the
//!   latest earlier stamp), `prev_at}`.
//! - `bad_rows`: `count`, `first: [{at, line, message}]`; `stopped`: the error that ended
//!   reading, or null; `non_finite`: `count`, `first: [{index, at, line}]`.
//! - `axes`: per axis (`gyro x` … `acc z`) `unit`, `max`, `min`, `constant`,
//!   `flat_fraction`, `at_max` and `at_min` (`clipped`, `total`: samples at the extreme,
//!   `samples`, `runs`, `longest`, `first_index`, `first_at`: runs of ≥ 3 equal readings at
//!   it; clipped when they hold at least half of `total`).
//! - `units` (on the first 32 768 samples, or null): `samples`, `gravity_median_m_s2`,
//!   `gyro_median_rad_s`, `gyro_scale` (`pairs`, `misfit_deg`: `{deg_per_s, as_read,
//!   rad_per_s}`, or null), `error` (the unit check's message, or null).
//! - `still`: `window_samples` (0.5 s), `windows`, `still`, `fraction`.

use crate::imu_args::{ImuArgs, source_json};
use crate::progress::ReadingBar;
use crate::{CliError, Output};
use preint_io::audit::{
    Audit, AuditOptions, AxisReport, Event, EventList, FlatTop, HISTOGRAM_EDGES, Severity,
    audit_reader,
};
use preint_io::{Location, SourceInfo};
use serde_json::{Value, json};
use std::fmt::Write as _;

/// Flags of `preint audit`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Exit with status 2 when a defect is found (for scripts and CI).
    #[arg(long)]
    pub strict: bool,
}

/// An audit and what it was run on.
#[derive(Clone, Debug)]
pub struct AuditRun {
    /// The input, as printed.
    pub imu: String,
    /// How it was read.
    pub source: SourceInfo,
    /// What was found.
    pub audit: Audit,
}

/// Reads the recording once, sample by sample, and audits it.
pub fn compute(args: &Args) -> Result<AuditRun, CliError> {
    let reader = args.input.open()?;
    let source = reader.info().clone();
    let progress = reader.progress().clone();
    let _bar = ReadingBar::start(&progress, "audit");
    let mut audit = audit_reader(reader, AuditOptions::default());
    if args.input.no_unit_check {
        for f in audit.findings.iter_mut().filter(|f| f.kind == "units") {
            if f.severity == Severity::Defect {
                f.severity = Severity::Warning;
            }
        }
        audit.findings.sort_by_key(|f| f.severity);
    }
    Ok(AuditRun {
        imu: args.input.label(),
        source,
        audit,
    })
}

fn line(at: &Location) -> Value {
    match at {
        Location::Line(l) => json!(l),
        _ => Value::Null,
    }
}

fn event(e: &Event) -> Value {
    json!({"index": e.index, "at": e.at.to_string(), "line": line(&e.at), "t_ns": e.t_ns,
           "dt_ns": e.dt_ns(), "prev_at": e.prev_at.to_string()})
}

fn events(l: &EventList<Event>) -> Value {
    json!({"count": l.count, "first": l.first.iter().map(event).collect::<Vec<_>>()})
}

fn flat(t: &FlatTop) -> Value {
    json!({"clipped": t.clipped(), "total": t.total, "samples": t.samples, "runs": t.runs,
           "longest": t.longest,
           "first_index": t.first.map(|f| f.0), "first_at": t.first.map(|f| f.1.to_string())})
}

fn axis(a: &AxisReport, samples: u64) -> Value {
    json!({"axis": a.name, "unit": a.unit, "max": a.max, "min": a.min, "constant": a.constant(),
           "flat_fraction": a.flat_fraction(samples), "at_max": flat(&a.at_max),
           "at_min": flat(&a.at_min)})
}

/// The JSON form (keys in the module docs).
pub fn to_json(r: &AuditRun) -> Value {
    let a = &r.audit;
    let t = &a.timing;
    let mut from = 0.0;
    let histogram: Vec<Value> = (HISTOGRAM_EDGES.iter().zip(&t.histogram))
        .map(|(&to, &count)| {
            let bin = json!({"from": from, "to": to.is_finite().then_some(to), "count": count});
            from = to;
            bin
        })
        .collect();
    let findings: Vec<Value> = (a.findings.iter())
        .map(|f| json!({"severity": f.severity.to_string(), "kind": f.kind, "message": f.message}))
        .collect();
    let mut gaps = events(&t.gaps);
    gaps["missing_samples"] = json!(t.missing_samples);
    gaps["largest"] = t.largest_gap.as_ref().map_or(Value::Null, event);
    gaps["long"] = events(&t.long_gaps);
    let mut duplicates = events(&t.duplicates);
    duplicates["identical"] = json!(a.identical_duplicates);
    let tenth = t.tenth_rates_hz;
    json!({
        "imu": r.imu, "input": source_json(&r.source),
        "clean": a.is_clean(), "defects": a.count(Severity::Defect),
        "warnings": a.count(Severity::Warning), "findings": findings,
        "samples": t.samples, "t_first_ns": t.first_t_ns, "t_last_ns": t.last_t_ns,
        "span_s": t.span_s(),
        "rate": {"nominal_hz": t.rate_hz(), "median_interval_ns": t.median_ns,
                 "resolution_ns": t.resolution_ns, "mean_interval_ns": t.mean_ns,
                 "reference_interval_ns": t.reference_ns,
                 "first_tenth_hz": tenth.map(|x| x.0), "last_tenth_hz": tenth.map(|x| x.1),
                 "drift_ppm": t.drift_ppm()},
        "jitter": {"sd_ns": t.sd_ns, "robust_sd_ns": t.robust_sd_ns},
        "histogram": histogram,
        "gaps": gaps, "duplicates": duplicates, "out_of_order": events(&t.out_of_order),
        "bad_rows": {"count": a.bad_rows.count, "first": a.bad_rows.first.iter()
            .map(|b| json!({"at": b.at.to_string(), "line": line(&b.at), "message": b.message}))
            .collect::<Vec<_>>()},
        "stopped": a.stopped,
        "non_finite": {"count": a.non_finite.count, "first": a.non_finite.first.iter()
            .map(|(i, at)| json!({"index": i, "at": at.to_string(), "line": line(at)}))
            .collect::<Vec<_>>()},
        "axes": a.axes.iter().flatten().map(|x| axis(x, t.samples)).collect::<Vec<_>>(),
        "units": a.units.as_ref().map(|u| json!({
            "samples": u.samples, "gravity_median_m_s2": u.gravity_median_m_s2,
            "gyro_median_rad_s": u.gyro_median_rad_s,
            "gyro_scale": u.gyro_scale.map(|s| {
                let [d, one, rad] = s.median_error.map(f64::to_degrees);
                json!({"pairs": s.pairs,
                       "misfit_deg": {"deg_per_s": d, "as_read": one, "rad_per_s": rad}})
            }),
            "error": u.error})),
        "still": {"window_samples": a.still.window, "windows": a.still.windows,
                  "still": a.still.still, "fraction": a.still.fraction()},
    })
}

/// The human summary: the verdict, the findings, and the Δt histogram.
pub fn to_text(r: &AuditRun) -> String {
    let a = &r.audit;
    let mut s = format!("{} (read as {})\n", r.imu, r.source.describe());
    let verdict = if a.is_clean() { "clean" } else { "DEFECTS" };
    let _ = writeln!(
        s,
        "verdict: {verdict} ({} defects, {} warnings)",
        a.count(Severity::Defect),
        a.count(Severity::Warning)
    );
    for f in &a.findings {
        let _ = writeln!(s, "  {:<7} {:<13} {}", f.severity, f.kind, f.message);
    }
    let t = &a.timing;
    if let Some(r) = t.reference_ns {
        let _ = writeln!(s, "Δt histogram (multiples of the reference {r} ns):");
        let mut from = 0.0;
        for (&to, &n) in HISTOGRAM_EDGES.iter().zip(&t.histogram) {
            if n > 0 {
                let _ = writeln!(s, "  ({from:>5}, {to:>5}]  {n}");
            }
            from = to;
        }
    }
    s
}

/// Runs `preint audit`; with `--strict`, a defect is an error (exit 2) listing the defects.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    if args.strict && !r.audit.is_clean() {
        let defects: Vec<String> = r.audit.defects().map(|f| f.message.clone()).collect();
        return Err(CliError::Failed(format!(
            "{}: audit found {} defects (--strict): {}",
            r.imu,
            defects.len(),
            defects.join(" | ")
        )));
    }
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}
