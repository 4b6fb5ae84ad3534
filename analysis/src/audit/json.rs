//! The JSON form of `preint audit` (keys in the module docs of [`super`]).

use super::{AuditRun, Report};
use crate::recording::input_json;
use preint_io::Location;
use preint_io::audit::{
    AXES, Audit, AxisReport, BadRow, Event, EventList, FlatTop, HISTOGRAM_EDGES, Severity,
    SplitAudit, Timing, Verdict,
};
use serde_json::{Map, Value, json};

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

/// The timing keys of the module docs, from `samples` to `out_of_order`.
fn timing_json(t: &Timing) -> Map<String, Value> {
    let mut from = 0.0;
    let histogram: Vec<Value> = (HISTOGRAM_EDGES.iter().zip(&t.histogram))
        .map(|(&to, &count)| {
            // The last bin is open above: it has no `to`.
            let mut bin = json!({"from": from, "count": count});
            if to.is_finite() {
                bin["to"] = json!(to);
            }
            from = to;
            bin
        })
        .collect();
    let mut gaps = events(&t.gaps);
    gaps["missing_samples"] = json!(t.missing_samples);
    gaps["largest"] = t.largest_gap.as_ref().map_or(Value::Null, event);
    gaps["long"] = events(&t.long_gaps);
    let tenth = t.tenth_rates_hz;
    // Fewer than two samples have no interval: no rate, no jitter (`null` as a whole).
    let intervals = t.samples >= 2;
    let rate = intervals.then(|| {
        json!({"nominal_hz": t.rate_hz(), "median_interval_ns": t.median_ns,
               "resolution_ns": t.resolution_ns, "mean_interval_ns": t.mean_ns,
               "reference_interval_ns": t.reference_ns,
               "first_tenth_hz": tenth.map(|x| x.0), "last_tenth_hz": tenth.map(|x| x.1),
               "drift_ppm": t.drift_ppm()})
    });
    let jitter = intervals.then(|| json!({"sd_ns": t.sd_ns, "robust_sd_ns": t.robust_sd_ns}));
    let v = json!({
        "samples": t.samples, "t_first_ns": t.first_t_ns, "t_last_ns": t.last_t_ns,
        "span_s": t.span_s(),
        "rate": rate,
        "jitter": jitter,
        "histogram": histogram,
        "gaps": gaps, "duplicates": events(&t.duplicates), "out_of_order": events(&t.out_of_order),
    });
    match v {
        Value::Object(m) => m,
        _ => Map::new(),
    }
}

/// `bad_rows`, `stopped` and `non_finite` of the module docs, added to `m`.
fn reading_json(
    m: &mut Map<String, Value>,
    bad_rows: &EventList<BadRow>,
    stopped: &Option<String>,
    non_finite: &EventList<(u64, Location)>,
) {
    let bad: Vec<Value> = (bad_rows.first.iter())
        .map(|b| json!({"at": b.at.to_string(), "line": line(&b.at), "message": b.message}))
        .collect();
    let nf: Vec<Value> = (non_finite.first.iter())
        .map(|(i, at)| json!({"index": i, "at": at.to_string(), "line": line(at)}))
        .collect();
    m.insert(
        "bad_rows".into(),
        json!({"count": bad_rows.count, "first": bad}),
    );
    m.insert("stopped".into(), json!(stopped));
    m.insert(
        "non_finite".into(),
        json!({"count": non_finite.count, "first": nf}),
    );
}

/// `impossible` and `spikes` of the module docs, added to `m`.
fn readings_json(m: &mut Map<String, Value>, a: &Audit) {
    let impossible: Vec<Value> = (a.impossible.first.iter())
        .map(|e| json!({"index": e.index, "at": e.at.to_string(), "line": line(&e.at), "what": e.what}))
        .collect();
    let spikes: Vec<Value> = (a.spikes.first.iter())
        .map(|e| {
            json!({"index": e.index, "at": e.at.to_string(), "line": line(&e.at),
                   "axis": AXES[e.axis].0, "value": e.value, "sigmas": e.sigmas})
        })
        .collect();
    m.insert(
        "impossible".into(),
        json!({"count": a.impossible.count, "first": impossible}),
    );
    m.insert(
        "spikes".into(),
        json!({"count": a.spikes.count, "first": spikes}),
    );
}

fn single_json(a: &Audit) -> Map<String, Value> {
    let mut m = timing_json(&a.timing);
    m["duplicates"]["identical"] = json!(a.identical_duplicates);
    reading_json(&mut m, &a.bad_rows, &a.stopped, &a.non_finite);
    readings_json(&mut m, a);
    let axes: Vec<Value> = (a.axes.iter().flatten())
        .map(|x| axis(x, a.timing.samples))
        .collect();
    m.insert("axes".into(), json!(axes));
    let units = a.units.as_ref().map(|u| {
        json!({"samples": u.samples, "gravity_median_m_s2": u.gravity_median_m_s2,
               "raw_gravity_median_m_s2": u.raw_gravity_median_m_s2,
               "gyro_median_rad_s": u.gyro_median_rad_s,
               "gyro_scale": u.gyro_scale.map(|s| {
                   let [d, one, rad] = s.median_error.map(f64::to_degrees);
                   json!({"pairs": s.pairs,
                          "misfit_deg": {"deg_per_s": d, "as_read": one, "rad_per_s": rad}})
               }),
               "gyro_axes": u.gyro_axes.as_ref().map(axes_json),
               "error": u.error,
               "verdict": u.verdict.as_ref().map_or("failed", |v| v.name()),
               "why": u.verdict.as_ref().and_then(|v| v.why())})
    });
    m.insert("units".into(), json!(units));
    let st = &a.still;
    m.insert(
        "still".into(),
        json!({"window_samples": st.window, "windows": st.windows, "still": st.still,
               "fraction": st.fraction()}),
    );
    m
}

/// The JSON of a split recording's audit (keys in the module docs, after `split`).
pub fn split_json(a: &SplitAudit) -> Map<String, Value> {
    let mut m = Map::new();
    for c in [&a.gyro, &a.accel] {
        let mut t = timing_json(&c.timing);
        reading_json(&mut t, &c.bad_rows, &c.stopped, &c.non_finite);
        m.insert(c.sensor.to_string(), Value::Object(t));
    }
    let o = &a.offsets;
    m.insert(
        "offsets".into(),
        json!({"count": o.count, "mean_ns": o.mean_ns, "sd_ns": o.sd_ns, "min_ns": o.min_ns,
               "max_ns": o.max_ns, "coincident": o.coincident, "accel_before": o.accel_before,
               "accel_after": o.accel_after, "gyro_before": o.gyro_before,
               "gyro_after": o.gyro_after}),
    );
    m
}

/// The JSON form (keys in the module docs); `no_unit_check` as `--no-unit-check`.
pub fn to_json(r: &AuditRun, no_unit_check: bool) -> Value {
    let findings: Vec<Value> = (r.findings().iter())
        .map(|f| json!({"severity": f.severity.to_string(), "kind": f.kind, "message": f.message}))
        .collect();
    let defects = r.count(Severity::Defect);
    let mut m = Map::new();
    m.insert("imu".into(), json!(r.imu));
    if let Some(s) = &r.source {
        m.insert("input".into(), input_json(s, &r.unit_check(no_unit_check)));
    }
    m.insert("split".into(), json!(matches!(r.report, Report::Split(_))));
    m.insert("verdict".into(), json!(r.verdict().name()));
    m.insert("clean".into(), json!(r.verdict() == Verdict::Clean));
    m.insert("defects".into(), json!(defects));
    m.insert("warnings".into(), json!(r.count(Severity::Warning)));
    m.insert("findings".into(), json!(findings));
    m.insert(
        "calibration".into(),
        json!(r.calibration.as_ref().map(|(name, c)| json!({
            "file": name, "model": c.intrinsics.model.name(), "time_offset_s": c.time_offset_s,
        }))),
    );
    m.extend(match &r.report {
        Report::Single(a) => single_json(a),
        Report::Split(a) => split_json(a),
    });
    Value::Object(m)
}

/// `units.gyro_axes`: `{pairs, median_turn_deg, unexplained_as_read, best_other: {map,
/// unexplained}, verdict: agree|mismatch|cannot tell, text}` (fractions of the turn).
fn axes_json(a: &preint_io::plausibility::axes::AxisFit) -> Value {
    use preint_io::plausibility::axes::AxisVerdict;
    let (verdict, text) = match a.verdict() {
        AxisVerdict::Agree => (
            "agree",
            "the gyro's axes are the accelerometer's".to_string(),
        ),
        AxisVerdict::Mismatch(m) => ("mismatch", m),
        AxisVerdict::CannotTell(m) => ("cannot tell", m),
    };
    json!({"pairs": a.pairs, "median_turn_deg": a.median_turn_rad.to_degrees(),
           "unexplained_as_read": a.identity,
           "best_other": {"map": a.best_other.0.describe(), "unexplained": a.best_other.1},
           "verdict": verdict, "text": text})
}
