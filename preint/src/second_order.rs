//! The second-order covariance of a window's SE₂(3) error: what the first-order covariance
//! misses over long windows with noisy gyroscopes, computed on request from the window's
//! samples.
//!
//! # The error and its propagation
//!
//! Write the deltas as the SE₂(3) element `Υ = (ΔR, Δv, Δp)` (product
//! `(R₁, v₁, p₁)(R₂, v₂, p₂) = (R₁R₂, v₁ + R₁v₂, p₁ + R₁p₂)`). Over an interval of length `h`
//! every scheme composes `Υ_{k+1} = Φ_h(Υ_k) U_k`, where `Φ_h(R, v, p) = (R, v, p + v h)` is a
//! group automorphism and `U_k` the interval's increment from the samples. The error of the
//! measured deltas `Υ̂` against the true ones `Υ`, `η = Υ̂⁻¹ Υ`, then obeys
//!
//! ```text
//! η_{k+1} = [Û_k⁻¹ Φ_h(η_k) Û_k] [Û_k⁻¹ U_k],        ξ = Log η  (order [φ, v, p])
//! ξ_{k+1} = BCH(A_k ξ_k, w_k),    A_k = Ad(Û_k⁻¹) dΦ_h,    w_k = Log(Û_k⁻¹ U_k)
//! ```
//!
//! exactly: the first factor is an automorphism of `η_k`, so its logarithm is linear in `ξ_k`
//! (the log-linear property of group-affine systems, Barrau & Bonnabel 2017, Theorem 2; the
//! IMU case is Brossard et al. 2022, "Associating Uncertainty to Extended Poses for on Lie
//! Group IMU Preintegration With Rotating Earth"). At the true states `ξ` is the factor's Logmap
//! residual ([`ResidualMode`](crate::ResidualMode)). The first-order covariance `P_{k+1} = A P Aᵀ + Q`
//! (`Q = E[w wᵀ] = diag(Σ_g h, Σ_a h, 0)`, `Σ` the continuous-time densities) is, mapped into
//! this chart, the covariance every scheme propagates. The Baker–Campbell–Hausdorff series
//! `BCH(y, w) = y + w + ½[y, w] + …` has a second-order term that it drops: zero-mean (`w_k` is
//! independent of `y = A ξ_k`) but with covariance
//!
//! ```text
//! ¼ E[ad(y) Q ad(y)ᵀ] = ¼ C(A P Aᵀ),   C(P)_ij = K_g(P_ij)  (i, j ∈ {φ, v, p}),   C(P)_vv += K_a(P_φφ)
//! K(X) = E[[n]× X [n]×ᵀ] = Σ_c [l_c]× X [l_c]×ᵀ    (n ~ N(0, Σ h), Σ h = L Lᵀ, l_c its columns)
//! ```
//!
//! from `[y, w] = −B(w) y`, `B = [[W_g, 0, 0], [W_a, W_g, 0], [0, 0, W_g]]`, `W = [w]×`
//! (`K(X) = q (tr X I − Xᵀ)` for an isotropic `Σ h = q I`). It is of order `σ_g² · P`: the
//! rotation noise of each interval rotates the velocity and position errors accumulated so far,
//! which over a long window are large (metres per second after 10 s at 0.015 rad/s/√Hz on an
//! aggressive trajectory) while the residual's thinnest directions are not. Summed over the
//! window it does not shrink with the sample period. [`covariance`] propagates
//! `P₂ = A P₂ Aᵀ + Q + ¼ C(A P₂ Aᵀ)` beside `P₁ = A P₁ Aᵀ + Q` and returns `P₂ − P₁`, mapped to
//! the measurement's chart [δφ, δv, δp] by `T⁻¹ (·) T⁻ᵀ`, `T = diag(I, ΔRᵀ, ΔRᵀ)` (the map of
//! [`ResidualMode`](crate::ResidualMode)).
//!
//! # Scope
//!
//! - The increments `Û_k` are the held-input ones to first order in `h` (`Exp(ω h)`, `a h`,
//!   `½ a h²`, bias-corrected by the measurement's `bias_hat`): they enter only the second-order
//!   term, so their own error is of higher order.
//! - With `body_p_sensor` the samples and densities are rotated into the body frame; the
//!   lever arm is left out of this second-order term.
//! - The bias random walk's own second-order terms are left out (at EuRoC's random walk they are
//!   below 1e-3 of the white-noise ones over 10 s).
//!
//! # Effect (`docs/EVIDENCE.md`, "The Logmap residual and the second-order covariance")
//!
//! At the true states over 10 s windows (hermite4, 200 Hz, 8 000 realisations), with the
//! noisy-MEMS densities σ_g = 0.015 rad/s/√Hz, σ_a = 0.019 m/s²/√Hz the Logmap residual's mean
//! χ² is 9.23 / 9.56 (9 dof) on `aggressive` / `seed-ellipse` (the simulator's scenes: MAV-like
//! motion of sinusoids up to 3.1 Hz, and a slow horizontal ellipse with a 1 m vertical
//! oscillation ten times faster);
//! weighted with [`inflate`] and this term it is
//! 9.04 / 9.01, inside the 95 % band of 9 (15 dof: 15.17 / 15.47 → 14.99 / 15.00), and at
//! σ_g = 0.05, σ_a = 0.1 it is 8.97 / 8.96 instead of 10.47 / 11.75. At EuRoC densities the
//! term changes nothing. Cost: one pass over the window's samples with two 9×9 propagations
//! (about 1.2 µs per sample), on request.
//!
//! # Use
//!
//! [`covariance`]`(params, samples, &m)` propagates both covariances over the window's samples
//! and returns their difference in the measurement's chart; [`inflate`] adds it. The command
//! line asks for it with `integrate --second-order` and `factor --second-order`, the Python
//! package with `second_order_covariance` and `add_covariance`. `integrate --second-order`
//! prints the mean χ² the term accounts for, `tr(Σ⁻¹ S)`: 0.19 on 10 s of `aggressive` at the
//! noisy-MEMS densities above, 2e-6 at EuRoC's. The component-wise residual cannot be repaired
//! this way: its error is not log-linear.

use crate::error::PreintError;
use crate::measurement::PreintegratedImu;
use crate::params::PreintParams;
use crate::sample::ImuSample;
use crate::scheme::Scheme;
use crate::window::window_samples;
use nalgebra::{Matrix3, SMatrix, Vector3};
use preint_lie::{SO3, hat};

type M9 = SMatrix<f64, 9, 9>;

/// The second-order covariance term of the window `m` (module docs), in the measurement's chart
/// [δφ (rad), δv (m/s), δp (m)]: add it to `m.cov` ([`inflate`]) to weight a factor with the
/// second-order covariance. `samples` is the stream `m` was preintegrated from, with `params`;
/// the window's samples are cut from it with linear boundary samples.
///
/// Errors: those of [`window_samples`] (non-finite or unordered samples, gaps, keyframes
/// outside the samples).
pub fn covariance(
    params: &PreintParams,
    samples: &[ImuSample],
    m: &PreintegratedImu,
) -> Result<M9, PreintError> {
    let nodes = window_samples(
        Scheme::Euler,
        samples,
        m.t_i_ns,
        m.t_j_ns,
        params.max_gap_ns,
    )?;
    let r_bs = params
        .body_p_sensor
        .map_or_else(Matrix3::identity, |x| *x.rotation.matrix());
    let to_body = |c: &Matrix3<f64>| r_bs * c * r_bs.transpose();
    let (sg, sa) = (to_body(&params.gyro_cov), to_body(&params.acc_cov));
    let (lg1, la1) = (sqrt_psd(&sg), sqrt_psd(&sa));
    let b = &m.bias_hat;
    let (mut p1, mut p2) = (M9::zeros(), M9::zeros());
    // The samples as the preintegrator sees them: corrected by the intrinsics.
    let corr = params
        .intrinsics
        .filter(|x| !x.model.is_identity())
        .map(|x| x.model.correction());
    let corrected = |s: &ImuSample| corr.map_or(*s, |c| c.apply(s));
    for pair in nodes.windows(2) {
        let pair = [corrected(&pair[0]), corrected(&pair[1])];
        let h = (pair[1].t_ns - pair[0].t_ns) as f64 * 1e-9;
        let (w, a) = (r_bs * (pair[0].gyro - b.gyro), r_bs * (pair[0].acc - b.acc));
        let step = transition(&w, &a, h);
        let (lg, la) = (lg1 * h.sqrt(), la1 * h.sqrt());
        let y1 = step * p1 * step.transpose();
        let y2 = step * p2 * step.transpose();
        p1 = add_white(y1, &sg, &sa, h);
        p2 = add_white(y2, &sg, &sa, h) + bracket_covariance(&y2, &lg, &la) * 0.25;
    }
    let t = crate::factor::logmap::chart_map9(m);
    let s = t.transpose() * (p2 - p1) * t;
    // Symmetric by construction; the difference of two propagations is not, to round-off.
    Ok((s + s.transpose()) * 0.5)
}

/// `m` with `term` added to its 9×9 covariance and to the 9×9 block of its 15×15 one.
pub fn inflate(m: &PreintegratedImu, term: &M9) -> PreintegratedImu {
    let mut out = m.clone();
    out.cov += term;
    out.cov15
        .fixed_view_mut::<9, 9>(0, 0)
        .zip_apply(term, |x, y| *x += y);
    out
}

/// `A = Ad(Û⁻¹) dΦ_h` for the held increment `Û = (Exp(ω h), a h, ½ a h²)`; tangent [φ, v, p].
fn transition(w: &Vector3<f64>, a: &Vector3<f64>, h: f64) -> M9 {
    let rt = SO3::exp(&(w * h)).matrix().transpose();
    // Û⁻¹ = (Rᵀ, −Rᵀ v, −Rᵀ p); Ad(R, v, p) = [[R, 0, 0], [v^R, R, 0], [p^R, 0, R]].
    let (vi, pi) = (-rt * (a * h), -rt * (a * (0.5 * h * h)));
    let mut ad = M9::zeros();
    for k in 0..3 {
        ad.fixed_view_mut::<3, 3>(3 * k, 3 * k).copy_from(&rt);
    }
    ad.fixed_view_mut::<3, 3>(3, 0).copy_from(&(hat(&vi) * rt));
    ad.fixed_view_mut::<3, 3>(6, 0).copy_from(&(hat(&pi) * rt));
    // dΦ_h: p += v h.
    let mut dphi = M9::identity();
    dphi.fixed_view_mut::<3, 3>(6, 3)
        .copy_from(&(Matrix3::identity() * h));
    ad * dphi
}

/// `P + diag(Σ_g h, Σ_a h, 0)`.
fn add_white(mut p: M9, sg: &Matrix3<f64>, sa: &Matrix3<f64>, h: f64) -> M9 {
    p.fixed_view_mut::<3, 3>(0, 0)
        .zip_apply(&(sg * h), |x, y| *x += y);
    p.fixed_view_mut::<3, 3>(3, 3)
        .zip_apply(&(sa * h), |x, y| *x += y);
    p
}

/// `C(P) = E[B(w) P B(w)ᵀ]` (module docs) for `w_g`, `w_a` of covariances `L_g L_gᵀ`, `L_a L_aᵀ`.
fn bracket_covariance(p: &M9, lg: &Matrix3<f64>, la: &Matrix3<f64>) -> M9 {
    let mut c = M9::zeros();
    for i in 0..3 {
        for j in 0..3 {
            let x: Matrix3<f64> = p.fixed_view::<3, 3>(3 * i, 3 * j).into();
            c.fixed_view_mut::<3, 3>(3 * i, 3 * j)
                .copy_from(&skew_sandwich(&x, lg));
        }
    }
    let pff: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into();
    c.fixed_view_mut::<3, 3>(3, 3)
        .zip_apply(&skew_sandwich(&pff, la), |x, y| *x += y);
    c
}

/// `K(X) = E[[n]× X [n]×ᵀ] = Σ_c [l_c]× X [l_c]×ᵀ` for `n ~ N(0, L Lᵀ)`.
pub(crate) fn skew_sandwich(x: &Matrix3<f64>, l: &Matrix3<f64>) -> Matrix3<f64> {
    (0..3)
        .map(|c| {
            let s = hat(&l.column(c).into_owned());
            s * x * s.transpose()
        })
        .fold(Matrix3::zeros(), |acc, m| acc + m)
}

/// A square root `L` with `L Lᵀ = S` of a symmetric positive semi-definite 3×3 `S`
/// (eigen-decomposition, negative round-off eigenvalues clamped to 0).
fn sqrt_psd(s: &Matrix3<f64>) -> Matrix3<f64> {
    let e = s.symmetric_eigen();
    let d = Matrix3::from_diagonal(&e.eigenvalues.map(|x| x.max(0.0).sqrt()));
    e.eigenvectors * d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skew_sandwich_equals_the_isotropic_closed_form() {
        let x = Matrix3::new(2.0, 0.3, -0.1, 0.7, 1.5, 0.2, -0.4, 0.6, 3.0);
        let q: f64 = 0.37;
        let l = Matrix3::identity() * q.sqrt();
        let closed = (Matrix3::identity() * x.trace() - x.transpose()) * q;
        assert!((skew_sandwich(&x, &l) - closed).norm() < 1e-14);
    }

    #[test]
    fn skew_sandwich_is_the_expectation_over_a_gaussian() {
        // E[[n]× X [n]×ᵀ] by exact quadrature of a Gaussian: n = L z over the 2-point rule
        // z_c = ±1 per axis (exact for the second moments this expectation needs).
        let x = Matrix3::new(1.0, 0.2, 0.0, -0.3, 2.0, 0.5, 0.1, 0.4, 0.7);
        let l = Matrix3::new(0.5, 0.0, 0.0, 0.2, 0.3, 0.0, -0.1, 0.05, 0.4);
        let mut mean = Matrix3::zeros();
        for bits in 0..8 {
            let z = Vector3::from_fn(|c, _| if bits >> c & 1 == 1 { 1.0 } else { -1.0 });
            let s = hat(&(l * z));
            mean += s * x * s.transpose() / 8.0;
        }
        assert!((skew_sandwich(&x, &l) - mean).norm() < 1e-14);
    }

    #[test]
    fn square_root_reproduces_the_matrix() {
        let s = Matrix3::new(2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5);
        let l = sqrt_psd(&s);
        assert!((l * l.transpose() - s).norm() < 1e-14);
    }
}
