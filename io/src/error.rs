//! [`IoError`]: every reader and writer error, naming the file and where in it.

use std::fmt;

/// Where in a source a problem is: a 1-based text line, a 1-based message of a container
/// (bag, MCAP), or a byte offset when the line number is not known (after a seek).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of a text file.
    Line(u64),
    /// 1-based message (of the selected topic) in a container file.
    Message(u64),
    /// Byte offset of the start of the line in a text file.
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Message(m) => write!(f, "message {m}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// Errors from reading or writing IMU data, ground truth and noise files. Every variant names
/// the source (a path, or a label for in-memory text) and, for content errors, where in it.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    File {
        /// Path of the file.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A line or message is malformed or breaks a rule (timestamps increasing, values finite).
    #[error("{}", located(source_name, at, msg))]
    Parse {
        /// File name (or another label for in-memory text).
        source_name: String,
        /// Where: `Location::Line` prints as `file:line: msg`.
        at: Location,
        /// What is wrong.
        msg: String,
    },
    /// The source holds no samples.
    #[error("{source_name}: no data rows")]
    Empty {
        /// File name.
        source_name: String,
    },
    /// A required key is missing (Kalibr yaml).
    #[error("{source_name}: missing key `{key}`")]
    MissingKey {
        /// File name.
        source_name: String,
        /// The key.
        key: &'static str,
    },
    /// The values look like they are in the wrong units.
    #[error("{source_name}: {msg}")]
    Units {
        /// File name.
        source_name: String,
        /// What looks wrong, and the likely fix.
        msg: String,
    },
    /// The format could not be recognised, or the reader options do not fit the source.
    #[error("{source_name}: {msg}")]
    Format {
        /// File name.
        source_name: String,
        /// What is missing, and the flag that supplies it.
        msg: String,
    },
    /// A size limit would be exceeded (checked before allocating).
    #[error("{source_name}: {msg}")]
    TooLarge {
        /// File name.
        source_name: String,
        /// Which limit, and how to stay below it.
        msg: String,
    },
    /// A file would be written with a non-finite number in it (nothing is written).
    #[error(
        "{path}: not written: line {line} would hold a non-finite number ({text}); the values \
         it was computed from are out of range (check the inputs named above this message)"
    )]
    NotFinite {
        /// The file that was not written.
        path: String,
        /// 1-based line of the text that holds it.
        line: usize,
        /// That line (shortened).
        text: String,
    },
}

fn located(source_name: &str, at: &Location, msg: &str) -> String {
    match at {
        Location::Line(l) => format!("{source_name}:{l}: {msg}"),
        other => format!("{source_name}: {other}: {msg}"),
    }
}

impl IoError {
    /// A [`IoError::Parse`] at `at` of `source_name`.
    pub fn parse(source_name: &str, at: Location, msg: impl Into<String>) -> Self {
        IoError::Parse {
            source_name: source_name.to_string(),
            at,
            msg: msg.into(),
        }
    }

    /// A [`IoError::Format`] of `source_name`.
    pub fn format(source_name: &str, msg: impl Into<String>) -> Self {
        IoError::Format {
            source_name: source_name.to_string(),
            msg: msg.into(),
        }
    }

    /// A [`IoError::File`] for `path`.
    pub fn file(path: &std::path::Path, source: std::io::Error) -> Self {
        IoError::File {
            path: path.display().to_string(),
            source,
        }
    }

    /// The 1-based line of a [`IoError::Parse`] in a text source, if any.
    pub fn line(&self) -> Option<u64> {
        match self {
            IoError::Parse {
                at: Location::Line(l),
                ..
            } => Some(*l),
            _ => None,
        }
    }
}

/// Reads a whole (small) text file: ground truth, `imu.yaml`.
pub(crate) fn read_text(path: &std::path::Path) -> Result<String, IoError> {
    std::fs::read_to_string(path).map_err(|e| IoError::file(path, e))
}

/// Writes a whole text file, refusing one that holds a non-finite number
/// ([`non_finite_line`]): nothing non-finite leaves the program.
pub(crate) fn write_text(path: &std::path::Path, text: &str) -> Result<(), IoError> {
    if let Some((line, t)) = non_finite_line(text) {
        return Err(IoError::NotFinite {
            path: path.display().to_string(),
            line,
            text: t,
        });
    }
    std::fs::write(path, text).map_err(|e| IoError::file(path, e))
}

/// The first line of `text` that holds a non-finite number as Rust prints one (`inf`, `-inf`,
/// `NaN`, as a whole word), with its 1-based number and its first 120 characters.
pub fn non_finite_line(text: &str) -> Option<(usize, String)> {
    text.lines()
        .enumerate()
        .find_map(|(k, l)| has_non_finite_word(l).then(|| (k + 1, l.chars().take(120).collect())))
}

/// Whether `line` holds `inf` or `NaN` as a whole word (letters, digits and `_` around it are
/// other words: `info`, `inferred`, `NaN_count` are not numbers).
fn has_non_finite_word(line: &str) -> bool {
    let b = line.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    ["inf", "NaN"].iter().any(|w| {
        line.match_indices(w).any(|(i, _)| {
            let before = i == 0 || !word(b[i - 1]);
            let after = i + w.len() == b.len() || !word(b[i + w.len()]);
            before && after
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_words_and_other_words() {
        assert_eq!(non_finite_line("a: 1\nb: inf  # x\n").map(|x| x.0), Some(2));
        assert_eq!(non_finite_line("x,-inf,2").map(|x| x.0), Some(1));
        assert_eq!(non_finite_line("[NaN, 1]").map(|x| x.0), Some(1));
        assert_eq!(non_finite_line("info: inferred from NaN_count\nint"), None);
        assert_eq!(non_finite_line("1e308, 0.5"), None);
    }
}
