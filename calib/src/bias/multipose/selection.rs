//! Model selection by the Bayesian information criterion (Schwarz 1978; Kass & Raftery, JASA
//! 1995).
//!
//! Every candidate ([`MultiPoseModel`], from the simplest: bias only; accelerometer scale; both
//! scales; accelerometer scale + misalignment; that plus gyro scale; the full imu_tk model with
//! accelerometer 3 scales + 3 misalignments and gyro 3 scales + 6 misalignments) is solved, and
//!
//! ```text
//! BIC = χ² + k·ln m
//! ```
//!
//! with χ² = ‖r‖² of the whitened residuals (−2 log-likelihood up to a constant, since the noise
//! is known: `ln det Σ` is the same for every model), k the number of observable parameters
//! (the rank of JᵀJ) and m the number of scalar residuals. A model is eligible only if all its
//! parameters are observable (rank = dim − 1, the yaw gauge) **and** its solver converged; the
//! eligible model with the lowest BIC wins. Every BIC is reported ([`ModelFit`]), and the reason
//! names the winner's and the runner-up's BIC and their difference (ΔBIC > 10: "very strong"
//! evidence, Kass & Raftery 1995), and warns when the winner's χ²/dof exceeds
//! `1 + 3√(2/dof)` (3σ of the χ² distribution: the residuals are not the stated noise, so the
//! ranking is unreliable). No eligible model is an error.

use super::super::BiasError;
use super::model::MultiPoseModel;
use crate::gauss_newton::Solution;
use preint::ImuNoise;

/// Fit statistics of one candidate model.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelFit {
    /// The model.
    pub model: MultiPoseModel,
    /// χ² = ‖r‖² of the whitened residuals at the estimate.
    pub chi2: f64,
    /// Number of observable parameters k (rank of JᵀJ).
    pub params: usize,
    /// Number of scalar residuals m.
    pub residuals: usize,
    /// `χ² + k·ln m`.
    pub bic: f64,
    /// All parameters observable up to the yaw gauge (rank = dim − 1).
    pub identifiable: bool,
    /// The solver converged.
    pub converged: bool,
}

impl ModelFit {
    /// Eligible to win the selection: identifiable and converged.
    pub fn eligible(&self) -> bool {
        self.identifiable && self.converged
    }

    /// The statistics of `model`'s solution; `dim` is the dimension of its state (parameters
    /// and attitudes).
    pub(super) fn of<X>(model: MultiPoseModel, sol: &Solution<X>, dim: usize) -> Self {
        let m = sol.residual_count;
        let chi2 = 2.0 * sol.cost;
        ModelFit {
            model,
            chi2,
            params: sol.rank,
            residuals: m,
            bic: chi2 + sol.rank as f64 * (m as f64).ln(),
            identifiable: sol.rank + 1 >= dim,
            converged: sol.stop.converged(),
        }
    }
}

/// How the winner was chosen, for [`select`]'s reason text.
pub(super) struct Context<'a> {
    pub(super) noise: &'a ImuNoise,
    pub(super) marginalised: bool,
    pub(super) t_ref_ns: i64,
}

/// Index of the eligible fit with the lowest BIC and the reason for humans (module docs).
/// Error when no fit is eligible.
pub(super) fn select(fits: &[ModelFit], ctx: &Context) -> Result<(usize, String), BiasError> {
    let listing = listing(fits);
    let mut order: Vec<usize> = (0..fits.len()).filter(|&i| fits[i].eligible()).collect();
    if order.is_empty() {
        return Err(BiasError::InvalidParameter {
            name: "samples",
            reason: format!(
                "no candidate model is both identifiable and converged (need more, diverse \
                 still attitudes). {listing}"
            ),
        });
    }
    order.sort_by(|&a, &b| fits[a].bic.total_cmp(&fits[b].bic));
    let best = order[0];
    let fb = &fits[best];
    let mut reason = match order.get(1) {
        Some(&second) => versus_runner_up(fb, &fits[second], &listing),
        None => format!(
            "{} is the only eligible model (BIC {:.1}). All candidates: {listing}",
            fb.model.name(),
            fb.bic
        ),
    };
    if let Some(warning) = goodness_of_fit_warning(fb, ctx.marginalised) {
        reason.push_str(&warning);
    }
    if ctx.marginalised {
        reason.push_str(&format!(
            " Bias random walk marginalised (σ_bg {:.2e} rad/s²/√Hz, σ_ba {:.2e} m/s³/√Hz); \
             biases at t_ref = {} ns.",
            ctx.noise.gyro_random_walk, ctx.noise.acc_random_walk, ctx.t_ref_ns
        ));
    }
    Ok((best, reason))
}

/// Every candidate's BIC, χ², k and m, and why it is not eligible.
fn listing(fits: &[ModelFit]) -> String {
    fits.iter()
        .map(|f| {
            format!(
                "{}: BIC {:.1} = χ² {:.1} + {}·ln {}{}{}",
                f.model.name(),
                f.bic,
                f.chi2,
                f.params,
                f.residuals,
                if f.identifiable {
                    ""
                } else {
                    " (not identifiable)"
                },
                if f.converged { "" } else { " (not converged)" }
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The winner against the runner-up: their BIC difference and its strength (ΔBIC > 10: very
/// strong evidence).
fn versus_runner_up(fb: &ModelFit, fs: &ModelFit, listing: &str) -> String {
    let d = fs.bic - fb.bic;
    format!(
        "{} has the lowest BIC of the eligible models, {:.1}, which is {:.1} below the \
         runner-up {} ({:.1}): {}. All candidates: {listing}",
        fb.model.name(),
        fb.bic,
        d,
        fs.model.name(),
        fs.bic,
        if d > 10.0 {
            "very strong evidence"
        } else {
            "weak evidence (ΔBIC ≤ 10)"
        },
    )
}

/// A warning when the winner's χ²/dof exceeds `1 + 3√(2/dof)` (3σ of the χ² distribution): the
/// residuals are not the stated noise, and the BIC ranking is then unreliable.
fn goodness_of_fit_warning(fb: &ModelFit, marginalised: bool) -> Option<String> {
    let dof = fb.residuals.saturating_sub(fb.params);
    if dof == 0 {
        return None;
    }
    let q = fb.chi2 / dof as f64;
    let excessive = q > 1.0 + 3.0 * (2.0 / dof as f64).sqrt();
    excessive.then(|| {
        let why = if marginalised {
            "wrong densities, or biases that drift faster than the stated random walk"
        } else {
            "wrong densities, or biases that drift during the protocol: the model holds them \
             constant"
        };
        format!(
            " WARNING: χ²/dof = {q:.2} for {dof} dof: the residuals exceed the stated noise \
             ({why}), so the selection is unreliable."
        )
    })
}
