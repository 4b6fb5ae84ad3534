//! What both forms of `factor` share: the keyframes and the window read from the recording,
//! the ground truth's errors and the noise model from the flags, and one window's factor
//! evaluated at the ground truth.

use super::Args;
use crate::{CliError, input};
use preint::{
    CombinedImuFactor, ImuFactor, ImuNoise, Level, NavState, PreintParams, PreintegratedImu,
    preintegrate,
};
use preint_analysis::consistency::{Evaluation, ResidualJacobians, TruthNoise, evaluate};
use preint_analysis::stream::StreamWindow;
use preint_analysis::{ImuInput, checks};
use preint_io::{GroundTruthState, read_euroc_groundtruth};

fn nav(s: &GroundTruthState) -> NavState {
    NavState::new(s.rotation(), s.p, s.v)
}

/// The ground-truth rows nearest to `--from` and `--to`: two different rows, the first
/// earlier.
pub(super) fn keyframes(
    args: &Args,
    (from, to): (i64, i64),
) -> Result<(GroundTruthState, GroundTruthState), CliError> {
    let gt = read_euroc_groundtruth(&args.poses)?;
    let (gi, gj) = (*input::nearest_row(&gt, from), *input::nearest_row(&gt, to));
    if gj.t_ns <= gi.t_ns {
        return Err(CliError::Usage(format!(
            "{}: the ground-truth rows nearest to --from {} and --to {} are at {} and {} ns; \
             they must be two different rows, the first earlier",
            args.poses.display(),
            from,
            to,
            gi.t_ns,
            gj.t_ns
        )));
    }
    Ok((gi, gj))
}

pub(crate) use preint_analysis::truth_windows::read_window as window;

/// The ground truth's own errors (`--pose-rot-std`, `--pose-pos-std`, `--vel-std`,
/// `--bias-gyro-std`, `--bias-acc-std`), each checked finite and non-negative.
pub(crate) fn truth_noise(args: &Args) -> Result<TruthNoise, CliError> {
    let tn = TruthNoise {
        rot_rad: args.pose_rot_std,
        pos_m: args.pose_pos_std,
        vel_m_s: args.vel_std,
        bias_gyro_rad_s: args.bias_gyro_std,
        bias_acc_m_s2: args.bias_acc_std,
    };
    checks::non_negative("--pose-rot-std", tn.rot_rad)?;
    checks::non_negative("--pose-pos-std", tn.pos_m)?;
    checks::non_negative("--vel-std", tn.vel_m_s)?;
    checks::non_negative("--bias-gyro-std", tn.bias_gyro_rad_s)?;
    checks::non_negative("--bias-acc-std", tn.bias_acc_m_s2)?;
    Ok(tn)
}

/// The noise model and parameters at the factor's level (the bias random walk with
/// `--combined` or `--in-window-drift`, whose noise file must hold it).
pub(crate) fn noise_params(args: &Args) -> Result<(ImuNoise, PreintParams), CliError> {
    let level = if args.combined || args.in_window_drift {
        Level::Combined
    } else {
        Level::Covariance
    };
    let (noise, params) = args.preint.params(level)?;
    if let (true, Some(path)) = (args.combined || args.in_window_drift, &args.preint.noise) {
        preint_io::read_kalibr_bias_model(path)?;
    }
    Ok((noise, params))
}

/// Why a window could not be evaluated: preintegration (indices in `samples`), the factor or
/// its weight.
#[derive(Debug)]
pub(crate) enum WindowError {
    Preint(preint::PreintError),
    Factor(preint::FactorError),
    Weight(preint_analysis::Error),
}

impl std::fmt::Display for WindowError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WindowError::Preint(e) => write!(f, "{e}"),
            WindowError::Factor(e) => write!(f, "{e}"),
            WindowError::Weight(e) => write!(f, "{e}"),
        }
    }
}

/// The error of a window of `w`, in the recording's terms (sample indices of the stream).
pub(super) fn in_window(e: WindowError, input: &ImuInput, w: &StreamWindow) -> CliError {
    match e {
        WindowError::Preint(e) => CliError::failed_in(input.path(), w.in_stream(e)),
        WindowError::Factor(e) => CliError::failed_in(input.path(), e),
        WindowError::Weight(e) => e.into(),
    }
}

/// The window `[gi, gj]` of `samples` preintegrated with the ground truth's bias at i (and the
/// second-order term with `--second-order`), its factor evaluated at the ground truth.
pub(crate) fn evaluate_window(
    args: &Args,
    params: &PreintParams,
    samples: &[preint::ImuSample],
    (gi, gj): (&GroundTruthState, &GroundTruthState),
    tn: TruthNoise,
) -> Result<(PreintegratedImu, Evaluation), WindowError> {
    use WindowError as E;
    let mut pim = preintegrate(params, &gi.bias, samples, gi.t_ns, gj.t_ns).map_err(E::Preint)?;
    if args.second_order {
        let term = preint::second_order::covariance(params, samples, &pim).map_err(E::Preint)?;
        pim = preint::second_order::inflate(&pim, &term);
    }
    let (xi, xj) = (nav(gi), nav(gj));
    let ev = if args.combined {
        let f = CombinedImuFactor::with_mode(pim.clone(), args.residual).map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias, &gj.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    } else {
        let f = if args.in_window_drift {
            ImuFactor::with_in_window_drift(pim.clone(), args.residual)
        } else {
            ImuFactor::with_mode(pim.clone(), args.residual)
        }
        .map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    }
    .map_err(E::Weight)?;
    Ok((pim, ev))
}

fn jacobians<const R: usize>(j: &preint::FactorJacobians<R>) -> ResidualJacobians<R> {
    ResidualJacobians {
        state_i: j.state_i(),
        state_j: j.state_j(),
        bias_i: j.bias_i(),
    }
}
