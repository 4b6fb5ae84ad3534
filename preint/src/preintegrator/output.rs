//! The measurement in the documented chart ([`PreintegratedImu`](crate::PreintegratedImu)) from the pulled-back
//! error state: pushed forward to the window's end (`Φ_N`), then the rotation rows and
//! columns taken from rotated coordinates `ψ = ΔR δφ` to `δφ`.

use crate::measurement::{BiasJacobians, Cov9, Cov15};
use crate::propagation::blocks::{M3, PackedSym9, V3};
use crate::propagation::transition::Transition;
use crate::propagation::{BiasWalk, ErrorState};
use nalgebra::SVector;

/// Covariances and bias Jacobians in the chart.
pub(crate) struct Chart {
    pub cov: Cov9,
    pub cov15: Cov15,
    pub jac: BiasJacobians,
}

impl Chart {
    /// All zero (a measurement without linearisation).
    pub(crate) fn zeros() -> Self {
        Self {
            cov: Cov9::zeros(),
            cov15: Cov15::zeros(),
            jac: BiasJacobians::default(),
        }
    }

    /// From the error state `e` whose white-noise covariance, with the edge samples added, is
    /// `p`; `tr = Φ_N`, `r = ΔR` at the end of the window.
    pub(crate) fn of(
        e: &ErrorState,
        p: &PackedSym9,
        tr: &Transition,
        r: &M3,
        walk: &BiasWalk,
    ) -> Self {
        let rt = r.transpose();
        let to_chart = |p: &PackedSym9| {
            let p = tr.push_forward(p);
            let mut m = Cov9::zeros();
            let blocks = [
                (0, 0, rt * p.rr * r),
                (0, 3, rt * p.rv),
                (0, 6, rt * p.rp),
                (3, 3, p.vv),
                (3, 6, p.vp),
                (6, 6, p.pp),
            ];
            for (i, j, b) in blocks {
                m.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
                if i != j {
                    m.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
                }
            }
            (m + m.transpose()) * 0.5
        };
        let cov = to_chart(p);
        let cov_walk = to_chart(&e.p_walk);
        let j = tr.apply(&e.j);
        let jac = BiasJacobians {
            d_r_d_bg: rt * j.gyro_block(0),
            d_v_d_bg: j.gyro_block(1),
            d_v_d_ba: j.acc_block(1),
            d_p_d_bg: j.gyro_block(2),
            d_p_d_ba: j.acc_block(2),
        };
        let mut cov15 = Cov15::zeros();
        cov15
            .fixed_view_mut::<9, 9>(0, 0)
            .copy_from(&(cov + cov_walk));
        let c = &e.c;
        let cross = [
            (0, 9, rt * c.gyro_block(0)),
            (3, 9, c.gyro_block(1)),
            (3, 12, c.acc_block(1)),
            (6, 9, c.gyro_block(2)),
            (6, 12, c.acc_block(2)),
        ];
        for (i, j, b) in cross {
            cov15.fixed_view_mut::<3, 3>(i, j).copy_from(&b);
            cov15.fixed_view_mut::<3, 3>(j, i).copy_from(&b.transpose());
        }
        cov15
            .fixed_view_mut::<3, 3>(9, 9)
            .copy_from(&(walk.g * e.walk_t));
        cov15
            .fixed_view_mut::<3, 3>(12, 12)
            .copy_from(&(walk.a * e.walk_t));
        Self { cov, cov15, jac }
    }
}

/// `∂[δφ, δv, δp]/∂t_d` of deltas `(ΔR, Δv [m/s], Δp [m])` over `delta_t` \[s\] with the
/// bias-corrected end samples `(ω_i, a_i)`, `(ω_j, a_j)` [rad/s, m/s²] ([`crate::time_offset`]:
/// the end-sample algebra, no re-integration). Units of the rows: rad/s, m/s², m/s.
pub fn time_offset_jacobian(
    (w_i, a_i): (&V3, &V3),
    (w_j, a_j): (&V3, &V3),
    (delta_r, delta_v, delta_p): (&M3, &V3, &V3),
    delta_t: f64,
) -> SVector<f64, 9> {
    let phi = w_j - delta_r.transpose() * w_i;
    let v = delta_r * a_j - a_i - w_i.cross(delta_v);
    let p = delta_v - a_i * delta_t - w_i.cross(delta_p);
    let mut j = SVector::<f64, 9>::zeros();
    j.fixed_rows_mut::<3>(0).copy_from(&phi);
    j.fixed_rows_mut::<3>(3).copy_from(&v);
    j.fixed_rows_mut::<3>(6).copy_from(&p);
    j
}
