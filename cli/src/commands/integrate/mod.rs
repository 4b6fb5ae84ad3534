//! `preint integrate`: preintegrate a window of an IMU recording and print the deltas, their
//! covariances and the bias Jacobians ([`print`]), with what the flags ask beside them, each
//! printed by its own type: the prediction and the deltas inside the window
//! ([`prediction`]), the window's truncation error and second-order covariance
//! ([`window_error`]), the calibration file applied ([`calibration`]).

mod calibration;
mod prediction;
mod print;
mod window_error;

pub use print::{to_json, to_text};

use crate::imu_args::ImuArgs;
use crate::preint_args::PreintArgs;
use crate::{CliError, Output, input};
use calibration::AppliedCalibration;
use nalgebra::Vector3;
use prediction::{AtTimes, Prediction};
use preint::{
    ImuBias, ImuNoise, Level, PreintError, PreintParams, PreintegratedImu, Preintegrator, predict,
    preintegrate,
};
use preint_analysis::checks::UnitCheck;
use preint_analysis::progress::ReadingBar;
use preint_analysis::stream::{self, CheckedSamples, StreamWindow};
use preint_analysis::{ImuInput, checks, noise};
use preint_io::SourceInfo;
use window_error::{SecondOrder, Truncation};

/// Flags of `preint integrate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording and how to read it.
    #[command(flatten)]
    pub input: ImuArgs,
    /// Scheme, noise densities and gravity.
    #[command(flatten)]
    pub preint: PreintArgs,
    /// Gyro bias estimate b_g (rad/s) as x,y,z (negative values allowed: --bias-gyro=-0.01,0,0).
    #[arg(help_heading = "Preintegration", long, allow_hyphen_values = true, value_parser = preint_analysis::parse::vec3)]
    pub bias_gyro: Option<Vector3<f64>>,
    /// Accelerometer bias estimate b_a (m/s^2) as x,y,z.
    #[arg(help_heading = "Preintegration", long, allow_hyphen_values = true, value_parser = preint_analysis::parse::vec3)]
    pub bias_acc: Option<Vector3<f64>>,
    /// First keyframe time in ns (default: first sample).
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Last keyframe time in ns (default: last sample).
    #[arg(help_heading = "Window", long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// Earth rotation and the predicted state at the window's end.
    #[command(flatten)]
    pub predict: crate::earth_args::PredictArgs,
    /// Times in ns inside the window (non-decreasing, comma-separated): also print the deltas
    /// from t_i at each, and with --initial-state the predicted state (keeps the window's
    /// samples in memory).
    #[arg(
        help_heading = "Extras",
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "T1,T2,..."
    )]
    pub at: Vec<i64>,
    /// Also estimate the window's own discretisation (truncation) error from its samples
    /// (`preint::truncation`: a hermite4 companion, or Richardson for hermite4). Reads the
    /// window rather than streaming the whole recording.
    #[arg(help_heading = "Extras", long)]
    pub truncation: bool,
    /// Also compute the second-order covariance term of the window's SE₂(3) error
    /// (`preint::second_order`: what the first-order covariance misses over long windows with
    /// noisy gyroscopes) and the increase of the mean χ² it accounts for. Reads the window
    /// rather than streaming the whole recording.
    #[arg(help_heading = "Extras", long)]
    pub second_order: bool,
    /// An IMU calibration file (what `calibrate --out` writes: OpenVINS kalibr_imu_chain.yaml,
    /// or Kalibr's imu.yaml with a scale-misalignment model): its intrinsics are applied to the
    /// raw samples, and its `time_offset` (s; t_imu = t_keyframe + time_offset) moves
    /// --from/--to onto the IMU's clock. Noise densities still come from --noise. A time
    /// offset recorded for a scheme that lags differently from --scheme (euler and galilean
    /// are half a sample behind midpoint and hermite4) is warned about, with the size of the
    /// lag; it is applied as recorded.
    #[arg(help_heading = "Input", long, value_name = "FILE")]
    pub calibration: Option<std::path::PathBuf>,
}

/// A preintegrated window.
#[derive(Clone, Debug)]
pub struct Integration {
    /// The IMU file, as printed.
    pub imu: String,
    /// How it was read.
    pub source: SourceInfo,
    /// What the unit checks said.
    pub unit_check: UnitCheck,
    /// The scheme used.
    pub scheme: preint::Scheme,
    /// Number of samples with timestamps in the window.
    pub samples: usize,
    /// The noise densities used.
    pub noise: ImuNoise,
    /// Where they came from (file path or the defaults).
    pub noise_source: String,
    /// The bias estimate the window was integrated with.
    pub bias: ImuBias,
    /// The preintegrated measurement (with the 15×15 covariance).
    pub pim: PreintegratedImu,
    /// The IMU's pose in the body (`--body-p-sensor`): the deltas are then the body's.
    pub body_p_sensor: Option<preint::SensorPose>,
    /// How its lever arm was removed.
    pub lever_arm: preint::LeverArm,
    /// The state at the window's end predicted from `--initial-state`.
    pub predicted: Option<Prediction>,
    /// The deltas (and with `--initial-state` the predicted state) at each `--at` time.
    pub at: AtTimes,
    /// The estimated truncation error of the deltas (`--truncation`).
    pub truncation: Option<Truncation>,
    /// The second-order covariance term (`--second-order`).
    pub second_order: Option<SecondOrder>,
    /// The calibration file applied (`--calibration`).
    pub calibration: Option<AppliedCalibration>,
}

/// What the window gives: the measurement, the samples in it, and what the flags ask beside.
struct Integrated {
    pim: PreintegratedImu,
    samples: usize,
    at: AtTimes,
    truncation: Option<Truncation>,
    second_order: Option<SecondOrder>,
}

/// Reads the file once and preintegrates `[--from, --to]` at [`Level::Combined`]: the whole
/// recording through a [`Preintegrator`] that stores no samples, a window from the part of the
/// stream it needs (reading stops after `--to`). Memory is bounded by the window, not the file.
pub fn compute(args: &Args) -> Result<Integration, CliError> {
    checks::window_order(args.from, args.to)?;
    let (noise, mut params) = args.preint.params(Level::Combined)?;
    if let Some((w, mode)) = args.predict.earth()? {
        params = params.with_omega_coriolis(w).with_coriolis(mode);
    }
    let bias = ImuBias::new(
        args.bias_gyro.unwrap_or_default(),
        args.bias_acc.unwrap_or_default(),
    );
    let file = args
        .calibration
        .as_deref()
        .map(|p| AppliedCalibration::read(p, &mut params))
        .transpose()?;
    // The keyframes on the IMU's clock.
    let td = file.as_ref().map_or(0, |(c, _)| c.time_offset_ns);
    let (from, to) = (args.from.map(|t| t + td), args.to.map(|t| t + td));
    let (scheme, body_p_sensor, lever_arm) =
        (params.scheme, params.body_p_sensor, params.lever_arm);
    let input = args.input.to_input();
    let (source, unit_check, noise, w) = read(args, &input, params, noise, &bias, (from, to))?;
    let calibration = match (&args.calibration, file) {
        (Some(path), Some((applied, cal))) => {
            let dt_s = w.pim.delta_t / w.samples.max(1) as f64;
            Some(applied.with_scheme(&cal, path, scheme, dt_s))
        }
        _ => None,
    };
    Ok(Integration {
        imu: input.label(),
        source,
        unit_check,
        scheme,
        samples: w.samples,
        noise,
        noise_source: args.preint.noise_source(),
        bias,
        predicted: (args.predict.initial_state).map(|x| Prediction(predict(&w.pim, &x, &bias))),
        pim: w.pim,
        body_p_sensor,
        lever_arm,
        at: w.at,
        truncation: w.truncation,
        second_order: w.second_order,
        calibration,
    })
}

/// Reads the recording of `input` and preintegrates the window `[from, to]` (IMU clock) with
/// `params` (the accelerometer density of a split recording's merged samples set in it): how
/// it was read, its unit checks, the densities used and the window's results.
fn read(
    args: &Args,
    input: &ImuInput,
    mut params: PreintParams,
    noise: ImuNoise,
    bias: &ImuBias,
    (from, to): (Option<i64>, Option<i64>),
) -> Result<(SourceInfo, UnitCheck, ImuNoise, Integrated), CliError> {
    let fail = |e| CliError::failed_in(input.path(), e);
    if input.is_split() {
        // The merged accelerometer's effective density is known once the files are read.
        let (w, source, split, units) = stream::split_window(input, from, to)?;
        let noise = noise::apply_split(&noise, split.as_ref(), &mut params);
        return Ok((source, units, noise, window(args, &params, bias, w, fail)?));
    }
    // `--truncation` reads enough samples around the window for its companion's stencils.
    let edge = if args.truncation {
        stream::EDGE_SAMPLES.max(preint::truncation::CONTEXT_SAMPLES)
    } else {
        stream::EDGE_SAMPLES
    };
    let stream = stream::open_checked_window(input, to, edge)?;
    let (source, units) = (stream.info().clone(), stream.unit_check().clone());
    let _bar = ReadingBar::start(stream.progress(), "integrate");
    let streamed = from.is_none() && to.is_none();
    let result = if streamed && args.at.is_empty() && !args.truncation && !args.second_order {
        let (pim, samples) = whole_recording(stream, params, bias, fail)?;
        Integrated {
            pim,
            samples,
            at: AtTimes::default(),
            truncation: None,
            second_order: None,
        }
    } else {
        let w = stream::cut_window_with_edge(stream, from, to, edge)?;
        window(args, &params, bias, w, fail)?
    };
    Ok((source, units, noise, result))
}

/// Preintegrates the window `w` and computes what `--at`, `--truncation` and `--second-order`
/// ask; errors name the samples by their index in the whole stream.
fn window(
    args: &Args,
    params: &PreintParams,
    bias: &ImuBias,
    w: StreamWindow,
    fail: impl Fn(PreintError) -> CliError,
) -> Result<Integrated, CliError> {
    let fail = |e| fail(w.in_stream(e));
    let pim = preintegrate(params, bias, &w.samples, w.t_i_ns, w.t_j_ns).map_err(fail)?;
    let initial = args.predict.initial_state;
    let at = AtTimes::compute(params, bias, &w, &args.at, initial.as_ref()).map_err(fail)?;
    let truncation = (args.truncation)
        .then(|| preint::truncation::estimate(params, bias, &w.samples, &pim))
        .transpose()
        .map_err(fail)?
        .map(Truncation);
    let second_order = (args.second_order)
        .then(|| preint::second_order::covariance(params, &w.samples, &pim))
        .transpose()
        .map_err(fail)?
        .map(SecondOrder);
    Ok(Integrated {
        samples: input::count_in(&w.samples, w.t_i_ns, w.t_j_ns),
        pim,
        at,
        truncation,
        second_order,
    })
}

/// Samples pushed into the preintegrator at a time.
const CHUNK: usize = 4096;

/// Preintegrates every sample of `stream` (the window from its first to its last sample) in
/// chunks, without storing them; returns the measurement and the number of samples.
fn whole_recording(
    stream: CheckedSamples,
    params: PreintParams,
    bias: &ImuBias,
    fail: impl Fn(PreintError) -> CliError,
) -> Result<(PreintegratedImu, usize), CliError> {
    let params = PreintParams {
        keep_samples: false,
        ..params
    };
    let mut pi = Preintegrator::new(params, *bias).map_err(&fail)?;
    let (mut chunk, mut count) = (Vec::with_capacity(CHUNK), 0usize);
    for s in stream {
        chunk.push(s?);
        if chunk.len() == CHUNK {
            pi.integrate_slice(&chunk).map_err(&fail)?;
            count += chunk.len();
            chunk.clear();
        }
    }
    pi.integrate_slice(&chunk).map_err(&fail)?;
    count += chunk.len();
    Ok((pi.finish().map_err(&fail)?, count))
}

/// Runs `preint integrate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}
