//! What both forms of `factor` share: the keyframes and the window read from the recording,
//! the ground truth's errors, the noise model and the factor from the flags (the factor at the
//! ground truth: [`preint_analysis::factor_windows`]).

use super::Args;
use crate::{CliError, input};
use preint::{ImuNoise, Level, PreintParams};
use preint_analysis::consistency::TruthNoise;
use preint_analysis::factor_windows::FactorKind;
pub(crate) use preint_analysis::factor_windows::WindowError;
use preint_analysis::stream::StreamWindow;
use preint_analysis::{ImuInput, checks};
use preint_io::{GroundTruthState, read_euroc_groundtruth};

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

/// The error of a window of `w`, in the recording's terms (sample indices of the stream).
pub(super) fn in_window(e: WindowError, input: &ImuInput, w: &StreamWindow) -> CliError {
    match e {
        WindowError::Preint(e) => CliError::failed_in(input.path(), w.in_stream(e)),
        WindowError::Factor(e) => CliError::failed_in(input.path(), e),
        WindowError::Weight(e) => e.into(),
    }
}

impl Args {
    /// Which factor, residual and weight the flags ask for.
    pub(crate) fn kind(&self) -> FactorKind {
        FactorKind {
            combined: self.combined,
            in_window_drift: self.in_window_drift,
            residual: self.residual,
            second_order: self.second_order,
        }
    }
}
