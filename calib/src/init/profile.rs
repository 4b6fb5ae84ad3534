//! The scale by its profile likelihood.
//!
//! The keyframe positions are noisy in the poses' unit, so their noise in metres is `s·σ_p`:
//! the residual covariance depends on the scale, `Σ(s) = Σ_IMU + s² Σ_poses`. A solve with the
//! scale as an ordinary unknown and `Σ` held at its linearisation point minimises
//! `r(s)ᵀΣ(s₀)⁻¹r(s)`, whose noise term grows with `s²`: it pulls the scale towards zero (the
//! attenuation of a regression on a noisy regressor), by several per cent on EuRoC at 10 Hz
//! keyframes. The maximum-likelihood scale minimises the profile
//!
//! ```text
//! χ²(s) = min over (b, v, g) of  r(s)ᵀ Σ(s)⁻¹ r(s)  (+ the bias prior)
//! ```
//!
//! each evaluation a known-pose solve at the fixed scale `s` with its own `Σ(s)`. The minimum
//! is found by parabolic steps through three points (`s(1 ± h)`), and its curvature gives
//! `σ_s = √(2 / χ²″)` (the interval where χ² rises by 1). The other unknowns' covariance is
//! the conditional one at `ŝ` plus the scale's, carried by their sensitivity to it:
//! `Σ = Σ|ŝ + (∂x/∂s) σ_s² (∂x/∂s)ᵀ`, exact for a linear-Gaussian problem.

use crate::bias::{BiasError, KnownPose, KnownPoseCalibration, KnownPoseOptions};
use nalgebra::DVector;
use preint::ImuSample;

/// The profile's minimum: the conditional solve there, its neighbours at `s(1 ± h)` and the
/// scale's σ.
pub(crate) struct Profile {
    pub(crate) scale: f64,
    pub(crate) scale_std: f64,
    pub(crate) at: KnownPoseCalibration,
    /// `∂x/∂s` for `x = [g, b_g, b_a, v_0, …]`.
    pub(crate) sensitivity: DVector<f64>,
}

/// The profile `χ²(s)` of `opts` (its scale held, not estimated).
struct Chi2<'a> {
    samples: &'a [ImuSample],
    poses: &'a [KnownPose],
    opts: KnownPoseOptions,
    evaluations: usize,
}

impl Chi2<'_> {
    fn at(&mut self, s: f64) -> Result<KnownPoseCalibration, BiasError> {
        self.evaluations += 1;
        let opts = KnownPoseOptions {
            initial_scale: s,
            estimate_scale: false,
            ..self.opts.clone()
        };
        crate::bias::calibrate_known_poses(self.samples, self.poses, &opts)
    }
}

/// The state a profile point reached, `[g, b_g, b_a, v_0, …]`.
fn state(c: &KnownPoseCalibration) -> DVector<f64> {
    let mut x: Vec<f64> = c.gravity.iter().copied().collect();
    x.extend(c.bias.gyro.iter().chain(c.bias.acc.iter()));
    x.extend(c.velocities.iter().flat_map(|v| v.iter().copied()));
    DVector::from_vec(x)
}

/// The profile's minimum from `s0` with a first step `h0` (relative), module docs. `opts`
/// holds the start of the other unknowns.
pub(crate) fn minimise(
    samples: &[ImuSample],
    poses: &[KnownPose],
    opts: KnownPoseOptions,
    (s0, h0): (f64, f64),
) -> Result<Profile, BiasError> {
    let mut f = Chi2 {
        samples,
        poses,
        opts,
        evaluations: 0,
    };
    let mut s = s0;
    let mut h = h0.clamp(1e-3, 0.2);
    for _ in 0..12 {
        let (lo, mid, hi) = (f.at(s * (1.0 - h))?, f.at(s)?, f.at(s * (1.0 + h))?);
        let (a, b, c) = (lo.chi2, mid.chi2, hi.chi2);
        let curvature = (a + c - 2.0 * b) / (s * h).powi(2);
        let slope = (c - a) / (2.0 * s * h);
        if curvature.is_nan() || curvature <= 0.0 {
            // Not convex at this step: move downhill by the step, or stop where flat.
            if c < b || a < b {
                s *= if c < a { 1.0 + h } else { 1.0 - h };
                h = (2.0 * h).min(0.5);
                continue;
            }
            return Ok(finish(s, f64::INFINITY, mid, (&lo, &hi), s * h));
        }
        let step = (-slope / curvature).clamp(-0.5 * s, s);
        let sigma = (2.0 / curvature).sqrt();
        warm(&mut f.opts, &mid);
        if step.abs() <= 1e-4 * s || step.abs() <= 0.01 * sigma {
            return Ok(finish(s, sigma, mid, (&lo, &hi), s * h));
        }
        s += step;
        // The next three points straddle the minimum by about its σ.
        h = (sigma / s).clamp(1e-3, 0.2);
    }
    let mid = f.at(s)?;
    let (lo, hi) = (f.at(s * (1.0 - h))?, f.at(s * (1.0 + h))?);
    let curvature = (lo.chi2 + hi.chi2 - 2.0 * mid.chi2) / (s * h).powi(2);
    let sigma = if curvature > 0.0 {
        (2.0 / curvature).sqrt()
    } else {
        f64::INFINITY
    };
    Ok(finish(s, sigma, mid, (&lo, &hi), s * h))
}

/// The next solves start where the last one ended.
fn warm(opts: &mut KnownPoseOptions, c: &KnownPoseCalibration) {
    opts.initial_bias = c.bias;
    opts.params.gravity = c.gravity;
}

fn finish(
    scale: f64,
    scale_std: f64,
    at: KnownPoseCalibration,
    (lo, hi): (&KnownPoseCalibration, &KnownPoseCalibration),
    ds: f64,
) -> Profile {
    let sensitivity = (state(hi) - state(lo)) / (2.0 * ds);
    Profile {
        scale,
        scale_std,
        at,
        sensitivity,
    }
}
