//! The cheapest scheme and lowest rate whose discretisation error stays below a
//! fraction of the noise-induced standard deviation of the preintegrated deltas.
//!
//! Method (everything estimated from the recording itself; the input class, smooth or held, is
//! declared by the user: [`crate::input_class`]):
//! 0. Smooth input: the white noise is separated from the motion (see [`crate::denoise`]):
//!    discretisation error is a property of the motion, and comparing noisy decimated samples
//!    would measure the noise (it enters a decimated-vs-full difference at ≈ σ√(d − 1)). Held
//!    input is not filtered (a low-pass would smear its steps), and its lower rates average the
//!    samples, which keeps the noise's first-order contribution out of the comparison.
//! 1. Windows of `--window` seconds are laid over the recording (at most 24, evenly spread).
//! 2. Reference: the input class's reference scheme at the recording's rate (hermite4 for
//!    smooth input, galilean, exact, for held input).
//! 3. For each scheme and each decimation d ∈ {1, 2, 4, …} (the stream at rate/d,
//!    [`InputClass::decimate`]) two errors per window, each as rotation angle \[rad\], |Δv|
//!    [m/s], |Δp| \[m\], the maximum over windows:
//!    - the **reference distance**, to the reference's deltas (not defined for the reference
//!      itself at d = 1);
//!    - the **embedded estimate** `ê`, from the candidate's own samples alone: for smooth
//!      input `preint::truncation::estimate` (a hermite4 companion on the samples upsampled,
//!      or Richardson for hermite4); for held input `D_scheme ⊖ D_galilean` on the same samples,
//!      exact since galilean is. With it, its χ² `êᵀΣ⁻¹ê` (Σ the candidate's 9×9 covariance,
//!      order [δφ, δv, δp]): the excess a factor at the true states would show on average.
//! 4. The noise σ is from the preintegrated covariance at that rate: `√trace` of the δφ, δv and
//!    δp blocks (the RMS norm of each error vector).
//! 5. The discretisation error `disc_err` is the larger of the two errors per component (the
//!    embedded estimate alone for the reference at d = 1), and a (scheme, rate) is acceptable
//!    when all three are below `fraction·σ`: both criteria must hold. The reference distance
//!    sees what decimation loses, which the decimated samples alone cannot; the embedded
//!    estimate sees the error the reference shares with a candidate (at d = 1 the distance
//!    of every scheme is only relative to a reference that may itself be too coarse). The
//!    cheapest acceptable one (ns/sample measured on this machine × rate) is recommended,
//!    where costs within 15 % of the cheapest count as equal and the simplest scheme among them
//!    wins.

//!
//! # Goodness of fit
//! [`fit`]: the embedded estimate's χ² `êᵀΣ⁻¹ê` (max over windows) of the recommended
//! candidate (of the reference when none is acceptable) against `χ²₉`: the discretisation
//! error alone would then make an `ImuFactor` at the true states fail a χ² test. Credible
//! when its upper-tail p-value is ≥ 1e-6 ([`preint_calib::fit`]); a χ² far below 9 is the
//! aim here, not a pessimistic noise model, and is not flagged.

use crate::Error;
use crate::input_class::InputClass;
use crate::speed::{best_ns_per_sample, synthetic_stream};
use nalgebra::SVector;
use preint::{
    ImuBias, ImuNoise, ImuSample, Level, PreintParams, PreintegratedImu, Scheme, preintegrate,
    truncation,
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
    /// Discretisation error used in the decision, max over windows: per component the larger
    /// of [`ref_dist`](Self::ref_dist) and [`embedded_err`](Self::embedded_err) (the latter
    /// alone for the reference itself): [rotation rad, velocity m/s, position m].
    pub disc_err: [f64; 3],
    /// Distance to the reference's deltas, max over windows: [rad, m/s, m]; `None` for the
    /// reference itself (the reference scheme at d = 1).
    pub ref_dist: Option<[f64; 3]>,
    /// Norms of the blocks of the embedded truncation-error estimate `ê`, max over windows:
    /// [rad, m/s, m].
    pub embedded_err: [f64; 3],
    /// `êᵀΣ⁻¹ê` (Σ the 9×9 covariance, order [δφ, δv, δp]), max over windows; infinite when Σ
    /// is singular.
    pub embedded_chi2: f64,
    /// Noise-induced σ (RMS norm) at that rate: [rad, m/s, m].
    pub noise_sigma: [f64; 3],
    /// Cost [ns per second of IMU data] on this machine.
    pub cost_ns_per_s: f64,
    /// All three errors below `fraction·σ`.
    pub acceptable: bool,
}

impl Candidate {
    /// Whether this is the reference itself (the reference scheme at the recording's rate).
    pub fn is_reference(&self) -> bool {
        self.ref_dist.is_none()
    }
}

fn errors(a: &PreintegratedImu, b: &PreintegratedImu) -> [f64; 3] {
    blocks(&a.delta_error(b))
}

/// Norms of the [δφ, δv, δp] blocks of a 9-vector.
fn blocks(e: &SVector<f64, 9>) -> [f64; 3] {
    [0, 1, 2].map(|k| e.fixed_rows::<3>(3 * k).norm())
}

/// `eᵀ cov⁻¹ e`, infinite when `cov` is not positive definite.
fn chi2(m: &PreintegratedImu, e: &SVector<f64, 9>) -> f64 {
    let cov: nalgebra::SMatrix<f64, 9, 9> = nalgebra::SMatrix::from_fn(|r, c| m.cov[(r, c)]);
    cov.cholesky()
        .map_or(f64::INFINITY, |ch| e.dot(&ch.solve(e)))
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
fn windows(samples: &[ImuSample], window_s: f64) -> Result<(Vec<i64>, i64), Error> {
    let n = samples.len();
    let span = samples[n - 1].t_ns - samples[0].t_ns;
    let w_ns = (window_s * 1e9).round() as i64;
    if w_ns <= 0 || w_ns > span {
        return Err(Error::Usage(format!(
            "--window {window_s} s must be positive and at most the recording's length ({:.3} s)",
            span as f64 * 1e-9
        )));
    }
    let margin = 64 * (span / (n as i64 - 1).max(1));
    let usable = span - w_ns - 2 * margin;
    if usable < 0 {
        return Err(Error::Usage(format!(
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

/// [`evaluate_input`] for smooth input (the default).
pub fn evaluate(
    samples: &[ImuSample],
    noise: &ImuNoise,
    gravity: f64,
    window_s: f64,
    fraction: f64,
) -> Result<Vec<Candidate>, Error> {
    evaluate_input(
        samples,
        noise,
        gravity,
        window_s,
        fraction,
        InputClass::Smooth,
    )
}

/// The maxima over windows of one (scheme, rate).
#[derive(Clone, Copy, Default)]
struct Maxima {
    dist: [f64; 3],
    est: [f64; 3],
    chi2: f64,
    sigma: [f64; 3],
}

impl Maxima {
    fn add(&mut self, dist: [f64; 3], est: &SVector<f64, 9>, chi2: f64, sigma: [f64; 3]) {
        let e = blocks(est);
        for k in 0..3 {
            self.dist[k] = self.dist[k].max(dist[k]);
            self.est[k] = self.est[k].max(e[k]);
            self.sigma[k] = self.sigma[k].max(sigma[k]);
        }
        self.chi2 = self.chi2.max(chi2);
    }
}

/// Evaluates every scheme at the recording's rate and at decimated rates for input of class
/// `input` (see the module docs): gravity `(0, 0, −gravity)` m/s², windows of `window_s` s,
/// acceptable below `fraction·σ`. `samples` are the (for smooth input, denoised) samples.
pub fn evaluate_input(
    samples: &[ImuSample],
    noise: &ImuNoise,
    gravity: f64,
    window_s: f64,
    fraction: f64,
    input: InputClass,
) -> Result<Vec<Candidate>, Error> {
    let fail = |e: preint::PreintError| Error::Failed(e.to_string());
    let (starts, w_ns) = windows(samples, window_s)?;
    let n = samples.len();
    let dt_s = (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (n - 1) as f64;
    let params = |s: Scheme, level: Level| {
        PreintParams::from_noise(noise)
            .with_scheme(s)
            .with_level(level)
            .with_gravity(nalgebra::Vector3::new(0.0, 0.0, -gravity))
    };
    let reference_scheme = input.reference();
    let (reference_params, bias) = (params(reference_scheme, Level::Deltas), ImuBias::zero());
    // Cost per sample does not depend on the rate: measured once per scheme (best of 11 runs,
    // the schemes taking turns, so that a busy machine rarely decides a tie).
    let ns = best_ns_per_sample(
        Scheme::ALL,
        Level::Covariance,
        &synthetic_stream(20_000),
        11,
    )?;
    let mut out = Vec::new();
    let mut d = 1;
    let pb = crate::progress::bar(starts.len() as u64, "advise");
    while decimation_in_range(dt_s, d, window_s) {
        if let Some(pb) = &pb {
            pb.set_position(0);
            pb.set_message(format!("{:.1} Hz", 1.0 / (dt_s * d as f64)));
        }
        let dec = input.decimate(samples, d);
        if gap_beyond_limit(samples, d).is_some() {
            // [`gap_beyond_limit`] names it; lower rates widen it further.
            break;
        }
        let mut max = [Maxima::default(); Scheme::ALL.len()];
        for &t0 in &starts {
            if let Some(pb) = &pb {
                pb.inc(1);
            }
            let (t_i, t_j) = keyframes(&dec, t0, w_ns);
            let reference =
                preintegrate(&reference_params, &bias, samples, t_i, t_j).map_err(fail)?;
            let ms = Scheme::ALL
                .iter()
                .map(|&s| preintegrate(&params(s, Level::Covariance), &bias, &dec, t_i, t_j))
                .collect::<Result<Vec<_>, _>>()
                .map_err(fail)?;
            // Held input: the scheme exact on it, on the candidate's own samples, is exact for
            // them.
            let held_exact = Scheme::ALL
                .iter()
                .position(|&s| Some(s) == InputClass::Held.exact_scheme())
                .map(|k| &ms[k]);
            for (ks, (&s, m)) in Scheme::ALL.iter().zip(&ms).enumerate() {
                let est = match (input, held_exact) {
                    (InputClass::Held, Some(g)) => m.delta_error(g),
                    _ => {
                        truncation::estimate(&params(s, Level::Covariance), &bias, &dec, m)
                            .map_err(fail)?
                            .error
                    }
                };
                max[ks].add(errors(m, &reference), &est, chi2(m, &est), sigma(m));
            }
        }
        let rate = 1.0 / (dt_s * d as f64);
        let is_ref = |s: Scheme| d == 1 && s == reference_scheme;
        out.extend(rate_candidates(&max, d, rate, &ns, fraction, is_ref));
        d *= 2;
    }
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(out)
}

/// The candidates of every scheme at decimation `d` (rate `rate` \[Hz\]) from their maxima
/// over the windows: the discretisation error is the larger of the distance to the reference
/// and the embedded estimate (the estimate alone for the reference itself, `is_ref`);
/// acceptable when each of its three parts is below `fraction` of the noise σ.
fn rate_candidates(
    max: &[Maxima],
    d: usize,
    rate: f64,
    ns_per_sample: &[f64],
    fraction: f64,
    is_ref: impl Fn(Scheme) -> bool,
) -> Vec<Candidate> {
    let row = |(ks, &s): (usize, &Scheme)| {
        let mx = max[ks];
        let disc_err = if is_ref(s) {
            mx.est
        } else {
            [0, 1, 2].map(|k| mx.dist[k].max(mx.est[k]))
        };
        Candidate {
            scheme: s,
            decimation: d,
            rate_hz: rate,
            disc_err,
            ref_dist: (!is_ref(s)).then_some(mx.dist),
            embedded_err: mx.est,
            embedded_chi2: mx.chi2,
            noise_sigma: mx.sigma,
            cost_ns_per_s: ns_per_sample[ks] * rate,
            acceptable: (0..3).all(|k| disc_err[k] < fraction * mx.sigma[k]),
        }
    };
    Scheme::ALL.iter().enumerate().map(row).collect()
}

/// Whether the decimation `d` of a stream sampled every `dt_s` s is one [`evaluate_input`]
/// tries: at least 8 samples per window of `window_s` s and at least 5 Hz.
pub fn decimation_in_range(dt_s: f64, d: usize, window_s: f64) -> bool {
    dt_s * d as f64 <= window_s / 8.0 && 1.0 / (dt_s * d as f64) >= 5.0
}

/// The longest interval the evaluation at decimation `d` preintegrates over, when it exceeds
/// preintegration's gap limit ([`preint::DEFAULT_MAX_GAP_NS`]): `(that interval [ns],
/// the recording's longest interval [ns], the index of the sample that ends it)`. The
/// embedded estimate of hermite4 (Richardson's, [`preint::truncation`]) integrates every
/// other sample of the candidate's stream, so the stream that counts is every `2d`-th sample.
/// The recording itself is within the limit (its gaps are refused when read), but decimation
/// widens an interval by up to `2d − 1` sample periods.
pub fn gap_beyond_limit(samples: &[ImuSample], d: usize) -> Option<(i64, i64, usize)> {
    let longest = |step: usize| {
        let t = samples.iter().step_by(step).map(|s| s.t_ns);
        t.clone()
            .zip(t.skip(1))
            .enumerate()
            .map(|(k, (a, b))| (b - a, step * (k + 1)))
            .max()
    };
    let (wide, _) = longest(2 * d)?;
    if wide <= preint::DEFAULT_MAX_GAP_NS {
        return None;
    }
    let (gap, at) = longest(1)?;
    Some((wide, gap, at))
}

/// The advice's fit (module docs): the embedded χ² of the recommended candidate, or of the
/// reference when none is acceptable, against `χ²₉`. `None` without a candidate.
pub fn fit(candidates: &[Candidate], recommended: Option<&Candidate>) -> Option<preint_calib::Fit> {
    let c = recommended.or_else(|| candidates.iter().find(|c| c.is_reference()))?;
    let mut f = preint_calib::Fit::new(c.embedded_chi2, 9);
    f.pessimistic = false;
    let what = format!(
        "{} at {:.1} Hz{}",
        c.scheme.name(),
        c.rate_hz,
        if recommended.is_some() {
            " (recommended)"
        } else {
            " (the reference; none is acceptable)"
        }
    );
    f.why = if f.credible {
        format!(
            "{what}: its truncation error adds χ² = {:.3e} (max over windows, 9 dof, p = {:.3}) to \
             a factor at the true states",
            c.embedded_chi2, f.p_value
        )
    } else {
        format!(
            "{what}: its truncation error alone adds χ² = {:.3e} (max over windows, 9 dof) to a \
             factor at the true states, which would then be inconsistent; likely cause: the \
             rate is too low for the motion: use hermite4 or record faster",
            c.embedded_chi2
        )
    };
    Some(f)
}

/// Costs within this factor of the cheapest count as equal: run-to-run timing on a shared
/// machine moves by tens of %, so a smaller measured difference says nothing.
pub const COST_TIE: f64 = 1.15;

/// The cheapest acceptable candidate, if any; among those within [`COST_TIE`] of the cheapest,
/// the simplest scheme (the registry's rank, [`preint::SchemeInfo::rank`]: euler, then
/// midpoint, then galilean, then hermite4), then the cheapest: model no more than the scene
/// needs, and do not let timing noise decide between near-equal costs. Galilean ranks after
/// midpoint: it is first order on smooth input and exact only when the input is held over each
/// interval, which the distance to the reference already measures.
pub fn recommend(c: &[Candidate]) -> Option<&Candidate> {
    let ok = || c.iter().filter(|c| c.acceptable);
    let best = ok().map(|c| c.cost_ns_per_s).min_by(f64::total_cmp)?;
    let rank = |s: Scheme| s.info().rank;
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
            ref_dist: Some([0.0; 3]),
            embedded_err: [0.0; 3],
            embedded_chi2: 0.0,
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
