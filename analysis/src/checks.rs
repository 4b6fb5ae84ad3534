//! Checks of flag values and of the units of the data, with messages that name the flag or file.

use crate::Error;
use preint::ImuSample;
use preint_io::{UnitVerdict, Units};
use serde_json::{Value, json};
use std::path::Path;

/// `flag`'s value `v` must be finite and ≥ 0.
pub fn non_negative(flag: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "{flag} must be a non-negative number, got {v}"
        )))
    }
}

/// `--from` must come before `--to` when both are given (timestamps in ns).
pub fn window_order(from: Option<i64>, to: Option<i64>) -> Result<(), Error> {
    match (from, to) {
        (Some(f), Some(t)) if f >= t => Err(Error::Usage(format!(
            "--from {f} is not before --to {t}: a window runs from --from to a later --to (both \
             timestamps in ns, on the recording's clock)"
        ))),
        _ => Ok(()),
    }
}

/// `flag`'s value `v` must be finite and > 0.
pub fn positive(flag: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "{flag} must be a positive number, got {v}"
        )))
    }
}

/// `flag`'s value `g` must be a gravity magnitude in [0, 100] m/s² ([`crate::parse::gravity`]),
/// for values that do not come through the flag's parser (library callers).
pub fn gravity(flag: &str, g: f64) -> Result<(), Error> {
    crate::parse::gravity(&g.to_string())
        .map(|_| ())
        .map_err(|e| Error::Usage(format!("{flag}: {e}")))
}

/// The samples of `file` look like the units `read_as` they were read in (time unit,
/// accelerometer m/s², gyroscope rad/s, moving and still; see [`preint_io::plausibility`]):
/// data in g, deg/s or another time unit is refused with a message naming the file and the
/// flag that fixes it; otherwise the verdict says whether the units were confirmed.
pub fn si_units(
    samples: &[ImuSample],
    file: &Path,
    read_as: Option<Units>,
) -> Result<UnitVerdict, Error> {
    let name = file.display().to_string();
    Ok(preint_io::plausibility::check_units_read_as(
        samples, &name, read_as,
    )?)
}

/// What the unit checks said about the recording a command read.
#[derive(Clone, Debug, PartialEq)]
pub enum UnitCheck {
    /// Checked on the first `samples` samples.
    Checked {
        /// Passed or inconclusive.
        verdict: UnitVerdict,
        /// Samples checked (a prefix of the recording, or all of it).
        samples: usize,
    },
    /// `--no-unit-check`.
    Skipped,
}

impl UnitCheck {
    /// `{"verdict": "passed" | "inconclusive" | "skipped", "why", "samples"}`: `why` says
    /// what the checks missed (null unless inconclusive), `samples` how many were checked
    /// (null when skipped).
    pub fn json(&self) -> Value {
        match self {
            UnitCheck::Checked { verdict, samples } => json!({
                "verdict": verdict.name(), "why": verdict.why(), "samples": samples,
            }),
            UnitCheck::Skipped => json!({
                "verdict": "skipped", "why": "--no-unit-check", "samples": null,
            }),
        }
    }

    /// `unit check inconclusive (N samples checked): why` and a newline when the checks could
    /// not decide; empty otherwise.
    pub fn text(&self) -> String {
        match self {
            UnitCheck::Checked {
                verdict: UnitVerdict::Inconclusive(why),
                samples,
            } => format!(
                "unit check inconclusive ({samples} samples checked): {}\n",
                why.join("; ")
            ),
            _ => String::new(),
        }
    }
}

/// No interval between consecutive samples of `file` exceeds `max_gap_ns`; the error names
/// the two samples (indices and times) around the first gap.
pub fn no_gaps(samples: &[ImuSample], file: &Path, max_gap_ns: i64) -> Result<(), Error> {
    match samples
        .windows(2)
        .position(|w| w[1].t_ns - w[0].t_ns > max_gap_ns)
    {
        None => Ok(()),
        Some(k) => Err(Error::Failed(format!(
            "{}: gap of {:.6} s between samples {k} (t = {} ns) and {} (t = {} ns), above {} s; \
             choose a continuous part with --from/--to",
            file.display(),
            (samples[k + 1].t_ns - samples[k].t_ns) as f64 * 1e-9,
            samples[k].t_ns,
            k + 1,
            samples[k + 1].t_ns,
            max_gap_ns as f64 * 1e-9
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flag_values() {
        assert!(non_negative("--x", 0.0).is_ok());
        let e = non_negative("--pose-pos-std", -1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--pose-pos-std") && e.contains("-1"), "{e}");
        assert!(non_negative("--x", f64::NAN).is_err());
        assert!(positive("--gravity", 0.0).is_err());
        assert!(positive("--gravity", 9.81).is_ok());
    }
}
