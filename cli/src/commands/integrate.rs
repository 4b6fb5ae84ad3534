//! `preint integrate`: preintegrate a window of an IMU recording and print the deltas, their
//! covariances and the bias Jacobians.

use crate::imu_args::ImuArgs;
use crate::preint_args::PreintArgs;
use crate::scheme::{self};
use crate::{CliError, Output, input};
use nalgebra::Vector3;
use preint::deskew::{deltas_at, states_at};
use preint::{
    DeltasAt, ImuBias, ImuNoise, Level, NavState, PreintError, PreintParams, PreintegratedImu,
    Preintegrator, predict, preintegrate,
};
use preint_analysis::checks::UnitCheck;
use preint_analysis::format::{list, rows, text_matrix};
use preint_analysis::progress::ReadingBar;
use preint_analysis::recording::input_json;
use preint_analysis::{checks, noise, stream};
use preint_io::SourceInfo;
use serde_json::{Value, json};
use std::fmt::Write as _;

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
    #[arg(long, allow_hyphen_values = true, value_parser = preint_analysis::parse::vec3)]
    pub bias_gyro: Option<Vector3<f64>>,
    /// Accelerometer bias estimate b_a (m/s^2) as x,y,z.
    #[arg(long, allow_hyphen_values = true, value_parser = preint_analysis::parse::vec3)]
    pub bias_acc: Option<Vector3<f64>>,
    /// First keyframe time in ns (default: first sample).
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<i64>,
    /// Last keyframe time in ns (default: last sample).
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<i64>,
    /// Earth rotation and the predicted state at the window's end.
    #[command(flatten)]
    pub predict: crate::earth_args::PredictArgs,
    /// Times in ns inside the window (non-decreasing, comma-separated): also print the deltas
    /// from t_i at each, and with --initial-state the predicted state (keeps the window's
    /// samples in memory).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "T1,T2,..."
    )]
    pub at: Vec<i64>,
    /// Also estimate the window's own discretisation (truncation) error from its samples
    /// (`preint::truncation`: a hermite4 companion, or Richardson for hermite4). Reads the
    /// window rather than streaming the whole recording.
    #[arg(long)]
    pub truncation: bool,
    /// Also compute the second-order covariance term of the window's SE₂(3) error
    /// (`preint::second_order`: what the first-order covariance misses over long windows with
    /// noisy gyroscopes) and the increase of the mean χ² it accounts for. Reads the window
    /// rather than streaming the whole recording.
    #[arg(long)]
    pub second_order: bool,
    /// An IMU calibration file (what `calibrate --out` writes: OpenVINS kalibr_imu_chain.yaml,
    /// or Kalibr's imu.yaml with a scale-misalignment model): its intrinsics are applied to the
    /// raw samples, and its `time_offset` (s; t_imu = t_keyframe + time_offset) moves
    /// --from/--to onto the IMU's clock. Noise densities still come from --noise. A time
    /// offset recorded for a scheme that lags differently from --scheme (euler and galilean
    /// are half a sample behind midpoint and hermite4) is warned about, with the size of the
    /// lag; it is applied as recorded.
    #[arg(long, value_name = "FILE")]
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
    /// The state at the window's end predicted from `--initial-state` ([`preint::predict`]
    /// with the bias estimate and the Earth rate of the measurement).
    pub predicted: Option<NavState>,
    /// The deltas (and with `--initial-state` the predicted state) at each `--at` time
    /// ([`preint::deskew`]).
    pub at: Vec<(DeltasAt, Option<NavState>)>,
    /// The estimated truncation error of the deltas (`--truncation`).
    pub truncation: Option<preint::TruncationEstimate>,
    /// The second-order covariance term, [δφ, δv, δp] (`--second-order`).
    pub second_order: Option<preint::nalgebra::SMatrix<f64, 9, 9>>,
    /// The calibration file applied (`--calibration`): its path, intrinsics and the time
    /// offset \[ns\] added to `--from`/`--to`.
    pub calibration: Option<(String, preint::intrinsics::ImuIntrinsics, i64)>,
    /// The scheme the file's time offset was estimated for (`preint_scheme`), and the line
    /// [`preint_analysis::calibration_file::scheme_note`] prints when it lags differently from the
    /// scheme used, or is unknown.
    pub calibration_scheme: (Option<preint::Scheme>, Option<String>),
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
        .map(preint_analysis::calibration_file::read)
        .transpose()?;
    let calibration = match (&args.calibration, &file) {
        (Some(path), Some(cal)) => {
            if !cal.intrinsics.is_identity() {
                params.intrinsics =
                    Some(preint::intrinsics::AppliedIntrinsics::new(cal.intrinsics));
            }
            let td = preint_analysis::calibration_file::time_offset_ns(cal);
            Some((path.display().to_string(), cal.intrinsics, td))
        }
        _ => None,
    };
    // The keyframes on the IMU's clock.
    let td = calibration.as_ref().map_or(0, |c| c.2);
    let (from, to) = (args.from.map(|t| t + td), args.to.map(|t| t + td));
    let scheme = params.scheme;
    let (body_p_sensor, lever_arm) = (params.body_p_sensor, params.lever_arm);
    let input = args.input.to_input();
    let fail = |e| CliError::failed_in(input.path(), e);
    let initial = args.predict.initial_state;
    let window = |params: &PreintParams, w: stream::StreamWindow| {
        let pim = preintegrate(params, &bias, &w.samples, w.t_i_ns, w.t_j_ns)
            .map_err(|e| fail(w.in_stream(e)))?;
        let at = inside(params, &bias, &w, &args.at, initial.as_ref())
            .map_err(|e| fail(w.in_stream(e)))?;
        let truncation = args
            .truncation
            .then(|| preint::truncation::estimate(params, &bias, &w.samples, &pim))
            .transpose()
            .map_err(|e| fail(w.in_stream(e)))?;
        let second_order = args
            .second_order
            .then(|| preint::second_order::covariance(params, &w.samples, &pim))
            .transpose()
            .map_err(|e| fail(w.in_stream(e)))?;
        let count = input::count_in(&w.samples, w.t_i_ns, w.t_j_ns);
        Ok::<_, CliError>((pim, count, at, truncation, second_order))
    };
    let (source, unit_check, noise, (pim, samples, at, truncation, second_order)) = if input
        .is_split()
    {
        // The merged accelerometer's effective density is known once the files are read.
        let (w, source, split, units) = stream::split_window(&input, from, to)?;
        let noise = noise::apply_split(&noise, split.as_ref(), &mut params);
        (source, units, noise, window(&params, w)?)
    } else {
        // `--truncation` reads enough samples around the window for its companion's stencils.
        let edge = if args.truncation {
            stream::EDGE_SAMPLES.max(preint::truncation::CONTEXT_SAMPLES)
        } else {
            stream::EDGE_SAMPLES
        };
        let stream = stream::open_checked_window(&input, to, edge)?;
        let (source, units) = (stream.info().clone(), stream.unit_check().clone());
        let _bar = ReadingBar::start(stream.progress(), "integrate");
        let streamed = from.is_none() && to.is_none();
        let result = if streamed && args.at.is_empty() && !args.truncation && !args.second_order {
            let (pim, count) = whole_recording(stream, params, &bias, fail)?;
            (pim, count, vec![], None, None)
        } else {
            window(
                &params,
                stream::cut_window_with_edge(stream, from, to, edge)?,
            )?
        };
        (source, units, noise, result)
    };
    let calibration_scheme = match (&args.calibration, &file) {
        (Some(path), Some(cal)) => {
            let dt_s = pim.delta_t / samples.max(1) as f64;
            let note = preint_analysis::calibration_file::scheme_note(cal, path, scheme, dt_s);
            (cal.scheme, note)
        }
        _ => (None, None),
    };
    Ok(Integration {
        calibration_scheme,
        imu: input.label(),
        source,
        unit_check,
        scheme,
        samples,
        noise,
        noise_source: args.preint.noise_source(),
        bias,
        predicted: args.predict.initial_state.map(|x| predict(&pim, &x, &bias)),
        pim,
        body_p_sensor,
        lever_arm,
        at,
        truncation,
        second_order,
        calibration,
    })
}

/// The deltas (and states from `initial`) at the `--at` times of the window `w`, in one pass.
fn inside(
    params: &PreintParams,
    bias: &ImuBias,
    w: &stream::StreamWindow,
    times: &[i64],
    initial: Option<&NavState>,
) -> Result<Vec<(DeltasAt, Option<NavState>)>, PreintError> {
    if times.is_empty() {
        return Ok(vec![]);
    }
    let ends = (w.t_i_ns, w.t_j_ns);
    Ok(match initial {
        Some(x) => states_at(params, bias, &w.samples, ends, x, times)?
            .into_iter()
            .map(|s| (s.deltas, Some(s.state)))
            .collect(),
        None => deltas_at(params, bias, &w.samples, ends, times)?
            .into_iter()
            .map(|d| (d, None))
            .collect(),
    })
}

/// The `--at` rows as JSON.
fn at_json(at: &[(DeltasAt, Option<NavState>)]) -> Value {
    at.iter()
        .map(|(d, x)| {
            let mut row = json!({
                "t_ns": d.t_ns,
                "delta_t": d.delta_t,
                "delta_R": rows(d.delta_r.matrix()),
                "delta_R_log": list(&d.delta_r.log()),
                "delta_v": list(&d.delta_v),
                "delta_p": list(&d.delta_p),
            });
            if let Some(x) = x {
                row["predicted"] = json!({
                    "position": list(&x.p), "velocity": list(&x.v), "rotation": rows(x.r.matrix()),
                });
            }
            row
        })
        .collect()
}

/// Samples pushed into the preintegrator at a time.
const CHUNK: usize = 4096;

/// Preintegrates every sample of `stream` (the window from its first to its last sample) in
/// chunks, without storing them; returns the measurement and the number of samples.
fn whole_recording(
    stream: stream::CheckedSamples,
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

/// What each printed covariance describes, and how GTSAM's relate to them.
fn covariance_notes() -> Value {
    json!({
        "covariance": "covariance of the error [dphi, dv, dp] = measured minus true deltas \
            (dphi: DR_measured = DR_true Exp(dphi)); white measurement noise. It is also the \
            covariance of ImuFactor's residual [r_phi, r_v, r_p] (= -[dphi, dv, dp]).",
        "covariance15": "covariance of the error state [dphi, dv, dp, db_g, db_a], db = b_j - b_i, \
            with the bias random walk over the window; what merging windows composes. A gyro \
            bias that drifts up makes the measured rotation run ahead: the delta-bias blocks \
            are those of measured minus true.",
        "residual_covariance15": "covariance of CombinedImuFactor's residual [r_phi, r_v, r_p, \
            b_g,j - b_g,i, b_a,j - b_a,i] at the true states (the deltas' rows are true minus \
            measured): covariance15 with its 9x6 and 6x9 delta-bias blocks negated. Weight a \
            combined residual with this one.",
        "gtsam": "GTSAM 4.3 orders [rot, pos, vel, b_a, b_g] and expresses pos and vel errors \
            rotated by delta_R^T: with P the reordering and T = diag(I, delta_R^T, delta_R^T, I, I), \
            PreintegratedCombinedMeasurements::preintMeasCov() = T P covariance15 P^T T^T and \
            residualCovariance() = T P residual_covariance15 P^T T^T (tested to 1e-12 on \
            PreintegratedCombinedMeasurementsManifold, the euler scheme).",
    })
}

/// The JSON form: deltas, covariances (with notes on what each describes), bias Jacobians, the noise
/// used and the units.
pub fn to_json(r: &Integration) -> Value {
    let m = &r.pim;
    let jac = &m.jac;
    let mut noise = noise::densities_json(&r.noise);
    noise["source"] = json!(r.noise_source);
    noise["units"] = json!(
        "continuous-time densities: rad/s/sqrt(Hz), rad/s^2/sqrt(Hz), m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)"
    );
    let mut out = json!({
        "imu": r.imu,
        "input": input_json(&r.source, &r.unit_check),
        "scheme": scheme::label(r.scheme),
        "samples": r.samples,
        "t_i_ns": m.t_i_ns,
        "t_j_ns": m.t_j_ns,
        "delta_t": m.delta_t,
        "delta_R": rows(m.delta_r.matrix()),
        "delta_R_log": list(&m.delta_r.log()),
        "delta_v": list(&m.delta_v),
        "delta_p": list(&m.delta_p),
        "tangent_order": ["dphi_x", "dphi_y", "dphi_z", "dv_x", "dv_y", "dv_z", "dp_x", "dp_y", "dp_z"],
        "covariance": rows(&m.cov),
        "covariance15_order": "[dphi, dv, dp, db_g, db_a]",
        "covariance15": rows(&m.cov15),
        "residual_covariance15_order": "[r_phi, r_v, r_p, r_bg, r_ba]",
        "residual_covariance15": rows(&m.residual_cov15()),
        "covariance_notes": covariance_notes(),
        "bias_hat": {"gyro": list(&r.bias.gyro), "acc": list(&r.bias.acc)},
        "gravity": list(&m.gravity),
        "body_p_sensor": r.body_p_sensor.map(|p| json!({
            "translation": list(&p.translation),
            "rotation": rows(p.rotation.matrix()),
            "lever_arm": r.lever_arm.name(),
            "note": "IMU pose in the body: translation = IMU origin in body coordinates [m], \
                rotation = sensor-to-body; delta_R, delta_v, delta_p and their covariances are \
                the body's, biases the IMU's (its own axes)",
        })),
        "noise": noise,
        "units": {"delta_t": "s", "delta_v": "m/s (body frame i)", "delta_p": "m (body frame i)",
                  "covariance": "rad^2, (m/s)^2, m^2 blocks", "jacobians": "d(delta)/d(bias), bias order [b_g, b_a]"},
        "jacobians": {
            "dR_dbg": rows(&jac.d_r_d_bg), "dv_dbg": rows(&jac.d_v_d_bg), "dv_dba": rows(&jac.d_v_d_ba),
            "dp_dbg": rows(&jac.d_p_d_bg), "dp_dba": rows(&jac.d_p_d_ba),
        },
        "omega_coriolis": m.omega_coriolis.map(|w| list(&w)),
        "coriolis": m.omega_coriolis.map(|_| crate::earth_args::mode_label(m.coriolis)),
    });
    if !r.at.is_empty() {
        out["at"] = at_json(&r.at);
    }
    if let Some(t) = &r.truncation {
        out["truncation"] = json!({
            "error": t.error.iter().copied().collect::<Vec<f64>>(), "method": t.method,
            "companion_covariance": rows(&t.companion_cov),
            "order": "[dphi, dv, dp]: measured minus exact deltas, the chart of covariance",
            "units": {"dphi": "rad", "dv": "m/s", "dp": "m"},
        });
    }
    if let Some((file, x, td)) = &r.calibration {
        out["calibration"] = json!({
            "file": file, "time_offset_ns": td, "model": x.model.name(),
            "Tw": rows(&x.t_w), "R_IMUtoGYRO": rows(&x.r_imu_to_gyro), "Ta": rows(&x.t_a),
            "R_IMUtoACC": rows(&x.r_imu_to_acc), "Tg": rows(&x.t_g),
            "note": "intrinsics applied to the raw samples (preint::intrinsics); t_i_ns and \
                     t_j_ns are on the IMU clock: --from/--to plus time_offset_ns",
            "scheme": r.calibration_scheme.0.map(scheme::label),
            "scheme_note": r.calibration_scheme.1,
        });
    }
    if let Some(c) = &r.second_order {
        out["second_order"] = json!({
            "covariance": rows(c),
            "chi2_increase": chi2_increase(&r.pim, c),
            "order": "[dphi, dv, dp], the chart of covariance",
            "units": "rad^2, (m/s)^2, m^2 blocks",
            "note": "add to covariance to weight a factor with the second-order covariance; \
                     chi2_increase = tr(covariance^-1 term), the mean chi2 at the true states \
                     that the first-order covariance does not account for",
        });
    }
    if let Some(x) = &r.predicted {
        out["predicted"] = json!({
            "position": list(&x.p), "velocity": list(&x.v), "rotation": rows(x.r.matrix()),
            "units": {"position": "m (world frame)", "velocity": "m/s (world frame)",
                      "rotation": "3x3 rows, body -> world"},
        });
    }
    out
}

/// The human summary: deltas, noise, 1σ, the 9×9 covariance and the five bias Jacobians.
pub fn to_text(r: &Integration) -> String {
    let (m, noise) = (&r.pim, &r.noise);
    let mut h = String::new();
    let _ = writeln!(
        h,
        "{} (read as {}): {} samples, scheme {}, Δt = {:.9} s",
        r.imu,
        r.source.describe(),
        r.samples,
        scheme::label(r.scheme),
        m.delta_t
    );
    h.push_str(&preint_analysis::recording::input_text(
        &r.source,
        &r.unit_check,
    ));
    let phi = m.delta_r.log();
    let _ = writeln!(
        h,
        "ΔR = Exp([{:.9}, {:.9}, {:.9}]) (rotation vector, rad; |φ| = {:.6}°)",
        phi.x,
        phi.y,
        phi.z,
        phi.norm().to_degrees()
    );
    let _ = writeln!(
        h,
        "Δv = [{:.9}, {:.9}, {:.9}] m/s (body frame i, gravity excluded)",
        m.delta_v.x, m.delta_v.y, m.delta_v.z
    );
    let _ = writeln!(
        h,
        "Δp = [{:.9}, {:.9}, {:.9}] m (body frame i, gravity excluded)",
        m.delta_p.x, m.delta_p.y, m.delta_p.z
    );
    if let Some(pose) = &r.body_p_sensor {
        let t = pose.translation;
        let _ = writeln!(
            h,
            "body frame: IMU at [{:.4}, {:.4}, {:.4}] m in the body, rotated by {:.4}° (the deltas \
             are the body's, lever arm removed exactly; biases are the IMU's)",
            t.x,
            t.y,
            t.z,
            pose.rotation.log().norm().to_degrees()
        );
    }
    let sd: Vec<f64> = (0..9).map(|i| m.cov[(i, i)].sqrt()).collect();
    let _ = writeln!(
        h,
        "noise: {}: σ_g = {:.4e} rad/s/√Hz, σ_a = {:.4e} m/s²/√Hz, σ_bg = {:.4e} rad/s²/√Hz, σ_ba = {:.4e} m/s³/√Hz",
        r.noise_source,
        noise.gyro_noise_density,
        noise.acc_noise_density,
        noise.gyro_random_walk,
        noise.acc_random_walk
    );
    let _ = writeln!(
        h,
        "1σ (noise): φ [{:.3e} {:.3e} {:.3e}] rad, v [{:.3e} {:.3e} {:.3e}] m/s, p [{:.3e} {:.3e} {:.3e}] m",
        sd[0], sd[1], sd[2], sd[3], sd[4], sd[5], sd[6], sd[7], sd[8]
    );
    let _ = writeln!(h, "covariance, tangent order [δφ, δv, δp]:");
    h.push_str(&text_matrix(&m.cov, "  "));
    let jac = &m.jac;
    for (name, j) in [
        ("∂ΔR/∂b_g", &jac.d_r_d_bg),
        ("∂Δv/∂b_g", &jac.d_v_d_bg),
        ("∂Δv/∂b_a", &jac.d_v_d_ba),
        ("∂Δp/∂b_g", &jac.d_p_d_bg),
        ("∂Δp/∂b_a", &jac.d_p_d_ba),
    ] {
        let _ = writeln!(h, "{name}:");
        h.push_str(&text_matrix(j, "  "));
    }
    if let Some(w) = m.omega_coriolis {
        let _ = writeln!(
            h,
            "world frame rotating at ω = [{:e}, {:e}, {:e}] rad/s, Coriolis mode {}",
            w.x,
            w.y,
            w.z,
            crate::earth_args::mode_label(m.coriolis)
        );
    }
    if let Some(t) = &r.truncation {
        let e = &t.error;
        let n = |i: usize| e.fixed_rows::<3>(i).norm();
        let _ = writeln!(
            h,
            "truncation error (estimated, {}): |δφ| {:.2e} rad, |δv| {:.2e} m/s, |δp| {:.2e} m \
             (1σ of the noise: {:.2e} rad, {:.2e} m/s, {:.2e} m)",
            t.method,
            n(0),
            n(3),
            n(6),
            (m.cov[(0, 0)] + m.cov[(1, 1)] + m.cov[(2, 2)]).sqrt(),
            (m.cov[(3, 3)] + m.cov[(4, 4)] + m.cov[(5, 5)]).sqrt(),
            (m.cov[(6, 6)] + m.cov[(7, 7)] + m.cov[(8, 8)]).sqrt()
        );
    }
    if let Some((file, x, td)) = &r.calibration {
        let _ = writeln!(
            h,
            "calibration {file}: intrinsics ({} model{}) applied to the raw samples; keyframes \
             moved by the time offset {td} ns onto the IMU clock",
            x.model.name(),
            if x.is_identity() { ", identity" } else { "" }
        );
        if let Some(n) = &r.calibration_scheme.1 {
            let _ = writeln!(h, "{n}");
        }
    }
    if let Some(c) = &r.second_order {
        let _ = writeln!(
            h,
            "second-order covariance term [δφ, δv, δp] (add to the 9×9 covariance; the mean χ² \
             at the true states it accounts for: +{:.3}):",
            chi2_increase(m, c)
        );
        h.push_str(&text_matrix(c, "  "));
    }
    if let Some(x) = &r.predicted {
        let _ = writeln!(
            h,
            "predicted at t_j: p = [{:.9}, {:.9}, {:.9}] m, v = [{:.9}, {:.9}, {:.9}] m/s (world frame)",
            x.p.x, x.p.y, x.p.z, x.v.x, x.v.y, x.v.z
        );
        let _ = writeln!(h, "predicted R (body → world):");
        h.push_str(&text_matrix(x.r.matrix(), "  "));
    }
    for (d, x) in &r.at {
        let phi = d.delta_r.log();
        let _ = write!(
            h,
            "at {} ns (Δt = {:.9} s): φ = [{:.9}, {:.9}, {:.9}] rad, Δv = [{:.9}, {:.9}, {:.9}] m/s, \
             Δp = [{:.9}, {:.9}, {:.9}] m",
            d.t_ns,
            d.delta_t,
            phi.x,
            phi.y,
            phi.z,
            d.delta_v.x,
            d.delta_v.y,
            d.delta_v.z,
            d.delta_p.x,
            d.delta_p.y,
            d.delta_p.z
        );
        if let Some(x) = x {
            let _ = write!(
                h,
                "; p = [{:.9}, {:.9}, {:.9}] m, v = [{:.9}, {:.9}, {:.9}] m/s",
                x.p.x, x.p.y, x.p.z, x.v.x, x.v.y, x.v.z
            );
        }
        h.push('\n');
    }
    h
}

/// Runs `preint integrate`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let r = compute(args)?;
    Ok(Output {
        human: to_text(&r),
        json: to_json(&r),
    })
}

/// `tr(Σ⁻¹ S)`: the mean χ² at the true states a term `S` adds over the first-order `Σ`
/// (`E[rᵀ Σ⁻¹ r] = tr(Σ⁻¹ (Σ + S))`); `NaN` when `Σ` is singular.
fn chi2_increase(m: &PreintegratedImu, s: &preint::nalgebra::SMatrix<f64, 9, 9>) -> f64 {
    m.cov
        .cholesky()
        .map_or(f64::NAN, |c| (c.inverse() * s).trace())
}
