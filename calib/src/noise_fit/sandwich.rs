//! Standard errors when windows share data: the sandwich (Godambe) covariance.
//!
//! Windows of several lengths cut from one recording overlap (a 4 s window holds the data of
//! eight 0.5 s ones), so their residuals are not independent and the likelihood of
//! [`super::fit`] is a composite likelihood: its maximum is still consistent, but the inverse
//! Fisher information counts the shared data once per window and is too small. With the
//! windows grouped into blocks that share no data ([`super::NoiseWindow::block`]), the
//! covariance of the estimate is `H⁻¹ J H⁻¹`, `H` the Fisher information and
//! `J = Σ_b s_b s_bᵀ` the empirical variance of the blocks' scores `s_b = Σ_{w∈b} g_w`
//! (C. Varin, N. Reid, D. Firth, "An overview of composite likelihood methods", *Statistica
//! Sinica* 21, 2011, §2.3; V. P. Godambe, *Ann. Math. Statist.* 31, 1960). With one window per
//! block the windows are independent and `H⁻¹` is kept.

use super::{NoiseWindow, PARAMS, sigma};
use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};

/// Whether some block holds more than one window (the windows share data).
pub fn shared(windows: &[NoiseWindow]) -> bool {
    let mut b: Vec<usize> = windows.iter().map(|w| w.block).collect();
    b.sort_unstable();
    b.windows(2).any(|p| p[0] == p[1])
}

/// `J = Σ_b s_b s_bᵀ` of the scores of `θ` (residuals `res`), and `J_g` of the gravity
/// correction's score `Σ_{w∈b} G_wᵀ Σ_w⁻¹ r_w`.
pub fn score_variance(
    windows: &[NoiseWindow],
    res: &[SVector<f64, 9>],
    theta: &SVector<f64, PARAMS>,
) -> (SMatrix<f64, PARAMS, PARAMS>, Matrix3<f64>) {
    let mut blocks: Vec<(usize, SVector<f64, PARAMS>, Vector3<f64>)> = Vec::new();
    for (w, r) in windows.iter().zip(res) {
        let Some(chol) = sigma(w, theta).cholesky() else {
            continue;
        };
        let u = chol.solve(r);
        let g = SVector::<f64, PARAMS>::from_fn(|k, _| {
            0.5 * (u.dot(&(w.basis[k] * u)) - chol.solve(&w.basis[k]).trace())
        });
        let gg = w.gravity_jacobian.transpose() * u;
        match blocks.iter_mut().find(|b| b.0 == w.block) {
            Some(b) => {
                b.1 += g;
                b.2 += gg;
            }
            None => blocks.push((w.block, g, gg)),
        }
    }
    blocks.iter().fold(
        (SMatrix::zeros(), Matrix3::zeros()),
        |(j, jg), (_, s, sg)| (j + s * s.transpose(), jg + sg * sg.transpose()),
    )
}

/// `H_ss⁻¹ J_ss H_ss⁻¹` on the index set `s`, from `h_inv = H_ss⁻¹` (infinite where `h_inv` is).
pub fn on(h_inv: &DMatrix<f64>, j: &SMatrix<f64, PARAMS, PARAMS>, s: &[usize]) -> DMatrix<f64> {
    if h_inv.iter().any(|x| !x.is_finite()) {
        return h_inv.clone();
    }
    let js = DMatrix::from_fn(s.len(), s.len(), |a, b| j[(s[a], s[b])]);
    h_inv * js * h_inv
}
