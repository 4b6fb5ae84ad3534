//! Back-to-back windows over the span where a recording and its ground truth overlap, as
//! `preint factor --window` and `preint calibrate --estimate noise` cut them.
//!
//! The span is where the recording and the ground truth overlap; windows of length `L` start
//! at its beginning and follow each other without overlap (`⌊span/L⌋` of them). Each window's
//! keyframes are the ground-truth rows nearest to its edges ([`nearest_row`]). A window is
//! skipped (and counted) when it cannot be evaluated: no ground-truth row within `L/2` of an
//! edge, two edges on the same row, fewer than 2 samples, a gap (consecutive samples more than
//! [`GAP_FACTOR`] median sample intervals apart) or when the caller's evaluation fails.

use crate::checks::UnitCheck;
use crate::stream::{self, EDGE_SAMPLES, StreamWindow};
use crate::{Error, ImuInput};
use preint::{ImuNoise, ImuSample, PreintParams};
use preint_io::{GroundTruthState, SourceInfo};

/// Consecutive samples further apart than this many median sample intervals are a gap.
pub const GAP_FACTOR: f64 = 5.0;
/// Most windows of one length.
pub const MAX_WINDOWS: i64 = 1_000_000;

/// The ground-truth row nearest to `t_ns` (rows sorted by time, at least one).
pub fn nearest_row(gt: &[GroundTruthState], t_ns: i64) -> &GroundTruthState {
    let k = gt.partition_point(|s| s.t_ns < t_ns);
    let candidates = [k.saturating_sub(1), k.min(gt.len() - 1)];
    let best = candidates
        .into_iter()
        .min_by_key(|&c| (gt[c].t_ns - t_ns).unsigned_abs())
        .unwrap();
    &gt[best]
}

/// The window lengths \[s\] (`--window`): at least one, each finite and positive.
pub fn check_lengths(lengths: &[f64]) -> Result<(), Error> {
    if lengths.is_empty() {
        return Err(Error::Usage(
            "--window needs at least one length (s), e.g. --window 0.5,1,2".into(),
        ));
    }
    for &l in lengths {
        if !(l.is_finite() && l > 0.0) {
            return Err(Error::Usage(format!(
                "--window: every length must be a positive number of seconds, got {l}"
            )));
        }
    }
    Ok(())
}

fn median_step(t: impl Iterator<Item = i64>) -> Option<f64> {
    let t: Vec<i64> = t.collect();
    let mut d: Vec<i64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_unstable();
    d.get(d.len() / 2).map(|&x| x as f64)
}

/// The samples a window `[t_i, t_j]` needs, with [`EDGE_SAMPLES`] on each side; `None` for a
/// gap or fewer than 2 samples inside.
fn window_samples(samples: &[ImuSample], (t_i, t_j): (i64, i64), dt: f64) -> Option<&[ImuSample]> {
    let a = samples.partition_point(|s| s.t_ns < t_i);
    let b = samples.partition_point(|s| s.t_ns <= t_j);
    if b < a + 2 {
        return None;
    }
    let (lo, hi) = (
        a.saturating_sub(EDGE_SAMPLES),
        (b + EDGE_SAMPLES).min(samples.len()),
    );
    let inner = &samples[a.saturating_sub(1)..(b + 1).min(samples.len())];
    let gap = inner
        .windows(2)
        .any(|w| (w[1].t_ns - w[0].t_ns) as f64 > GAP_FACTOR * dt);
    (!gap).then_some(&samples[lo..hi])
}

/// The back-to-back windows of one length over `span` (module docs): `f` of each window's
/// samples and keyframes, or `None` (counted as skipped) when it cannot be evaluated.
/// `dt` is the median sample interval \[ns\], `length_ns` the window length \[ns\].
pub fn for_each_window<T>(
    (samples, gt): (&[ImuSample], &[GroundTruthState]),
    (span, dt): ((i64, i64), f64),
    length_ns: i64,
    mut f: impl FnMut(&[ImuSample], (&GroundTruthState, &GroundTruthState)) -> Option<T>,
) -> (Vec<T>, usize) {
    let n = (span.1 - span.0) / length_ns;
    let (mut out, mut skipped) = (Vec::new(), 0);
    for k in 0..n {
        let (a, b) = (span.0 + k * length_ns, span.0 + (k + 1) * length_ns);
        let (gi, gj) = (nearest_row(gt, a), nearest_row(gt, b));
        let far = |g: &GroundTruthState, t: i64| 2 * (g.t_ns - t).abs() > length_ns;
        let evaluated = (gj.t_ns > gi.t_ns && !far(gi, a) && !far(gj, b))
            .then(|| window_samples(samples, (gi.t_ns, gj.t_ns), dt))
            .flatten()
            .and_then(|w| f(w, (gi, gj)));
        match evaluated {
            Some(x) => out.push(x),
            None => skipped += 1,
        }
    }
    (out, skipped)
}

/// The span where `samples` and `gt` overlap \[ns\], and the median sample interval \[ns\];
/// `imu` and `poses` name the files and `what` the mode (e.g. `--window`) in the errors.
pub fn overlap(
    samples: &[ImuSample],
    gt: &[GroundTruthState],
    (imu, poses): (&str, &std::path::Path),
    what: &str,
) -> Result<((i64, i64), f64), Error> {
    let (Some(s0), Some(s1), Some(g0), Some(g1)) =
        (samples.first(), samples.last(), gt.first(), gt.last())
    else {
        return Err(Error::Usage(format!(
            "{imu} or {} is empty: {what} needs samples and ground truth",
            poses.display()
        )));
    };
    let span = (s0.t_ns.max(g0.t_ns), s1.t_ns.min(g1.t_ns));
    if span.1 <= span.0 {
        return Err(Error::Usage(format!(
            "{imu} ({} to {} ns) and {} ({} to {} ns) do not overlap: {what} needs the ground \
             truth of the recording",
            s0.t_ns,
            s1.t_ns,
            poses.display(),
            g0.t_ns,
            g1.t_ns
        )));
    }
    let dt = median_step(samples.iter().map(|s| s.t_ns)).unwrap_or(f64::INFINITY);
    Ok((span, dt))
}

/// The number of nanoseconds of a window length `l` \[s\], refused when `span` would hold more
/// than [`MAX_WINDOWS`] of them.
pub fn length_ns(l: f64, span: (i64, i64)) -> Result<i64, Error> {
    let length_ns = (l * 1e9).round() as i64;
    if length_ns <= 0 || (span.1 - span.0) / length_ns.max(1) > MAX_WINDOWS {
        return Err(Error::Usage(format!(
            "--window {l}: more than {MAX_WINDOWS} windows of {l} s in the {:.3} s span; \
             give a longer length",
            (span.1 - span.0) as f64 * 1e-9
        )));
    }
    Ok(length_ns)
}

/// The window `[t_i, t_j]` of the recording, how it was read and its unit checks. Only the
/// part the window needs is read; a split recording is merged whole, and the effective
/// accelerometer density of its merged samples is set in `params`.
/// `None` for `t_i` and `t_j`: the whole recording.
pub fn read_window(
    input: &ImuInput,
    noise: &ImuNoise,
    params: &mut PreintParams,
    (t_i, t_j): (Option<i64>, Option<i64>),
) -> Result<(StreamWindow, SourceInfo, UnitCheck), Error> {
    if input.is_split() {
        let (w, source, split, units) = stream::split_window(input, t_i, t_j)?;
        crate::noise::apply_split(noise, split.as_ref(), params);
        return Ok((w, source, units));
    }
    let stream = stream::open_checked_until(input, t_j)?;
    let (source, units) = (stream.info().clone(), stream.unit_check().clone());
    let _bar = crate::progress::ReadingBar::start(stream.progress(), "factor");
    let w = stream::cut_window(stream, t_i, t_j)?;
    Ok((w, source, units))
}
