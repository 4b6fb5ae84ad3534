//! Merging two consecutive preintegrated windows (the model: [`merge()`]).

use crate::choices::Level;
use crate::edges::{EdgeNoise, EdgeSource};
use crate::measurement::{BiasJacobians, Cov9, Cov15, PreintegratedImu};
use nalgebra::{Matrix3, SMatrix};
use preint_lie::hat;
use thiserror::Error;

/// Why two preintegrations cannot be merged.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MergeError {
    /// `a.t_j_ns != b.t_i_ns`: the windows are not consecutive.
    #[error(
        "windows are not consecutive: first ends at {a_t_j_ns} ns, second starts at {b_t_i_ns} ns"
    )]
    NotConsecutive {
        /// End of the first window \[ns\].
        a_t_j_ns: i64,
        /// Start of the second window \[ns\].
        b_t_i_ns: i64,
    },
    /// The two windows were integrated with different bias estimates (compared exactly);
    /// re-integrate or correct one of them first.
    #[error("windows were integrated with different bias estimates (bias_hat differs)")]
    BiasMismatch,
    /// The two windows use different gravity vectors (compared exactly).
    #[error("windows use different gravity vectors")]
    GravityMismatch,
    /// The two windows use different navigation-frame rotation rates or Coriolis modes
    /// (`omega_coriolis`, `coriolis`, compared exactly).
    #[error("windows use different Earth rotation rates or Coriolis modes")]
    EarthRateMismatch,
    /// The two windows correct their deltas for a bias change differently
    /// ([`PreintegratedImu::bias_correction`]).
    #[error("windows use different bias corrections ({a:?} and {b:?})")]
    BiasCorrectionMismatch {
        /// Correction of the first window.
        a: crate::BiasCorrection,
        /// Correction of the second window.
        b: crate::BiasCorrection,
    },
    /// The two windows were computed at different [`Level`]s (e.g. one without the combined
    /// covariance): the merged `cov15` would mix models.
    #[error("windows were computed at different levels ({a:?} and {b:?})")]
    LevelMismatch {
        /// Level of the first window.
        a: Level,
        /// Level of the second window.
        b: Level,
    },
}

type M96 = SMatrix<f64, 9, 6>;

/// Merges two consecutive preintegrations `a` over `[t_i, t_k]` and `b` over `[t_k, t_j]`
/// into one over `[t_i, t_j]`: deltas, 9×9 and 15×15 covariances and bias Jacobians, by the
/// formulas below. `Δt` is recomputed from the integer timestamps
/// (`(t_j − t_i)·1e-9` s) when both inputs' `delta_t` agree with theirs, else summed.
///
/// The result's `edge_noise` holds a's start-side and b's end-side samples (with their gains
/// on the merged error), so merged windows merge exactly again.
///
/// ```
/// use preint::nalgebra::Vector3;
/// use preint::{ImuBias, ImuSample, PreintParams, merge, preintegrate};
/// let s: Vec<ImuSample> = (0..401i64)
///     .map(|k| ImuSample::new(k * 5_000_000, Vector3::new(0.1, 0.0, 0.3), Vector3::new(0.2, 0.0, 9.81)))
///     .collect();
/// let (p, b) = (PreintParams::default(), ImuBias::zero());
/// let a = preintegrate(&p, &b, &s, 0, 1_000_000_000).unwrap();
/// let c = preintegrate(&p, &b, &s, 1_000_000_000, 2_000_000_000).unwrap();
/// let whole = preintegrate(&p, &b, &s, 0, 2_000_000_000).unwrap();
/// let m = merge(&a, &c).unwrap();
/// assert!((m.delta_p - whole.delta_p).norm() < 1e-12);
/// assert!((m.cov - whole.cov).amax() < 1e-12 * whole.cov.amax());
/// ```
///
/// Errors: [`MergeError::NotConsecutive`] if `a.t_j_ns != b.t_i_ns`,
/// [`MergeError::BiasMismatch`] / [`MergeError::GravityMismatch`] if `bias_hat` / `gravity`
/// differ (exact comparison), [`MergeError::EarthRateMismatch`] if `omega_coriolis` or (with
/// a rate) `coriolis` differ, [`MergeError::BiasCorrectionMismatch`] if `bias_correction`
/// differs, [`MergeError::LevelMismatch`] if `level` differs. The merged measurement keeps the
/// two windows' `bias_correction`.
///
/// The merge of `a = [t_i, t_k]` and `b = [t_k, t_j]` is one window over `[t_i, t_j]`.
///
/// # Deltas (exact composition; `Δv`, `Δp` exclude gravity, see [`PreintegratedImu`])
///
/// ```text
/// ΔR = ΔR_a ΔR_b,   Δv = Δv_a + ΔR_a Δv_b,   Δp = Δp_a + Δv_a Δt_b + ΔR_a Δp_b,   Δt = Δt_a + Δt_b
/// ```
///
/// # Covariance (first order, chart of [`PreintegratedImu`](crate::PreintegratedImu), order [δφ, δv, δp])
///
/// Linearising the composition in the errors of `a` and `b` (both expressed in their own start
/// frame):
///
/// ```text
/// A = [[ΔR_bᵀ, 0, 0], [−ΔR_a [Δv_b]×, I, 0], [−ΔR_a [Δp_b]×, Δt_b I, I]]   (w.r.t. a's error)
/// B = diag(I, ΔR_a, ΔR_a)                                                  (w.r.t. b's error)
/// Σ = A Σ_a Aᵀ + B Σ_b Bᵀ
/// ```
///
/// plus, when the windows share stream samples, their covariance (below). Bias Jacobians
/// (9×6, columns [b_g, b_a]) compose the same way: `J = A J_a + B J_b`, and so does the
/// time-offset column [`PreintegratedImu::jac_td`]: `J_td = A J_td,a + B J_td,b`, because a
/// common offset shifts the inner keyframe for both windows; its terms cancel and the result is
/// the whole window's ([`crate::time_offset`], "Merge"). Windows integrated with different
/// offsets do not share that shift, and their merged column means nothing.
///
/// # Shared samples
///
/// Consecutive windows of one stream share the samples around their common keyframe `t_k`:
/// the sample at `t_k`, or the samples an interpolated boundary sample is made of, and for hermite4
/// the stencil neighbours ([`preintegrate`](crate::preintegrate())). Each window records those samples with their
/// gains `G` on its error ([`crate::edges::EdgeNoise`]); for a sample `s` in both,
/// the white part of the merged covariance gains
///
/// ```text
/// A G_a Q G_bᵀ Bᵀ + B G_b Q G_aᵀ Aᵀ   (Q = the sample's noise covariance)
/// ```
///
/// and, if the two windows gave the sample different cells (samples pushed into two
/// preintegrators directly: each saw only one of the sample's neighbours), the terms
/// `A G_a (Q − Q_a) G_aᵀ Aᵀ + B G_b (Q − Q_b) G_bᵀ Bᵀ` replace each window's one-sided cell
/// `Q_a`, `Q_b` by the cell from both neighbours, `Q`. Samples are identified by timestamp, so
/// both windows must come from the same stream (and the same noise densities and cell rule;
/// otherwise no sample is taken as shared).
///
/// Combined 15×15 covariance [δφ, δv, δp, δb_g, δb_a] with `δb = b_t − b_i` (bias random walk):
/// at `t_k` the bias has drifted by `δb_a` (a's last six components), which window b sees as
/// an uncorrected bias error, moving its deltas by `−J_b δb_a` (first order, same sign as in
/// the propagation). Hence
///
/// ```text
/// F_a = [[A, −B J_b], [0, I₆]],   G_b = [[B, 0], [0, I₆]],   Σ15 = F_a Σ15_a F_aᵀ + G_b Σ15_b G_bᵀ
/// ```
///
/// plus the shared-sample terms in its 9×9 block. For [`Level::Covariance`] measurements
/// (`cov15` without the random walk's effect on the deltas) the result is
/// `diag(Σ, Σ_bb,a + Σ_bb,b)`: no cross blocks are invented.
///
/// # Exactness
///
/// The merged covariance is the exact first-order covariance of the composed deltas under the
/// noise model of [`ImuNoise`](crate::ImuNoise) (tested against numeric differentiation with respect to
/// every stream sample in `preint/tests/linearisation.rs`). For windows split at a stream
/// sample, merging equals integrating the whole window at once to round-off — deltas,
/// covariances and Jacobians — for every scheme when the windows come from
/// [`crate::window::preintegrate`], and for Euler and midpoint also when the samples were
/// pushed into preintegrators directly (direct hermite4 windows use one-sided edge stencils, so
/// their composition differs from the whole window by the O(h⁴) integration error; the merge
/// is still the exact covariance of that composition). For a split between samples the
/// composition equals the whole stream with the boundary sample inserted
/// ([`preintegrate`](crate::preintegrate())).
pub fn merge(a: &PreintegratedImu, b: &PreintegratedImu) -> Result<PreintegratedImu, MergeError> {
    check_mergeable(a, b)?;
    let ra = *a.delta_r.matrix();
    let dtb = b.delta_t;
    let (am, bm) = transitions(a, b);
    let (shared, edge_noise) = shared_noise(a, b, &am, &bm);
    let cov: Cov9 = am * a.cov * am.transpose() + bm * b.cov * bm.transpose() + shared;
    let jb = b.jac.as_matrix();
    let jac = BiasJacobians::from_matrix(&(am * a.jac.as_matrix() + bm * jb));
    let cov15 = combined_cov(a, b, &am, &bm, &jb, &shared, &cov);
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
        jac_td: am * a.jac_td + bm * b.jac_td,
        bias_hat: a.bias_hat,
        gravity: a.gravity,
        omega_coriolis: a.omega_coriolis,
        coriolis: a.coriolis,
        level: a.level,
        edge_noise,
        bias_correction: a.bias_correction,
    })
}

/// The errors of [`merge`].
fn check_mergeable(a: &PreintegratedImu, b: &PreintegratedImu) -> Result<(), MergeError> {
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
    if a.omega_coriolis != b.omega_coriolis
        || (a.omega_coriolis.is_some() && a.coriolis != b.coriolis)
    {
        return Err(MergeError::EarthRateMismatch);
    }
    if a.bias_correction != b.bias_correction {
        return Err(MergeError::BiasCorrectionMismatch {
            a: a.bias_correction,
            b: b.bias_correction,
        });
    }
    if a.level != b.level {
        return Err(MergeError::LevelMismatch {
            a: a.level,
            b: b.level,
        });
    }
    Ok(())
}

/// `A` and `B` of [`merge()`]: the composed error's derivatives with respect to a's and
/// b's errors.
fn transitions(a: &PreintegratedImu, b: &PreintegratedImu) -> (M9, M9) {
    let ra = *a.delta_r.matrix();
    let mut am = M9::identity();
    am.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&b.delta_r.matrix().transpose());
    am.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-ra * hat(&b.delta_v)));
    am.fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(-ra * hat(&b.delta_p)));
    am.fixed_view_mut::<3, 3>(6, 3)
        .copy_from(&(Matrix3::identity() * b.delta_t));
    let mut bm = M9::identity();
    bm.fixed_view_mut::<3, 3>(3, 3).copy_from(&ra);
    bm.fixed_view_mut::<3, 3>(6, 6).copy_from(&ra);
    (am, bm)
}

/// The merged 15×15 error-state covariance ([`merge()`]): `F_a Σ15_a F_aᵀ + G_b Σ15_b G_bᵀ`
/// plus the shared samples' terms for [`Level::Combined`]; `diag(Σ, Σ_bb,a + Σ_bb,b)` for
/// [`Level::Covariance`].
#[allow(clippy::too_many_arguments)]
fn combined_cov(
    a: &PreintegratedImu,
    b: &PreintegratedImu,
    am: &M9,
    bm: &M9,
    jb: &M96,
    shared: &M9,
    cov: &Cov9,
) -> Cov15 {
    match a.level {
        Level::Combined => {
            let mut fa = Cov15::identity();
            fa.fixed_view_mut::<9, 9>(0, 0).copy_from(am);
            fa.fixed_view_mut::<9, 6>(0, 9).copy_from(&(-bm * jb));
            let mut gb = Cov15::identity();
            gb.fixed_view_mut::<9, 9>(0, 0).copy_from(bm);
            let mut c = fa * a.cov15 * fa.transpose() + gb * b.cov15 * gb.transpose();
            let blk = c.fixed_view::<9, 9>(0, 0) + shared;
            c.fixed_view_mut::<9, 9>(0, 0).copy_from(&blk);
            c
        }
        Level::Covariance => {
            let mut c = Cov15::zeros();
            c.fixed_view_mut::<9, 9>(0, 0).copy_from(cov);
            let bb = a.cov15.fixed_view::<6, 6>(9, 9) + b.cov15.fixed_view::<6, 6>(9, 9);
            c.fixed_view_mut::<6, 6>(9, 9).copy_from(&bb);
            c
        }
        Level::Deltas => Cov15::zeros(),
    }
}

type M9 = SMatrix<f64, 9, 9>;

/// The covariance added by the samples `a` and `b` share ([`merge()`]) and the merged
/// window's edge sources.
fn shared_noise(a: &PreintegratedImu, b: &PreintegratedImu, am: &M9, bm: &M9) -> (M9, EdgeNoise) {
    let (ea, eb) = (&a.edge_noise, &b.edge_noise);
    let mut add = M9::zeros();
    if !ea.same_model(eb) {
        return (add, EdgeNoise::default());
    }
    let mut out = EdgeNoise::new(ea.gyro_cov, ea.acc_cov, ea.cell_rule);
    let in_a = |t: i64| ea.find(t).is_some();
    let times = ea.sources().iter().map(|s| s.t_ns);
    let times = times.chain(eb.sources().iter().map(|s| s.t_ns).filter(|&t| !in_a(t)));
    for t_ns in times {
        let (ra, rb) = (ea.find(t_ns), eb.find(t_ns));
        let ga = ra.map(|r| am * r.gain);
        let gb = rb.map(|r| bm * r.gain);
        // The sample's intervals as the merged window sees them.
        let left_s = match (ra, rb) {
            (Some(r), _) if r.left_s > 0.0 => r.left_s,
            (_, Some(r)) => r.left_s,
            (Some(r), None) => r.left_s,
            (None, None) => 0.0,
        };
        let right_s = match (ra, rb) {
            (_, Some(r)) if r.right_s > 0.0 => r.right_s,
            (Some(r), _) => r.right_s,
            (None, Some(r)) => r.right_s,
            (None, None) => 0.0,
        };
        if let (Some(ra), Some(rb), Some(ga), Some(gb)) = (ra, rb, ga, gb) {
            let q = ea.sample_cov(left_s, right_s);
            let dqa = q - ea.sample_cov(ra.left_s, ra.right_s);
            let dqb = q - eb.sample_cov(rb.left_s, rb.right_s);
            let x = ga * q * gb.transpose();
            add += x + x.transpose() + ga * dqa * ga.transpose() + gb * dqb * gb.transpose();
        }
        let start = ra.is_some_and(|r| r.start);
        let end = rb.is_some_and(|r| r.end);
        if start || end {
            let zero = SMatrix::<f64, 9, 6>::zeros();
            out.push(EdgeSource {
                t_ns,
                gain: ga.unwrap_or(zero) + gb.unwrap_or(zero),
                left_s,
                right_s,
                start,
                end,
            });
        }
    }
    (add, out)
}
