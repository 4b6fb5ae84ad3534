//! The world gravity correction of the noise fit: the residuals' mean `G_w δg`.
//!
//! A factor's velocity and position residuals are linear in the world gravity vector `g`
//! (`r_v = R_iᵀ(v_j − v_i − g Δt) − Δv`, `r_p = R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²) − Δp`), so a
//! correction `δg` moves each window's residual to `r_w + G_w δg` exactly, `G_w = ∂r_w/∂g`. At
//! fixed `θ` the maximum-likelihood `δg` is the generalised least-squares solution
//! `δg = −(Σ_w G_wᵀ Σ_w⁻¹ G_w)⁻¹ Σ_w G_wᵀ Σ_w⁻¹ r_w`, with covariance
//! `(Σ_w G_wᵀ Σ_w⁻¹ G_w)⁻¹` (Kay, vol. I, §4.5); the fit alternates it with the Fisher step
//! on `θ` (block coordinate ascent: each half-step raises `ℓ`).

use super::{NoiseFit, NoiseWindow, PARAMS, sigma};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// The fitted world gravity correction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GravityEstimate {
    /// `δg` \[m/s²\], world frame: the gravity that fits is the given one plus `δg`.
    pub correction: Vector3<f64>,
    /// Its covariance \[(m/s²)²\].
    pub cov: Matrix3<f64>,
    /// The likelihood-ratio statistic `2(ℓ_with − ℓ_without)`.
    pub lr: f64,
    /// The BIC penalty of its three parameters, `3 ln n` (`n` residual components).
    pub penalty: f64,
    /// `lr > penalty`: the correction is applied (its fit stands); otherwise the fit without it.
    pub supported: bool,
}

impl GravityEstimate {
    /// The standard deviation of each component of `δg` \[m/s²\], world frame.
    pub fn std(&self) -> Vector3<f64> {
        self.cov.diagonal().map(|d| d.max(0.0).sqrt())
    }

    /// The correction the fit applies \[m/s²\]: `δg` when supported, else zero.
    pub fn applied(&self) -> Vector3<f64> {
        if self.supported {
            self.correction
        } else {
            Vector3::zeros()
        }
    }

    /// The angle \[rad\] between `g0` and the corrected gravity `g0 + δg`.
    pub fn tilt_from(&self, g0: &Vector3<f64>) -> f64 {
        g0.angle(&(g0 + self.correction))
    }

    /// The standard deviation \[rad\] of [`Self::tilt_from`], to first order: the covariance
    /// of `δg` across `g0`, `√(tr(P Σ P))/|g|` with `P` the projector orthogonal to `g0`, taken
    /// along the tilt's direction when the tilt is not zero.
    pub fn tilt_std_from(&self, g0: &Vector3<f64>) -> f64 {
        let g = g0 + self.correction;
        let n = g.norm();
        let u = g / n;
        let across = Matrix3::identity() - u * u.transpose();
        let d = across * g0;
        if d.norm() > 0.0 {
            let e = d / d.norm();
            (e.dot(&(self.cov * e))).max(0.0).sqrt() / n
        } else {
            (across * self.cov * across).trace().max(0.0).sqrt() / n
        }
    }
}

/// The GLS correction `δg` at `θ` and its covariance (module docs); zero and an infinite
/// covariance when the windows do not determine it.
pub fn correction(
    windows: &[NoiseWindow],
    theta: &SVector<f64, PARAMS>,
) -> (SVector<f64, 3>, Matrix3<f64>) {
    let mut info = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for w in windows {
        let Some(chol) = sigma(w, theta).cholesky() else {
            continue;
        };
        let sg: SMatrix<f64, 9, 3> = chol.solve(&w.gravity_jacobian);
        info += w.gravity_jacobian.transpose() * sg;
        rhs += sg.transpose() * w.r;
    }
    match info.try_inverse() {
        Some(cov) if info.determinant() > 0.0 => (-(cov * rhs), cov),
        _ => (SVector::zeros(), Matrix3::from_element(f64::INFINITY)),
    }
}

/// The windows' residuals at the corrected gravity, `r_w + G_w δg`.
pub fn shifted(windows: &[NoiseWindow], dg: &SVector<f64, 3>) -> Vec<SVector<f64, 9>> {
    windows
        .iter()
        .map(|w| w.r + w.gravity_jacobian * dg)
        .collect()
}

/// The fit with the correction when BIC supports it (`2Δℓ > 3 ln n`), else the fit without
/// it, carrying the correction as not supported.
pub fn select(plain: NoiseFit, mut with: NoiseFit, n: usize) -> NoiseFit {
    let lr = 2.0 * (with.log_likelihood - plain.log_likelihood);
    let penalty = 3.0 * (n.max(1) as f64).ln();
    let supported = lr > penalty;
    let g = with.gravity.take().map(|g| GravityEstimate {
        lr,
        penalty,
        supported,
        ..g
    });
    let mut out = if supported { with } else { plain };
    out.gravity = g;
    out
}
