//! Merging two consecutive preintegrations `a = [t_i, t_k]` and `b = [t_k, t_j]` into one
//! over `[t_i, t_j]`.
//!
//! # Deltas (exact composition; `Δv`, `Δp` exclude gravity, see [`PreintegratedImu`])
//!
//! ```text
//! ΔR = ΔR_a ΔR_b,   Δv = Δv_a + ΔR_a Δv_b,   Δp = Δp_a + Δv_a Δt_b + ΔR_a Δp_b,   Δt = Δt_a + Δt_b
//! ```
//!
//! # Covariance (first order, chart of [`crate::measurement`], order [δφ, δv, δp])
//!
//! Linearising the composition in the errors of `a` and `b` (both expressed in their own start
//! frame):
//!
//! ```text
//! A = [[ΔR_bᵀ, 0, 0], [−ΔR_a [Δv_b]×, I, 0], [−ΔR_a [Δp_b]×, Δt_b I, I]]   (w.r.t. a's error)
//! B = diag(I, ΔR_a, ΔR_a)                                                  (w.r.t. b's error)
//! Σ = A Σ_a Aᵀ + B Σ_b Bᵀ
//! ```
//!
//! (the white noises of the two windows are independent). Bias Jacobians (9×6, columns
//! [b_g, b_a]) compose the same way: `J = A J_a + B J_b`.
//!
//! Combined 15×15 covariance [δφ, δv, δp, δb_g, δb_a] with `δb = b_t − b_i` (bias random walk):
//! at `t_k` the bias has drifted by `δb_a` (a's last six components), which window b sees as
//! an uncorrected bias error, moving its deltas by `−J_b δb_a` (first order, same sign as in
//! the propagation). Hence
//!
//! ```text
//! F_a = [[A, −B J_b], [0, I₆]],   G_b = [[B, 0], [0, I₆]],   Σ15 = F_a Σ15_a F_aᵀ + G_b Σ15_b G_bᵀ
//! ```
//!
//! # Exactness
//!
//! For the `euler` scheme (each interval uses one sample) the merge equals integrating the
//! whole window to round-off: deltas, covariances and Jacobians (tested in
//! `preint/tests/merge.rs`). For `midpoint` and the high-order scheme, the samples near `t_k`
//! enter intervals of both windows, so the merged covariance neglects their noise correlation
//! across the boundary and the high-order edge stencils differ from the interior ones: the
//! merge is then a (close) approximation, not an identity.

use crate::measurement::{BiasJacobians, Cov9, Cov15, PreintegratedImu};
use lie::hat;
use nalgebra::{Matrix3, SMatrix};
use thiserror::Error;

/// Why two preintegrations cannot be merged.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MergeError {
    /// `a.t_j_ns != b.t_i_ns`: the windows are not consecutive.
    #[error(
        "windows are not consecutive: first ends at {a_t_j_ns} ns, second starts at {b_t_i_ns} ns"
    )]
    NotConsecutive {
        /// End of the first window [ns].
        a_t_j_ns: i64,
        /// Start of the second window [ns].
        b_t_i_ns: i64,
    },
    /// The two windows were integrated with different bias estimates (compared exactly);
    /// re-integrate or correct one of them first.
    #[error("windows were integrated with different bias estimates (bias_hat differs)")]
    BiasMismatch,
    /// The two windows use different gravity vectors (compared exactly).
    #[error("windows use different gravity vectors")]
    GravityMismatch,
}

type M96 = SMatrix<f64, 9, 6>;

fn jac_to_mat(j: &BiasJacobians) -> M96 {
    let mut m = M96::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&j.d_r_d_bg);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&j.d_v_d_bg);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&j.d_v_d_ba);
    m.fixed_view_mut::<3, 3>(6, 0).copy_from(&j.d_p_d_bg);
    m.fixed_view_mut::<3, 3>(6, 3).copy_from(&j.d_p_d_ba);
    m
}

fn mat_to_jac(m: &M96) -> BiasJacobians {
    BiasJacobians {
        d_r_d_bg: m.fixed_view::<3, 3>(0, 0).into_owned(),
        d_v_d_bg: m.fixed_view::<3, 3>(3, 0).into_owned(),
        d_v_d_ba: m.fixed_view::<3, 3>(3, 3).into_owned(),
        d_p_d_bg: m.fixed_view::<3, 3>(6, 0).into_owned(),
        d_p_d_ba: m.fixed_view::<3, 3>(6, 3).into_owned(),
    }
}

/// Merges two consecutive preintegrations `a` over `[t_i, t_k]` and `b` over `[t_k, t_j]`
/// into one over `[t_i, t_j]`: deltas, 9×9 and 15×15 covariances and bias Jacobians, by the
/// formulas of the module docs. `Δt` is recomputed from the integer timestamps
/// (`(t_j − t_i)·1e-9` s) when both inputs' `delta_t` agree with theirs, else summed.
///
/// Errors: [`MergeError::NotConsecutive`] if `a.t_j_ns != b.t_i_ns`,
/// [`MergeError::BiasMismatch`] / [`MergeError::GravityMismatch`] if `bias_hat` / `gravity`
/// differ (exact comparison).
pub fn merge(a: &PreintegratedImu, b: &PreintegratedImu) -> Result<PreintegratedImu, MergeError> {
    if a.t_j_ns != b.t_i_ns {
        return Err(MergeError::NotConsecutive {
            a_t_j_ns: a.t_j_ns,
            b_t_i_ns: b.t_i_ns,
        });
    }
    if a.bias_hat != b.bias_hat {
        return Err(MergeError::BiasMismatch);
    }
    if a.gravity != b.gravity {
        return Err(MergeError::GravityMismatch);
    }
    let ra = *a.delta_r.matrix();
    let dtb = b.delta_t;

    let mut am = SMatrix::<f64, 9, 9>::identity();
    am.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&b.delta_r.matrix().transpose());
    am.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-ra * hat(&b.delta_v)));
    am.fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(-ra * hat(&b.delta_p)));
    am.fixed_view_mut::<3, 3>(6, 3)
        .copy_from(&(Matrix3::identity() * dtb));
    let mut bm = SMatrix::<f64, 9, 9>::identity();
    bm.fixed_view_mut::<3, 3>(3, 3).copy_from(&ra);
    bm.fixed_view_mut::<3, 3>(6, 6).copy_from(&ra);

    let cov: Cov9 = am * a.cov * am.transpose() + bm * b.cov * bm.transpose();
    let ja = jac_to_mat(&a.jac);
    let jb = jac_to_mat(&b.jac);
    let jac = mat_to_jac(&(am * ja + bm * jb));

    let mut fa = Cov15::identity();
    fa.fixed_view_mut::<9, 9>(0, 0).copy_from(&am);
    fa.fixed_view_mut::<9, 6>(0, 9).copy_from(&(-bm * jb));
    let mut gb = Cov15::identity();
    gb.fixed_view_mut::<9, 9>(0, 0).copy_from(&bm);
    let cov15: Cov15 = fa * a.cov15 * fa.transpose() + gb * b.cov15 * gb.transpose();

    let summed = a.delta_t + b.delta_t;
    let from_ns = crate::sample::dt_seconds(a.t_i_ns, b.t_j_ns);
    let consistent = a.delta_t == crate::sample::dt_seconds(a.t_i_ns, a.t_j_ns)
        && b.delta_t == crate::sample::dt_seconds(b.t_i_ns, b.t_j_ns);
    Ok(PreintegratedImu {
        t_i_ns: a.t_i_ns,
        t_j_ns: b.t_j_ns,
        delta_t: if consistent { from_ns } else { summed },
        delta_r: a.delta_r.compose(&b.delta_r),
        delta_v: a.delta_v + ra * b.delta_v,
        delta_p: a.delta_p + a.delta_v * dtb + ra * b.delta_p,
        cov: 0.5 * (cov + cov.transpose()),
        cov15: 0.5 * (cov15 + cov15.transpose()),
        jac,
        bias_hat: a.bias_hat,
        gravity: a.gravity,
    })
}
