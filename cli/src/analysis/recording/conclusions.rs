//! The statements at the top of the `report --imu` page, each computed from the figures.

use super::{
    ADVISE_WINDOW_FRACTION, Consistency, RecordingData, StaticCheck, TruthCheck, still_fraction,
};
use crate::analysis::report::worst_ratio;
use crate::scheme;
use preint_analysis::audit::{AuditRun, Report};
use preint_analysis::calibrate::Calibration;
use preint_analysis::calibrate::noise_model;
use preint_io::audit::{Severity, Timing, Verdict};

/// The timing of the recording (the gyroscope's of a split one).
pub fn timing(a: &AuditRun) -> &Timing {
    match &a.report {
        Report::Single(a) => &a.timing,
        Report::Split(a) => &a.gyro.timing,
    }
}

/// Rate \[Hz\] (1 / median interval) and span \[s\] of the recording, when known.
pub fn rate_span(a: &AuditRun) -> Option<(f64, f64)> {
    let t = timing(a);
    let rate = 1e9 / t.median_ns?;
    let span = (t.last_t_ns? - t.first_t_ns?) as f64 * 1e-9;
    Some((rate, span))
}

fn audit_statement(d: &RecordingData) -> String {
    let a = &d.audit;
    let (defects, warnings) = (a.count(Severity::Defect), a.count(Severity::Warning));
    let what = rate_span(a).map_or(String::new(), |(rate, span)| {
        format!(
            " ({} samples at {rate:.1} Hz over {span:.1} s)",
            timing(a).samples
        )
    });
    match a.verdict() {
        Verdict::Clean => format!(
            "Audit: clean{what}, no defect and {warnings} warning{}.",
            if warnings == 1 { "" } else { "s" }
        ),
        Verdict::Defects => {
            let first = a
                .findings()
                .iter()
                .find(|f| f.severity == Severity::Defect)
                .map_or("", |f| f.message.as_str());
            format!(
                "Audit: DEFECTS{what}: {defects} defect{} (first: {first}); the figures below \
                 are computed on the recording as it is.",
                if defects == 1 { "" } else { "s" }
            )
        }
        Verdict::TooShort => {
            format!("Audit: too short to judge{what}; the figures below rest on few samples.")
        }
    }
}

fn advice_statement(d: &RecordingData) -> String {
    let (window, fraction) = ADVISE_WINDOW_FRACTION;
    let a = match &d.advice {
        Ok(a) => a,
        Err(e) => return format!("`preint advise` cannot answer on this recording: {e}"),
    };
    let ok = a.candidates.iter().filter(|c| c.acceptable).count();
    let mut caveats = Vec::new();
    if a.cutoffs.iter().any(Option::is_none) {
        caveats.push(
            "no low-pass cutoff leaves white noise of the densities used on every sensor \
             (vibration, or densities set too low), so that content counts as motion here",
        );
    }
    if d.still.is_some() {
        caveats.push("the recording is static: there is little motion to discretise");
    }
    let caveat = if caveats.is_empty() {
        String::new()
    } else {
        format!(" Caveat: {}.", caveats.join("; "))
    };
    let statement = match a.recommendation() {
        Some(c) => format!(
            "On its own motion this recording needs `{}` at {:.1} Hz with keyframes {window} s \
             apart: its worst discretisation error is {:.3}·σ of the noise (threshold \
             {fraction}·σ), at {:.1} µs per second of data on this machine; {ok} of {} \
             (scheme, rate) pairs are acceptable.",
            scheme::label(c.scheme),
            c.rate_hz,
            worst_ratio(c),
            c.cost_ns_per_s * 1e-3,
            a.candidates.len()
        ),
        None => format!(
            "On its own motion no scheme keeps the discretisation error over {window} s \
             keyframes below {fraction}·σ at the rates evaluated: use `hermite4` at the full \
             rate, or record faster."
        ),
    };
    statement + &caveat
}

/// `χ²/dof` means per length, as `0.5 s: 1.02, 1 s: 1.10`.
fn per_length(c: &Consistency) -> String {
    let parts: Vec<String> = c
        .lengths
        .iter()
        .filter_map(|l| {
            let s = l.stats.as_ref()?;
            Some(format!("{} s: {:.2}", l.length_s, s.mean / l.dof as f64))
        })
        .collect();
    if parts.is_empty() {
        "no length has 2 windows".into()
    } else {
        format!("mean χ²/dof {}", parts.join(", "))
    }
}

fn truth_statements(d: &RecordingData, t: &TruthCheck) -> Vec<String> {
    let n = &t.fitted.model.noise;
    let g = &d.noise.0;
    let fit = noise_model::fit(&t.fit);
    let after = (t.fit.fit.per_length.iter()).map(|l| l.after);
    let (lo, hi) = after.fold((f64::INFINITY, 0.0_f64), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    vec![
        format!(
            "With the given noise ({}), the IMU factor at the ground truth is {} ({}).",
            d.noise.1,
            t.given.verdict.text(),
            per_length(&t.given)
        ),
        format!(
            "With the fitted noise (gyro {:.3e} rad/s/√Hz, ×{:.2} the given; accelerometer \
             {:.3e} m/s²/√Hz, ×{:.2}; fit {}, χ²/dof {lo:.2} to {hi:.2} over the lengths; {}), \
             the `ImuFactor` weighted with the bias random walk within each window is {} ({}); \
             the fitted model is written to `{}`.",
            n.gyro_noise_density,
            n.gyro_noise_density / g.gyro_noise_density,
            n.acc_noise_density,
            n.acc_noise_density / g.acc_noise_density,
            if fit.credible {
                "credible"
            } else {
                "not credible"
            },
            gravity_text(&t.fit),
            t.fitted.verdict.text(),
            per_length(&t.fitted),
            super::FITTED_YAML
        ),
    ]
}

/// The fitted world gravity's tilt, or why the given gravity stands.
fn gravity_text(r: &preint_analysis::calibrate::noise_model::NoiseRun) -> String {
    match &r.fit.gravity {
        Some(g) if g.supported => format!(
            "world gravity tilted {:.3} ± {:.3}° from the given",
            g.tilt_from(&r.gravity_given).to_degrees(),
            g.tilt_std_from(&r.gravity_given).to_degrees()
        ),
        _ => "the given gravity".into(),
    }
}

fn static_statements(d: &RecordingData, s: &StaticCheck) -> Vec<String> {
    let still = 100.0 * still_fraction(&d.audit);
    let allan = match &s.allan {
        Ok(r) => {
            let n = r.allan.to_imu_noise();
            format!(
                "Static recording (still in {still:.0} % of the audit's windows): the Allan \
                 deviation gives gyro N = {:.3e} rad/s/√Hz, K = {:.3e} rad/s²/√Hz and \
                 accelerometer N = {:.3e} m/s²/√Hz, K = {:.3e} m/s³/√Hz (max over the axes, \
                 written to `{}`).",
                n.gyro_noise_density,
                n.gyro_random_walk,
                n.acc_noise_density,
                n.acc_random_walk,
                super::ALLAN_YAML
            )
        }
        Err(e) => format!(
            "Static recording (still in {still:.0} % of the audit's windows), but the Allan \
             deviation cannot be computed: {e}"
        ),
    };
    let cal = match &s.calibration {
        Ok(r) => match &r.calibrated.calibration {
            Calibration::Static { c, used, .. } => format!(
                "Static calibration on the longest still interval ({:.1} s): gyro bias ({:.3e}, \
                 {:.3e}, {:.3e}) rad/s, σ ≤ {:.1e}; roll {:.2}°, pitch {:.2}°; fit {}.",
                used.duration_s(),
                c.gyro_bias.x,
                c.gyro_bias.y,
                c.gyro_bias.z,
                c.gyro_bias_std.max(),
                c.roll.to_degrees(),
                c.pitch.to_degrees(),
                if r.calibrated.fit.credible {
                    "credible"
                } else {
                    "not credible"
                }
            ),
            other => format!(
                "The {} was chosen for this recording (still intervals at several attitudes).",
                other.problem()
            ),
        },
        Err(e) => format!("The static calibration cannot answer: {e}"),
    };
    vec![allan, cal]
}

/// The conclusions, in the order of the page's sections.
pub fn conclusions(d: &RecordingData) -> Vec<String> {
    let mut c = vec![audit_statement(d), advice_statement(d)];
    match &d.truth {
        Some(t) => c.extend(truth_statements(d, t)),
        None => c.push(
            "No ground truth given (`--poses`): the noise model's consistency is not tested."
                .into(),
        ),
    }
    match &d.still {
        Some(s) => c.extend(static_statements(d, s)),
        None => c.push(format!(
            "Still in {:.0} % of the audit's windows: not a static recording, so no Allan \
             deviation (it would describe the motion, not the sensor).",
            100.0 * still_fraction(&d.audit)
        )),
    }
    c
}
