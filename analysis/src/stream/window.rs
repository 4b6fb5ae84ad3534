//! The keyframe window cut from a stream: the samples `[t_i, t_j]` needs, reading stopped
//! after them, and errors counted in the whole stream.

use super::{EDGE_SAMPLES, MAX_WINDOW_SAMPLES};
use crate::Error;
use crate::checks::UnitCheck;
use crate::recording::ImuInput;
use preint::{ImuSample, PreintError};
use preint_io::SourceInfo;
use std::collections::VecDeque;

/// The part of a stream that the keyframe window `[t_i, t_j]` needs: the samples from
/// [`EDGE_SAMPLES`] before `t_i` to [`EDGE_SAMPLES`] − 1 after `t_j` (reading stops there).
#[derive(Debug)]
pub struct StreamWindow {
    /// The samples, in order.
    pub samples: Vec<ImuSample>,
    /// Index in the stream of `samples[0]`.
    pub offset: usize,
    /// Time of the stream's first sample \[ns\].
    pub first_ns: i64,
    /// Time of the stream's last sample \[ns\], when the stream was read to its end (the
    /// window reaches past it, or lies before the first sample).
    pub last_ns: Option<i64>,
    /// `t_i` \[ns\]: `--from`, or the first sample's time.
    pub t_i_ns: i64,
    /// `t_j` \[ns\]: `--to`, or the last sample's time.
    pub t_j_ns: i64,
}

/// Cuts the window `[from, to]` (defaults: the first and the last sample) from `stream`.
/// Memory holds the window only; without `to`, reading goes to the end.
pub fn cut_window(
    stream: impl Iterator<Item = Result<ImuSample, Error>>,
    from: Option<i64>,
    to: Option<i64>,
) -> Result<StreamWindow, Error> {
    cut_window_with_edge(stream, from, to, EDGE_SAMPLES)
}

/// [`cut_window`] keeping `edge` (≥ [`EDGE_SAMPLES`]) samples before `from` and `edge` − 1
/// after `to`. A window that ends before the stream's first sample is refused by the
/// preintegrator: the rest of the stream is then read (not kept) for its last time, which
/// the error names.
pub fn cut_window_with_edge(
    mut stream: impl Iterator<Item = Result<ImuSample, Error>>,
    from: Option<i64>,
    to: Option<i64>,
    edge: usize,
) -> Result<StreamWindow, Error> {
    let mut before: VecDeque<ImuSample> = VecDeque::with_capacity(edge + 1);
    let mut inside: Vec<ImuSample> = Vec::new();
    let (mut first_ns, mut dropped, mut after) = (None, 0usize, 0usize);
    for s in stream.by_ref() {
        let s = s?;
        let t_i = *first_ns.get_or_insert(s.t_ns);
        let t_i = from.unwrap_or(t_i);
        if s.t_ns < t_i {
            before.push_back(s);
            if before.len() > edge {
                before.pop_front();
                dropped += 1;
            }
            continue;
        }
        if to.is_some_and(|t_j| s.t_ns > t_j) {
            after += 1;
        }
        if inside.len() == MAX_WINDOW_SAMPLES {
            return Err(Error::Failed(format!(
                "the window holds more than {MAX_WINDOW_SAMPLES} samples; choose a shorter \
                 --from/--to"
            )));
        }
        inside.push(s);
        if after == edge - 1 {
            break;
        }
    }
    let first_ns = first_ns.unwrap_or(0);
    let mut samples: Vec<ImuSample> = before.into_iter().collect();
    samples.append(&mut inside);
    let mut last_ns = samples.last().map_or(first_ns, |s| s.t_ns);
    let ended = after < edge - 1;
    let before_first = [from, to].into_iter().flatten().any(|t| t < first_ns);
    if !ended && before_first {
        for s in stream.by_ref() {
            last_ns = s?.t_ns;
        }
    }
    Ok(StreamWindow {
        offset: dropped,
        first_ns,
        last_ns: (ended || before_first).then_some(last_ns),
        t_i_ns: from.unwrap_or(first_ns),
        t_j_ns: to.unwrap_or(last_ns),
        samples,
    })
}

/// A split recording (`--gyro/--accel`, `--gyro-topic/--accel-topic`) read whole, as the
/// window `[from, to]` (defaults: its first and last merged sample), with how it was read,
/// the merge report the effective accelerometer density comes from and the unit checks'
/// verdict.
pub fn split_window(
    args: &ImuInput,
    from: Option<i64>,
    to: Option<i64>,
) -> Result<
    (
        StreamWindow,
        SourceInfo,
        Option<preint_io::split::MergeReport>,
        UnitCheck,
    ),
    Error,
> {
    let r = args.read_all_checked()?;
    let samples = r.samples;
    let (first_ns, last_ns) = (samples[0].t_ns, samples[samples.len() - 1].t_ns);
    let w = StreamWindow {
        offset: 0,
        first_ns,
        last_ns: Some(last_ns),
        t_i_ns: from.unwrap_or(first_ns),
        t_j_ns: to.unwrap_or(last_ns),
        samples,
    };
    Ok((w, r.info, r.report, r.unit_check))
}

impl StreamWindow {
    /// `e` from [`preint::preintegrate`] on [`StreamWindow::samples`], with sample indices
    /// counted in the whole stream and the stream's first sample time.
    pub fn in_stream(&self, e: PreintError) -> PreintError {
        let o = self.offset;
        match e {
            PreintError::NonFinite { index, t_ns, field } => PreintError::NonFinite {
                index: index + o,
                t_ns,
                field,
            },
            PreintError::DuplicateTimestamp { index, t_ns } => PreintError::DuplicateTimestamp {
                index: index + o,
                t_ns,
            },
            PreintError::DecreasingTimestamp {
                index,
                t_ns,
                prev_t_ns,
            } => PreintError::DecreasingTimestamp {
                index: index + o,
                t_ns,
                prev_t_ns,
            },
            PreintError::GapTooLarge {
                index,
                t_ns,
                gap_ns,
                max_gap_ns,
            } => PreintError::GapTooLarge {
                index: index + o,
                t_ns,
                gap_ns,
                max_gap_ns,
            },
            PreintError::KeyframeOutsideSamples { t_ns, last_ns, .. } => {
                PreintError::KeyframeOutsideSamples {
                    t_ns,
                    first_ns: self.first_ns,
                    last_ns: self.last_ns.unwrap_or(last_ns),
                }
            }
            other => other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::test_stream as stream;

    #[test]
    fn the_window_keeps_four_samples_before_and_three_after() {
        let w = cut_window(stream(100), Some(305), Some(505)).unwrap();
        // Samples 27..=30 before t_i = 305, 31..=50 inside, 51..=53 after t_j = 505.
        let t: Vec<i64> = w.samples.iter().map(|s| s.t_ns).collect();
        assert_eq!(t.first(), Some(&270));
        assert_eq!(t.last(), Some(&530));
        assert_eq!(t.len(), 27);
        assert_eq!(
            (w.offset, w.first_ns, w.t_i_ns, w.t_j_ns),
            (27, 0, 305, 505)
        );
    }

    #[test]
    fn without_keyframes_the_window_is_the_whole_stream() {
        let w = cut_window(stream(10), None, None).unwrap();
        assert_eq!(
            (w.samples.len(), w.offset, w.t_i_ns, w.t_j_ns),
            (10, 0, 0, 90)
        );
    }

    #[test]
    fn reading_stops_after_the_window() {
        let mut read = 0;
        let counted = stream(1000).inspect(|_| read += 1);
        cut_window(counted, Some(100), Some(200)).unwrap();
        assert_eq!(read, 24, "samples 0..=23 read, the rest left unread");
    }

    #[test]
    fn a_window_before_the_first_sample_names_the_last_one() {
        let w = cut_window(stream(100), Some(-50), Some(-40)).unwrap();
        assert_eq!((w.first_ns, w.last_ns), (0, Some(990)));
        let e = w.in_stream(PreintError::KeyframeOutsideSamples {
            t_ns: -50,
            first_ns: 0,
            last_ns: 20,
        });
        assert!(e.to_string().contains("[0, 990]"), "{e}");
        // Inside the stream, reading stops after the window and the last time is not known.
        assert_eq!(
            cut_window(stream(100), Some(100), Some(200))
                .unwrap()
                .last_ns,
            None
        );
    }

    #[test]
    fn errors_count_samples_in_the_whole_stream() {
        let w = cut_window(stream(100), Some(505), Some(705)).unwrap();
        let e = w.in_stream(PreintError::GapTooLarge {
            index: 2,
            t_ns: 0,
            gap_ns: 1,
            max_gap_ns: 0,
        });
        assert!(
            matches!(e, PreintError::GapTooLarge { index: 49, .. }),
            "{e:?}"
        );
    }
}
