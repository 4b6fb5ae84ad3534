//! Sample validation, shared by the preintegrator and the window path: finite readings,
//! strictly increasing timestamps, and gaps no larger than allowed.

use crate::error::PreintError;
use crate::sample::ImuSample;

/// The common case of a valid sample, in one test: `x·0 = 0` for finite x and NaN otherwise
/// (a sum that overflows only sends the sample to the exact checks); a later timestamp than
/// `last_t_ns`, and the gap as the exact u64 difference of two i64 that are in order.
#[inline(always)]
pub(crate) fn common_case(s: &ImuSample, last_t_ns: i64, gap_limit: u64) -> bool {
    let (g, a) = (&s.gyro, &s.acc);
    let finite = ((g.x + a.x) + (g.y + a.y) + (g.z + a.z)) * 0.0 == 0.0;
    let gap = (s.t_ns as u64).wrapping_sub(last_t_ns as u64);
    finite && s.t_ns > last_t_ns && gap <= gap_limit
}

/// Checks sample `s`, number `index` of its sequence, after a sample at `prev_t_ns` (`None`
/// for the first): finite readings, a strictly later timestamp, and (with `max_gap_ns`) a gap
/// no larger than that. The error names the index and timestamp.
pub(crate) fn check_sample(
    s: &ImuSample,
    index: usize,
    prev_t_ns: Option<i64>,
    max_gap_ns: Option<i64>,
) -> Result<(), PreintError> {
    for (v, field) in [(&s.gyro, "gyro"), (&s.acc, "acc")] {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(PreintError::NonFinite {
                index,
                t_ns: s.t_ns,
                field,
            });
        }
    }
    let Some(prev) = prev_t_ns else {
        return Ok(());
    };
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
    // i128: a gap that overflows i64 is reported as i64::MAX.
    let gap = s.t_ns as i128 - prev as i128;
    match max_gap_ns {
        Some(max_gap_ns) if gap > max_gap_ns as i128 => Err(PreintError::GapTooLarge {
            index,
            t_ns: s.t_ns,
            gap_ns: i64::try_from(gap).unwrap_or(i64::MAX),
            max_gap_ns,
        }),
        _ => Ok(()),
    }
}
