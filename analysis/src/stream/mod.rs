//! Reading a recording once, in bounded memory: the unit checks on a prefix, then every
//! sample in order; the keyframe window cut from the stream with an early stop
//! ([`cut_window`]); the span a solver holds ([`read_span`]).
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

mod span;
mod window;

pub use span::{Span, hold_span, read_span};
pub use window::{StreamWindow, cut_window, cut_window_with_edge, split_window};

use crate::Error;
use crate::checks::{self, UnitCheck};
use crate::recording::ImuInput;
use preint::ImuSample;
use preint_io::plausibility::limits;
use preint_io::{ImuReader, IoError, Progress, SourceInfo};
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

/// A stream of the samples `0, 10, …, 10(n − 1)` ns, gyro x = the index (for tests).
#[cfg(test)]
pub(crate) fn test_stream(n: i64) -> impl Iterator<Item = Result<ImuSample, Error>> {
    (0..n).map(|k| {
        Ok(ImuSample::new(
            k * 10,
            nalgebra::Vector3::new(k as f64, 0.0, 0.0),
            nalgebra::Vector3::zeros(),
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
