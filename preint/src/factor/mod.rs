//! IMU factors (the residual, its Jacobians and whitening: [`ImuFactor`]), the combined
//! variant with the bias random walk, and the SE₂(3) Logmap residual ([`ResidualMode`]).

mod combined;
mod imu;
pub mod logmap;
mod residual;
mod rotating;

pub use combined::CombinedImuFactor;
pub use imu::ImuFactor;
pub use logmap::ResidualMode;

use crate::choices::Level;
use crate::measurement::PreintegratedImu;
use nalgebra::{DMatrix, SMatrix, SVector};
use thiserror::Error;

/// Why a factor could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FactorError {
    /// A field of the preintegrated measurement is NaN or infinite.
    #[error("preintegrated measurement has a non-finite {field}")]
    NonFinite {
        /// Which field (`"delta_r"`, `"delta_v"`, `"cov"`, …).
        field: &'static str,
    },
    /// `delta_t` is zero or negative.
    #[error("preintegrated measurement has non-positive Δt = {delta_t} s")]
    NonPositiveDeltaT {
        /// The offending Δt \[s\].
        delta_t: f64,
    },
    /// The covariance is not (numerically) symmetric positive definite, so it has no
    /// square-root information (e.g. a preintegration computed without noise, or with a zero
    /// bias random walk for the combined factor).
    #[error(
        "the {dim}×{dim} covariance is not positive definite (Cholesky failed at pivot {pivot})"
    )]
    CovarianceNotPositiveDefinite {
        /// Dimension of the covariance (9 or 15).
        dim: usize,
        /// First pivot (0-based, in the reversed order used internally) that failed, or `dim`
        /// if the factor overflowed.
        pivot: usize,
    },
    /// The measurement was computed at a [`Level`] that lacks the covariance the factor
    /// weights with: [`ImuFactor`] needs [`Level::Covariance`] or more, [`CombinedImuFactor`]
    /// needs [`Level::Combined`] (at `Level::Covariance`, `cov15` has no random-walk effect
    /// on the deltas and no delta–bias cross blocks).
    #[error(
        "the measurement was preintegrated at level {got:?}; this factor needs {needed:?} (set PreintParams::level)"
    )]
    LevelTooLow {
        /// Level the factor needs.
        needed: Level,
        /// Level of the measurement.
        got: Level,
    },
}

/// Upper Cholesky factor `U` of `Σ⁻¹` (`Σ⁻¹ = UᵀU`, positive diagonal), computed as
/// `U = P L⁻¹ P` from `P Σ P = L Lᵀ` (`P` reverses the order), see [`ImuFactor`].
///
/// `Σ` is symmetrised (`½(Σ + Σᵀ)`) first. Errors: [`FactorError::NonFinite`] for NaN/∞,
/// [`FactorError::CovarianceNotPositiveDefinite`] if a pivot is not strictly positive.
pub fn sqrt_information<const N: usize>(
    cov: &SMatrix<f64, N, N>,
) -> Result<SMatrix<f64, N, N>, FactorError> {
    if !cov.iter().all(|x| x.is_finite()) {
        return Err(FactorError::NonFinite { field: "cov" });
    }
    // Reversed, symmetrised copy.
    let rev = DMatrix::from_fn(N, N, |r, c| {
        0.5 * (cov[(N - 1 - r, N - 1 - c)] + cov[(N - 1 - c, N - 1 - r)])
    });
    // Plain Cholesky with an explicit pivot check (nalgebra's only reports failure).
    let mut l = DMatrix::<f64>::zeros(N, N);
    for j in 0..N {
        let mut d = rev[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if d.is_nan() || d <= 0.0 {
            return Err(FactorError::CovarianceNotPositiveDefinite { dim: N, pivot: j });
        }
        let djj = d.sqrt();
        l[(j, j)] = djj;
        for i in j + 1..N {
            let mut s = rev[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / djj;
        }
    }
    // L⁻¹ (lower) by forward substitution on the identity.
    let mut linv = DMatrix::<f64>::zeros(N, N);
    for c in 0..N {
        for i in c..N {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for k in c..i {
                s -= l[(i, k)] * linv[(k, c)];
            }
            linv[(i, c)] = s / l[(i, i)];
        }
    }
    let u = SMatrix::<f64, N, N>::from_fn(|r, c| linv[(N - 1 - r, N - 1 - c)]);
    if !u.iter().all(|x| x.is_finite()) {
        return Err(FactorError::CovarianceNotPositiveDefinite { dim: N, pivot: N });
    }
    Ok(u)
}

/// Jacobians of an `R`-dimensional IMU residual (rows in the residual's order: [r_φ, r_v, r_p]
/// for [`ImuFactor`], [r_φ, r_v, r_p, r_bg, r_ba] for [`CombinedImuFactor`]), one `R×3` block
/// per perturbation; the perturbation of each block is in [`ImuFactor`]'s documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorJacobians<const R: usize> {
    /// `∂r/∂δφ_i`, `R_i ← R_i Exp(δφ_i)` [1/rad].
    pub phi_i: SMatrix<f64, R, 3>,
    /// `∂r/∂δp_i`, `p_i ← p_i + R_i δp_i` (body frame) [1/m].
    pub p_i: SMatrix<f64, R, 3>,
    /// `∂r/∂δv_i`, `v_i ← v_i + δv_i` (world frame) [s/m].
    pub v_i: SMatrix<f64, R, 3>,
    /// `∂r/∂δφ_j`, `R_j ← R_j Exp(δφ_j)`.
    pub phi_j: SMatrix<f64, R, 3>,
    /// `∂r/∂δp_j`, `p_j ← p_j + R_j δp_j` (body frame).
    pub p_j: SMatrix<f64, R, 3>,
    /// `∂r/∂δv_j`, `v_j ← v_j + δv_j` (world frame).
    pub v_j: SMatrix<f64, R, 3>,
    /// `∂r/∂δb_g,i` (gyro bias at i) [1/(rad/s)].
    pub bg_i: SMatrix<f64, R, 3>,
    /// `∂r/∂δb_a,i` (accelerometer bias at i) [1/(m/s²)].
    pub ba_i: SMatrix<f64, R, 3>,
    /// `∂r/∂δb_g,j` (identically zero for [`ImuFactor`]).
    pub bg_j: SMatrix<f64, R, 3>,
    /// `∂r/∂δb_a,j` (identically zero for [`ImuFactor`]).
    pub ba_j: SMatrix<f64, R, 3>,
}

/// Jacobians of the 9-dim [`ImuFactor`] residual.
pub type ImuFactorJacobians = FactorJacobians<9>;
/// Jacobians of the 15-dim [`CombinedImuFactor`] residual.
pub type CombinedImuFactorJacobians = FactorJacobians<15>;

impl<const R: usize> FactorJacobians<R> {
    fn zeros() -> Self {
        let z = SMatrix::<f64, R, 3>::zeros();
        Self {
            phi_i: z,
            p_i: z,
            v_i: z,
            phi_j: z,
            p_j: z,
            v_j: z,
            bg_i: z,
            ba_i: z,
            bg_j: z,
            ba_j: z,
        }
    }

    fn cat3(
        a: &SMatrix<f64, R, 3>,
        b: &SMatrix<f64, R, 3>,
        c: &SMatrix<f64, R, 3>,
    ) -> SMatrix<f64, R, 9> {
        let mut m = SMatrix::<f64, R, 9>::zeros();
        m.fixed_columns_mut::<3>(0).copy_from(a);
        m.fixed_columns_mut::<3>(3).copy_from(b);
        m.fixed_columns_mut::<3>(6).copy_from(c);
        m
    }

    fn cat2(a: &SMatrix<f64, R, 3>, b: &SMatrix<f64, R, 3>) -> SMatrix<f64, R, 6> {
        let mut m = SMatrix::<f64, R, 6>::zeros();
        m.fixed_columns_mut::<3>(0).copy_from(a);
        m.fixed_columns_mut::<3>(3).copy_from(b);
        m
    }

    /// `∂r/∂δx_i` for the [`NavState`](crate::NavState) tangent at i, columns **[δφ_i, δp_i, δv_i]**.
    pub fn state_i(&self) -> SMatrix<f64, R, 9> {
        Self::cat3(&self.phi_i, &self.p_i, &self.v_i)
    }

    /// `∂r/∂δx_j` for the [`NavState`](crate::NavState) tangent at j, columns **[δφ_j, δp_j, δv_j]**.
    pub fn state_j(&self) -> SMatrix<f64, R, 9> {
        Self::cat3(&self.phi_j, &self.p_j, &self.v_j)
    }

    /// `∂r/∂δb_i`, columns **[δb_g, δb_a]**.
    pub fn bias_i(&self) -> SMatrix<f64, R, 6> {
        Self::cat2(&self.bg_i, &self.ba_i)
    }

    /// `∂r/∂δb_j`, columns **[δb_g, δb_a]** (zero for [`ImuFactor`]).
    pub fn bias_j(&self) -> SMatrix<f64, R, 6> {
        Self::cat2(&self.bg_j, &self.ba_j)
    }

    /// Every block left-multiplied by `w` (e.g. the square-root information `U`).
    pub fn left_mul(&self, w: &SMatrix<f64, R, R>) -> Self {
        let mut out = *self;
        for b in out.blocks_mut() {
            *b = w * *b;
        }
        out
    }

    /// The ten blocks in the order of the variables: [φ_i, p_i, v_i, φ_j, p_j, v_j, b_g,i,
    /// b_a,i, b_g,j, b_a,j].
    pub(crate) fn blocks_mut(&mut self) -> [&mut SMatrix<f64, R, 3>; 10] {
        [
            &mut self.phi_i,
            &mut self.p_i,
            &mut self.v_i,
            &mut self.phi_j,
            &mut self.p_j,
            &mut self.v_j,
            &mut self.bg_i,
            &mut self.ba_i,
            &mut self.bg_j,
            &mut self.ba_j,
        ]
    }
}

fn check_pim(pim: &PreintegratedImu) -> Result<(), FactorError> {
    let fin = |s: &[f64]| s.iter().all(|x| x.is_finite());
    let j = &pim.jac;
    let omega_ok = pim.omega_coriolis.is_none_or(|w| fin(w.as_slice()));
    let checks: [(&'static str, bool); 9] = [
        ("delta_r", fin(pim.delta_r.matrix().as_slice())),
        ("delta_v", fin(pim.delta_v.as_slice())),
        ("delta_p", fin(pim.delta_p.as_slice())),
        ("delta_t", pim.delta_t.is_finite()),
        ("gravity", fin(pim.gravity.as_slice())),
        ("omega_coriolis", omega_ok),
        (
            "bias_hat",
            fin(pim.bias_hat.gyro.as_slice()) && fin(pim.bias_hat.acc.as_slice()),
        ),
        (
            "jac",
            [j.d_r_d_bg, j.d_v_d_bg, j.d_v_d_ba, j.d_p_d_bg, j.d_p_d_ba]
                .iter()
                .all(|m| fin(m.as_slice())),
        ),
        ("cov", fin(pim.cov.as_slice())),
    ];
    if let Some((field, _)) = checks.iter().find(|(_, ok)| !ok) {
        return Err(FactorError::NonFinite { field });
    }
    if pim.delta_t <= 0.0 {
        return Err(FactorError::NonPositiveDeltaT {
            delta_t: pim.delta_t,
        });
    }
    Ok(())
}

/// A preintegrated measurement with the square-root information of the covariance that
/// weights an `R`-dimensional residual: what both factors share.
#[derive(Clone, Debug, PartialEq)]
struct Weighted<const R: usize> {
    pim: PreintegratedImu,
    sqrt_info: SMatrix<f64, R, R>,
    /// The covariance `U` is the square-root information of (the residual's, in `mode`).
    cov: SMatrix<f64, R, R>,
    mode: ResidualMode,
}

impl<const R: usize> Weighted<R> {
    /// Checks `pim` (its level at least `needed`, finite fields, positive Δt) and computes the
    /// square-root information of `cov` (the component-wise residual's covariance, named
    /// `field` in errors), mapped to the Logmap chart for [`ResidualMode::Logmap`].
    fn new(
        pim: PreintegratedImu,
        needed: Level,
        field: &'static str,
        cov: SMatrix<f64, R, R>,
        mode: ResidualMode,
    ) -> Result<Self, FactorError> {
        if pim.level < needed {
            return Err(FactorError::LevelTooLow {
                needed,
                got: pim.level,
            });
        }
        check_pim(&pim)?;
        if !cov.iter().all(|x| x.is_finite()) {
            return Err(FactorError::NonFinite { field });
        }
        let cov = match mode {
            ResidualMode::ComponentWise => cov,
            ResidualMode::Logmap => logmap::logmap_cov(&pim, &cov),
        };
        let sqrt_info = sqrt_information(&cov)?;
        Ok(Self {
            pim,
            sqrt_info,
            cov,
            mode,
        })
    }

    /// The 9-dim residual and Jacobians in this factor's [`ResidualMode`], extended to `R`
    /// rows (the rows past nine zero, for the combined factor to fill).
    fn residual9_mode(
        &self,
        xi: &crate::NavState,
        xj: &crate::NavState,
        bias_i: &crate::ImuBias,
    ) -> (SVector<f64, 9>, ImuFactorJacobians) {
        let c = crate::bias_correction::correct(&self.pim, bias_i);
        let (mut r, mut j, _) = residual::residual9_at(&self.pim, xi, xj, &c);
        if self.mode == ResidualMode::Logmap {
            logmap::to_logmap(&self.pim, &c, &mut r, &mut j, None);
        }
        (r, j)
    }

    /// As [`residual9_mode`](Self::residual9_mode) with the deltas corrected for a time-offset
    /// change `dtd_s` \[s\] ([`crate::time_offset`]), and the column `∂r/∂δt_d`.
    fn residual9_mode_td(
        &self,
        xi: &crate::NavState,
        xj: &crate::NavState,
        bias_i: &crate::ImuBias,
        dtd_s: f64,
    ) -> (SVector<f64, 9>, ImuFactorJacobians, SVector<f64, 9>) {
        let (c, z) = crate::bias_correction::correct_with_time_offset(&self.pim, bias_i, dtd_s);
        let (mut r, mut j, rot) = residual::residual9_at(&self.pim, xi, xj, &c);
        let mut col = residual::td_column(&rot, &z);
        if self.mode == ResidualMode::Logmap {
            let dir = z.fixed_rows::<3>(0).into_owned();
            logmap::to_logmap(&self.pim, &c, &mut r, &mut j, Some((&mut col, dir)));
        }
        (r, j, col)
    }

    /// `(U r, U J)`.
    fn whiten(
        &self,
        (r, j): (SVector<f64, R>, FactorJacobians<R>),
    ) -> (SVector<f64, R>, FactorJacobians<R>) {
        (self.sqrt_info * r, j.left_mul(&self.sqrt_info))
    }

    /// `‖U r‖²`.
    fn chi2(&self, r: &SVector<f64, R>) -> f64 {
        (self.sqrt_info * r).norm_squared()
    }
}
