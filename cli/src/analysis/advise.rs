//! The cheapest scheme and lowest rate whose discretisation error stays below a
//! fraction of the noise-induced standard deviation of the preintegrated deltas.
//!
//! Method (everything estimated from the recording itself):
//! 0. The white noise is separated from the motion (see [`super::denoise`]): discretisation
//!    error is a property of the motion, and comparing noisy decimated samples would measure the
//!    noise (it enters a decimated-vs-full difference at ≈ σ√(d − 1)).
//! 1. Windows of `--window` seconds are laid over the recording (at most 24, evenly spread).
//! 2. Reference: the 4th-order scheme (hermite4) at the recording's rate. The reference's own
//!    error is estimated by Richardson extrapolation, `|Δ₄(h) − Δ₄(2h)| / (2⁴ − 1)`.
//! 3. For each scheme and each decimation d ∈ {1, 2, 4, …} (every d-th sample, i.e. what an IMU
//!    sampling the same signal at rate/d would deliver, without its internal filtering) the
//!    discretisation error is the distance to the reference: rotation angle \[rad\], |Δv| [m/s],
//!    |Δp| \[m\], the maximum over windows.
//! 4. The noise σ is from the preintegrated covariance at that rate: `√trace` of the δφ, δv and
//!    δp blocks (the RMS norm of each error vector).
//! 5. A (scheme, rate) is acceptable when all three errors are below `fraction·σ`; the cheapest
//!    acceptable one (ns/sample measured on this machine × rate) is recommended, where costs
//!    within 15 % of the cheapest count as equal and the simplest scheme among them wins.

use super::speed::{best_ns_per_sample, synthetic_stream};
use crate::{CliError, scheme};
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, PreintParams, PreintegratedImu, Scheme, preintegrate,
};

/// One (scheme, rate) evaluation.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Integration scheme.
    pub scheme: Scheme,
    /// Decimation factor (1 = the recording's rate).
    pub decimation: usize,
    /// Sample rate \[Hz\].
    pub rate_hz: f64,
    /// Discretisation error, max over windows: [rotation rad, velocity m/s, position m].
    pub disc_err: [f64; 3],
    /// Noise-induced σ (RMS norm) at that rate: [rad, m/s, m].
    pub noise_sigma: [f64; 3],
    /// Cost [ns per second of IMU data] on this machine.
    pub cost_ns_per_s: f64,
    /// All three errors below `fraction·σ`.
    pub acceptable: bool,
}

fn errors(a: &PreintegratedImu, b: &PreintegratedImu) -> [f64; 3] {
    [
        a.delta_r.minus(&b.delta_r).norm(),
        (a.delta_v - b.delta_v).norm(),
        (a.delta_p - b.delta_p).norm(),
    ]
}

fn sigma(m: &PreintegratedImu) -> [f64; 3] {
    let tr = |k: usize| {
        (0..3)
            .map(|i| m.cov[(3 * k + i, 3 * k + i)])
            .sum::<f64>()
            .sqrt()
    };
    [tr(0), tr(1), tr(2)]
}

/// Window starts \[ns\] and the window length \[ns\]: evenly spread over the recording, at
/// most 24, leaving 64 sample periods on each side for hermite4's neighbours.
fn windows(samples: &[ImuSample], window_s: f64) -> Result<(Vec<i64>, i64), CliError> {
    let n = samples.len();
    let span = samples[n - 1].t_ns - samples[0].t_ns;
    let w_ns = (window_s * 1e9).round() as i64;
    if w_ns <= 0 || w_ns > span {
        return Err(CliError::Usage(format!(
            "--window {window_s} s must be positive and at most the recording's length ({:.3} s)",
            span as f64 * 1e-9
        )));
    }
    let margin = 64 * (span / (n as i64 - 1).max(1));
    let usable = span - w_ns - 2 * margin;
    if usable < 0 {
        return Err(CliError::Usage(format!(
            "recording of {:.3} s ({n} samples) too short for a {window_s} s window: advise needs \
             the window plus 64 samples on each side ({:.3} s in all); give a shorter --window",
            span as f64 * 1e-9,
            (w_ns + 2 * margin) as f64 * 1e-9
        )));
    }
    let nw = (usable / w_ns + 1).clamp(1, 24);
    let starts = (0..nw)
        .map(|k| samples[0].t_ns + margin + if nw > 1 { usable * k / (nw - 1) } else { 0 })
        .collect();
    Ok((starts, w_ns))
}

/// The keyframes of the window starting at `t0`, on the grid of `dec` (so no boundary
/// interpolation enters): the first sample at or after `t0`, and the first at or after
/// `t_i + w_ns` (or the last).
fn keyframes(dec: &[ImuSample], t0: i64, w_ns: i64) -> (i64, i64) {
    let t_i = dec[dec.partition_point(|s| s.t_ns < t0)].t_ns;
    let j0 = dec
        .partition_point(|s| s.t_ns < t_i + w_ns)
        .min(dec.len() - 1);
    (t_i, dec[j0].t_ns)
}

/// Evaluates every scheme at the recording's rate and at decimated rates (see the module docs):
/// gravity `(0, 0, −gravity)` m/s², windows of `window_s` s, acceptable below `fraction·σ`.
pub fn evaluate(
    samples: &[ImuSample],
    noise: &ImuNoise,
    gravity: f64,
    window_s: f64,
    fraction: f64,
) -> Result<Vec<Candidate>, CliError> {
    let fail = |e: preint::PreintError| CliError::Failed(e.to_string());
    let (starts, w_ns) = windows(samples, window_s)?;
    let n = samples.len();
    let dt_s = (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (n - 1) as f64;
    let params = |s: Scheme, level: Level| {
        PreintParams::from_noise(noise)
            .with_scheme(s)
            .with_level(level)
            .with_gravity(nalgebra::Vector3::new(0.0, 0.0, -gravity))
    };
    let (reference_params, bias) = (params(Scheme::Hermite4, Level::Deltas), ImuBias::zero());
    // Cost per sample does not depend on the rate: measured once per scheme (best of 11 runs,
    // the schemes taking turns, so that a busy machine rarely decides a tie).
    let ns = best_ns_per_sample(
        &scheme::ALL,
        Level::Covariance,
        &synthetic_stream(20_000),
        11,
    )?;
    // Every other sample, for the Richardson estimate of the reference's own error.
    let half: Vec<ImuSample> = samples.iter().step_by(2).copied().collect();
    let mut out = Vec::new();
    let mut d = 1;
    let pb = crate::progress::bar(starts.len() as u64, "advise");
    while dt_s * d as f64 <= window_s / 8.0 && 1.0 / (dt_s * d as f64) >= 5.0 {
        if let Some(pb) = &pb {
            pb.set_position(0);
            pb.set_message(format!("{:.1} Hz", 1.0 / (dt_s * d as f64)));
        }
        let dec: Vec<ImuSample> = samples.iter().step_by(d).copied().collect();
        // Per scheme, the maxima over the windows.
        let (mut err, mut sig) = (
            [[0.0f64; 3]; scheme::ALL.len()],
            [[0.0f64; 3]; scheme::ALL.len()],
        );
        for &t0 in &starts {
            if let Some(pb) = &pb {
                pb.inc(1);
            }
            let (t_i, t_j) = keyframes(&dec, t0, w_ns);
            let reference =
                preintegrate(&reference_params, &bias, samples, t_i, t_j).map_err(fail)?;
            for (ks, scheme) in scheme::ALL.into_iter().enumerate() {
                let m = preintegrate(&params(scheme, Level::Covariance), &bias, &dec, t_i, t_j)
                    .map_err(fail)?;
                let mut e = errors(&m, &reference);
                if d == 1 && scheme == Scheme::Hermite4 {
                    // The reference itself: |Δ₄(h) − Δ₄(2h)| / (2⁴ − 1).
                    if let Ok(c) = preintegrate(&reference_params, &bias, &half, t_i, t_j) {
                        e = errors(&c, &reference).map(|x| x / 15.0);
                    }
                }
                let s = sigma(&m);
                for k in 0..3 {
                    err[ks][k] = err[ks][k].max(e[k]);
                    sig[ks][k] = sig[ks][k].max(s[k]);
                }
            }
        }
        let rate = 1.0 / (dt_s * d as f64);
        for (ks, scheme) in scheme::ALL.into_iter().enumerate() {
            out.push(Candidate {
                scheme,
                decimation: d,
                rate_hz: rate,
                disc_err: err[ks],
                noise_sigma: sig[ks],
                cost_ns_per_s: ns[ks] * rate,
                acceptable: (0..3).all(|k| err[ks][k] < fraction * sig[ks][k]),
            });
        }
        d *= 2;
    }
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(out)
}

/// Costs within this factor of the cheapest count as equal: run-to-run timing on a shared
/// machine moves by tens of %, so a smaller measured difference says nothing.
pub const COST_TIE: f64 = 1.15;

/// The cheapest acceptable candidate, if any; among those within [`COST_TIE`] of the cheapest,
/// the simplest scheme (euler, then midpoint, then galilean, then hermite4), then the cheapest:
/// model no more than the scene needs, and do not let timing noise decide between near-equal
/// costs. Galilean ranks after midpoint: it is first order on smooth input and exact only when
/// the input is held over each interval, which the distance to the reference already measures.
pub fn recommend(c: &[Candidate]) -> Option<&Candidate> {
    let ok = || c.iter().filter(|c| c.acceptable);
    let best = ok().map(|c| c.cost_ns_per_s).min_by(f64::total_cmp)?;
    let rank = |s: Scheme| match s {
        Scheme::Euler => 0,
        Scheme::Midpoint => 1,
        Scheme::Galilean => 2,
        Scheme::Hermite4 => 3,
    };
    ok().filter(|c| c.cost_ns_per_s <= COST_TIE * best)
        .min_by(|a, b| {
            rank(a.scheme)
                .cmp(&rank(b.scheme))
                .then(a.cost_ns_per_s.total_cmp(&b.cost_ns_per_s))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(scheme: Scheme, rate_hz: f64, cost: f64, acceptable: bool) -> Candidate {
        Candidate {
            scheme,
            decimation: 1,
            rate_hz,
            disc_err: [0.0; 3],
            noise_sigma: [1.0; 3],
            cost_ns_per_s: cost,
            acceptable,
        }
    }

    /// Near-equal costs (within 15 %) go to the simpler scheme; a clearly cheaper scheme wins;
    /// unacceptable candidates never do.
    #[test]
    fn recommend_breaks_near_ties_towards_the_simpler_scheme() {
        // A static recording at 12.5 Hz: midpoint measured 3 % cheaper than euler (timing noise).
        let c = [
            cand(Scheme::Euler, 12.5, 3356.0, true),
            cand(Scheme::Midpoint, 12.5, 3260.0, true),
            cand(Scheme::Hermite4, 12.5, 13895.0, true),
            cand(Scheme::Galilean, 12.5, 3300.0, true),
        ];
        assert_eq!(recommend(&c).unwrap().scheme, Scheme::Euler);
        // Galilean within 15 % of midpoint: midpoint is the simpler model; 30 % cheaper, it wins.
        let c = [
            cand(Scheme::Galilean, 50.0, 30_000.0, true),
            cand(Scheme::Midpoint, 50.0, 29_000.0, true),
        ];
        assert_eq!(recommend(&c).unwrap().scheme, Scheme::Midpoint);
        let c = [
            cand(Scheme::Galilean, 50.0, 20_000.0, true),
            cand(Scheme::Midpoint, 100.0, 29_000.0, true),
            cand(Scheme::Hermite4, 25.0, 21_000.0, true),
        ];
        assert_eq!(recommend(&c).unwrap().scheme, Scheme::Galilean);
        // Midpoint 30 % cheaper: it wins.
        let c = [
            cand(Scheme::Euler, 400.0, 50_000.0, true),
            cand(Scheme::Midpoint, 50.0, 35_000.0, true),
        ];
        assert_eq!(recommend(&c).unwrap().scheme, Scheme::Midpoint);
        // The cheapest is not acceptable: the cheapest acceptable one is chosen.
        let c = [
            cand(Scheme::Euler, 25.0, 1_000.0, false),
            cand(Scheme::Hermite4, 25.0, 20_000.0, true),
            cand(Scheme::Midpoint, 200.0, 40_000.0, true),
        ];
        assert_eq!(recommend(&c).unwrap().scheme, Scheme::Hermite4);
        assert!(recommend(&[cand(Scheme::Euler, 25.0, 1.0, false)]).is_none());
    }
}
