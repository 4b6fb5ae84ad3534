//! Keyframe windows on a sample stream: boundary interpolation and splitting.
//!
//! A keyframe time `t` between samples `t_m < t < t_m+1` gets a boundary sample interpolated
//! from the stream, which ends one window and starts the next. Both windows use the *same*
//! boundary sample, so for Euler and midpoint the composition of consecutive windows
//! `[a, b]`, `[b, c]` (`ΔR_ac = ΔR_ab ΔR_bc`, `Δv_ac = Δv_ab + ΔR_ab Δv_bc`,
//! `Δp_ac = Δp_ab + Δv_ab Δt_bc + ΔR_ab Δp_bc`) equals, to round-off, the integration of
//! `[a, c]` over the stream with that boundary sample inserted, and durations add exactly
//! (integer ns). Interpolation:
//! - Euler and midpoint: linear between the two bracketing samples;
//! - rk4: cubic Lagrange through four surrounding stream samples (one-sided at the stream
//!   ends), so the window edge keeps 4th order; a stream sample closer to the boundary than
//!   1/8 of its interval is dropped from the window (its information is in the interpolated
//!   boundary sample) to keep the Lagrange stencils well conditioned. rk4 windows therefore
//!   compose only up to the scheme's O(h⁴) error.

use crate::error::PreintError;
use crate::measurement::PreintegratedImu;
use crate::params::{PreintParams, Scheme};
use crate::preintegrator::Preintegrator;
use crate::sample::{ImuBias, ImuSample};
use crate::scheme::span_s;
use nalgebra::Vector3;

/// Sample at `t_ns` on the straight line through `s0` and `s1` (`s0.t_ns < s1.t_ns`);
/// `λ = (t − t0)/(t1 − t0)` from integer-ns differences.
pub fn interpolate_linear(s0: &ImuSample, s1: &ImuSample, t_ns: i64) -> ImuSample {
    let lam = (t_ns as i128 - s0.t_ns as i128) as f64 / (s1.t_ns as i128 - s0.t_ns as i128) as f64;
    ImuSample {
        t_ns,
        gyro: s0.gyro + (s1.gyro - s0.gyro) * lam,
        acc: s0.acc + (s1.acc - s0.acc) * lam,
    }
}

/// Sample at `t_ns` on the Lagrange polynomial through `nodes` (1–4 samples with distinct
/// times; degree `nodes.len() − 1`). Times are taken relative to `nodes[0]` in seconds.
pub fn interpolate_lagrange(nodes: &[ImuSample], t_ns: i64) -> ImuSample {
    let x: Vec<f64> = nodes
        .iter()
        .map(|s| span_s(nodes[0].t_ns, s.t_ns))
        .collect();
    let tau = span_s(nodes[0].t_ns, t_ns);
    let (mut gyro, mut acc) = (Vector3::zeros(), Vector3::zeros());
    for (j, s) in nodes.iter().enumerate() {
        let mut l = 1.0;
        for (m, xm) in x.iter().enumerate() {
            if m != j {
                l *= (tau - xm) / (x[j] - xm);
            }
        }
        gyro += s.gyro * l;
        acc += s.acc * l;
    }
    ImuSample { t_ns, gyro, acc }
}

/// Checks `samples[range]` (indices are those of `samples`): finite values, strictly
/// increasing timestamps, gaps ≤ `max_gap_ns`.
pub fn check_samples(
    samples: &[ImuSample],
    range: std::ops::Range<usize>,
    max_gap_ns: i64,
) -> Result<(), PreintError> {
    for index in range {
        let s = &samples[index];
        for (v, field) in [(&s.gyro, "gyro"), (&s.acc, "acc")] {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(PreintError::NonFinite {
                    index,
                    t_ns: s.t_ns,
                    field,
                });
            }
        }
        if index > 0 {
            let prev = samples[index - 1].t_ns;
            if s.t_ns == prev {
                return Err(PreintError::DuplicateTimestamp {
                    index,
                    t_ns: s.t_ns,
                });
            }
            if s.t_ns < prev {
                return Err(PreintError::DecreasingTimestamp {
                    index,
                    t_ns: s.t_ns,
                    prev_t_ns: prev,
                });
            }
            let gap = s.t_ns as i128 - prev as i128;
            if gap > max_gap_ns as i128 {
                let gap_ns = i64::try_from(gap).unwrap_or(i64::MAX);
                return Err(PreintError::GapTooLarge {
                    index,
                    t_ns: s.t_ns,
                    gap_ns,
                    max_gap_ns,
                });
            }
        }
    }
    Ok(())
}

/// The samples of the keyframe window `[t_i_ns, t_j_ns]` taken from a time-ordered stream:
/// boundary samples at exactly `t_i` and `t_j` (stream samples if they fall there, else
/// interpolated as the module doc says for `scheme`) and the stream samples strictly between.
/// Validates the stream around the window (indices in errors refer to `samples`).
pub fn window_samples(
    scheme: Scheme,
    samples: &[ImuSample],
    t_i_ns: i64,
    t_j_ns: i64,
    max_gap_ns: i64,
) -> Result<Vec<ImuSample>, PreintError> {
    if t_j_ns <= t_i_ns {
        return Err(PreintError::NonPositiveWindow { t_i_ns, t_j_ns });
    }
    let (first_ns, last_ns) = match (samples.first(), samples.last()) {
        (Some(f), Some(l)) => (f.t_ns, l.t_ns),
        _ => (i64::MAX, i64::MIN),
    };
    for t_ns in [t_i_ns, t_j_ns] {
        if t_ns < first_ns || t_ns > last_ns {
            return Err(PreintError::KeyframeOutsideSamples {
                t_ns,
                first_ns,
                last_ns,
            });
        }
    }
    let n = samples.len();
    let lo = samples.partition_point(|s| s.t_ns < t_i_ns);
    let hi = samples.partition_point(|s| s.t_ns <= t_j_ns);
    check_samples(samples, lo.saturating_sub(2)..(hi + 2).min(n), max_gap_ns)?;
    if lo < n && samples[lo].t_ns < t_i_ns || hi == 0 {
        // Only reachable with an unsorted stream outside the checked range.
        return Err(PreintError::KeyframeOutsideSamples {
            t_ns: t_i_ns,
            first_ns,
            last_ns,
        });
    }
    // Boundary sample at t between samples m−1 and m (t_{m−1} < t < t_m).
    let boundary = |m: usize, t: i64| -> ImuSample {
        match scheme {
            Scheme::Euler | Scheme::Midpoint => interpolate_linear(&samples[m - 1], &samples[m], t),
            Scheme::Rk4 => {
                let len = n.min(4);
                let start = m.saturating_sub(2).min(n - len);
                interpolate_lagrange(&samples[start..start + len], t)
            }
        }
    };
    let mut out = Vec::with_capacity(hi - lo + 2);
    let mut inner_lo = lo;
    if samples[lo].t_ns == t_i_ns {
        out.push(samples[lo]);
        inner_lo += 1;
    } else {
        out.push(boundary(lo, t_i_ns));
    }
    let end_exact = samples[hi - 1].t_ns == t_j_ns;
    let mut inner_hi = if end_exact { hi - 1 } else { hi };
    if scheme == Scheme::Rk4 {
        let too_close =
            |a: i64, b: i64, step: i64| (a as i128 - b as i128).abs() * 8 < step as i128;
        if inner_lo < inner_hi
            && lo > 0
            && samples[lo].t_ns != t_i_ns
            && too_close(
                samples[inner_lo].t_ns,
                t_i_ns,
                samples[inner_lo].t_ns - samples[inner_lo - 1].t_ns,
            )
        {
            inner_lo += 1;
        }
        if inner_lo < inner_hi
            && !end_exact
            && too_close(
                samples[inner_hi - 1].t_ns,
                t_j_ns,
                samples[hi].t_ns - samples[hi - 1].t_ns,
            )
        {
            inner_hi -= 1;
        }
    }
    out.extend_from_slice(&samples[inner_lo..inner_hi]);
    if end_exact {
        out.push(samples[hi - 1]);
    } else {
        out.push(boundary(hi, t_j_ns));
    }
    Ok(out)
}

/// Preintegrates the keyframe window `[t_i_ns, t_j_ns]` of a time-ordered sample stream with
/// bias estimate `bias` (see [`window_samples`] for the boundary treatment). The result has
/// `t_i_ns`, `t_j_ns` and `delta_t = (t_j − t_i)·1e-9 s` exactly.
pub fn preintegrate(
    params: &PreintParams,
    bias: &ImuBias,
    samples: &[ImuSample],
    t_i_ns: i64,
    t_j_ns: i64,
) -> Result<PreintegratedImu, PreintError> {
    let w = window_samples(params.scheme, samples, t_i_ns, t_j_ns, params.max_gap_ns)?;
    let mut pi = Preintegrator::with_capacity(params.clone(), *bias, w.len())?;
    pi.integrate_slice(&w)?;
    pi.finish()
}
