//! `preint audit`'s findings: what is wrong with a recording, in one streaming pass in bounded memory
//! ([`preint_io::audit`]): rate and its drift, Δt histogram and jitter, gaps, duplicate and
//! out-of-order samples (with their indices and lines), unreadable rows, non-finite readings,
//! flat tops at an axis' extremes (saturation/clipping), unit plausibility and the fraction of
//! time the sensor is still.
//!
//! A split recording (`--gyro FILE --accel FILE`, or `--gyro-topic`/`--accel-topic` of a
//! container) is audited channel by channel, with the offsets of the accelerometer stamps from
//! the nearest gyro stamps ([`preint_io::audit::audit_channels`]).
//!
//! With `--calibration FILE` (one stream), the file's intrinsics correct the samples of the unit
//! checks (the accelerometer's median norm is then that of the corrected samples; timing,
//! clipping and stillness stay on the raw readings, where the sensor produced them), and the
//! file is checked against the recording: an info finding states what it applies (largest
//! scale/misalignment, axis rotation, g-sensitivity, time offset) and the accelerometer's
//! median norm corrected and raw; a warning says when the intrinsics are beyond a MEMS
//! sensor's range (10 % scale or misalignment, 0.1 rad, 0.01 (rad/s)/(m/s²)) or when, on a
//! recording still at least half of the time, the correction moves that norm further from |g|
//! than the raw one by more than 0.5 %.
//!
//! The verdict is `clean`, `DEFECTS`, or `too short to judge` (fewer than 100 samples or
//! less than 1 s: [`preint_io::audit::MIN_JUDGED_SAMPLES`]); readings beyond any IMU's
//! range are defects, single-sample spikes and unit checks that cannot decide are warnings.
//! The command line exits with status 0 with a verdict; with `--strict`, 2 when a defect is
//! found or the recording is too short to judge. With `--no-unit-check` a unit problem is a
//! warning instead of a defect.
//!
//! # JSON (`--json`, [`to_json`])
//! - `imu`, `input` (`format`, `read_as`, `notes`): the recording and how it was read;
//!   `split`: false.
//! - `verdict` (`clean`, `defects`, `too_short`), `clean` (the verdict is `clean`: no
//!   defect, long enough to judge), `defects`, `warnings`: counts; `findings`: `[{severity`
//!   (`defect`, `warning`, `info`), `kind`, `message}]`, defects first. Kinds: `empty`,
//!   `too_short`, `bad_rows`, `stopped`, `non_finite`, `impossible`, `spikes`, `duplicates`,
//!   `out_of_order`, `long_gaps`, `gaps`, `rate`, `jitter`, `drift`, `clipping`,
//!   `constant_axis`, `units`, `still`, `calibration`.
//! - `calibration`: `{file, model, time_offset_s}` of `--calibration`, or null.
//! - `samples`; `t_first_ns`, `t_last_ns` (largest stamp), `span_s`.
//! - `rate`: `nominal_hz` (1 / median Δt), `median_interval_ns`, `resolution_ns` (of the
//!   median), `mean_interval_ns` (positive intervals), `reference_interval_ns` (median of the
//!   first 32 768 samples: the unit of the histogram and the gap threshold), `first_tenth_hz`,
//!   `last_tenth_hz`, `drift_ppm` (last vs first tenth).
//! - `jitter`: `sd_ns` (standard deviation of Δt, gaps left out), `robust_sd_ns`
//!   (1.4826 × MAD).
//! - `histogram`: `[{from, to, count}]`, Δt in multiples of the reference interval, bins
//!   `(from, to]` (the last, unbounded one has no `to`).
//! - `gaps` (Δt > 1.5 × reference): `count`, `missing_samples`, `largest`, `first`, and
//!   `long` (`count`, `first`: gaps above 0.25 s). `duplicates` (`count`, `identical`,
//!   `first`), `out_of_order` (`count`, `first`). An event is `{index` (0-based sample),
//!   `at` (`line N` or `message N`), `line` (null for containers), `t_ns`, `dt_ns` (from the
//!   latest earlier stamp), `prev_at}`.
//! - `bad_rows`: `count`, `first: [{at, line, message}]`; `stopped`: the error that ended
//!   reading, or null; `non_finite`: `count`, `first: [{index, at, line}]`; `impossible`
//!   (beyond any IMU's range): `count`, `first: [{index, at, line, what}]`; `spikes`:
//!   `count`, `first: [{index, at, line, axis, value, sigmas}]` (`sigmas`: distance from the
//!   nearer neighbour in robust σ of the axis' sample-to-sample change).
//! - `axes`: per axis (`gyro x` … `acc z`) `unit`, `max`, `min`, `constant`,
//!   `flat_fraction`, `at_max` and `at_min` (`clipped`, `total`: samples at the extreme,
//!   `samples`, `runs`, `longest`, `first_index`, `first_at`: runs of ≥ 3 equal readings at
//!   it; clipped when they hold at least half of `total`).
//! - `units` (on the first 32 768 samples, or null): `samples`, `gravity_median_m_s2`
//!   (corrected with `--calibration`), `raw_gravity_median_m_s2`,
//!   `gyro_median_rad_s`, `gyro_scale` (`pairs`, `misfit_deg`: `{deg_per_s, as_read,
//!   rad_per_s}`, or null), `gyro_axes` (`pairs`, `median_turn_deg`, `unexplained_as_read`,
//!   `best_other: {map, unexplained}`, `verdict`: `agree`, `mismatch` or `cannot tell`,
//!   `text`; or null: `preint_io::plausibility::axes`), `error` (the unit check's message, or null), `verdict`
//!   (`passed`, `inconclusive`, or `failed` with an error) and `why` (what an inconclusive check
//!   missed, or null). `input.unit_check` holds the same verdict as every other command's
//!   (`skipped` with `--no-unit-check`).
//! - `still`: `window_samples` (0.5 s), `windows`, `still`, `fraction`.
//!
//! A split recording gives `imu`, `split`: true, `verdict`, `clean`, `defects`, `warnings`,
//! `findings`
//! (kinds as above, prefixed `gyro: ` or `accel: ` in the messages, and `stamps`), `gyro` and
//! `accel` (each: `samples`, `t_first_ns`, `t_last_ns`, `span_s`, `rate`, `jitter`,
//! `histogram`, `gaps`, `duplicates`, `out_of_order`, `bad_rows`, `stopped`, `non_finite`),
//! and `offsets` (accelerometer stamp − nearest gyro stamp: `count`, `mean_ns`, `sd_ns`,
//! `min_ns`, `max_ns`, `coincident`; samples outside the other stream's span:
//! `accel_before`, `accel_after`, `gyro_before`, `gyro_after`).

mod json;

pub use json::{split_json, to_json};

use crate::progress::ReadingBar;
use crate::{Error, ImuInput, calibration_file};
use preint_io::audit::{
    Audit, AuditOptions, Finding, Severity, SplitAudit, Verdict, audit_channels, audit_reader,
};
use preint_io::{ChannelStream, Format, Sensor, SourceInfo};
use std::path::PathBuf;

/// What `audit` runs on (the flags of `preint audit` but `--strict`).
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The recording and how to read it.
    pub input: ImuInput,
    /// An IMU calibration file whose intrinsics correct the samples of the unit checks, checked
    /// against the recording (`--calibration`; one stream only).
    pub calibration: Option<PathBuf>,
}

/// What was audited: one stream, or the two channels of a split recording.
#[derive(Clone, Debug)]
pub enum Report {
    /// One stream of IMU samples.
    Single(Box<Audit>),
    /// Separate gyro and accelerometer streams.
    Split(Box<SplitAudit>),
}

/// An audit and what it was run on.
#[derive(Clone, Debug)]
pub struct AuditRun {
    /// The input, as printed.
    pub imu: String,
    /// How it was read (one stream only).
    pub source: Option<SourceInfo>,
    /// What was found.
    pub report: Report,
    /// The calibration file applied (`--calibration`) and what it holds.
    pub calibration: Option<(String, preint_io::ImuCalibration)>,
}

impl AuditRun {
    /// The findings, defects first.
    pub fn findings(&self) -> &[Finding] {
        match &self.report {
            Report::Single(a) => &a.findings,
            Report::Split(a) => &a.findings,
        }
    }

    /// Number of findings of `severity`.
    pub fn count(&self, severity: Severity) -> usize {
        self.findings()
            .iter()
            .filter(|f| f.severity == severity)
            .count()
    }

    /// Clean, defects, or too short to judge.
    pub fn verdict(&self) -> Verdict {
        Verdict::of(self.findings())
    }

    /// The unit checks' verdict as every command prints it ([`crate::checks::UnitCheck`]).
    pub fn unit_check(&self, no_unit_check: bool) -> crate::checks::UnitCheck {
        use crate::checks::UnitCheck;
        match (&self.report, no_unit_check) {
            (_, true) => UnitCheck::Skipped,
            (Report::Single(a), false) => match a.units.as_ref().and_then(|u| {
                let v = u.verdict.clone()?;
                Some((v, u.samples))
            }) {
                Some((verdict, samples)) => UnitCheck::Checked { verdict, samples },
                None => UnitCheck::Checked {
                    verdict: preint_io::UnitVerdict::Inconclusive(vec![
                        "fewer than two readable samples with distinct stamps".into(),
                    ]),
                    samples: 0,
                },
            },
            (Report::Split(_), false) => UnitCheck::Checked {
                verdict: preint_io::UnitVerdict::Inconclusive(vec![
                    "the channels of a split recording are checked for their median norms \
                     only (merge them with `preint convert` for the full checks)"
                        .into(),
                ]),
                samples: 0,
            },
        }
    }
}

/// Reads the recording once, sample by sample, and audits it.
pub fn compute(args: &Options) -> Result<AuditRun, Error> {
    let mut opts = AuditOptions::default();
    let input = &args.input;
    let imu = input.label();
    let calibration = match &args.calibration {
        Some(p) => Some((p.display().to_string(), calibration_file::read(p)?)),
        None => None,
    };
    if let Some((gyro, accel)) = split_channels(input)? {
        if calibration.is_some() {
            return Err(Error::Usage(
                "--calibration: the intrinsics mix the gyro and accelerometer readings of a \
                 sample, which a split recording's channels audited apart do not have (merge \
                 them with `preint convert` first)"
                    .into(),
            ));
        }
        let audit = audit_channels(gyro, accel, &imu, opts);
        return Ok(AuditRun {
            imu,
            source: None,
            report: Report::Split(Box::new(audit)),
            calibration,
        });
    }
    opts.correction = calibration.as_ref().map(|(_, c)| c.intrinsics.correction());
    let reader = input.open()?;
    let source = reader.info().clone();
    opts.read_as = Some(source.units);
    let progress = reader.progress().clone();
    let _bar = ReadingBar::start(&progress, "audit");
    let mut audit = audit_reader(reader, opts);
    if args.input.no_unit_check {
        for f in audit.findings.iter_mut().filter(|f| f.kind == "units") {
            if f.severity == Severity::Defect {
                f.severity = Severity::Warning;
            }
        }
        audit.findings.sort_by_key(|f| f.severity);
    }
    if let Some((name, cal)) = &calibration {
        audit
            .findings
            .extend(calibration_findings(name, cal, &audit));
        audit.findings.sort_by_key(|f| f.severity);
    }
    Ok(AuditRun {
        imu,
        source: Some(source),
        report: Report::Single(Box::new(audit)),
        calibration,
    })
}

/// Largest plausible deviation of a MEMS IMU's scale or misalignment entries from the
/// identity (10 %), and of its g-sensitivity entries \[(rad/s)/(m/s²)\] (0.01, ≈ 5.6 °/s per g).
const PLAUSIBLE_SCALE: f64 = 0.1;
const PLAUSIBLE_G_SENSITIVITY: f64 = 0.01;

/// What the calibration file does to this recording (module docs): an info finding with the
/// resting accelerometer norm before and after, a warning when the intrinsics are beyond a MEMS
/// sensor's range or move a mostly still recording's accelerometer norm away from |g|.
fn calibration_findings(name: &str, cal: &preint_io::ImuCalibration, a: &Audit) -> Vec<Finding> {
    let x = &cal.intrinsics;
    let eye = nalgebra::Matrix3::identity();
    let scale = [(x.t_w - eye).amax(), (x.t_a - eye).amax()]
        .into_iter()
        .fold(0.0, f64::max);
    let angles = [x.r_imu_to_gyro, x.r_imu_to_acc]
        .iter()
        .map(|r| preint_lie::SO3::from_matrix(r).log().norm())
        .fold(0.0, f64::max);
    let mut out = Vec::new();
    let td = cal
        .time_offset_s
        .map_or(String::from("no time offset"), |t| {
            format!(
                "time offset {:+.3} ms (stamps audited as recorded)",
                t * 1e3
            )
        });
    let g = a.units.as_ref().map_or(String::new(), |u| {
        format!(
            "; accelerometer median norm {:.4} m/s² corrected, {:.4} raw",
            u.gravity_median_m_s2, u.raw_gravity_median_m_s2
        )
    });
    out.push(Finding::new(
        Severity::Info,
        "calibration",
        format!(
            "{name}: intrinsics ({} model, scale/misalignment up to {:.2} %, axis rotation up \
             to {:.2} mrad, g-sensitivity up to {:.1e} (rad/s)/(m/s²)) applied to the unit \
             checks; {td}{g}",
            x.model.name(),
            scale * 100.0,
            angles * 1e3,
            x.t_g.amax()
        ),
    ));
    if scale > PLAUSIBLE_SCALE || angles > PLAUSIBLE_SCALE || x.t_g.amax() > PLAUSIBLE_G_SENSITIVITY
    {
        out.push(Finding::new(
            Severity::Warning,
            "calibration",
            format!(
                "{name}: intrinsics beyond a MEMS sensor's range (scale/misalignment {:.1} %, \
                 rotation {:.1} mrad, g-sensitivity {:.1e}): is the file this sensor's, in \
                 OpenVINS' convention?",
                scale * 100.0,
                angles * 1e3,
                x.t_g.amax()
            ),
        ));
    }
    if let Some(u) = &a.units {
        let g0 = preint::PreintParams::default().gravity.norm();
        let (raw, corr) = (
            (u.raw_gravity_median_m_s2 - g0).abs(),
            (u.gravity_median_m_s2 - g0).abs(),
        );
        if a.still.fraction() >= 0.5 && corr > raw + 0.005 * g0 {
            out.push(Finding::new(
                Severity::Warning,
                "calibration",
                format!(
                    "{name}: on this mostly still recording the corrected accelerometer norm \
                     ({:.4} m/s²) is further from {g0} than the raw one ({:.4}): is the file \
                     this sensor's?",
                    u.gravity_median_m_s2, u.raw_gravity_median_m_s2
                ),
            ));
        }
    }
    out
}

/// The gyro and accelerometer channels of a split recording (`--gyro`/`--accel` files, or
/// `--gyro-topic`/`--accel-topic` of a container), or `None` for one stream.
fn split_channels(input: &ImuInput) -> Result<Option<(ChannelStream, ChannelStream)>, Error> {
    use preint_io::{containers::open_channel, split::open_text_channel};
    let opts = input.options();
    if let (Some(g), Some(a)) = (&input.gyro, &input.accel) {
        let gyro = open_text_channel(g, Sensor::Gyro, &opts)?;
        return Ok(Some((gyro, open_text_channel(a, Sensor::Accel, &opts)?)));
    }
    let (Some(path), Some(g), Some(a)) = (&input.imu, &input.gyro_topic, &input.accel_topic) else {
        return Ok(None);
    };
    let format = (input.format.or_else(|| Format::of_file(path)))
        .filter(|f| f.is_container())
        .ok_or_else(|| {
            Error::Usage(format!(
                "{}: --gyro-topic and --accel-topic need a bag, MCAP or db3 file",
                path.display()
            ))
        })?;
    let gyro = open_channel(path, format, g, Sensor::Gyro, &opts)?;
    Ok(Some((
        gyro,
        open_channel(path, format, a, Sensor::Accel, &opts)?,
    )))
}
