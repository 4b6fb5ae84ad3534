//! The 9-dim residual with a navigation-frame rotation rate ω (Earth rotation) and its
//! analytic Jacobians; the prediction it inverts is in [`crate::earth`].
//!
//! The residual compares the deltas the two states imply with the measured ones, in body
//! frame i, exactly as without rotation: with `(Y, w_v, w_p)` the deltas for which the mode's
//! prediction from `x_i` lands on `x_j`,
//!
//! ```text
//! r_φ = Log(ΔR(b)ᵀ Y),   r_v = w_v − Δv(b),   r_p = w_p − Δp(b)
//! ```
//!
//! so that to first order `r = −[δφ, δv, δp]` and its covariance is still the measurement's
//! `cov` (resp. `residual_cov15()`): no whitening term is added in this chart. (GTSAM's
//! residual lives in body frame j with the physical velocity `v = v̄ − ω×p`; there the same
//! error picks up the block `−R_jᵀ[ω]×A R_i` from δp into δv, GTSAM PR #2806's whitening
//! correction. `preint/tests/earth_gtsam.rs` maps this residual's covariance through that
//! chart change and matches GTSAM 4.3's `residualCovariance()`.)
//!
//! Implied deltas, with `Ω = [ω]×`, `T = Δt`, `B = Exp(ωT)`, `v̄ = v + ω×p`:
//!
//! ```text
//! Exact:        Y = R_iᵀ B R_j
//!               w_v = R_iᵀ (B (v̄_j − T J_l(−ωT) g) − v̄_i)
//!               w_p = R_iᵀ (B (p_j − T² Γ_P(−ωT) g) − p_i − T v̄_i)
//! First/second: Y = Exp(ξ),  ξ = Log(R_iᵀ R_j) + T R_iᵀ ω
//!               w_v = R_iᵀ (v_j − v_i − g T + 2T ω×v_i + T c)
//!               w_p = R_iᵀ (p_j − p_i − T v_i − ½ g T² + T² ω×v_i + ½ T² c)
//! ```
//!
//! (`c = ω×(ω×p_i)` for second order, else 0). Jacobians of `Y` (right perturbation), `w_v`
//! and `w_p` w.r.t. the state blocks (perturbations of [`ImuFactor`](crate::ImuFactor)), `θ = Log(R_iᵀR_j)`:
//!
//! ```text
//! Exact:  ∂Y/∂δφ_i = −Yᵀ, ∂Y/∂δφ_j = I
//!         ∂w_v: δφ_i [w_v]×, δp_i −R_iᵀΩR_i, δv_i −R_iᵀ, δp_j R_iᵀBΩR_j, δv_j R_iᵀB
//!         ∂w_p: δφ_i [w_p]×, δp_i −I − T R_iᵀΩR_i, δv_i −T R_iᵀ, δp_j R_iᵀBR_j
//! Approx: ∂Y/∂δφ_i = Jr(ξ)(−Jl⁻¹(θ) + T[R_iᵀω]×), ∂Y/∂δφ_j = Jr(ξ) Jr⁻¹(θ)
//!         ∂w_v: δφ_i [w_v]×, δp_i T R_iᵀΩ²R_i (second order), δv_i R_iᵀ(2TΩ − I), δv_j R_iᵀ
//!         ∂w_p: δφ_i [w_p]×, δp_i −I + ½T² R_iᵀΩ²R_i (second order), δv_i R_iᵀ(T²Ω − T I),
//!               δp_j R_iᵀR_j
//! ```
//!
//! and `∂r_φ/∂x = Jr⁻¹(r_φ) ∂Y/∂x`, `∂r_v/∂x = ∂w_v/∂x`, `∂r_p/∂x = ∂w_p/∂x`; the bias blocks
//! are those without rotation. Checked against central differences in `preint/tests/earth.rs`.

use super::ImuFactorJacobians;
use crate::choices::CoriolisMode;
use crate::earth::{Transport, centrifugal};
use crate::measurement::PreintegratedImu;
use crate::navstate::NavState;
use nalgebra::{Matrix3, SVector, Vector3};
use preint_lie::{SO3, hat, jl_inv, jr};

/// Deltas implied by two states and their Jacobians; blocks in the order
/// [δφ_i, δp_i, δv_i, δφ_j, δp_j, δv_j].
struct Implied {
    y: SO3,
    wv: Vector3<f64>,
    wp: Vector3<f64>,
    dy: [Matrix3<f64>; 6],
    dv: [Matrix3<f64>; 6],
    dp: [Matrix3<f64>; 6],
}

fn implied_exact(
    pim: &PreintegratedImu,
    xi: &NavState,
    xj: &NavState,
    w: &Vector3<f64>,
) -> Implied {
    let t = pim.delta_t;
    let tr = Transport::new(w, t, &pim.gravity);
    let b = tr.a.inverse();
    let ri_t = xi.r.inverse();
    let y = ri_t.compose(&b).compose(&xj.r);
    let vbar_i = xi.v + w.cross(&xi.p);
    let vbar_j = xj.v + w.cross(&xj.p);
    let wv = ri_t.act(&(b.act(&(vbar_j - tr.vg)) - vbar_i));
    let wp = ri_t.act(&(b.act(&(xj.p - tr.pg)) - xi.p - vbar_i * t));
    let (rim, rjm, bm) = (*xi.r.matrix(), *xj.r.matrix(), *b.matrix());
    let om = hat(w);
    let z = Matrix3::zeros();
    let id = Matrix3::identity();
    let ri_om_ri = rim.transpose() * om * rim;
    Implied {
        y,
        wv,
        wp,
        dy: [-y.matrix().transpose(), z, z, id, z, z],
        dv: [
            hat(&wv),
            -ri_om_ri,
            -rim.transpose(),
            z,
            rim.transpose() * bm * om * rjm,
            rim.transpose() * bm,
        ],
        dp: [
            hat(&wp),
            -id - ri_om_ri * t,
            -rim.transpose() * t,
            z,
            rim.transpose() * bm * rjm,
            z,
        ],
    }
}

fn implied_approx(
    pim: &PreintegratedImu,
    xi: &NavState,
    xj: &NavState,
    w: &Vector3<f64>,
    mode: CoriolisMode,
) -> Implied {
    let t = pim.delta_t;
    let g = pim.gravity;
    let ri_t = xi.r.inverse();
    let (theta, jr_inv_theta) = ri_t.compose(&xj.r).log_jac();
    let u = ri_t.act(w);
    let xi_r = theta + u * t;
    let jr_xi = jr(&xi_r);
    let c = centrifugal(w, &xi.p, mode);
    let wc = w.cross(&xi.v);
    let wv = ri_t.act(&(xj.v - xi.v - g * t + wc * (2.0 * t) + c * t));
    let wp =
        ri_t.act(&(xj.p - xi.p - xi.v * t - g * (0.5 * t * t) + wc * (t * t) + c * (0.5 * t * t)));
    let (rim, rjm) = (*xi.r.matrix(), *xj.r.matrix());
    let om = hat(w);
    let om2 = if mode == CoriolisMode::SecondOrder {
        rim.transpose() * om * om * rim
    } else {
        Matrix3::zeros()
    };
    let z = Matrix3::zeros();
    let id = Matrix3::identity();
    Implied {
        y: SO3::exp(&xi_r),
        wv,
        wp,
        dy: [
            jr_xi * (-jl_inv(&theta) + hat(&u) * t),
            z,
            z,
            jr_xi * jr_inv_theta,
            z,
            z,
        ],
        dv: [
            hat(&wv),
            om2 * t,
            rim.transpose() * (om * (2.0 * t) - id),
            z,
            z,
            rim.transpose(),
        ],
        dp: [
            hat(&wp),
            -id + om2 * (0.5 * t * t),
            rim.transpose() * (om * (t * t) - id * t),
            z,
            rim.transpose() * rjm,
            z,
        ],
    }
}

/// The 9-dim residual and its Jacobians with the Earth rate `w` [rad/s, navigation frame]
/// ([`ImuFactor`](crate::ImuFactor)).
pub(super) fn residual9_rotating(
    pim: &PreintegratedImu,
    xi: &NavState,
    xj: &NavState,
    c: &crate::bias_correction::Corrected,
    w: &Vector3<f64>,
) -> (SVector<f64, 9>, ImuFactorJacobians, Matrix3<f64>) {
    let imp = match pim.coriolis {
        CoriolisMode::Exact => implied_exact(pim, xi, xj, w),
        mode => implied_approx(pim, xi, xj, w, mode),
    };
    let (dr, jr_db, dv, dp) = (c.r, c.jr, c.v, c.p);
    let jb = &c.jac;
    let e = dr.inverse().compose(&imp.y);
    let (r_phi, jr_inv_e) = e.log_jac();

    let mut r = SVector::<f64, 9>::zeros();
    r.fixed_rows_mut::<3>(0).copy_from(&r_phi);
    r.fixed_rows_mut::<3>(3).copy_from(&(imp.wv - dv));
    r.fixed_rows_mut::<3>(6).copy_from(&(imp.wp - dp));

    let mut jac = ImuFactorJacobians::zeros();
    // The state blocks [φ_i, p_i, v_i, φ_j, p_j, v_j].
    for (k, blk) in jac.blocks_mut().into_iter().take(6).enumerate() {
        blk.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(jr_inv_e * imp.dy[k]));
        blk.fixed_view_mut::<3, 3>(3, 0).copy_from(&imp.dv[k]);
        blk.fixed_view_mut::<3, 3>(6, 0).copy_from(&imp.dp[k]);
    }
    let rot = jr_inv_e * e.matrix().transpose() * jr_db;
    super::residual::bias_blocks(&mut jac, &rot, jb);
    (r, jac, rot)
}
