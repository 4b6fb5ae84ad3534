//! The numbers of `preint report --imu`, on the user's recording:
//!
//! 1. the audit ([`preint_analysis::audit`]) and its verdict;
//! 2. `advise` on the recording's own motion ([`preint_analysis::advise::advise_samples`]),
//!    with the given densities (for a static recording without `--noise`, its Allan ones);
//! 3. with ground truth: the IMU factor's consistency per window length ([`consistency`])
//!    with the given noise model and with the one fitted by
//!    [`preint_analysis::calibrate::noise_model`], whose Kalibr `imu.yaml` is written;
//! 4. for a static recording (still in at least 90 % of the audit's windows): the Allan
//!    deviation ([`preint_analysis::allan`]) and the static calibration
//!    ([`preint_analysis::calibrate`]).
//!
//! A section whose computation cannot answer on this recording (e.g. `advise` on too few
//! samples) keeps the reason instead of failing the report; an input that cannot be read fails
//! it, naming the file and line.
//!
//! [`conclusions()`] turns these numbers into the statements at the top of the page.

mod conclusions;

pub use conclusions::conclusions;

use crate::CliError;
use nalgebra::Vector3;
use preint::{ImuNoise, Level, PreintParams, Scheme};
use preint_analysis::advise::{self, Advice};
use preint_analysis::allan::AllanRun;
use preint_analysis::audit::{AuditRun, Report};
use preint_analysis::calibrate::CalibrateRun;
use preint_analysis::calibrate::noise_model::{self, DEFAULT_WINDOWS_S, NoiseOptions, NoiseRun};
use preint_analysis::chi2_windows::{self, LengthSummary, Verdict};
use preint_analysis::consistency::TruthNoise;
use preint_analysis::factor_windows::{FactorKind, per_length};
use preint_analysis::input_class::InputClass;
use preint_analysis::truth_windows::{overlap, read_window};
use preint_analysis::{Error, ImuInput, stream};
use preint_calib::allan::StillnessOptions;
use preint_calib::noise_fit::Withheld;
use preint_io::{GroundTruthState, read_euroc_groundtruth};
use std::path::{Path, PathBuf};

/// The scheme the ground-truth windows are preintegrated with (`factor`'s default).
pub const SCHEME: Scheme = Scheme::Midpoint;
/// Gravity magnitude \[m/s²\] of the preintegration (`factor`'s default).
pub const GRAVITY_M_S2: f64 = 9.81;
pub use super::report::ADVISE_WINDOW_FRACTION;
/// The window lengths \[s\] of the consistency and of the noise fit (the fit's default).
pub const WINDOWS_S: [f64; 4] = DEFAULT_WINDOWS_S;
/// The file the fitted noise model is written to, in the output directory.
pub const FITTED_YAML: &str = "imu.yaml";
/// The file the Allan densities of a static recording are written to.
pub const ALLAN_YAML: &str = "imu_allan.yaml";

/// What `report --imu` runs on (each field is the flag of the same name).
#[derive(Clone, Debug)]
pub struct Options {
    /// The recording and how to read it (`--imu` and the reader flags).
    pub input: ImuInput,
    /// EuRoC ground truth with velocities and biases (`--poses`).
    pub poses: Option<PathBuf>,
    /// Kalibr imu.yaml with the noise densities (`--noise`; default: EuRoC figures).
    pub noise: Option<PathBuf>,
    /// The ground truth's own errors as given (`--pose-rot-std` \[rad\], `--pose-pos-std`
    /// \[m\], `--vel-std` \[m/s\], `--bias-gyro-std` \[rad/s\], `--bias-acc-std` \[m/s²\]):
    /// 0 in the weight with the given noise when not given, fitted when not given.
    pub truth: [Option<f64>; 5],
    /// The output directory.
    pub out: PathBuf,
}

impl Options {
    /// The given ground-truth errors, 0 where not given.
    pub fn truth_noise(&self) -> TruthNoise {
        let t = self.truth.map(|x| x.unwrap_or(0.0));
        TruthNoise {
            rot_rad: t[0],
            pos_m: t[1],
            vel_m_s: t[2],
            bias_gyro_rad_s: t[3],
            bias_acc_m_s2: t[4],
        }
    }
}

/// A noise model to test the IMU factor with: the sensor's densities and the ground truth's
/// own errors.
#[derive(Clone, Copy, Debug)]
pub struct NoiseModel {
    /// The noise densities and random walks.
    pub noise: ImuNoise,
    /// The ground truth's own errors added to the weight.
    pub truth: TruthNoise,
    /// The world gravity vector \[m/s²\].
    pub gravity: Vector3<f64>,
    /// `ImuFactor` weighted with the bias random walk within the window
    /// (`ImuFactor::with_in_window_drift`), else with the white noise alone (GTSAM's weight).
    pub in_window_drift: bool,
}

/// The IMU factor at the ground truth per window length, under one noise model.
#[derive(Clone, Debug)]
pub struct Consistency {
    /// The model tested.
    pub model: NoiseModel,
    /// The span where the recording and the ground truth overlap \[ns\].
    pub span_ns: (i64, i64),
    /// One summary per length of [`WINDOWS_S`].
    pub lengths: Vec<LengthSummary>,
    /// What they say about the model.
    pub verdict: Verdict,
}

/// The ground-truth part of the report.
#[derive(Clone, Debug)]
pub struct TruthCheck {
    /// With the given noise model (`--noise` or the EuRoC figures, the given ground-truth
    /// errors).
    pub given: Consistency,
    /// The noise fit (its Kalibr `imu.yaml` written to [`FITTED_YAML`]).
    pub fit: NoiseRun,
    /// With the fitted noise model (densities as written, the fitted ground-truth errors).
    pub fitted: Consistency,
}

/// The static part of the report: each result, or why it could not be computed.
#[derive(Clone, Debug)]
pub struct StaticCheck {
    /// The Allan deviation and its fits.
    pub allan: Result<AllanRun, String>,
    /// The static calibration (with the Allan densities unless `--noise` was given).
    pub calibration: Result<CalibrateRun, String>,
}

/// The machine the costs were timed on.
#[derive(Clone, Debug)]
pub struct Machine {
    /// CPU model (`model name` of /proc/cpuinfo; `unknown CPU` elsewhere).
    pub cpu: String,
    /// Logical cores available.
    pub cores: usize,
}

impl Machine {
    /// This machine.
    pub fn this() -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown CPU".into());
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        Machine { cpu, cores }
    }
}

/// Everything `report --imu` shows.
#[derive(Clone, Debug)]
pub struct RecordingData {
    /// The recording, as printed.
    pub imu: String,
    /// The audit.
    pub audit: AuditRun,
    /// The noise densities given (`--noise`, or the EuRoC figures) and where they came from.
    pub noise: (ImuNoise, String),
    /// `advise` on the recording, or why it could not answer.
    pub advice: Result<Advice, String>,
    /// The densities `advise` ran with, in words: the given ones, or for a static recording
    /// without `--noise` the Allan densities.
    pub advice_noise: String,
    /// With `--poses`: the consistency and the noise fit.
    pub truth: Option<TruthCheck>,
    /// For a static recording: the Allan deviation and the static calibration.
    pub still: Option<StaticCheck>,
    /// Where the costs were timed.
    pub machine: Machine,
    /// The unit checks were skipped (`--no-unit-check`).
    pub no_unit_check: bool,
}

/// An unreadable input fails the report; any other error is kept as the section's reason.
fn kept<T>(r: Result<T, Error>) -> Result<Result<T, String>, CliError> {
    match r {
        Ok(x) => Ok(Ok(x)),
        Err(Error::Io(e)) => Err(CliError::Io(e)),
        Err(e) => Ok(Err(e.to_string())),
    }
}

/// The fraction of the audit's still windows (one stream only; 0 for a split recording).
pub fn still_fraction(audit: &AuditRun) -> f64 {
    match &audit.report {
        Report::Single(a) => a.still.fraction(),
        Report::Split(_) => 0.0,
    }
}

/// Whether the recording is static: still in at least the fraction of windows the Allan
/// stillness check asks for.
pub fn is_static(audit: &AuditRun) -> bool {
    still_fraction(audit) >= StillnessOptions::default().min_still_fraction
}

/// Computes every section (module docs), calling `progress` with the name of each finished
/// one; writes the fitted `imu.yaml` (and, for a static recording, the Allan densities) into
/// `o.out`.
pub fn compute(o: &Options, progress: &mut dyn FnMut(&str)) -> Result<RecordingData, CliError> {
    let audit = preint_analysis::audit::compute(&preint_analysis::audit::Options {
        input: o.input.clone(),
        calibration: None,
    })?;
    progress("audit");
    let noise = preint_analysis::noise::or_default(o.noise.as_deref())?;
    let source = preint_analysis::noise::source(o.noise.as_deref());
    let still = if is_static(&audit) {
        Some(static_check(o)?)
    } else {
        None
    };
    progress("static");
    let advice_noise = match (&o.noise, &still) {
        (None, Some(StaticCheck { allan: Ok(a), .. })) => (
            a.allan.to_imu_noise(),
            format!("the Allan densities of `{ALLAN_YAML}`"),
        ),
        _ => (noise, "the given densities".to_string()),
    };
    let advice = kept(advise_recording(o, &advice_noise.0))?;
    progress("advise");
    let truth = match &o.poses {
        Some(poses) => Some(truth_check(o, poses, &noise)?),
        None => None,
    };
    progress("ground truth");
    Ok(RecordingData {
        imu: o.input.label(),
        audit,
        noise: (noise, source),
        advice,
        advice_noise: advice_noise.1,
        truth,
        still,
        machine: Machine::this(),
        no_unit_check: o.input.no_unit_check,
    })
}

/// Number of `progress` calls of [`compute`].
pub const STEPS: u64 = 4;

/// `advise` on the whole recording with the given densities and its default window and
/// threshold ([`ADVISE_WINDOW_FRACTION`]).
fn advise_recording(o: &Options, noise: &ImuNoise) -> Result<Advice, Error> {
    let (window, fraction) = ADVISE_WINDOW_FRACTION;
    let opts = advise::Options {
        input: o.input.clone(),
        noise: o.noise.clone().unwrap_or_default(),
        window,
        fraction,
        from: None,
        to: None,
        input_class: InputClass::Smooth,
        calibration: None,
    };
    let span = stream::read_span(&o.input, None, None, "advise")?;
    advise::advise_samples(
        &opts,
        &span.samples,
        noise,
        Some(span.source),
        span.unit_check,
    )
}

/// The IMU factor at the ground truth `gt` (read from `poses`) over back-to-back windows of
/// each length of [`WINDOWS_S`], weighted by `model`: its statistics per length and verdict
/// ([`preint_analysis::chi2_windows`]).
pub fn consistency(
    input: &ImuInput,
    (poses, gt): (&Path, &[GroundTruthState]),
    model: &NoiseModel,
) -> Result<Consistency, Error> {
    let level = if model.in_window_drift {
        Level::Combined
    } else {
        Level::Covariance
    };
    let mut params = PreintParams::from_noise(&model.noise)
        .with_scheme(SCHEME)
        .with_level(level)
        .with_gravity(model.gravity);
    let (w, _, _) = read_window(input, &model.noise, &mut params, (None, None))?;
    let samples = w.samples.as_slice();
    let span_dt = overlap(samples, gt, (&input.label(), poses), "--poses")?;
    let kind = FactorKind {
        in_window_drift: model.in_window_drift,
        ..FactorKind::default()
    };
    let lengths = per_length(
        &kind,
        &params,
        (samples, gt),
        span_dt,
        &WINDOWS_S,
        model.truth,
    )?;
    Ok(Consistency {
        model: *model,
        span_ns: span_dt.0,
        verdict: chi2_windows::verdict(&lengths),
        lengths,
    })
}

/// The noise fit's model: the densities as written to its `imu.yaml`, the ground-truth
/// errors fitted or held (0 where withheld, as the fit's JSON leaves them out), the world
/// gravity the fit supports (else the given one), and the in-window drift in the weight (the
/// fit's windows carry it).
pub fn fitted_model(fit: &NoiseRun) -> NoiseModel {
    let v = |k: usize| {
        let p = &fit.fit.params[k];
        match p.withheld {
            None | Some(Withheld::Held) => p.value,
            Some(_) => 0.0,
        }
    };
    NoiseModel {
        noise: noise_model::fitted_noise(fit),
        truth: TruthNoise {
            rot_rad: v(4),
            pos_m: v(5),
            vel_m_s: v(6),
            bias_gyro_rad_s: v(7),
            bias_acc_m_s2: v(8),
        },
        gravity: noise_model::gravity_in_use(fit),
        in_window_drift: true,
    }
}

/// The consistency with the given model, the noise fit (written to [`FITTED_YAML`]) and the
/// consistency with the fitted model.
fn truth_check(o: &Options, poses: &Path, noise: &ImuNoise) -> Result<TruthCheck, CliError> {
    let tn = o.truth_noise();
    let flags = [
        "--pose-rot-std",
        "--pose-pos-std",
        "--vel-std",
        "--bias-gyro-std",
        "--bias-acc-std",
    ];
    let values = [
        tn.rot_rad,
        tn.pos_m,
        tn.vel_m_s,
        tn.bias_gyro_rad_s,
        tn.bias_acc_m_s2,
    ];
    for (flag, v) in flags.into_iter().zip(values) {
        preint_analysis::checks::non_negative(flag, v)?;
    }
    let gt = read_euroc_groundtruth(poses)?;
    let model = NoiseModel {
        noise: *noise,
        truth: tn,
        gravity: Vector3::new(0.0, 0.0, -GRAVITY_M_S2),
        in_window_drift: false,
    };
    let given = consistency(&o.input, (poses, &gt), &model)?;
    let [rot, pos, vel, bg, ba] = o.truth;
    let fit = noise_model::compute(&NoiseOptions {
        input: o.input.clone(),
        poses: Some(poses.to_path_buf()),
        window: Some(WINDOWS_S.to_vec()),
        noise: o.noise.clone(),
        gravity: GRAVITY_M_S2,
        from: None,
        to: None,
        pose_rot_std: rot,
        pose_pos_std: pos,
        vel_std: vel,
        bias_gyro_std: bg,
        bias_acc_std: ba,
        body_p_sensor: None,
        scheme: SCHEME,
        out: Some(o.out.join(FITTED_YAML)),
    })?;
    let fitted = consistency(&o.input, (poses, &gt), &fitted_model(&fit))?;
    Ok(TruthCheck { given, fit, fitted })
}

/// The Allan deviation (its densities written to [`ALLAN_YAML`]) and the static calibration,
/// weighted with `--noise` when given, else with those densities.
fn static_check(o: &Options) -> Result<StaticCheck, CliError> {
    let allan = kept(preint_analysis::allan::compute(
        &preint_analysis::allan::Options {
            input: o.input.clone(),
            no_still_check: false,
        },
    ))?;
    let mut noise = o.noise.clone();
    if let Ok(a) = &allan {
        let path = o.out.join(ALLAN_YAML);
        preint_io::write_kalibr_yaml(&path, &a.allan.to_imu_noise())?;
        noise = noise.or(Some(path));
    }
    let calibration = kept(preint_analysis::calibrate::compute(
        &preint_analysis::calibrate::Options {
            input: o.input.clone(),
            poses: None,
            estimate: None,
            pose_spacing: 0.5,
            calibration: None,
            noise,
            gravity: GRAVITY_M_S2,
            from: None,
            to: None,
            pose_rot_std: 0.0,
            pose_pos_std: 0.0,
            body_p_sensor: None,
            latitude: None,
            heading: None,
            out: None,
            scheme: SCHEME,
        },
    ))?;
    Ok(StaticCheck { allan, calibration })
}
