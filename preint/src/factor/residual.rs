//! Forster's 9-dim residual and its analytic Jacobians (formulas in the parent module's docs).

use super::ImuFactorJacobians;
use crate::bias_correction::Corrected;
use crate::measurement::{BiasJacobians, PreintegratedImu};
use crate::navstate::NavState;
use nalgebra::{Matrix3, SVector};
use preint_lie::hat;

/// The 9-dim residual and its Jacobians ([`ImuFactor`](crate::ImuFactor)) at the corrected deltas `c` (for the bias `bias_i`,
/// and a time-offset change when `c` comes from [`crate::time_offset`]), and
/// `rot = Jr⁻¹(r_φ) Eᵀ Jr(c_φ)`: `∂r_φ/∂u = −rot` for a rotation correction moving along `u`
/// (`ΔR(b) ≈ ΔR(b) Exp(Jr(c_φ) u ε)`; [`td_column`]).
pub(super) fn residual9_at(
    pim: &PreintegratedImu,
    xi: &NavState,
    xj: &NavState,
    c: &Corrected,
) -> (SVector<f64, 9>, ImuFactorJacobians, Matrix3<f64>) {
    if let Some(w) = &pim.omega_coriolis {
        return super::rotating::residual9_rotating(pim, xi, xj, c, w);
    }
    let (dr, jr_db, dv, dp) = (c.r, c.jr, c.v, c.p);
    let jb = &c.jac;

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
    let rot = jr_inv * e.matrix().transpose() * jr_db;
    bias_blocks(&mut jac, &rot, jb);
    (r, jac, rot)
}

/// `∂r/∂δt_d` of the component-wise residual for corrected deltas that move along `z` with
/// the time offset ([`crate::time_offset`]'s `ζ`: rotation direction, `∂Δv`, `∂Δp`), with `rot`
/// from [`residual9_at`]: `[−rot z_φ, −z_v, −z_p]` (the residual is measured-subtracted).
pub(super) fn td_column(rot: &Matrix3<f64>, z: &SVector<f64, 9>) -> SVector<f64, 9> {
    let mut col = -z;
    let phi = -rot * z.fixed_rows::<3>(0);
    col.fixed_rows_mut::<3>(0).copy_from(&phi);
    col
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
