//! `preint convert`: any readable recording to EuRoC CSV (`t [ns], w [rad/s], a [m/s²]`),
//! streaming, in bounded memory.

use crate::imu_args::ImuArgs;
use crate::{CliError, Output};
use preint_analysis::checks::UnitCheck;
use preint_analysis::progress::ReadingBar;
use preint_analysis::recording::input_json;
use preint_analysis::stream;
use preint_io::euroc::write_euroc_stream;
use preint_io::{IoError, SourceInfo};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Flags of `preint convert`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// The EuRoC CSV file to write.
    #[arg(help_heading = "Output", long)]
    pub out: PathBuf,
}

/// What was converted.
#[derive(Clone, Debug)]
pub struct Conversion {
    /// The input, as printed.
    pub imu: String,
    /// How it was read.
    pub source: SourceInfo,
    /// What the unit checks said.
    pub unit_check: UnitCheck,
    /// The file written.
    pub out: String,
    /// Number of samples written.
    pub samples: u64,
}

/// Reads the recording sample by sample and writes each as a EuRoC row, after the unit checks
/// on its first samples (a file in deg/s or g must not come out labelled rad/s and m/s²).
pub fn compute(args: &Args) -> Result<Conversion, CliError> {
    let input = args.input.to_input();
    let stream = stream::open_checked(&input)?;
    let (mut source, unit_check) = (stream.info().clone(), stream.unit_check().clone());
    let merge = stream.merge();
    let _bar = ReadingBar::start(stream.progress(), "convert");
    let out_name = args.out.display().to_string();
    let file = std::fs::File::create(&args.out).map_err(|e| CliError::out_path(&args.out, e))?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
    // The checked stream's errors are the reader's.
    let samples = stream.map(|r| {
        r.map_err(|e| match e {
            preint_analysis::Error::Io(io) => io,
            other => IoError::format(&source.source_name, other.to_string()),
        })
    });
    let samples = write_euroc_stream(&mut out, samples, &out_name)?;
    source
        .warnings
        .extend(merge.and_then(|m| m.report().shortening()));
    if samples == 0 {
        return Err(CliError::Failed(format!("{}: no samples", input.label())));
    }
    Ok(Conversion {
        imu: input.label(),
        source,
        unit_check,
        out: out_name,
        samples,
    })
}

/// The JSON form.
pub fn to_json(c: &Conversion) -> Value {
    json!({"imu": c.imu, "input": input_json(&c.source, &c.unit_check), "out": c.out, "samples": c.samples,
           "out_format": "euroc: timestamp [ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2]"})
}

/// The human summary.
pub fn to_text(c: &Conversion) -> String {
    format!(
        "{} (read as {}) → {}: {} samples, EuRoC CSV (ns, rad/s, m/s²)\n{}",
        c.imu,
        c.source.describe(),
        c.out,
        c.samples,
        preint_analysis::recording::input_text(&c.source, &c.unit_check)
    )
}

/// Runs `preint convert`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let c = compute(args)?;
    Ok(Output {
        human: to_text(&c),
        json: to_json(&c),
    })
}
