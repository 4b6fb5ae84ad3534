//! An IMU factor's residual at ground-truth states, weighted: whitened residual, χ² and each
//! 3-row block's marginal χ².
//!
//! The weight is the factor's covariance `Σ_factor` plus the ground truth's own errors through
//! the factor's Jacobians at i and j: `Σ = Σ_factor + J_i S J_iᵀ + J_j S J_jᵀ`, with
//! `S = diag(σ_R² I, σ_p² I, σ_v² I)` in the `NavState` tangent [δφ, δp, δv], and the error of
//! the bias the ground truth supplies (the preintegration's estimate) through the measurement's
//! bias Jacobians: `+ J_bg σ_bg² J_bgᵀ + J_ba σ_ba² J_baᵀ`, `J_b = ∂r/∂δb_i` restricted to the
//! 9 rows [r_φ, r_v, r_p] (a bias error common to i and j cancels in a combined factor's
//! `b_j − b_i`). The whitened residual is `U r` with `UᵀU = Σ⁻¹` (`U` upper triangular),
//! `χ² = ‖U r‖²`; block b's marginal χ² is `r_bᵀ Σ_bb⁻¹ r_b` (3 dof) and its share of the χ²
//! is `r_bᵀ (Σ⁻¹ r)_b` (the shares of all blocks sum to χ²).
//!
//! The goodness of fit as every command prints it in JSON ([`preint_calib::fit`]):
//! [`fit_json`], the top-level `fit` object.

use crate::Error;
use nalgebra::{SMatrix, SVector};
use preint::sqrt_information;
use preint_calib::Fit;
use serde_json::{Value, json};

/// The standard deviations of the ground truth's own errors (0: exact).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TruthNoise {
    /// Attitude error \[rad\].
    pub rot_rad: f64,
    /// Position error \[m\].
    pub pos_m: f64,
    /// Velocity error [m/s].
    pub vel_m_s: f64,
    /// Error of the ground truth's gyroscope bias, per axis [rad/s].
    pub bias_gyro_rad_s: f64,
    /// Error of the ground truth's accelerometer bias, per axis [m/s²].
    pub bias_acc_m_s2: f64,
}

impl TruthNoise {
    /// All five are zero: the ground truth is taken as exact.
    pub fn is_exact(&self) -> bool {
        [
            self.rot_rad,
            self.pos_m,
            self.vel_m_s,
            self.bias_gyro_rad_s,
            self.bias_acc_m_s2,
        ]
        .iter()
        .all(|s| *s == 0.0)
    }
}

/// A factor's residual at the ground truth, weighted.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The residual `r` (order of the factor: [r_φ, r_v, r_p] or [r_φ, r_v, r_p, r_bg, r_ba]).
    pub residual: Vec<f64>,
    /// `U r` with `UᵀU = Σ⁻¹` (dimensionless).
    pub whitened: Vec<f64>,
    /// `‖U r‖²`, with `residual.len()` degrees of freedom.
    pub chi2: f64,
    /// Per 3-row block: `r_bᵀ Σ_bb⁻¹ r_b` (NaN when `Σ_bb` is not positive definite).
    pub marginal_chi2: Vec<f64>,
    /// Per 3-row block: its share of the χ², `r_bᵀ (Σ⁻¹ r)_b` (they sum to `chi2`; one may be
    /// negative when the blocks are correlated).
    pub chi2_share: Vec<f64>,
}

/// The Jacobians of a residual with `R` rows: with respect to the `NavState`s at i and j
/// (tangent [δφ, δp, δv]) and to the bias at i (columns [δb_g, δb_a]).
#[derive(Clone, Copy, Debug)]
pub struct ResidualJacobians<const R: usize> {
    /// `∂r/∂δx_i`.
    pub state_i: SMatrix<f64, R, 9>,
    /// `∂r/∂δx_j`.
    pub state_j: SMatrix<f64, R, 9>,
    /// `∂r/∂δb_i`.
    pub bias_i: SMatrix<f64, R, 6>,
}

/// The covariance the ground truth's errors `tn` add to a residual with Jacobians `jac`:
/// `J_i S J_iᵀ + J_j S J_jᵀ + J_b S_b J_bᵀ` (module docs; the bias rows of a combined factor
/// left out of `J_b`). Linear in the squared σ of `tn`.
pub fn truth_covariance<const R: usize>(
    jac: &ResidualJacobians<R>,
    tn: TruthNoise,
) -> SMatrix<f64, R, R> {
    let mut s = SMatrix::<f64, 9, 9>::zeros();
    let mut sb = SMatrix::<f64, 6, 6>::zeros();
    for k in 0..3 {
        s[(k, k)] = tn.rot_rad.powi(2);
        s[(3 + k, 3 + k)] = tn.pos_m.powi(2);
        s[(6 + k, 6 + k)] = tn.vel_m_s.powi(2);
        sb[(k, k)] = tn.bias_gyro_rad_s.powi(2);
        sb[(3 + k, 3 + k)] = tn.bias_acc_m_s2.powi(2);
    }
    let mut jb = jac.bias_i;
    for row in 9..R {
        jb.row_mut(row).fill(0.0);
    }
    let (ji, jj) = (jac.state_i, jac.state_j);
    ji * s * ji.transpose() + jj * s * jj.transpose() + jb * sb * jb.transpose()
}

/// Weights the residual `r` (Jacobians `jac`) by `cov` plus the ground truth's errors `tn`
/// (module docs).
pub fn evaluate<const R: usize>(
    r: SVector<f64, R>,
    jac: ResidualJacobians<R>,
    cov: SMatrix<f64, R, R>,
    tn: TruthNoise,
) -> Result<Evaluation, Error> {
    let sigma = cov + truth_covariance(&jac, tn);
    let u = sqrt_information(&sigma).map_err(|e| Error::Failed(format!("weight: {e}")))?;
    let w = u * r;
    let info_r = u.transpose() * w;
    let chi2_share = (0..R / 3)
        .map(|b| {
            let rb = r.fixed_rows::<3>(3 * b);
            rb.dot(&info_r.fixed_rows::<3>(3 * b))
        })
        .collect();
    let marginal_chi2 = (0..R / 3)
        .map(|b| {
            let rb = r.fixed_rows::<3>(3 * b).into_owned();
            let sb = sigma.fixed_view::<3, 3>(3 * b, 3 * b).into_owned();
            sb.cholesky().map_or(f64::NAN, |c| rb.dot(&c.solve(&rb)))
        })
        .collect();
    Ok(Evaluation {
        residual: r.iter().copied().collect(),
        whitened: w.iter().copied().collect(),
        chi2: w.norm_squared(),
        marginal_chi2,
        chi2_share,
    })
}

/// The `fit` object: `{chi2, dof, chi2_dof, p_value, p_value_lower, credible, pessimistic,
/// scale, why}` (`scale` = √(χ²/dof), the factor of every `*_std_scaled`); the p-values are
/// left out when the χ² has no distribution (`allan`'s correlated points).
pub fn fit_json(f: &Fit) -> Value {
    let mut v = json!({"chi2": f.chi2, "dof": f.dof, "chi2_dof": f.chi2_dof,
        "credible": f.credible, "pessimistic": f.pessimistic, "scale": f.scale(), "why": f.why});
    // A fit whose χ² has no distribution (Allan's correlated points) has no p-values: the
    // keys are left out rather than written as null.
    if f.p_value.is_finite() && f.p_value_lower.is_finite() {
        v["p_value"] = json!(f.p_value);
        v["p_value_lower"] = json!(f.p_value_lower);
    }
    v
}

/// χ² quantiles (scipy.stats.chi2.ppf) for 3, 9 and 15 degrees of freedom: (0.95, 0.99).
///
/// # Panics
/// For any other number of degrees of freedom.
pub fn chi2_quantiles(dof: usize) -> (f64, f64) {
    match dof {
        3 => (7.814_728, 11.344_867),
        9 => (16.918_978, 21.665_994),
        15 => (24.995_790, 30.577_914),
        _ => panic!("no χ² quantiles tabulated for {dof} dof"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    /// With `Σ = diag(4)` and no ground-truth noise, `U r = r/2` and the marginal χ² of each
    /// block is its share of the total.
    #[test]
    fn whitening_and_marginals() {
        let r = Vector3::new(2.0, -4.0, 6.0);
        let z = SMatrix::<f64, 3, 9>::zeros();
        let jac = ResidualJacobians {
            state_i: z,
            state_j: z,
            bias_i: SMatrix::<f64, 3, 6>::zeros(),
        };
        let e = evaluate(r, jac, Matrix3::identity() * 4.0, TruthNoise::default()).unwrap();
        assert_eq!(e.whitened, vec![1.0, -2.0, 3.0]);
        assert!((e.chi2 - 14.0).abs() < 1e-12);
        assert!((e.marginal_chi2[0] - 14.0).abs() < 1e-12);
        assert!((e.chi2_share[0] - 14.0).abs() < 1e-12);
        assert!(TruthNoise::default().is_exact());
    }

    /// Two correlated blocks, `Σ = [[2 I, I], [I, 2 I]]`, `r = [1,0,0, 1,0,0]`: `Σ⁻¹ r = r/3`,
    /// shares 1/3 and 1/3 (sum χ² = 2/3) where the marginals are 1/2 each. A gyro-bias σ of 1
    /// with `∂r/∂b_g = I` on the first block adds I to its covariance, per axis
    /// `Σ' = [[3, 1], [1, 2]]`: `Σ'⁻¹ (1, 1) = (1, 2)/5`, shares 1/5 and 2/5, χ² = 3/5.
    #[test]
    fn shares_sum_to_chi2_and_bias_noise_enters_the_weight() {
        let mut cov = SMatrix::<f64, 6, 6>::identity() * 2.0;
        for k in 0..3 {
            cov[(k, 3 + k)] = 1.0;
            cov[(3 + k, k)] = 1.0;
        }
        let r = SVector::<f64, 6>::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0);
        let mut jac = ResidualJacobians {
            state_i: SMatrix::<f64, 6, 9>::zeros(),
            state_j: SMatrix::<f64, 6, 9>::zeros(),
            bias_i: SMatrix::<f64, 6, 6>::zeros(),
        };
        let e = evaluate(r, jac, cov, TruthNoise::default()).unwrap();
        assert!((e.chi2 - 2.0 / 3.0).abs() < 1e-12);
        assert!((e.chi2_share[0] - 1.0 / 3.0).abs() < 1e-12);
        assert!((e.chi2_share[1] - 1.0 / 3.0).abs() < 1e-12);
        assert!((e.marginal_chi2[0] - 0.5).abs() < 1e-12);
        for k in 0..3 {
            jac.bias_i[(k, k)] = 1.0;
        }
        let tn = TruthNoise {
            bias_gyro_rad_s: 1.0,
            ..TruthNoise::default()
        };
        assert!(!tn.is_exact());
        let e = evaluate(r, jac, cov, tn).unwrap();
        assert!((e.chi2 - 0.6).abs() < 1e-12, "{}", e.chi2);
        assert!((e.chi2_share[0] - 0.2).abs() < 1e-12);
        assert!((e.chi2_share[1] - 0.4).abs() < 1e-12);
    }
}
