//! The error of every computation here: a reader's, an invalid option, or a computation that
//! cannot answer. The messages name the file, line or sample, the option (by its command-line
//! flag) and the fix.

/// Why a computation gave no result.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or parsing an input file failed (the message names file and line).
    #[error(transparent)]
    Io(#[from] preint_io::IoError),
    /// An option's value is invalid (the message names the flag).
    #[error("{0}")]
    Usage(String),
    /// The computation failed (the message says why).
    #[error("{0}")]
    Failed(String),
}

impl Error {
    /// A failure with the message of `e`.
    pub fn failed(e: impl std::fmt::Display) -> Self {
        Self::Failed(e.to_string())
    }

    /// An output path of `--out` that cannot be created or written (`--out path: e`).
    pub fn out_path(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        Self::Usage(format!(
            "--out {}: {e} (give a path where a new file or directory can be written)",
            path.display()
        ))
    }

    /// A failure with the message of `e`, prefixed with the file it concerns (`file: e`).
    pub fn failed_in(file: &std::path::Path, e: impl std::fmt::Display) -> Self {
        Self::Failed(format!("{}: {e}", file.display()))
    }
}
