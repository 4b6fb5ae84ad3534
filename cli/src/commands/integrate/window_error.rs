//! `integrate`'s estimates of what the first-order window misses: its own discretisation
//! (truncation) error (`--truncation`, [`preint::truncation`]) and the second-order covariance
//! term of its SE₂(3) error (`--second-order`, [`preint::second_order`]).

use preint::PreintegratedImu;
use preint::nalgebra::SMatrix;
use preint::truncation::TruncationEstimate;
use preint_analysis::format::{rows, text_matrix};
use serde_json::{Value, json};
use std::fmt::Write as _;

/// The estimated truncation error of the deltas (`--truncation`).
#[derive(Clone, Debug)]
pub struct Truncation(pub TruncationEstimate);

impl Truncation {
    /// `{error, method, companion_covariance, order, units}`.
    pub fn to_json(&self) -> Value {
        let t = &self.0;
        json!({
            "error": t.error.iter().copied().collect::<Vec<f64>>(), "method": t.method,
            "companion_covariance": rows(&t.companion_cov),
            "order": "[dphi, dv, dp]: measured minus exact deltas, the chart of covariance",
            "units": {"dphi": "rad", "dv": "m/s", "dp": "m"},
        })
    }

    /// The error's block norms beside the noise's 1σ of `m`.
    pub fn to_text(&self, m: &PreintegratedImu) -> String {
        let t = &self.0;
        let e = &t.error;
        let n = |i: usize| e.fixed_rows::<3>(i).norm();
        let sigma =
            |i: usize| (m.cov[(i, i)] + m.cov[(i + 1, i + 1)] + m.cov[(i + 2, i + 2)]).sqrt();
        format!(
            "truncation error (estimated, {}): |δφ| {:.2e} rad, |δv| {:.2e} m/s, |δp| {:.2e} m \
             (1σ of the noise: {:.2e} rad, {:.2e} m/s, {:.2e} m)\n",
            t.method,
            n(0),
            n(3),
            n(6),
            sigma(0),
            sigma(3),
            sigma(6)
        )
    }
}

/// The second-order covariance term of the window, [δφ, δv, δp] (`--second-order`).
#[derive(Clone, Debug)]
pub struct SecondOrder(pub SMatrix<f64, 9, 9>);

impl SecondOrder {
    /// `tr(Σ⁻¹ S)`: the mean χ² at the true states the term `S` adds over the first-order `Σ`
    /// of `m` (`E[rᵀ Σ⁻¹ r] = tr(Σ⁻¹ (Σ + S))`); `NaN` when `Σ` is singular.
    pub fn chi2_increase(&self, m: &PreintegratedImu) -> f64 {
        m.cov
            .cholesky()
            .map_or(f64::NAN, |c| (c.inverse() * self.0).trace())
    }

    /// `{covariance, chi2_increase, order, units, note}`.
    pub fn to_json(&self, m: &PreintegratedImu) -> Value {
        json!({
            "covariance": rows(&self.0),
            "chi2_increase": self.chi2_increase(m),
            "order": "[dphi, dv, dp], the chart of covariance",
            "units": "rad^2, (m/s)^2, m^2 blocks",
            "note": "add to covariance to weight a factor with the second-order covariance; \
                     chi2_increase = tr(covariance^-1 term), the mean chi2 at the true states \
                     that the first-order covariance does not account for",
        })
    }

    /// The term and the χ² it accounts for.
    pub fn to_text(&self, m: &PreintegratedImu) -> String {
        let mut h = String::new();
        let _ = writeln!(
            h,
            "second-order covariance term [δφ, δv, δp] (add to the 9×9 covariance; the mean χ² \
             at the true states it accounts for: +{:.3}):",
            self.chi2_increase(m)
        );
        h.push_str(&text_matrix(&self.0, "  "));
        h
    }
}
