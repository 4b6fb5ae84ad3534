//! The SE₂(3) Logmap residual of both factors (its definition, Jacobians and weight:
//! [`ResidualMode`]).
//!
//! The mode is chosen when a factor is built (`ImuFactor::with_mode`,
//! `CombinedImuFactor::with_mode`; `new` takes the default, [`ResidualMode::Logmap`]). The
//! Logmap mode reuses the component-wise residual and Jacobians of `factor/mod.rs` and maps them.
//! Why it is the default: at the true states over 10 s windows the component-wise χ² is
//! over-confident once the rotation noise is not tiny (numbers on [`ResidualMode::default`];
//! 9-dim 22.4 / 30.1 on `aggressive` / `seed-ellipse` at σ_g = 0.05 rad/s/√Hz, σ_a = 0.1
//! m/s²/√Hz, where the Logmap one is 10.5 / 11.8; `docs/EVIDENCE.md`), and at EuRoC
//! densities both are identical. What the Logmap residual keeps over 9 is not its chart but the
//! first-order covariance, which the second-order term ([`crate::second_order`]) completes. On
//! the command line `preint factor --residual component|logmap` selects the mode and prints it
//! (`residual_mode` in the JSON).

use super::FactorJacobians;
use crate::bias_correction::Corrected;
use crate::measurement::PreintegratedImu;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use preint_lie::se3::q_block;
use preint_lie::{hat, jl, jl_inv};

/// Which residual a factor evaluates (GTSAM's `ImuFactorErrorMode`, without its `Legacy`).
///
/// [`ResidualMode::Logmap`] below: the SE₂(3) residual of both factors, its analytic
/// Jacobians and its weight.
///
/// # Definition
///
/// Write a triple `(R, v, p)` as the SE₂(3) element `[[R, v, p], [0, 1, 0], [0, 0, 1]]`, with
/// `Log(R, v, p) = [φ, Jl(φ)⁻¹ v, Jl(φ)⁻¹ p]`, `φ = Log(R)` (`Jl` the SO(3) left Jacobian;
/// Barrau & Bonnabel 2017, Brossard et al. 2022). With `D(b) = (ΔR(b), Δv(b), Δp(b))` the
/// bias-corrected deltas (Forster 2017 eq. 44) and `Y = (Y_R, w_v, w_p)` the deltas the two
/// states imply (`Y_R = R_iᵀR_j`, `w_v = R_iᵀ(v_j − v_i − gΔt)`, `w_p = R_iᵀ(p_j − p_i − v_iΔt −
/// ½gΔt²)`; with an Earth rate the rotating-frame ones of `rotating.rs`), the residual is
///
/// ```text
/// r_L = Log(D(b)⁻¹ Y) = [r_φ, Jl(r_φ)⁻¹ ΔR(b)ᵀ r_v, Jl(r_φ)⁻¹ ΔR(b)ᵀ r_p]     [rad, m/s, m]
/// ```
///
/// in the order **[φ, v, p]** of the component-wise residual `r = [r_φ, r_v, r_p]`
/// ([`ImuFactor`](crate::ImuFactor)), which it reuses: `r_φ` is unchanged, the velocity and position rows are
/// rotated into the frame of the predicted attitude and sheared by `Jl(r_φ)⁻¹`. Without an
/// Earth rate, `D(b)⁻¹ Y = X̂_j⁻¹ X_j` (the prediction [`predict`](crate::predict) of `X_j`
/// compared with `X_j` on SE₂(3)), so `r_L = Log(X̂_j⁻¹ X_j)`.
///
/// # Relation to GTSAM (`ImuFactorErrorMode::Logmap`)
///
/// GTSAM 4.3's error is `e = Log(X_j⁻¹ X̂_j) = −Log(X̂_j⁻¹ X_j)` in the order [rot, pos, vel], so
/// **exactly** (no first-order step) `e = −P r_L` with `P` the reordering [φ, v, p] → [φ, p, v];
/// the Jacobians map the same way (`∂e/∂x = −P ∂r_L/∂x`), with GTSAM's pose perturbation
/// `[dw, dt]` and world velocity equal to the [`NavState`](crate::NavState) tangent
/// [δφ, δp, δv] to first order and its bias order [b_a, b_g]. Tested against GTSAM 4.3
/// fixtures in `preint/tests/factor_gtsam.rs` (9-dim) and
/// `preint/tests/combined_modes_gtsam.rs` (15-dim). With an Earth rate (`rotating.rs`) GTSAM
/// compares the states in body frame j with the physical velocity `v − ω×p`; its Logmap error is
/// then, exactly, `e = −P r_L + [0, 0, Jl(w)⁻¹ N r_p]` with `w = −r_φ`,
/// `N = R_jᵀ[ω]× Exp(−ωΔt) R_i` and `r_p` the component-wise position row — the same `δp → δv`
/// term as in the component-wise mode (GTSAM PR #2806's whitening), checked against GTSAM 4.3
/// in `preint/tests/earth_gtsam.rs`.
///
/// # Jacobians
///
/// With `φ = r_φ`, `Q = ΔR(b)ᵀ`, `u = Q r_k` and `ρ = Jl(φ)⁻¹ u` for `k ∈ {v, p}`, and the SE(3)
/// block `Q(ρ, φ)` (Barfoot 2017 eq. 7.86, [`preint_lie::se3::q_block`]): from
/// `Exp([ρ, φ]) = (Exp(φ), Jl(φ)ρ)` and the SE(3) left Jacobian,
/// `∂(Jl(φ)ρ)/∂φ = Q(ρ, φ) − [u]× Jl(φ)`, hence
///
/// ```text
/// ∂ρ/∂φ = G_k = −Jl(φ)⁻¹ (Q(ρ, φ) − [u]× Jl(φ)),      ∂ρ/∂u = Jl(φ)⁻¹
/// ∂r_L,k/∂x = Jl(φ)⁻¹ Q ∂r_k/∂x + G_k ∂r_φ/∂x  (+ Jl(φ)⁻¹ [u]× Jr(θ) J_R^g for x = δb_g,i)
/// ```
///
/// where the last term is `ΔR(b)ᵀ = Exp(−θ)ΔRᵀ` moving with the bias (`θ = J_R^g δb_g`). The
/// component-wise blocks `∂r/∂x` are those of [`ImuFactor`](crate::ImuFactor) (or `rotating.rs`), so every
/// perturbation is the same; all blocks are checked against central differences in
/// `preint/tests/factor_logmap.rs`.
///
/// # Weighting
///
/// To first order in the residual, `Jl(r_φ)⁻¹ → I` and `r_L = T r` with
/// `T = diag(I, ΔRᵀ, ΔRᵀ)` (`ΔR` at the integration bias `bias_hat`), a linear map of the
/// component-wise residual whose covariance is `cov` (resp. `residual_cov15()`), so `r_L` is
/// weighted by `T cov Tᵀ` (resp. `diag(T, I₆) residual_cov15() diag(T, I₆)ᵀ`). This is GTSAM's
/// weighting too: its `residualCovariance()` is the same in both error modes and lives in the
/// `ΔRᵀ`-rotated chart. The two residuals therefore have the same χ² to first order; they differ
/// in how the non-linear part of the error (rotation error coupling into velocity and position
/// over long windows) is charted, which is what the NEES evidence in `docs/EVIDENCE.md` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ResidualMode {
    /// Forster's component-wise residual `[r_φ, r_v, r_p]` ([`ImuFactor`](crate::ImuFactor)), weighted by
    /// `cov` (GTSAM `ComponentWise`).
    ComponentWise,
    /// The SE₂(3) residual `Log(D(b)⁻¹ Y)` (the enum's documentation), weighted by `T cov Tᵀ`
    /// (GTSAM `Logmap`, its default in 4.3).
    Logmap,
}

impl Default for ResidualMode {
    /// [`ResidualMode::Logmap`], as in GTSAM 4.3. At the true states over 10 s windows
    /// (hermite4, 200 Hz, 8 000 realisations, `tests/tests/factor_logmap_nees.rs`) both modes
    /// give the same mean χ² at EuRoC densities (8.93–8.95 / 14.99–15.06 for 9 / 15 dof), while
    /// at the noisy-MEMS densities σ_g = 0.015 rad/s/√Hz, σ_a = 0.019 m/s²/√Hz the
    /// component-wise residual is over-confident (9-dim 10.85 / 13.31 on `aggressive` /
    /// `seed-ellipse`, 15-dim 16.71 / 18.71) and the Logmap one much closer (9.23 / 9.56,
    /// 15.17 / 15.47), inside the band with the second-order covariance of
    /// [`crate::second_order`] (9.04 / 9.01, 14.99 / 15.00); `docs/EVIDENCE.md`, "The Logmap
    /// residual and the second-order covariance".
    fn default() -> Self {
        ResidualMode::Logmap
    }
}

impl ResidualMode {
    /// The command-line name: `"component"` or `"logmap"`.
    pub fn name(self) -> &'static str {
        match self {
            ResidualMode::ComponentWise => "component",
            ResidualMode::Logmap => "logmap",
        }
    }

    /// Parses `"component"` / `"componentwise"` / `"logmap"` (ASCII case-insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "component" | "componentwise" | "component-wise" => Some(ResidualMode::ComponentWise),
            "logmap" => Some(ResidualMode::Logmap),
            _ => None,
        }
    }
}

/// `T = diag(I, ΔRᵀ, ΔRᵀ)`, the first-order map from the component-wise residual to the
/// Logmap one ([`ResidualMode`]), at the integration bias.
pub(crate) fn chart_map9(pim: &PreintegratedImu) -> SMatrix<f64, 9, 9> {
    let rt = pim.delta_r.matrix().transpose();
    let mut t = SMatrix::<f64, 9, 9>::identity();
    t.fixed_view_mut::<3, 3>(3, 3).copy_from(&rt);
    t.fixed_view_mut::<3, 3>(6, 6).copy_from(&rt);
    t
}

/// `T cov Tᵀ` for an `R`-dimensional covariance whose first nine rows are [φ, v, p]
/// (`T` extended by the identity).
pub(super) fn logmap_cov<const R: usize>(
    pim: &PreintegratedImu,
    cov: &SMatrix<f64, R, R>,
) -> SMatrix<f64, R, R> {
    let mut t = SMatrix::<f64, R, R>::identity();
    t.fixed_view_mut::<9, 9>(0, 0).copy_from(&chart_map9(pim));
    t * cov * t.transpose()
}

/// Maps a component-wise residual and its Jacobians (first nine rows [r_φ, r_v, r_p]; any
/// further rows, the bias rows of the combined factor, are left as they are) to the Logmap
/// residual and its Jacobians, in place ([`ResidualMode`] for the formulas), at the corrected deltas
/// `c`. `td`, if given, is a further column `∂r/∂δt_d` (the time offset,
/// [`crate::time_offset`]) with the rotation direction `u` its correction moves `ΔR(b)` along
/// (`ΔR(b) Exp(Jr(c_φ) u ε)`); it maps as the gyro-bias columns do, `ΔR(b)ᵀ` moving with it.
pub(super) fn to_logmap<const R: usize>(
    pim: &PreintegratedImu,
    c: &Corrected,
    r: &mut SVector<f64, R>,
    jac: &mut FactorJacobians<R>,
    mut td: Option<(&mut SVector<f64, R>, Vector3<f64>)>,
) {
    let j_rg = pim.jac.d_r_d_bg;
    let (dr, jr_db) = (c.r, c.jr);
    let q = dr.matrix().transpose();
    let phi: Vector3<f64> = r.fixed_rows::<3>(0).into_owned();
    let jli = jl_inv(&phi);
    let jlp = jl(&phi);
    let rows_phi = |b: &SMatrix<f64, R, 3>| -> Matrix3<f64> { b.fixed_view::<3, 3>(0, 0).into() };
    let td_phi: Option<Vector3<f64>> = td.as_ref().map(|(col, _)| col.fixed_rows::<3>(0).into());
    for row in [3, 6] {
        let u = q * r.fixed_rows::<3>(row);
        let rho = jli * u;
        let g = -jli * (q_block(&rho, &phi) - hat(&u) * jlp);
        let jq = jli * q;
        let bias_term = jli * hat(&u) * jr_db * j_rg;
        for (k, b) in jac.blocks_mut().into_iter().enumerate() {
            let bk: Matrix3<f64> = b.fixed_view::<3, 3>(row, 0).into();
            let mut m = jq * bk + g * rows_phi(b);
            if k == 6 {
                m += bias_term;
            }
            b.fixed_view_mut::<3, 3>(row, 0).copy_from(&m);
        }
        if let (Some((col, dir)), Some(cp)) = (td.as_mut(), td_phi.as_ref()) {
            let ck: Vector3<f64> = col.fixed_rows::<3>(row).into();
            let m = jq * ck + g * cp + jli * hat(&u) * jr_db * *dir;
            col.fixed_rows_mut::<3>(row).copy_from(&m);
        }
        r.fixed_rows_mut::<3>(row).copy_from(&rho);
    }
}
