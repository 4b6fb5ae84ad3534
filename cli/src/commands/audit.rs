//! `preint audit`: what is wrong with a recording, in one streaming pass in bounded memory
//! (the findings, the verdict and the JSON: [`preint_analysis::audit`]). Exit status 0 with a
//! verdict; with `--strict`, exit 2 when a defect is found or the recording is too short to
//! judge (the defects are printed on stderr, each naming counts, indices and lines).

use crate::imu_args::ImuArgs;
use crate::{CliError, Output};
use preint_analysis::audit::{AuditRun, Options, Report, to_json};
use preint_io::audit::{Finding, HISTOGRAM_EDGES, Severity, Timing, Verdict};
use std::fmt::Write as _;

/// Flags of `preint audit`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Exit with status 2 when a defect is found (for scripts and CI).
    #[arg(help_heading = "Output", long)]
    pub strict: bool,
    /// An IMU calibration file (`calibrate --out`, OpenVINS kalibr_imu_chain.yaml or Kalibr
    /// imu.yaml): its intrinsics correct the samples of the unit checks, and it is checked
    /// against the recording (accelerometer norm at rest, plausible ranges). One stream only.
    #[arg(help_heading = "Input", long, value_name = "FILE")]
    pub calibration: Option<std::path::PathBuf>,
}

impl Args {
    /// What the library computes on.
    pub fn options(&self) -> Options {
        Options {
            input: self.input.to_input(),
            calibration: self.calibration.clone(),
        }
    }
}

/// The human summary: the verdict, the findings, and the Δt histogram.
pub fn to_text(r: &AuditRun) -> String {
    let mut s = match &r.source {
        Some(src) => format!("{} (read as {})\n", r.imu, src.describe()),
        None => format!("{} (split: gyro and accelerometer streams)\n", r.imu),
    };
    let defects = r.count(Severity::Defect);
    let verdict = match r.verdict() {
        Verdict::Clean => "clean",
        Verdict::Defects => "DEFECTS",
        Verdict::TooShort => "too short to judge",
    };
    let _ = writeln!(
        s,
        "verdict: {verdict} ({defects} defects, {} warnings)",
        r.count(Severity::Warning)
    );
    for f in r.findings() {
        let _ = writeln!(s, "  {:<7} {:<13} {}", f.severity, f.kind, f.message);
    }
    let timings: Vec<(&str, &Timing)> = match &r.report {
        Report::Single(a) => vec![("", &a.timing)],
        Report::Split(a) => vec![("gyro ", &a.gyro.timing), ("accel ", &a.accel.timing)],
    };
    for (label, t) in timings {
        let Some(reference) = t.reference_ns else {
            continue;
        };
        let _ = writeln!(
            s,
            "{label}Δt histogram (multiples of the reference {reference} ns):"
        );
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
/// The report is printed in both cases.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = preint_analysis::audit::compute(&args.options())?;
    let output = Output {
        human: to_text(&r),
        json: to_json(&r, args.input.no_unit_check),
    };
    let verdict = r.verdict();
    if args.strict && verdict != Verdict::Clean {
        let why = |keep: &dyn Fn(&Finding) -> bool| {
            let m: Vec<&str> = (r.findings().iter())
                .filter(|f| keep(f))
                .map(|f| f.message.as_str())
                .collect();
            (m.len(), m.join(" | "))
        };
        let msg = if verdict == Verdict::Defects {
            let (n, list) = why(&|f| f.severity == Severity::Defect);
            format!("{}: audit found {n} defects (--strict): {list}", r.imu)
        } else {
            let (_, list) = why(&|f| f.kind == "too_short");
            format!("{}: {list} (--strict)", r.imu)
        };
        return Err(CliError::Refused {
            output: Box::new(output),
            msg,
        });
    }
    Ok(output)
}
