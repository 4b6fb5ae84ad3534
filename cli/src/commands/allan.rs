//! `preint allan`: overlapping Allan deviation of a static recording, fitted white-noise
//! density (slope −½ read at τ = 1 s), random walk (slope +½ read at τ = 3 s) and bias
//! instability (flat minimum / 0.664); Kalibr `imu.yaml` (max over axes) and a chart
//! (IEEE Std 952-1997, annex C).
//!
//! Streaming, in bounded memory: the samples are read once and reduced to at most 2²⁰ block
//! means ([`preint_calib::allan::stream`]: τ₀ = Δt up to 2²⁰ samples, then doubling), so memory
//! does not grow with the file. Checks before an answer is given:
//! - **Units** on the first [`UNIT_CHECK_SECONDS`] s (at most [`UNIT_CHECK_MAX_SAMPLES`]
//!   samples; [`preint_analysis::checks::si_units`]), unless `--no-unit-check`.
//! - **Stillness** over the whole recording ([`preint_calib::allan::stillness`]): a moving
//!   recording is refused (exit 2) with the fraction of still windows, unless
//!   `--no-still-check` (for a sensor whose noise the detector takes for motion, e.g. strong
//!   popcorn noise).
//!
//! # Goodness of fit
//! The fit (JSON `fit`, [`preint_calib::allan::ImuAllan::fit`]) compares the model curve
//! `√(N²/τ + K²τ/3)` with the measured Allan deviation over the τ ranges its lines were fitted
//! on, in units of each point's statistical error: credible while no point is more than 5 of
//! them away (`chi2` = Σz², `dof` = the points; no p-value, the points are correlated). Not
//! credible: a `warning:` line names the channel, τ and line; `--strict` makes it a refusal
//! (exit 2, after the output).

use crate::charts::figures;
use crate::fit::fit_text;
use crate::imu_args::ImuArgs;
use crate::{CliError, Output};
use preint_analysis::consistency::fit_json;
use preint_analysis::format::IMU_AXES;
use preint_analysis::progress::ReadingBar;
use preint_analysis::stream;
use preint_calib::allan::{AllanStream, ImuAllan, Stillness, StillnessMonitor, StillnessOptions};
use preint_io::write_kalibr_yaml;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Length of the prefix on which the units are checked \[s\].
pub const UNIT_CHECK_SECONDS: f64 = 60.0;
/// Largest number of samples of that prefix (5.6 MB; 60 s up to 1.67 kHz).
pub const UNIT_CHECK_MAX_SAMPLES: usize = 100_000;

/// Flags of `preint allan`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording (at rest) and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Output directory for the charts allan_gyro.svg and allan_acc.svg and the Kalibr imu.yaml.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Skip the check that the recording is static (the Allan deviation of a moving recording
    /// describes the motion, not the sensor's noise).
    #[arg(long)]
    pub no_still_check: bool,
    /// Exit with status 2 (after printing the result) when the fit is not credible: the model
    /// curve √(N²/τ + K²τ/3) more than 5 statistical errors from the measured Allan deviation
    /// somewhere in the τ ranges its lines were fitted on.
    #[arg(long)]
    pub strict: bool,
}

/// The Allan deviations, their fits, and the files written.
#[derive(Clone, Debug)]
pub struct AllanRun {
    /// The IMU file, as printed.
    pub imu: String,
    /// Number of samples.
    pub samples: usize,
    /// Samples per base block of the curves (τ₀ = `block_len`·Δt).
    pub block_len: usize,
    /// Whether the units were checked (`--no-unit-check` not given).
    pub units_checked: bool,
    /// How the recording was read.
    pub source: preint_io::SourceInfo,
    /// What the unit checks said.
    pub unit_check: preint_analysis::checks::UnitCheck,
    /// The stillness check's findings (refused unless static or `--no-still-check`).
    pub stillness: Stillness,
    /// Curves and fits per channel (order [`IMU_AXES`]).
    pub allan: ImuAllan,
    /// Charts and `imu.yaml`, when `--out` is given.
    pub files: Vec<String>,
}

/// What the streamed pass read: base blocks, stillness, how the source was read and its unit
/// check.
type Streamed = (
    AllanStream,
    Stillness,
    preint_io::SourceInfo,
    preint_analysis::checks::UnitCheck,
);

/// The streamed pass: base blocks, the stillness monitor, and the unit check on the prefix.
fn read_stream(args: &Args) -> Result<Streamed, CliError> {
    let input = args.input.to_input();
    let file = input.path();
    let samples = stream::open_checked_prefix(
        &input,
        None,
        UNIT_CHECK_MAX_SAMPLES,
        Some(UNIT_CHECK_SECONDS),
        stream::EDGE_SAMPLES,
    )?;
    let (source, units) = (samples.info().clone(), samples.unit_check().clone());
    let _bar = ReadingBar::start(samples.progress(), "allan");
    let mut allan = AllanStream::new();
    let mut still = StillnessMonitor::new(StillnessOptions::default());
    for s in samples {
        let s = s?;
        allan.push(&s).map_err(|e| CliError::failed_in(file, e))?;
        still.push(&s);
    }
    Ok((allan, still.finish(), source, units))
}

/// Computes the Allan deviations and, with `--out`, writes the two charts and `imu.yaml`.
pub fn compute(args: &Args) -> Result<AllanRun, CliError> {
    let input = args.input.to_input();
    let file = input.path();
    let (stream, stillness, source, unit_check) = read_stream(args)?;
    if !args.no_still_check {
        stillness
            .verdict(&StillnessOptions::default())
            .map_err(|e| CliError::failed_in(file, format!("{e} (or pass --no-still-check)")))?;
    }
    let (samples, block_len) = (stream.samples() as usize, stream.block_len());
    let a = stream
        .finish(10)
        .map_err(|e| CliError::failed_in(file, e))?;
    let mut files = Vec::new();
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).map_err(|e| CliError::out_path(dir, e))?;
        for (sensor, name) in [(0, "allan_gyro.svg"), (1, "allan_acc.svg")] {
            let p = dir.join(name);
            figures::allan(&a, sensor, &p)?;
            files.push(p.display().to_string());
        }
        let y = dir.join("imu.yaml");
        write_kalibr_yaml(&y, &a.to_imu_noise())?;
        files.push(y.display().to_string());
    }
    Ok(AllanRun {
        imu: input.label(),
        samples,
        block_len,
        units_checked: !args.input.no_unit_check,
        source,
        unit_check,
        stillness,
        allan: a,
        files,
    })
}

/// The JSON form: per-sensor densities (per axis), bias instability, per-axis details, files.
pub fn to_json(r: &AllanRun) -> Value {
    let a = &r.allan;
    let per_axis: Vec<_> = (0..6)
        .map(|c| {
            let f = &a.fits[c];
            json!({"axis": IMU_AXES[c], "noise_density": f.white_density, "noise_density_err": f.white_density_err,
                   "noise_density_is_upper_bound": f.white_density_is_bound,
                   "random_walk": f.random_walk, "random_walk_err": f.random_walk_err,
                   "random_walk_is_upper_bound": f.random_walk_is_bound,
                   "bias_instability": f.bias_instability, "bias_instability_tau": f.bias_instability_tau})
        })
        .collect();
    let white = |c0: usize| {
        (c0..c0 + 3)
            .map(|c| a.fits[c].white_density)
            .collect::<Vec<_>>()
    };
    let walk = |c0: usize| {
        (c0..c0 + 3)
            .map(|c| a.fits[c].random_walk)
            .collect::<Vec<_>>()
    };
    let st = &r.stillness;
    json!({
        "input": preint_analysis::recording::input_json(&r.source, &r.unit_check),
        "samples": r.samples,
        "sample_period_s": a.dt,
        "base_tau_s": a.tau0,
        "block_len": r.block_len,
        "checks": {
            "units": if r.units_checked { format!("first {UNIT_CHECK_SECONDS} s") } else { "skipped (--no-unit-check)".into() },
            "still_fraction": st.still_fraction(),
            "still_windows": st.still_windows,
            "windows": st.windows,
            "max_tilt_deg": st.max_tilt_deg,
            "step_tilt_deg": st.step_tilt_deg,
            "max_norm_change_ms2": st.max_norm_change_ms2,
            "tilt_is_bias_walk": st.tilt_is_bias_walk(),
        },
        "gyroscope_noise_density": white(0),
        "gyroscope_random_walk": walk(0),
        "accelerometer_noise_density": white(3),
        "accelerometer_random_walk": walk(3),
        "bias_instability": (0..6).map(|c| a.fits[c].bias_instability).collect::<Vec<_>>(),
        "units": {"gyroscope_noise_density": "rad/s/sqrt(Hz)", "gyroscope_random_walk": "rad/s^2/sqrt(Hz)",
                  "accelerometer_noise_density": "m/s^2/sqrt(Hz)", "accelerometer_random_walk": "m/s^3/sqrt(Hz)",
                  "bias_instability": "rad/s (gyro), m/s^2 (acc)"},
        "yaml_aggregate": "maximum over the three axes (conservative)",
        "per_axis": per_axis,
        "files": r.files,
        "fit": fit_json(&a.fit()),
    })
}

/// The human summary: a table of the fits per axis.
pub fn to_text(r: &AllanRun) -> String {
    let a = &r.allan;
    let mut h = format!(
        "{}: {} samples at {:.1} Hz ({:.0} s)\n",
        r.imu,
        r.samples,
        1.0 / a.dt,
        a.dt * r.samples as f64
    );
    let st = &r.stillness;
    let walk = if st.max_tilt_deg > StillnessOptions::default().max_tilt_deg {
        if st.tilt_is_bias_walk() {
            format!(
                " (the accelerometer bias walk: its norm changes by {:.3} m/s² as well; \
                 {:.2}° across moving windows)",
                st.max_norm_change_ms2, st.step_tilt_deg
            )
        } else {
            String::new()
        }
    } else {
        String::new()
    };
    let _ = writeln!(
        h,
        "still: {:.1} % of {} one-second windows, gravity turns by up to {:.2}°{walk}; units {}",
        100.0 * st.still_fraction(),
        st.windows,
        st.max_tilt_deg,
        if r.units_checked {
            "checked on the first 60 s"
        } else {
            "not checked"
        }
    );
    h.push_str(&preint_analysis::recording::input_text(
        &r.source,
        &r.unit_check,
    ));
    if r.block_len > 1 {
        let _ = writeln!(
            h,
            "curves from means of {} samples (τ from {:.3} s; bounded memory)",
            r.block_len, a.tau0
        );
    }
    let _ = writeln!(
        h,
        "{:<8} {:>16} {:>16} {:>16}",
        "axis", "noise density", "random walk", "bias instab."
    );
    for c in 0..6 {
        let f = &a.fits[c];
        let _ = writeln!(
            h,
            "{:<8} {:>15.4e}{} {:>15.4e}{} {:>16.4e}",
            IMU_AXES[c],
            f.white_density,
            if f.white_density_is_bound { "≤" } else { " " },
            f.random_walk,
            if f.random_walk_is_bound { "≤" } else { " " },
            f.bias_instability
        );
    }
    let _ = writeln!(
        h,
        "units: gyro rad/s/√Hz, rad/s²/√Hz, rad/s; acc m/s²/√Hz, m/s³/√Hz, m/s². ≤: upper bound (no region of slope −½ resp. +½ in the data)"
    );
    h.push_str(&fit_text(&a.fit(), "Allan noise model"));
    let _ = writeln!(
        h,
        "imu.yaml uses the maximum over the axes.{}",
        if r.files.is_empty() {
            String::new()
        } else {
            format!(" Wrote {}", r.files.join(", "))
        }
    );
    h
}

/// Runs `preint allan`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    let output = Output {
        human: to_text(&r),
        json: to_json(&r),
    };
    crate::fit::strict(args.strict, output, &r.allan.fit(), "Allan noise model")
}
