//! `preint allan`'s numbers: overlapping Allan deviation of a static recording, fitted
//! white-noise density (slope −½ read at τ = 1 s), random walk (slope +½ read at τ = 3 s) and
//! bias instability (flat minimum / 0.664) (IEEE Std 952-1997, annex C); the command line adds
//! the Kalibr `imu.yaml` (max over axes) and the charts of `--out`.
//!
//! Streaming, in bounded memory: the samples are read once and reduced to at most 2²⁰ block
//! means ([`preint_calib::allan::stream`]: τ₀ = Δt up to 2²⁰ samples, then doubling), so memory
//! does not grow with the file. Checks before an answer is given:
//! - **Units** on the first [`UNIT_CHECK_SECONDS`] s (at most [`UNIT_CHECK_MAX_SAMPLES`]
//!   samples; [`crate::checks::si_units`]), unless `--no-unit-check`.
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

use crate::consistency::fit_json;
use crate::format::IMU_AXES;
use crate::progress::ReadingBar;
use crate::{Error, ImuInput, stream};
use preint_calib::allan::{AllanStream, ImuAllan, Stillness, StillnessMonitor, StillnessOptions};
use serde_json::{Value, json};

/// Length of the prefix on which the units are checked \[s\].
pub const UNIT_CHECK_SECONDS: f64 = 60.0;
/// Largest number of samples of that prefix (5.6 MB; 60 s up to 1.67 kHz).
pub const UNIT_CHECK_MAX_SAMPLES: usize = 100_000;

/// What `allan` runs on (the flags of `preint allan` but `--out` and `--strict`).
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The recording (at rest) and how to read it.
    pub input: ImuInput,
    /// Skip the check that the recording is static (`--no-still-check`).
    pub no_still_check: bool,
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
    pub unit_check: crate::checks::UnitCheck,
    /// The stillness check's findings (refused unless static or `--no-still-check`).
    pub stillness: Stillness,
    /// Curves and fits per channel (order [`IMU_AXES`]).
    pub allan: ImuAllan,
    /// The files written (the command line's charts and `imu.yaml` of `--out`; empty here).
    pub files: Vec<String>,
}

/// What the streamed pass read: base blocks, stillness, how the source was read and its unit
/// check.
type Streamed = (
    AllanStream,
    Stillness,
    preint_io::SourceInfo,
    crate::checks::UnitCheck,
);

/// The streamed pass: base blocks, the stillness monitor, and the unit check on the prefix.
fn read_stream(input: &ImuInput) -> Result<Streamed, Error> {
    let file = input.path();
    let samples = stream::open_checked_prefix(
        input,
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
        allan.push(&s).map_err(|e| Error::failed_in(file, e))?;
        still.push(&s);
    }
    Ok((allan, still.finish(), source, units))
}

/// Computes the Allan deviations (and the stillness and unit checks' verdicts); `files` is
/// left empty.
pub fn compute(o: &Options) -> Result<AllanRun, Error> {
    let file = o.input.path();
    let (stream, stillness, source, unit_check) = read_stream(&o.input)?;
    if !o.no_still_check {
        stillness
            .verdict(&StillnessOptions::default())
            .map_err(|e| Error::failed_in(file, format!("{e} (or pass --no-still-check)")))?;
    }
    let (samples, block_len) = (stream.samples() as usize, stream.block_len());
    let a = stream.finish(10).map_err(|e| Error::failed_in(file, e))?;
    Ok(AllanRun {
        imu: o.input.label(),
        samples,
        block_len,
        units_checked: !o.input.no_unit_check,
        source,
        unit_check,
        stillness,
        allan: a,
        files: Vec::new(),
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
        "input": crate::recording::input_json(&r.source, &r.unit_check),
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
