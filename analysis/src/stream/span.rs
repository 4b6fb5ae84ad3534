//! The span of a recording a solver holds: every sample of `[from, to]`, bounded, after the
//! unit checks.

use super::{MAX_HELD_SAMPLES, open_checked_until};
use crate::Error;
use crate::checks::{self, UnitCheck};
use crate::recording::ImuInput;
use preint::ImuSample;
use preint_io::SourceInfo;

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
    checks::no_gaps(&samples, args.path(), preint::DEFAULT_MAX_GAP_NS)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::test_stream as stream;

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
}
