//! Reading a recording once, in bounded memory: the unit checks on a prefix, then every
//! sample in order; and the keyframe window cut from the stream with an early stop.
//!
//! The unit checks ([`preint_io::plausibility`]) look at a prefix of the recording: the
//! samples up to a window's end and, if the checks cannot decide on those, more, doubling the
//! prefix until they decide, the recording ends or the prefix holds [`UNIT_CHECK_PREFIX`]
//! samples (2¹⁸, 22 min at 200 Hz, 15 MB): a short window of a long recording is checked on
//! the recording around it, not on the few seconds before its end. Every sample read, in the
//! prefix or after it, is also refused if its readings are beyond any IMU's range
//! ([`preint_io::plausibility::limits`], naming the line and the sample), `--no-unit-check`
//! or not. A row that cannot be read after a window's end ends the checks' reading there: the
//! window does not need it.

use crate::Error;
use crate::checks::{self, UnitCheck};
use crate::recording::ImuInput;
use preint::{ImuSample, PreintError};
use preint_io::plausibility::limits;
use preint_io::{ImuReader, IoError, Progress, SourceInfo};
use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

/// Most samples held in memory for the unit checks: 2¹⁸ (15 MB; 22 min at 200 Hz). The checks of
/// a longer recording look at this prefix only.
pub const UNIT_CHECK_PREFIX: usize = 1 << 18;

/// Most samples a window cut from a stream may hold: 50 million (2.8 GB).
pub const MAX_WINDOW_SAMPLES: usize = preint_io::reader::DEFAULT_MAX_SAMPLES;

/// Most samples `calibrate` and `advise` hold (their solvers need every sample of the span they
/// analyse): 2²³ (470 MB; 11.6 h at 200 Hz). A longer span is refused before it is read
/// further, with the flags that choose a part.
pub const MAX_HELD_SAMPLES: usize = 1 << 23;

/// Stream samples kept on each side of a window: the values and order checks of
/// [`preint::preintegrate`] reach three samples beyond the samples at `t_i` and `t_j`, one
/// more before `t_i` for the first checked interval.
pub const EDGE_SAMPLES: usize = 4;

/// The samples of a recording, in order, after the unit checks on a prefix (module docs;
/// unless `--no-unit-check`), each within any IMU's range. The rest of the recording is
/// parsed by a second thread (in chunks through a bounded channel) while the caller works on
/// what came before.
pub struct CheckedSamples {
    prefix: std::vec::IntoIter<ImuSample>,
    rest: Option<Prefetch>,
    info: SourceInfo,
    progress: Progress,
    unit_check: UnitCheck,
    merge: Option<preint_io::split::MergeHandle>,
}

/// Samples per chunk handed from the reading thread.
const CHUNK: usize = 4096;

/// Chunks parsed ahead of the consumer (memory: 4 × 4096 samples, 0.9 MB).
const CHUNKS_AHEAD: usize = 4;

/// A reader running on its own thread, handing over chunks of samples through a bounded
/// channel and getting the emptied chunks back, so that nothing is allocated per chunk
/// after the first few. Dropping it stops the thread at its next chunk.
struct Prefetch {
    full: Receiver<Result<Vec<ImuSample>, IoError>>,
    empty: SyncSender<Vec<ImuSample>>,
    chunk: Vec<ImuSample>,
    next: usize,
}

impl Prefetch {
    /// Reads the rest of `reader`, whose next sample has index `index`, checking each against
    /// the limits of any IMU.
    fn start(mut reader: ImuReader, mut index: u64) -> Self {
        let (full_tx, full) = sync_channel(CHUNKS_AHEAD);
        let (empty, empty_rx) = sync_channel::<Vec<ImuSample>>(CHUNKS_AHEAD + 1);
        std::thread::spawn(move || {
            loop {
                let mut chunk = empty_rx
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(CHUNK));
                chunk.clear();
                let mut failed = None;
                while chunk.len() < CHUNK {
                    match next_within_limits(&mut reader, index) {
                        Some(Ok(s)) => chunk.push(s),
                        Some(Err(e)) => {
                            failed = Some(e);
                            break;
                        }
                        None => break,
                    }
                    index += 1;
                }
                let done = chunk.len() < CHUNK;
                if !chunk.is_empty() && full_tx.send(Ok(chunk)).is_err() {
                    return;
                }
                if let Some(e) = failed {
                    let _ = full_tx.send(Err(e));
                    return;
                }
                if done {
                    return;
                }
            }
        });
        Self {
            full,
            empty,
            chunk: Vec::new(),
            next: 0,
        }
    }

    fn next_sample(&mut self) -> Option<Result<ImuSample, IoError>> {
        if self.next == self.chunk.len() {
            let used = std::mem::take(&mut self.chunk);
            self.next = 0;
            let _ = self.empty.try_send(used);
            match self.full.recv().ok()? {
                Ok(chunk) => self.chunk = chunk,
                Err(e) => return Some(Err(e)),
            }
        }
        self.next += 1;
        Some(Ok(self.chunk[self.next - 1]))
    }
}

/// The next sample of `reader` (number `index`, 0-based), refused when beyond the range of
/// any IMU ([`limits::check_reading`]).
fn next_within_limits(reader: &mut ImuReader, index: u64) -> Option<Result<ImuSample, IoError>> {
    let located = reader.next_located()?;
    let name = &reader.info().source_name;
    Some(located.and_then(|l| {
        limits::check_reading(&l.sample, index, l.at, name)?;
        Ok(l.sample)
    }))
}

/// Opens the recording of `args` and runs the unit checks on its prefix.
pub fn open_checked(args: &ImuInput) -> Result<CheckedSamples, Error> {
    open_checked_until(args, None)
}

/// As [`open_checked`], with a stream that holds at least the samples up to
/// [`EDGE_SAMPLES`] − 1 after `until` \[ns\] (a window's end) once its checks are done.
pub fn open_checked_until(args: &ImuInput, until: Option<i64>) -> Result<CheckedSamples, Error> {
    open_checked_prefix(args, until, UNIT_CHECK_PREFIX, None, EDGE_SAMPLES)
}

/// As [`open_checked_until`], the prefix reaching `edge` − 1 samples after `until` (a window
/// that reads `edge` samples on each side, [`cut_window_with_edge`]).
pub fn open_checked_window(
    args: &ImuInput,
    until: Option<i64>,
    edge: usize,
) -> Result<CheckedSamples, Error> {
    open_checked_prefix(args, until, UNIT_CHECK_PREFIX, None, edge)
}

/// The prefix being read for the checks.
struct Prefix {
    samples: Vec<ImuSample>,
    ended: bool,
}

impl Prefix {
    /// Reads from `reader` while `more` says so (given the prefix) and the recording goes on.
    /// A reading error is returned, or with `past_window` (samples read for the checks only)
    /// ends the prefix: what the window needs was read without it.
    fn read_while(
        &mut self,
        reader: &mut ImuReader,
        mut more: impl FnMut(&[ImuSample]) -> bool,
        past_window: bool,
    ) -> Result<(), Error> {
        while !self.ended && more(&self.samples) {
            match next_within_limits(reader, self.samples.len() as u64) {
                Some(Ok(s)) => self.samples.push(s),
                Some(Err(_)) if past_window => self.ended = true,
                Some(Err(e)) => return Err(e.into()),
                None => self.ended = true,
            }
        }
        Ok(())
    }
}

/// As [`open_checked_until`], with the unit checks on at most `max_samples` samples spanning at
/// most `max_span_s` seconds (the prefix ends with the first sample that reaches it), and
/// `edge` − 1 samples read after `until`. Without `until` the checks see the whole prefix;
/// with it, the samples up to the window's end, then more while they cannot decide (module
/// docs).
pub fn open_checked_prefix(
    args: &ImuInput,
    until: Option<i64>,
    max_samples: usize,
    max_span_s: Option<f64>,
    edge: usize,
) -> Result<CheckedSamples, Error> {
    let (mut reader, merge) = args.open_with_report()?;
    let (info, progress) = (reader.info().clone(), reader.progress().clone());
    let max_span_ns = max_span_s.map_or(i64::MAX, |s| (s * 1e9) as i64);
    let full = |p: &[ImuSample]| {
        p.len() >= max_samples
            || p.len() > 1 && p[p.len() - 1].t_ns.saturating_sub(p[0].t_ns) >= max_span_ns
    };
    let mut prefix = Prefix {
        samples: Vec::new(),
        ended: false,
    };
    // The window: up to `edge` − 1 samples after `until`, or the whole prefix without it.
    let window_read = |p: &[ImuSample]| match until {
        Some(t) => p.iter().rev().take_while(|s| s.t_ns > t).count() >= edge - 1,
        None => false,
    };
    prefix.read_while(&mut reader, |p| !full(p) && !window_read(p), false)?;
    if prefix.samples.is_empty() {
        return Err(IoError::Empty {
            source_name: info.source_name.clone(),
        }
        .into());
    }
    let unit_check = if args.no_unit_check {
        UnitCheck::Skipped
    } else {
        loop {
            let verdict = checks::si_units(&prefix.samples, args.path(), Some(info.units))?;
            let n = prefix.samples.len();
            if verdict.passed() || prefix.ended || full(&prefix.samples) {
                break UnitCheck::Checked {
                    verdict,
                    samples: n,
                };
            }
            let target = (2 * n).max(n + 1024);
            let past_window = until.is_some();
            prefix.read_while(&mut reader, |p| p.len() < target && !full(p), past_window)?;
        }
    };
    let index = prefix.samples.len() as u64;
    // Nothing more is read once the source ended or the window `until` is complete.
    let more = !prefix.ended && !window_read(&prefix.samples);
    Ok(CheckedSamples {
        prefix: prefix.samples.into_iter(),
        rest: more.then(|| Prefetch::start(reader, index)),
        info,
        progress,
        unit_check,
        merge,
    })
}

impl CheckedSamples {
    /// The merge report's handle of a split recording (complete once the samples are
    /// consumed).
    pub fn merge(&self) -> Option<preint_io::split::MergeHandle> {
        self.merge.clone()
    }

    /// What the unit checks said.
    pub fn unit_check(&self) -> &UnitCheck {
        &self.unit_check
    }

    /// How the source is read.
    pub fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// How far reading has got.
    pub fn progress(&self) -> &Progress {
        &self.progress
    }
}

impl Iterator for CheckedSamples {
    type Item = Result<ImuSample, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        match self.prefix.next() {
            Some(s) => Some(Ok(s)),
            None => self
                .rest
                .as_mut()?
                .next_sample()
                .map(|r| r.map_err(Error::from)),
        }
    }
}

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

/// The samples a solver holds ([`read_span`]), how the recording was read and what its unit
/// checks said.
#[derive(Clone, Debug)]
pub struct Span {
    /// The samples with `from ≤ t ≤ to`.
    pub samples: Vec<ImuSample>,
    /// How the recording was read.
    pub source: SourceInfo,
    /// The unit checks' verdict.
    pub unit_check: UnitCheck,
}

/// The samples of `args`' recording with `from ≤ t ≤ to` for the solver of `command`
/// ([`hold_span`] with [`MAX_HELD_SAMPLES`], after the unit checks, with a progress bar),
/// refused if two consecutive ones are more than the preintegrator's largest gap apart.
pub fn read_span(
    args: &ImuInput,
    from: Option<i64>,
    to: Option<i64>,
    command: &str,
) -> Result<Span, Error> {
    let stream = open_checked_until(args, to)?;
    let (source, unit_check) = (stream.info().clone(), stream.unit_check().clone());
    let bar = crate::progress::ReadingBar::start(stream.progress(), command);
    let samples = hold_span(stream, from, to, MAX_HELD_SAMPLES, args.path())?;
    drop(bar);
    checks::no_gaps(&samples, args.path(), preint::params::DEFAULT_MAX_GAP_NS)?;
    Ok(Span {
        samples,
        source,
        unit_check,
    })
}

/// The samples of `stream` with `from ≤ t ≤ to` (either bound optional), read up to `to`;
/// more than `limit` of them is an error naming `file` and the flags that shorten the span,
/// raised before the sample past the limit is stored.
pub fn hold_span(
    stream: impl Iterator<Item = Result<ImuSample, Error>>,
    from: Option<i64>,
    to: Option<i64>,
    limit: usize,
    file: &std::path::Path,
) -> Result<Vec<ImuSample>, Error> {
    let (lo, hi) = (from.unwrap_or(i64::MIN), to.unwrap_or(i64::MAX));
    let mut samples: Vec<ImuSample> = Vec::new();
    for s in stream {
        let s = s?;
        if s.t_ns > hi {
            break;
        }
        if s.t_ns < lo {
            continue;
        }
        if samples.len() == limit {
            return Err(Error::Failed(format!(
                "{}: more than {limit} samples ({:.0} MB) from t = {} ns on; analyse a part \
                 with --from/--to",
                file.display(),
                (limit * std::mem::size_of::<ImuSample>()) as f64 * 1e-6,
                samples.first().map_or(s.t_ns, |f| f.t_ns)
            )));
        }
        samples.push(s);
    }
    if samples.len() < 2 {
        return Err(Error::Failed(format!(
            "{}: fewer than two samples with timestamps in [{lo}, {hi}] ns",
            file.display()
        )));
    }
    Ok(samples)
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
    use nalgebra::Vector3;

    fn stream(n: i64) -> impl Iterator<Item = Result<ImuSample, Error>> {
        (0..n).map(|k| {
            Ok(ImuSample::new(
                k * 10,
                Vector3::new(k as f64, 0.0, 0.0),
                Vector3::zeros(),
            ))
        })
    }

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

    /// EuRoC text of `n` rows, row `bad` (if any) malformed.
    fn euroc_text(n: usize, bad: Option<usize>) -> String {
        let mut t = String::from("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n");
        for k in 0..n {
            if Some(k) == bad {
                t.push_str("not a row\n");
            } else {
                let w = k as f64 * 1e-3;
                t.push_str(&format!("{},{w},0.5,0,0,0,9.8\n", 1_000 + k * 5_000_000));
            }
        }
        t
    }

    #[test]
    fn the_prefetch_thread_hands_over_every_sample_in_order() {
        // 10 000 samples: two full chunks and a partial one.
        let text = euroc_text(10_000, None);
        let reader = ImuReader::from_text(&text, "p.csv", &preint_io::ReadOptions::euroc());
        let mut p = Prefetch::start(reader.unwrap(), 0);
        let mut k = 0usize;
        while let Some(s) = p.next_sample() {
            let s = s.unwrap();
            assert_eq!(
                (s.t_ns, s.gyro.x),
                ((1_000 + k * 5_000_000) as i64, k as f64 * 1e-3)
            );
            k += 1;
        }
        assert_eq!(k, 10_000);
    }

    #[test]
    fn the_prefetch_thread_passes_an_error_on_after_the_samples_before_it() {
        let text = euroc_text(10_000, Some(9_000));
        let reader = ImuReader::from_text(&text, "p.csv", &preint_io::ReadOptions::euroc());
        let mut p = Prefetch::start(reader.unwrap(), 0);
        let mut k = 0usize;
        let err = loop {
            match p.next_sample() {
                Some(Ok(_)) => k += 1,
                Some(Err(e)) => break e.to_string(),
                None => panic!("no error after {k} samples"),
            }
        };
        assert_eq!(k, 9_000);
        // Header on line 1, row 9000 on line 9002.
        assert!(err.contains("p.csv:9002"), "{err}");
        assert!(p.next_sample().is_none());
    }

    #[test]
    fn the_prefetch_thread_refuses_a_reading_beyond_any_imu_naming_line_and_sample() {
        let text = euroc_text(10_000, None).replace(
            &format!("{},8.5,0.5", 1_000 + 8_500 * 5_000_000i64),
            &format!("{},1e308,0.5", 1_000 + 8_500 * 5_000_000i64),
        );
        let reader = ImuReader::from_text(&text, "p.csv", &preint_io::ReadOptions::euroc());
        let mut p = Prefetch::start(reader.unwrap(), 0);
        let err = std::iter::from_fn(|| p.next_sample())
            .find_map(Result::err)
            .expect("refused")
            .to_string();
        assert!(
            err.starts_with("p.csv:8502: sample 8500 ") && err.contains("1e308"),
            "{err}"
        );
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
    fn a_held_span_is_bounded_before_it_grows_past_the_limit() {
        let file = std::path::Path::new("rec.csv");
        let held = hold_span(stream(100), Some(200), Some(300), 11, file).unwrap();
        assert_eq!(held.len(), 11);
        assert_eq!((held[0].t_ns, held[10].t_ns), (200, 300));
        let e = hold_span(stream(100), Some(200), Some(300), 10, file).unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("rec.csv")
                && e.contains("more than 10 samples")
                && e.contains("--from/--to"),
            "{e}"
        );
        let e = hold_span(stream(100), Some(2000), None, 10, file).unwrap_err();
        assert!(e.to_string().contains("fewer than two samples"), "{e}");
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
