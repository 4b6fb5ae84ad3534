//! An IMU factor evaluated at ground-truth states, one window or back-to-back windows of
//! several lengths, as `preint factor` (`--from`/`--to`, `--window`) and `preint report --imu`
//! evaluate them.
//!
//! A window `[gi, gj]` is preintegrated with the ground truth's bias at i as the estimate (and,
//! with [`FactorKind::second_order`], the second-order covariance term of
//! `preint::second_order` added), and `ImuFactor` (or, with [`FactorKind::combined`],
//! `CombinedImuFactor` with the ground truth's bias at j as well) is evaluated at the two
//! states, weighted as [`crate::consistency`] says. The windows are [`crate::truth_windows`]'
//! and their statistics per length [`crate::chi2_windows`]'.

use crate::Error;
use crate::chi2_windows::{self, LengthSummary, WindowChi2};
use crate::consistency::{Evaluation, ResidualJacobians, TruthNoise, evaluate};
use crate::truth_windows::{for_each_window, length_ns};
use preint::{
    CombinedImuFactor, ImuFactor, ImuSample, NavState, PreintParams, PreintegratedImu,
    ResidualMode, preintegrate,
};
use preint_io::GroundTruthState;

/// Which factor, with which residual and weight.
#[derive(Clone, Copy, Debug, Default)]
pub struct FactorKind {
    /// `CombinedImuFactor` (15 dof, with the bias change), else `ImuFactor` (9 dof).
    pub combined: bool,
    /// `ImuFactor` weighted with the bias random walk within the window
    /// (`ImuFactor::with_in_window_drift`; the measurement at `Level::Combined`).
    pub in_window_drift: bool,
    /// The factor's residual.
    pub residual: ResidualMode,
    /// Weighted with the second-order covariance term.
    pub second_order: bool,
}

impl FactorKind {
    /// The residual's degrees of freedom: 15 for the combined factor, else 9.
    pub fn dof(&self) -> usize {
        if self.combined { 15 } else { 9 }
    }
}

/// Why a window could not be evaluated: preintegration (indices in the window's samples), the
/// factor or its weight.
#[derive(Debug)]
pub enum WindowError {
    /// Preintegration failed.
    Preint(preint::PreintError),
    /// The factor could not be built.
    Factor(preint::FactorError),
    /// The weight is not positive definite.
    Weight(Error),
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

fn nav(s: &GroundTruthState) -> NavState {
    NavState::new(s.rotation(), s.p, s.v)
}

fn jacobians<const R: usize>(j: &preint::FactorJacobians<R>) -> ResidualJacobians<R> {
    ResidualJacobians {
        state_i: j.state_i(),
        state_j: j.state_j(),
        bias_i: j.bias_i(),
    }
}

/// The window `[gi, gj]` of `samples` preintegrated with the ground truth's bias at i, its
/// factor evaluated at the ground truth and weighted with the ground truth's errors `tn`
/// (module docs).
pub fn evaluate_window(
    kind: &FactorKind,
    params: &PreintParams,
    samples: &[ImuSample],
    (gi, gj): (&GroundTruthState, &GroundTruthState),
    tn: TruthNoise,
) -> Result<(PreintegratedImu, Evaluation), WindowError> {
    use WindowError as E;
    let mut pim = preintegrate(params, &gi.bias, samples, gi.t_ns, gj.t_ns).map_err(E::Preint)?;
    if kind.second_order {
        let term = preint::second_order::covariance(params, samples, &pim).map_err(E::Preint)?;
        pim = preint::second_order::inflate(&pim, &term);
    }
    let (xi, xj) = (nav(gi), nav(gj));
    let ev = if kind.combined {
        let f = CombinedImuFactor::with_mode(pim.clone(), kind.residual).map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias, &gj.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    } else {
        let f = if kind.in_window_drift {
            ImuFactor::with_in_window_drift(pim.clone(), kind.residual)
        } else {
            ImuFactor::with_mode(pim.clone(), kind.residual)
        }
        .map_err(E::Factor)?;
        let (r, j) = f.evaluate(&xi, &xj, &gi.bias);
        evaluate(r, jacobians(&j), *f.residual_covariance(), tn)
    }
    .map_err(E::Weight)?;
    Ok((pim, ev))
}

/// Per length of `lengths_s` \[s\], in the order given: the back-to-back windows of that
/// length over `span` (\[ns\], with the median sample interval `dt` \[ns\]) evaluated
/// ([`evaluate_window`]; a window that cannot be cut or evaluated, or whose χ² is not finite,
/// is skipped and counted) and summarised ([`chi2_windows::summarise`]).
pub fn per_length(
    kind: &FactorKind,
    params: &PreintParams,
    data: (&[ImuSample], &[GroundTruthState]),
    (span, dt): ((i64, i64), f64),
    lengths_s: &[f64],
    tn: TruthNoise,
) -> Result<Vec<LengthSummary>, Error> {
    let mut summaries = Vec::new();
    for &l in lengths_s {
        let (windows, skipped) =
            for_each_window(
                data,
                (span, dt),
                length_ns(l, span)?,
                |w, g| match evaluate_window(kind, params, w, g, tn) {
                    Ok((_, ev)) if ev.chi2.is_finite() => Some(WindowChi2 {
                        chi2: ev.chi2,
                        share: ev.chi2_share,
                    }),
                    _ => None,
                },
            );
        summaries.push(chi2_windows::summarise(l, kind.dof(), &windows, skipped));
    }
    Ok(summaries)
}
