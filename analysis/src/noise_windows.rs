//! The windows of the noise fit ([`preint_calib::noise_fit`]): one `ImuFactor` between two
//! ground-truth states, its residual `r` and the basis `A_k` of its covariance,
//! `Σ(θ) = Σ_k θ_k A_k` with `θ = [N_g², N_a², K_g², K_a², σ_R², σ_p², σ_v², σ_bg², σ_ba²]`.
//!
//! - `A_{N_g}`, `A_{N_a}`: the preintegration covariance `cov` computed with a unit white-noise
//!   density on that sensor alone (every other density zero). The discrete noise of a step `h`
//!   is `σ² I / h` and the propagation `Σ ← A Σ Aᵀ + B (σ²/h) Bᵀ` is linear in it, so
//!   `cov(θ) = N_g² A_{N_g} + N_a² A_{N_a}` exactly (the test checks it).
//! - `A_{K_g}`, `A_{K_a}`: the top-left 9×9 block ([δφ, δv, δp]) of the combined covariance
//!   `cov15` ([`preint::Level::Combined`]) computed with a unit bias random walk on that sensor
//!   alone and no white noise: the factor holds the bias at its value at i while the true bias
//!   drifts, and the combined propagation carries that drift into the deltas. The test checks
//!   it against a Monte Carlo of drifting biases.
//! - `A_{σ_R}`, `A_{σ_p}`, `A_{σ_v}`, `A_{σ_bg}`, `A_{σ_ba}`:
//!   [`truth_covariance`] with that σ at 1 and the others 0.
//!
//! The residual is the component-wise `[r_φ, r_v, r_p]` at the ground truth, the preintegration
//! at the ground truth's bias at i (as `factor` evaluates it); [`gravity_jacobian`] is its
//! exact derivative with respect to the world gravity vector.

use crate::consistency::{ResidualJacobians, TruthNoise, truth_covariance};
use nalgebra::{Matrix3, SMatrix};
use preint::{
    ImuBias, ImuFactor, ImuSample, Level, NavState, PreintError, PreintParams, ResidualMode,
    preintegrate,
};
use preint_calib::noise_fit::{NoiseWindow, PARAMS};
use preint_io::GroundTruthState;

/// Which noise source a unit basis is computed for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Gyroscope white noise.
    GyroWhite,
    /// Accelerometer white noise.
    AccWhite,
    /// Gyroscope bias random walk.
    GyroWalk,
    /// Accelerometer bias random walk.
    AccWalk,
}

/// `params` with a unit density on `source` alone (all other densities zero), at the level
/// that computes its effect.
fn unit_params(params: &PreintParams, source: Source) -> PreintParams {
    let mut p = params.clone();
    let z = Matrix3::zeros();
    (p.gyro_cov, p.acc_cov, p.gyro_bias_rw_cov, p.acc_bias_rw_cov) = (z, z, z, z);
    p.integration_cov = None;
    let i = Matrix3::identity();
    match source {
        Source::GyroWhite => p.gyro_cov = i,
        Source::AccWhite => p.acc_cov = i,
        Source::GyroWalk => p.gyro_bias_rw_cov = i,
        Source::AccWalk => p.acc_bias_rw_cov = i,
    }
    p.level = match source {
        Source::GyroWhite | Source::AccWhite => Level::Covariance,
        Source::GyroWalk | Source::AccWalk => Level::Combined,
    };
    p
}

/// The 9×9 covariance of `[δφ, δv, δp]` over `[t_i, t_j]` at a unit density of `source`
/// (module docs).
pub fn unit_basis(
    params: &PreintParams,
    source: Source,
    bias: &ImuBias,
    samples: &[ImuSample],
    (t_i, t_j): (i64, i64),
) -> Result<SMatrix<f64, 9, 9>, PreintError> {
    let pim = preintegrate(&unit_params(params, source), bias, samples, t_i, t_j)?;
    Ok(match source {
        Source::GyroWhite | Source::AccWhite => pim.cov,
        Source::GyroWalk | Source::AccWalk => pim.cov15.fixed_view::<9, 9>(0, 0).into_owned(),
    })
}

/// Why a window cannot join the fit.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// The preintegration failed.
    #[error("{0}")]
    Preint(#[from] PreintError),
    /// The factor could not be built.
    #[error("{0}")]
    Factor(#[from] preint::FactorError),
}

fn nav(s: &GroundTruthState) -> NavState {
    NavState::new(s.rotation(), s.p, s.v)
}

/// Where a window sits and how its residual moves with the ground-truth states at its ends:
/// what [`crate::calibrate::noise_correlation`] needs to tell errors correlated in time.
#[derive(Clone, Copy, Debug)]
pub struct Endpoints {
    /// The ground-truth rows at i and j \[ns\].
    pub t_ns: (i64, i64),
    /// `∂r/∂x_i`, `∂r/∂x_j` in the `NavState` tangent [δφ, δp, δv].
    pub state: (SMatrix<f64, 9, 9>, SMatrix<f64, 9, 9>),
}

/// The window `[gi, gj]` of `samples` ([`NoiseWindow`], module docs); `params` (at
/// [`Level::Covariance`] or above, with non-zero white noise) builds the factor whose residual
/// and Jacobians are taken.
pub fn noise_window(
    params: &PreintParams,
    samples: &[ImuSample],
    ends: (&GroundTruthState, &GroundTruthState),
    length_s: f64,
) -> Result<NoiseWindow, WindowError> {
    noise_window_at(params, samples, ends, length_s).map(|(w, _)| w)
}

/// [`noise_window`] and the window's [`Endpoints`].
pub fn noise_window_at(
    params: &PreintParams,
    samples: &[ImuSample],
    (gi, gj): (&GroundTruthState, &GroundTruthState),
    length_s: f64,
) -> Result<(NoiseWindow, Endpoints), WindowError> {
    let span = (gi.t_ns, gj.t_ns);
    let mut p = params.clone();
    p.level = Level::Covariance;
    let pim = preintegrate(&p, &gi.bias, samples, span.0, span.1)?;
    let f = ImuFactor::with_mode(pim, ResidualMode::ComponentWise)?;
    let (r, j) = f.evaluate(&nav(gi), &nav(gj), &gi.bias);
    let jac = ResidualJacobians {
        state_i: j.state_i(),
        state_j: j.state_j(),
        bias_i: j.bias_i(),
    };
    let unit = |k: usize| {
        let mut s = [0.0; 5];
        s[k] = 1.0;
        truth_covariance(
            &jac,
            TruthNoise {
                rot_rad: s[0],
                pos_m: s[1],
                vel_m_s: s[2],
                bias_gyro_rad_s: s[3],
                bias_acc_m_s2: s[4],
            },
        )
    };
    let sources = [
        Source::GyroWhite,
        Source::AccWhite,
        Source::GyroWalk,
        Source::AccWalk,
    ];
    let mut basis = [SMatrix::<f64, 9, 9>::zeros(); PARAMS];
    for (k, s) in sources.iter().enumerate() {
        basis[k] = unit_basis(params, *s, &gi.bias, samples, span)?;
    }
    for k in 0..5 {
        basis[4 + k] = unit(k);
    }
    let window = NoiseWindow {
        length_s,
        r,
        basis,
        gravity_jacobian: gravity_jacobian(gi, (span.1 - span.0) as f64 * 1e-9),
        block: 0,
    };
    let ends = Endpoints {
        t_ns: span,
        state: (jac.state_i, jac.state_j),
    };
    Ok((window, ends))
}

/// Sets each window's [`NoiseWindow::block`]: the stretch `[t₀ + kB, t₀ + (k+1)B)` its start
/// row falls in, `B = block_ns` (the longest window length: back-to-back windows of lengths
/// dividing it then share data only within a block; `t₀` the start of the span cut).
pub fn assign_blocks(windows: &mut [NoiseWindow], ends: &[Endpoints], t0_ns: i64, block_ns: i64) {
    for (w, e) in windows.iter_mut().zip(ends) {
        w.block = ((e.t_ns.0 - t0_ns).max(0) / block_ns.max(1)) as usize;
    }
}

/// `∂r/∂g` of the component-wise residual at the state `gi` over `dt_s` \[s\]: zero in
/// rotation, `−R_iᵀ Δt` in velocity and `−½ R_iᵀ Δt²` in position (the residual's
/// `R_iᵀ(v_j − v_i − g Δt)` and `R_iᵀ(p_j − p_i − v_i Δt − ½ g Δt²)`).
pub fn gravity_jacobian(gi: &GroundTruthState, dt_s: f64) -> SMatrix<f64, 9, 3> {
    let rt = gi.rotation().matrix().transpose();
    let mut g = SMatrix::<f64, 9, 3>::zeros();
    g.fixed_view_mut::<3, 3>(3, 0).copy_from(&(rt * -dt_s));
    g.fixed_view_mut::<3, 3>(6, 0)
        .copy_from(&(rt * (-0.5 * dt_s * dt_s)));
    g
}

#[cfg(test)]
#[path = "noise_windows_tests.rs"]
mod tests;
