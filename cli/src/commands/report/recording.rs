//! `preint report --imu FILE`: the page on the user's recording (the numbers:
//! [`crate::analysis::recording`]). After the conclusions box: the audit's findings, the scheme
//! and rate the motion needs, with `--poses` the consistency of the given and of the fitted
//! noise model per window length and the fitted parameters (their Kalibr `imu.yaml` linked),
//! and for a static recording the Allan deviation and the static calibration.

use super::sections::{Advised, advice_rows, allan_charts};
use super::{Args, failed};
use crate::analysis::recording::{
    self, ADVISE_WINDOW_FRACTION, ALLAN_YAML, Consistency, FITTED_YAML, Options, RecordingData,
    StaticCheck, TruthCheck, WINDOWS_S,
};
use crate::charts::figures;
use crate::html::Page;
use crate::{CliError, Output, scheme};
use preint_analysis::calibrate::Calibration;
use preint_analysis::calibrate::noise_model::{self, KEYS};
use preint_analysis::chi2_windows::{length_json, verdict_json};
use preint_analysis::format::IMU_AXES;
use preint_calib::noise_fit::Withheld;
use serde_json::{Value, json};
use std::path::Path;

/// The report's options from the flags: `None` without `--imu` (the built-in scenes); a flag
/// that needs a recording without one is a usage error.
pub fn options(args: &Args) -> Result<Option<Options>, CliError> {
    let truth = [
        args.pose_rot_std,
        args.pose_pos_std,
        args.vel_std,
        args.bias_gyro_std,
        args.bias_acc_std,
    ];
    let Some(input) = &args.input else {
        let given = [
            ("--poses", args.poses.is_some()),
            ("--noise", args.noise.is_some()),
            ("--pose-rot-std", truth[0].is_some()),
            ("--pose-pos-std", truth[1].is_some()),
            ("--vel-std", truth[2].is_some()),
            ("--bias-gyro-std", truth[3].is_some()),
            ("--bias-acc-std", truth[4].is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, g)| *g) {
            return Err(CliError::Usage(format!(
                "{flag} needs --imu FILE: it applies to a recording (preint report --imu FILE \
                 --poses GT); without --imu the report runs on the built-in scenes"
            )));
        }
        return Ok(None);
    };
    if input.imu.is_none() && input.gyro.is_none() {
        return Err(CliError::Usage(
            "the reader flags (--format, --columns, --stamp, …) need --imu FILE (or --gyro \
             FILE --accel FILE): the recording to report on"
                .into(),
        ));
    }
    Ok(Some(Options {
        input: input.to_input(),
        poses: args.poses.clone(),
        noise: args.noise.clone(),
        truth,
        out: args.out.clone(),
    }))
}

/// The report on a recording: its numbers, conclusions and the files written.
#[derive(Clone, Debug)]
pub struct RecordingReport {
    /// The numbers.
    pub data: RecordingData,
    /// The conclusions drawn from them.
    pub conclusions: Vec<String>,
    /// The charts and files written, then `index.html`.
    pub files: Vec<String>,
}

/// Computes the numbers (with a progress bar at a terminal) and writes the page into `out`.
pub fn compute(o: &Options) -> Result<RecordingReport, CliError> {
    let out = &o.out;
    std::fs::create_dir_all(out).map_err(|e| CliError::out_path(out, e))?;
    let data = super::with_progress(recording::STEPS, |step| recording::compute(o, step))?;
    let conclusions = recording::conclusions(&data);
    let files = write_page(&data, &conclusions, out)?;
    Ok(RecordingReport {
        data,
        conclusions,
        files,
    })
}

/// Writes the charts and `index.html` into `out`; returns the files written (the page last).
pub fn write_page(
    d: &RecordingData,
    conclusions: &[String],
    out: &Path,
) -> Result<Vec<String>, CliError> {
    let mut page = Page::new(&format!("preint report: {}", d.imu));
    let m = &d.machine;
    page.p(&format!(
        "Every figure below is computed by `preint report --imu` (preint {}) from the recording \
         `{}`; costs are timings on this machine ({}, {} logical cores). Noise densities given: \
         {}. Conventions: z-up world, g = (0, 0, −9.81) m/s², right perturbations, tangent \
         order [δφ, δv, δp], bias order [b_g, b_a].",
        env!("CARGO_PKG_VERSION"),
        d.imu,
        m.cpu,
        m.cores,
        d.noise.1
    ));
    page.conclusions(conclusions).toc();
    audit_section(&mut page, d);
    let mut files = advice_section(&mut page, d, out)?;
    if let Some(t) = &d.truth {
        consistency_section(&mut page, t);
        fit_section(&mut page, t);
        files.push(out.join(FITTED_YAML).display().to_string());
    }
    if let Some(s) = &d.still {
        files.extend(static_section(&mut page, s, out)?);
    }
    let index = out.join("index.html");
    page.write(&index).map_err(failed)?;
    files.push(index.display().to_string());
    Ok(files)
}

fn audit_section(page: &mut Page, d: &RecordingData) {
    page.h2("Audit: what is wrong with the recording");
    page.p("`preint audit` in one streaming pass: rate and its drift, Δt jitter, gaps, duplicate and out-of-order samples, unreadable rows, non-finite readings, clipping, unit plausibility and the fraction of time the sensor is still. Its findings, defects first:");
    let rows: Vec<Vec<String>> = (d.audit.findings().iter())
        .map(|f| {
            vec![
                f.severity.to_string(),
                f.kind.to_string(),
                f.message.clone(),
            ]
        })
        .collect();
    page.table(&["severity", "kind", "finding"], &rows);
}

fn advice_section(page: &mut Page, d: &RecordingData, out: &Path) -> Result<Vec<String>, CliError> {
    let (window, fraction) = ADVISE_WINDOW_FRACTION;
    page.h2("Which scheme and rate this motion needs");
    let a = match &d.advice {
        Ok(a) => a,
        Err(e) => {
            page.p(&format!(
                "`preint advise` cannot answer on this recording: {e}"
            ));
            return Ok(Vec::new());
        }
    };
    page.p(&format!("`preint advise` on the recording itself: the white noise of {} is removed by a zero-phase low-pass, each scheme's discretisation error over {window} s windows (keyframes {window} s apart) is measured at the recording's rate and at decimated rates against `hermite4` at the full rate, and compared with the noise-induced σ of the preintegrated deltas. Acceptable: all three errors (rotation, velocity, position) below {fraction}·σ; recommended: the cheapest acceptable (scheme, rate). Costs are this machine's.", d.advice_noise));
    let name = "recording";
    let scenes: Vec<Advised> = vec![(name, a.candidates.as_slice(), a.recommended)];
    let path = out.join("advise.svg");
    figures::advice(&scenes, fraction, &path)?;
    page.svg(&path, &format!("Worst ratio of discretisation error to noise σ (over rotation, velocity and position) against rate; below the grey dashed line ({fraction}·σ) a (scheme, rate) is acceptable; the black ring marks the recommendation.")).map_err(failed)?;
    let rate = a.candidates.iter().map(|c| c.rate_hz).fold(0.0, f64::max);
    page.p("Per scheme, its lowest acceptable rate:");
    page.table(
        &[
            "recording",
            "scheme",
            "rate [Hz]",
            "worst error / σ",
            "cost [µs per s of data]",
            "",
        ],
        &advice_rows(&scenes, rate),
    );
    let cut = |c: Option<f64>| c.map_or("none".into(), |c| format!("{c:.2} Hz"));
    page.p(&format!(
        "Low-pass cutoffs found: gyro {}, accelerometer {}.",
        cut(a.cutoffs[0]),
        cut(a.cutoffs[1])
    ));
    Ok(vec![path.display().to_string()])
}

fn e3(x: f64) -> String {
    format!("{x:.3e}")
}

/// One row per window length: count, skipped, mean and median χ², χ²/dof, fraction above the
/// 0.99 quantile, KS p-value.
fn consistency_rows(c: &Consistency) -> Vec<Vec<String>> {
    (c.lengths.iter())
        .map(|l| {
            let head = vec![
                format!("{}", l.length_s),
                l.count.to_string(),
                l.skipped.to_string(),
            ];
            let stats = match &l.stats {
                Some(s) => vec![
                    format!("{:.3}", s.mean),
                    format!("{:.3}", s.median),
                    format!("{:.3}", s.mean / l.dof as f64),
                    format!("{:.1} %", 100.0 * s.fraction_above_p99),
                    s.ks_p_value.map_or("—".into(), |p| format!("{p:.2e}")),
                ],
                None => vec![
                    "fewer than 2 windows".into(),
                    "".into(),
                    "".into(),
                    "".into(),
                    "".into(),
                ],
            };
            head.into_iter().chain(stats).collect()
        })
        .collect()
}

/// A noise model in one sentence: its densities and the ground truth's errors.
fn model_text(c: &Consistency) -> String {
    let (n, t, g) = (&c.model.noise, &c.model.truth, &c.model.gravity);
    format!(
        "gyro {} rad/s/√Hz, accelerometer {} m/s²/√Hz, random walks {} rad/s²/√Hz and {} \
         m/s³/√Hz; ground-truth errors {} rad, {} m, {} m/s, biases {} rad/s and {} m/s²; \
         gravity ({:.4}, {:.4}, {:.4}) m/s²; weight {}",
        e3(n.gyro_noise_density),
        e3(n.acc_noise_density),
        e3(n.gyro_random_walk),
        e3(n.acc_random_walk),
        e3(t.rot_rad),
        e3(t.pos_m),
        e3(t.vel_m_s),
        e3(t.bias_gyro_rad_s),
        e3(t.bias_acc_m_s2),
        g[0],
        g[1],
        g[2],
        if c.model.in_window_drift {
            "with the bias random walk within the window (`factor --in-window-drift`)"
        } else {
            "the white noise alone (GTSAM's `ImuFactor`)"
        }
    )
}

fn consistency_section(page: &mut Page, t: &TruthCheck) {
    let lengths: Vec<String> = WINDOWS_S.iter().map(|l| format!("{l}")).collect();
    page.h2("Consistency of the noise model per window length");
    page.p(&format!("`ImuFactor` (midpoint, 9 dof) evaluated at the ground truth over back-to-back windows of {} s between the ground-truth rows nearest to their edges, as `preint factor --window` does, weighted by the factor's covariance plus the ground truth's own errors through its Jacobians. A consistent model gives χ²/dof ≈ 1, about 1 % of windows above χ²₉(0.99) and a Kolmogorov–Smirnov p-value that is not small. Span: {:.1} s.", lengths.join(", "), (t.given.span_ns.1 - t.given.span_ns.0) as f64 * 1e-9));
    let header = [
        "length [s]",
        "windows",
        "skipped",
        "mean χ²",
        "median χ²",
        "χ²/dof",
        "above χ²₉(0.99)",
        "KS p",
    ];
    for (what, c) in [("given", &t.given), ("fitted", &t.fitted)] {
        page.p(&format!(
            "With the {what} noise model ({}): {}.",
            model_text(c),
            c.verdict.text()
        ));
        page.table(&header, &consistency_rows(c));
    }
}

fn fit_section(page: &mut Page, t: &TruthCheck) {
    let r = &t.fit;
    let n: usize = r.fit.per_length.iter().map(|l| l.count).sum();
    let fit = noise_model::fit(r);
    page.h2("Fitted noise model");
    page.p(&format!("`preint calibrate --estimate noise`: maximum likelihood over {n} `ImuFactor` windows at the ground truth ({} Fisher-scoring iterations, χ²/dof {:.3} after the fit, {}). A ground-truth error given on the command line is held; the others are fitted.", r.fit.iterations, fit.chi2_dof, if fit.credible { "credible" } else { "not credible" }));
    let rows: Vec<Vec<String>> = (r.fit.params.iter().enumerate())
        .map(|(k, p)| {
            let unit = p.param.unit();
            let (value, std, note) = match p.withheld {
                None => (e3(p.value), format!("{:.1e}", p.std), String::new()),
                Some(Withheld::Held) => (e3(p.value), String::new(), "held".into()),
                Some(w) => (String::new(), String::new(), w.reason(unit)),
            };
            vec![format!("`{}`", KEYS[k]), value, std, unit.into(), note]
        })
        .collect();
    page.table(&["parameter", "value", "σ", "unit", "note"], &rows);
    let rows: Vec<Vec<String>> = (r.fit.per_length.iter().zip(&r.skipped))
        .map(|(l, (_, skipped))| {
            vec![
                format!("{}", l.length_s),
                l.count.to_string(),
                skipped.to_string(),
                format!("{:.3}", l.before),
                format!("{:.3}", l.after),
            ]
        })
        .collect();
    if let (Some(g), Some(v)) = (&r.fit.gravity, noise_model::fitted_gravity(r)) {
        let g0 = r.gravity_given;
        page.p(&format!("World gravity fitted with the densities (the ground truth's frame need not be levelled): ({:.4}, {:.4}, {:.4}) ± {:.1e} m/s², {:.3} ± {:.3}° from ({}, {}, {}); likelihood ratio {:.1} against the information criterion's {:.1}: {}.", v[0], v[1], v[2], g.std().max(), g.tilt_from(&g0).to_degrees(), g.tilt_std_from(&g0).to_degrees(), g0[0], g0[1], g0[2], g.lr, g.penalty, if g.supported { "kept, and used by the fitted model's consistency above" } else { "not supported, the given gravity kept" }));
    }
    page.p(&format!(
        "The ground truth in time: {}.",
        preint_analysis::calibrate::noise_correlation::verdict(&r.time_correlation)
    ));
    page.p("The fit's own χ²/dof per window length, at the given model and at the fitted one. Its window covariance carries the bias random walk within each window (the bias held at its value at i while the true bias drifts): the fitted model's consistency above uses the same weight (`ImuFactor::with_in_window_drift`); GTSAM's `ImuFactor`, weighted by the white noise alone, leaves it out.");
    page.table(
        &[
            "length [s]",
            "windows",
            "skipped",
            "χ²/dof given",
            "χ²/dof fitted",
        ],
        &rows,
    );
    page.p_link(
        "The fitted densities as a Kalibr imu.yaml (a withheld density at its start value), for `--noise`:",
        FITTED_YAML,
    );
}

fn static_section(page: &mut Page, s: &StaticCheck, out: &Path) -> Result<Vec<String>, CliError> {
    page.h2("Allan deviation of the static recording");
    let mut files = Vec::new();
    match &s.allan {
        Ok(r) => {
            page.p(&format!("`preint allan`: {} samples at {:.1} Hz ({:.0} s). The fitted white-noise line (slope −½) read at τ = 1 s gives the noise density N, the random-walk line (slope +½) read at τ = 3 s gives K.", r.samples, 1.0 / r.allan.dt, r.allan.dt * r.samples as f64));
            files = allan_charts(page, &r.allan, out)?;
            let rows: Vec<Vec<String>> = (0..6)
                .map(|c| {
                    let f = &r.allan.fits[c];
                    let bound = |b: bool| if b { "≤ " } else { "" };
                    vec![
                        format!("`{}`", IMU_AXES[c]),
                        format!("{}{}", bound(f.white_density_is_bound), e3(f.white_density)),
                        format!("{}{}", bound(f.random_walk_is_bound), e3(f.random_walk)),
                        e3(f.bias_instability),
                    ]
                })
                .collect();
            page.p("Per axis (gyro: N in rad/s/√Hz, K in rad/s²/√Hz, bias instability in rad/s; accelerometer: m/s²/√Hz, m/s³/√Hz, m/s²; ≤: an upper bound, no region of that slope in the data):");
            page.table(&["axis", "N", "K", "bias instability"], &rows);
            page.p_link(
                "The densities (max over the axes) as a Kalibr imu.yaml:",
                ALLAN_YAML,
            );
            files.push(out.join(ALLAN_YAML).display().to_string());
        }
        Err(e) => {
            page.p(&format!("`preint allan` cannot answer: {e}"));
        }
    }
    calibration_section(page, s);
    Ok(files)
}

fn calibration_section(page: &mut Page, s: &StaticCheck) {
    page.h2("Static calibration");
    let r = match &s.calibration {
        Ok(r) => r,
        Err(e) => {
            page.p(&format!("`preint calibrate` cannot answer: {e}"));
            return;
        }
    };
    let Calibration::Static { c, used, .. } = &r.calibrated.calibration else {
        page.p(&format!(
            "`preint calibrate` chose the {} (run it for its estimates).",
            r.calibrated.calibration.problem()
        ));
        return;
    };
    let rows: Vec<Vec<String>> = (0..3)
        .map(|k| {
            vec![
                ["x", "y", "z"][k].into(),
                format!("{:.6}", c.gyro_bias[k]),
                format!("{:.1e}", c.gyro_bias_std[k]),
            ]
        })
        .collect();
    let fit = &r.calibrated.fit;
    page.p(&format!("`preint calibrate` on the longest still interval ({:.1} s, {} samples), weighted with the Allan densities unless `--noise` is given: gyro bias [rad/s] with its σ; roll {:.3}° ± {:.3}°, pitch {:.3}° ± {:.3}°; fit χ²/dof {:.3} ({}).", used.duration_s(), c.samples, c.roll.to_degrees(), c.roll_std.to_degrees(), c.pitch.to_degrees(), c.pitch_std.to_degrees(), fit.chi2_dof, if fit.credible { "credible" } else { "not credible" }));
    page.table(&["axis", "b_g", "σ"], &rows);
    page.p(&format!("`acc_bias`: {}", c.acc_bias_note));
}

/// The JSON form: the files, the conclusions and a summary (audit verdict, `advise`'s
/// recommendation, the consistency per length with both models, the noise fit, the static
/// results).
pub fn to_json(r: &RecordingReport) -> Value {
    let d = &r.data;
    let a = &d.audit;
    let rec = d.advice.as_ref().ok().and_then(|a| a.recommendation());
    let audit = preint_analysis::audit::to_json(a, d.no_unit_check);
    let mut summary = json!({
        "imu": d.imu,
        "audit": {"verdict": audit["verdict"], "clean": audit["clean"],
                  "defects": audit["defects"], "warnings": audit["warnings"],
                  "still_fraction": recording::still_fraction(a)},
        "advise": {"recommended_scheme": rec.map(|c| scheme::label(c.scheme)),
                   "recommended_rate": rec.map(|c| c.rate_hz),
                   "error": d.advice.as_ref().err()},
        "machine": {"cpu": d.machine.cpu, "cores": d.machine.cores},
        "version": env!("CARGO_PKG_VERSION"),
    });
    if let Some(t) = &d.truth {
        let c = |c: &Consistency| {
            json!({"windows": c.lengths.iter().map(length_json).collect::<Vec<_>>(),
                   "verdict": verdict_json(&c.verdict)})
        };
        summary["consistency"] = json!({"given": c(&t.given), "fitted": c(&t.fitted)});
        summary["noise_fit"] = noise_model::to_json(&t.fit);
    }
    if let Some(s) = &d.still {
        summary["static"] = json!({
            "allan": s.allan.as_ref().map(|r| preint_analysis::noise::densities_json(&r.allan.to_imu_noise())).unwrap_or_else(|e| json!({"error": e})),
            "calibration": s.calibration.as_ref().map(preint_analysis::calibrate::to_json).unwrap_or_else(|e| json!({"error": e})),
        });
    }
    json!({"files": r.files, "conclusions": r.conclusions, "summary": summary})
}

/// Runs `preint report --imu`.
pub fn run(o: &Options) -> Result<Output, CliError> {
    let r = compute(o)?;
    Ok(Output {
        human: super::text(&r.files, &r.conclusions),
        json: to_json(&r),
    })
}
