//! Goodness of fit of a least-squares estimate: is its χ² what the noise model predicts?
//!
//! # The test
//! The whitened residuals of a correct model are standard normal, so at the optimum
//! `χ² ~ χ²_dof` (`dof` = residuals − rank). A fit is **credible** when its χ² is plausible
//! for that distribution:
//! - for **few degrees of freedom** (`dof` < [`LARGE_DOF`] = 30), when the upper-tail p-value
//!   `P(X ≥ χ²)` is at least [`P_MIN`] = 10⁻⁶: a correct model fails once in a million fits;
//! - for **many degrees of freedom** (`dof` ≥ 30), when `χ²/dof ≤` [`MAX_CHI2_DOF`] = 3, i.e.
//!   the residuals are at most √3 ≈ 1.7 times the noise model's σ. There the p-value alone
//!   would refuse fits whose estimates are sound: at `dof` = 1000 a noise density 10 % too
//!   small already gives `p < 10⁻⁶`, and no real noise model is that exact. The
//!   `1 − 10⁻⁶` quantile of `χ²_dof/dof` is 2.73 at `dof` = 30, 1.82 at 100 and 1.23 at 1000
//!   (4.98 at 9, 2.77 at 29), so 3 never refuses a correct model and the two rules meet near
//!   `dof` = 30.
//!
//! A χ² far *below* its distribution (lower-tail p-value `P(X ≤ χ²) <` 10⁻⁶ for `dof` < 30,
//! `χ²/dof < 1/3` for `dof` ≥ 30) is still credible: the estimates are unbiased, but the noise
//! model is pessimistic and the modelled σ are too large ([`Fit::pessimistic`]).
//!
//! # Scaled standard deviations
//! When the noise level itself is uncertain, `σ·√(χ²/dof)` ([`Fit::scale`]) is the standard
//! deviation with the noise model's σ rescaled to the residuals (the reduced-χ² correction of
//! weighted least squares; scipy's `curve_fit(absolute_sigma=False)`). It assumes the misfit is
//! a uniform scale of the noise: with a model error (a wrong frame, a drifting bias) neither
//! the modelled nor the scaled σ describes the error of the estimate.
//!
//! The χ² distribution functions are statrs' regularised incomplete gamma functions,
//! `P(X ≥ x) = Q(dof/2, x/2)` (Abramowitz & Stegun 26.4.19).

use statrs::function::gamma::{gamma_lr, gamma_ur};

/// Degrees of freedom from which the test is on `χ²/dof` rather than the p-value (module docs).
pub const LARGE_DOF: usize = 30;
/// Largest credible `χ²/dof` for `dof ≥` [`LARGE_DOF`]: residuals √3 times the noise model's σ.
pub const MAX_CHI2_DOF: f64 = 3.0;
/// Smallest credible upper-tail p-value for `dof <` [`LARGE_DOF`].
pub const P_MIN: f64 = 1e-6;

/// The goodness of fit of an estimate (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// χ² of the whitened residuals at the estimate.
    pub chi2: f64,
    /// Its degrees of freedom (residuals − rank).
    pub dof: usize,
    /// `χ²/dof` (NaN for `dof` = 0).
    pub chi2_dof: f64,
    /// Upper-tail p-value `P(X ≥ χ²)`, `X ~ χ²_dof` (NaN when not defined: `dof` = 0, or a
    /// statistic without a χ² distribution, see [`Fit::from_band`]).
    pub p_value: f64,
    /// Lower-tail p-value `P(X ≤ χ²)` (NaN when `p_value` is).
    pub p_value_lower: f64,
    /// Whether the residuals are what the noise model predicts (module docs).
    pub credible: bool,
    /// χ²/dof far below 1: credible, but the noise model is pessimistic (its σ too large).
    pub pessimistic: bool,
    /// Why, in one sentence (with the likely cause when not credible, if the caller knows it:
    /// [`Fit::because`]).
    pub why: String,
}

impl Fit {
    /// The test of `chi2` against `χ²_dof` (module docs). A non-finite or negative χ² is not
    /// credible; `dof` = 0 leaves nothing to test and is credible, with a `why` that says so.
    ///
    /// ```
    /// use preint_calib::fit::Fit;
    /// assert!(Fit::new(105.0, 100).credible);
    /// assert!(!Fit::new(400.0, 100).credible); // residuals twice the noise model's σ
    /// assert!(!Fit::new(45.7, 9).credible); // p = 6.8e-7
    /// let low = Fit::new(0.5, 15);
    /// assert!(low.credible && low.pessimistic);
    /// ```
    pub fn new(chi2: f64, dof: usize) -> Self {
        if !(chi2.is_finite() && chi2 >= 0.0) {
            return Self::verdict(
                chi2,
                dof,
                (f64::NAN, f64::NAN),
                false,
                false,
                format!("χ² = {chi2} is not a finite non-negative number"),
            );
        }
        if dof == 0 {
            return Self::verdict(
                chi2,
                0,
                (f64::NAN, f64::NAN),
                true,
                false,
                "no redundancy (0 degrees of freedom): the residuals cannot check the noise \
                 model"
                    .into(),
            );
        }
        let (a, x) = (dof as f64 / 2.0, chi2 / 2.0);
        // statrs takes x in (0, ∞): at χ² = 0 the tails are 1 and 0.
        let (upper, lower) = if x > 0.0 {
            (gamma_ur(a, x), gamma_lr(a, x))
        } else {
            (1.0, 0.0)
        };
        let r = chi2 / dof as f64;
        let (credible, pessimistic) = if dof >= LARGE_DOF {
            (r <= MAX_CHI2_DOF, r < 1.0 / MAX_CHI2_DOF)
        } else {
            (upper >= P_MIN, lower < P_MIN)
        };
        let why = if !credible {
            format!(
                "χ²/dof = {} with {dof} dof ({}): the residuals are {:.3} times the noise \
                 model's σ",
                number(r),
                p_text(upper),
                r.sqrt()
            )
        } else if pessimistic {
            format!(
                "χ²/dof = {} with {dof} dof (P(χ² ≤ {}) = {:.1e}): the residuals are {:.3} \
                 times the noise model's σ; the noise model is pessimistic and the modelled σ \
                 too large",
                number(r),
                number(chi2),
                lower,
                r.sqrt()
            )
        } else if upper >= P_MIN {
            format!(
                "χ²/dof = {} with {dof} dof ({}): consistent with the noise model",
                number(r),
                p_text(upper)
            )
        } else {
            // Many dof: a χ² the distribution rules out, from residuals within √3 of the model.
            format!(
                "χ²/dof = {} with {dof} dof ({}): the residuals are {:.3} times the noise \
                 model's σ, more than chance allows but within the √{MAX_CHI2_DOF} a noise \
                 model is trusted to (the scaled σ allow for it)",
                number(r),
                p_text(upper),
                r.sqrt()
            )
        };
        Self::verdict(chi2, dof, (upper, lower), credible, pessimistic, why)
    }

    /// A statistic without a χ² distribution (e.g. correlated residuals), judged by a band on
    /// another measure that the caller justifies: `χ²` and `dof` are reported, the p-values are
    /// NaN, `credible` and `why` are the caller's.
    pub fn from_band(chi2: f64, dof: usize, credible: bool, why: String) -> Self {
        Self::verdict(chi2, dof, (f64::NAN, f64::NAN), credible, false, why)
    }

    fn verdict(
        chi2: f64,
        dof: usize,
        (p_value, p_value_lower): (f64, f64),
        credible: bool,
        pessimistic: bool,
        why: String,
    ) -> Self {
        Self {
            chi2,
            dof,
            chi2_dof: if dof == 0 {
                f64::NAN
            } else {
                chi2 / dof as f64
            },
            p_value,
            p_value_lower,
            credible,
            pessimistic,
            why,
        }
    }

    /// `√(χ²/dof)`: the factor of [`Fit::scaled`] (1 for `dof` = 0 or a non-finite χ²).
    pub fn scale(&self) -> f64 {
        if self.chi2_dof.is_finite() {
            self.chi2_dof.sqrt()
        } else {
            1.0
        }
    }

    /// A modelled standard deviation scaled by `√(χ²/dof)` (module docs).
    pub fn scaled(&self, std: f64) -> f64 {
        std * self.scale()
    }

    /// The same fit with `; likely cause: {cause}` appended to `why` when it is not credible
    /// (the caller's likely cause: "the poses' quaternions look like x,y,z,w order", …).
    pub fn because(mut self, cause: &str) -> Self {
        if !self.credible && !cause.is_empty() {
            self.why = format!("{}; likely cause: {cause}", self.why);
        }
        self
    }
}

/// A number for a sentence: 4 significant digits, exponent form outside [1e-3, 1e6).
fn number(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
        format!("{x:.3e}")
    } else {
        format!("{}", (x * 1e3).round() / 1e3)
    }
}

/// `p = 0.41`, `p = 6.8e-7`, or `p < 1e-300` when it underflows.
fn p_text(p: f64) -> String {
    if p < 1e-300 {
        "p < 1e-300".into()
    } else if p < 1e-3 {
        format!("p = {p:.1e}")
    } else {
        format!("p = {p:.3}")
    }
}
