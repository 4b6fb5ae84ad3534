//! Data preparation: the still intervals and their means, the link windows between them, the
//! initial state and the reference time of the biases.
//!
//! For still interval k (averaging time `T_k = N_k·Δt`) the means `ω̄_k`, `f̄_k` are kept with
//! their white-noise standard deviations `σ_g/√T_k`, `σ_a/√T_k`; between consecutive intervals
//! the gyro samples from the last sample of interval k to the first of interval k+1 (the link
//! window) are kept for re-integration, with the rotation block `Σ_φ,k` of `preint`'s covariance
//! of that window ([`preint::preintegrate`], midpoint scheme, at the initial gyro bias).
//!
//! Initial state: `b_g` = the sample-weighted mean of the interval gyro means, `b_a = 0`, no
//! scale or misalignment; the first attitude from its specific force at zero yaw (the tilt of
//! [`roll_pitch_of_up`](crate::bias::roll_pitch_of_up)), the next ones chained by the link
//! rotations `ΔR_k(b_g)`.

use super::super::BiasError;
use super::super::stats::{SegmentStats, mean_period};
use super::super::still::{StillInterval, StillOptions, detect_still_intervals};
use super::super::tilt::attitude_from_up;
use super::MultiPoseOptions;
use super::link_rotation::rotation_preintegration;
use super::random_walk;
use super::residuals::Whitening;
use nalgebra::{Matrix3, Vector3};
use preint::sqrt_information;
use preint::{ImuBias, ImuNoise, ImuSample, PreintParams, Scheme, preintegrate};
use preint_lie::SO3;

/// The means of one still interval and their white-noise standard deviations.
pub(super) struct Interval {
    /// Mean gyro reading `ω̄` \[rad/s\].
    pub(super) w_mean: Vector3<f64>,
    /// Mean specific force `f̄` \[m/s²\].
    pub(super) f_mean: Vector3<f64>,
    /// `σ_g/√T` \[rad/s\].
    pub(super) s_w: f64,
    /// `σ_a/√T` \[m/s²\].
    pub(super) s_f: f64,
}

/// A link window between two consecutive still intervals.
pub(super) struct Link {
    /// Its samples, from the last of the earlier interval to the first of the later one.
    pub(super) samples: Vec<ImuSample>,
    /// White-noise covariance Σ_φ of the link rotation \[rad²\].
    pub(super) cov: Matrix3<f64>,
    /// `U` with `UᵀU = Σ_φ⁻¹`.
    pub(super) sqrt_info: Matrix3<f64>,
}

/// What the residuals are built from.
pub(super) struct Observations {
    /// The still intervals (sample ranges).
    pub(super) ivs: Vec<StillInterval>,
    /// Their means.
    pub(super) intervals: Vec<Interval>,
    /// The windows between consecutive intervals.
    pub(super) links: Vec<Link>,
    /// Initial gyro bias \[rad/s\], at which the links' covariances and drift coefficients are
    /// evaluated.
    pub(super) bg0: Vector3<f64>,
    /// Reference time `t_ref` \[ns\] of the biases.
    pub(super) t_ref_ns: i64,
}

/// The observations, the initial attitudes and the whitening of the stacked residual.
pub(super) struct Prepared {
    pub(super) obs: Observations,
    /// Initial attitude of each still interval.
    pub(super) r0: Vec<SO3>,
    /// World up unit vector `−g/|g|`.
    pub(super) up_w: Vector3<f64>,
    pub(super) whitening: Whitening,
    /// Whether the bias random walk is marginalised (`Whitening::Full`).
    pub(super) marginalised: bool,
}

/// Builds everything the candidate models share (module docs); `gnorm = |g|`.
pub(super) fn prepare(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &MultiPoseOptions,
    gnorm: f64,
) -> Result<Prepared, BiasError> {
    let ivs = still_intervals(samples, noise, opts)?;
    let intervals = interval_means(samples, noise, &ivs);
    let bg0 = initial_gyro_bias(&ivs, &intervals);
    let links = links(samples, noise, &ivs, &bg0)?;
    let up_w = -opts.gravity / gnorm;
    let r0 = initial_attitudes(&intervals, &links, &bg0, &up_w);
    let t_ref_ns = reference_time(samples, &ivs, opts.reference_time_ns)?;
    let obs = Observations {
        ivs,
        intervals,
        links,
        bg0,
        t_ref_ns,
    };
    let marginalised =
        opts.include_random_walk && (noise.gyro_random_walk > 0.0 || noise.acc_random_walk > 0.0);
    let whitening = if marginalised {
        Whitening::Full(random_walk::whitening_matrix(samples, noise, &obs)?)
    } else {
        Whitening::Block
    };
    Ok(Prepared {
        obs,
        r0,
        up_w,
        whitening,
        marginalised,
    })
}

/// The still intervals ([`detect_still_intervals`], by default with thresholds from the noise
/// at the measured rate); at least `max(min_intervals, 2)`.
fn still_intervals(
    samples: &[ImuSample],
    noise: &ImuNoise,
    opts: &MultiPoseOptions,
) -> Result<Vec<StillInterval>, BiasError> {
    let still_opts = opts
        .still
        .unwrap_or_else(|| StillOptions::from_noise(noise, 1.0 / mean_period(samples)));
    let ivs = detect_still_intervals(samples, &still_opts)?;
    let needed = opts.min_intervals.max(2);
    if ivs.len() < needed {
        return Err(BiasError::TooFew {
            what: "still intervals",
            found: ivs.len(),
            needed,
        });
    }
    Ok(ivs)
}

/// Means of each interval and their white-noise standard deviations `σ/√T`.
fn interval_means(samples: &[ImuSample], noise: &ImuNoise, ivs: &[StillInterval]) -> Vec<Interval> {
    ivs.iter()
        .map(|iv| {
            let st = SegmentStats::of(&samples[iv.start..iv.end]);
            let t = st.averaging_time();
            Interval {
                w_mean: st.gyro_mean,
                f_mean: st.acc_mean,
                s_w: noise.gyro_noise_density / t.sqrt(),
                s_f: noise.acc_noise_density / t.sqrt(),
            }
        })
        .collect()
}

/// The sample-weighted mean of the intervals' gyro means \[rad/s\].
fn initial_gyro_bias(ivs: &[StillInterval], intervals: &[Interval]) -> Vector3<f64> {
    let tw: f64 = ivs.iter().map(|iv| iv.len() as f64).sum();
    ivs.iter()
        .zip(intervals)
        .map(|(iv, d)| d.w_mean * iv.len() as f64)
        .sum::<Vector3<f64>>()
        / tw
}

/// The link windows between consecutive intervals, with the white-noise covariance of their
/// rotation (midpoint preintegration at `bg0`, no gap limit) and its square-root information.
fn links(
    samples: &[ImuSample],
    noise: &ImuNoise,
    ivs: &[StillInterval],
    bg0: &Vector3<f64>,
) -> Result<Vec<Link>, BiasError> {
    let mut params = PreintParams::from_noise(noise).with_scheme(Scheme::Midpoint);
    params.max_gap_ns = i64::MAX;
    let bias0 = ImuBias::new(*bg0, Vector3::zeros());
    let mut links = Vec::with_capacity(ivs.len() - 1);
    for w in ivs.windows(2) {
        let seg = &samples[w[0].end - 1..=w[1].start];
        let pim = preintegrate(&params, &bias0, seg, seg[0].t_ns, seg[seg.len() - 1].t_ns)?;
        let cov: Matrix3<f64> = pim.cov.fixed_view::<3, 3>(0, 0).into_owned();
        let sqrt_info = sqrt_information(&cov).map_err(|e| BiasError::InvalidParameter {
            name: "noise",
            reason: format!("rotation covariance of a link window: {e}"),
        })?;
        links.push(Link {
            samples: seg.to_vec(),
            cov,
            sqrt_info,
        });
    }
    Ok(links)
}

/// The first attitude from its specific force at zero yaw, the next ones chained by the link
/// rotations `ΔR_k(b_g0)`.
fn initial_attitudes(
    intervals: &[Interval],
    links: &[Link],
    bg0: &Vector3<f64>,
    up_w: &Vector3<f64>,
) -> Vec<SO3> {
    let mut r0 = Vec::with_capacity(intervals.len());
    r0.push(attitude_from_up(&intervals[0].f_mean, up_w));
    for (l, link) in links.iter().enumerate() {
        let (dr, _, _) = rotation_preintegration(&link.samples, bg0, &Vector3::zeros());
        let next = r0[l].compose(&dr);
        r0.push(next);
    }
    r0
}

/// The reference time of the biases: `given` (which must lie within the recording) or the
/// sample time nearest the middle of the span from the first interval's start to the last one's
/// end.
fn reference_time(
    samples: &[ImuSample],
    ivs: &[StillInterval],
    given: Option<i64>,
) -> Result<i64, BiasError> {
    let n = samples.len();
    let (first, last) = (samples[0].t_ns, samples[n - 1].t_ns);
    if let Some(t) = given {
        if !(first..=last).contains(&t) {
            return Err(BiasError::InvalidParameter {
                name: "reference_time_ns",
                reason: format!("{t} ns is outside the recording [{first}, {last}] ns"),
            });
        }
        return Ok(t);
    }
    let (a, b) = (ivs[0].t_start_ns, ivs[ivs.len() - 1].t_end_ns);
    let mid = a + (b - a) / 2;
    let k = samples.partition_point(|s| s.t_ns < mid).min(n - 1);
    let k = if k > 0 && mid - samples[k - 1].t_ns <= samples[k].t_ns - mid {
        k - 1
    } else {
        k
    };
    Ok(samples[k].t_ns)
}
