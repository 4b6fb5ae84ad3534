//! Forster's 9-dim residual and its analytic Jacobians (formulas in the parent module's docs).

use super::ImuFactorJacobians;
use crate::measurement::{BiasJacobians, PreintegratedImu};
use crate::navstate::NavState;
use crate::sample::ImuBias;
use nalgebra::{Matrix3, SVector, Vector3};
use preint_lie::{SO3, hat};

/// The 9-dim residual and its Jacobians (module docs).
pub(super) fn residual9(
    pim: &PreintegratedImu,
    xi: &NavState,
    xj: &NavState,
    bias_i: &ImuBias,
) -> (SVector<f64, 9>, ImuFactorJacobians) {
    if let Some(w) = &pim.omega_coriolis {
        return super::rotating::residual9_rotating(pim, xi, xj, bias_i, w);
    }
    let (dr, jr_db, dv, dp, jb) = corrected(pim, bias_i);
    let jb = &jb;

    let dt = pim.delta_t;
    let g = pim.gravity;
    let ri_t = xi.r.inverse();
    let ri_t_rj = ri_t.compose(&xj.r);
    let e = dr.inverse().compose(&ri_t_rj);
    let (r_phi, jr_inv) = e.log_jac();
    let wv = ri_t.act(&(xj.v - xi.v - g * dt));
    let wp = ri_t.act(&(xj.p - xi.p - xi.v * dt - g * (0.5 * dt * dt)));
    let r_v = wv - dv;
    let r_p = wp - dp;

    let mut r = SVector::<f64, 9>::zeros();
    r.fixed_rows_mut::<3>(0).copy_from(&r_phi);
    r.fixed_rows_mut::<3>(3).copy_from(&r_v);
    r.fixed_rows_mut::<3>(6).copy_from(&r_p);

    let ri_tm = *ri_t.matrix();
    let mut jac = ImuFactorJacobians::zeros();
    // Rows 0..3: r_φ; 3..6: r_v; 6..9: r_p.
    jac.phi_i
        .fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-jr_inv * ri_t_rj.matrix().transpose()));
    jac.phi_i.fixed_view_mut::<3, 3>(3, 0).copy_from(&hat(&wv));
    jac.phi_i.fixed_view_mut::<3, 3>(6, 0).copy_from(&hat(&wp));
    jac.p_i
        .fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(-Matrix3::identity()));
    jac.v_i.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-ri_tm));
    jac.v_i
        .fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(-ri_tm * dt));
    jac.phi_j.fixed_view_mut::<3, 3>(0, 0).copy_from(&jr_inv);
    jac.p_j
        .fixed_view_mut::<3, 3>(6, 0)
        .copy_from(ri_t_rj.matrix());
    jac.v_j.fixed_view_mut::<3, 3>(3, 0).copy_from(&ri_tm);
    bias_blocks(&mut jac, &(jr_inv * e.matrix().transpose() * jr_db), jb);
    (r, jac)
}

/// The deltas corrected to first order for the bias `bias_i` (as
/// [`PreintegratedImu::corrected`], in its [`BiasCorrection`](crate::BiasCorrection)):
/// `(ΔR(b), Jr(∂ΔR/∂b_g δb_g), Δv(b) [m/s], Δp(b) [m], J)`, the right Jacobian of the rotation
/// correction and `J` the derivatives of `Δv(b)`, `Δp(b)` with respect to `δb`
/// ([`crate::bias_correction`]; its rotation block is `∂ΔR/∂b_g`) for the bias Jacobians.
pub(super) fn corrected(
    pim: &PreintegratedImu,
    bias_i: &ImuBias,
) -> (SO3, Matrix3<f64>, Vector3<f64>, Vector3<f64>, BiasJacobians) {
    let c = crate::bias_correction::correct(pim, bias_i);
    (c.r, c.jr, c.v, c.p, c.jac)
}

/// The bias-i blocks of a 9-dim residual's Jacobian: the rotation row through the first-order
/// bias correction, `−(∂r_φ/∂ΔR(b)) ∂ΔR/∂b_g` with `rot = ∂r_φ/∂ΔR(b)` (3×3), and the velocity
/// and position rows `−∂Δv/∂b`, `−∂Δp/∂b`.
pub(super) fn bias_blocks(jac: &mut ImuFactorJacobians, rot: &Matrix3<f64>, jb: &BiasJacobians) {
    for (row, m) in [
        (0, -rot * jb.d_r_d_bg),
        (3, -jb.d_v_d_bg),
        (6, -jb.d_p_d_bg),
    ] {
        jac.bg_i.fixed_view_mut::<3, 3>(row, 0).copy_from(&m);
    }
    for (row, m) in [(3, -jb.d_v_d_ba), (6, -jb.d_p_d_ba)] {
        jac.ba_i.fixed_view_mut::<3, 3>(row, 0).copy_from(&m);
    }
}
