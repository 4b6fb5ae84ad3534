//! What a subcommand returns: its [`Output`], or a [`CliError`].

use serde_json::Value;

/// What a subcommand prints: a human summary, or (with `--json`) one JSON object.
#[derive(Clone, Debug)]
pub struct Output {
    /// Human-readable summary (ends with a newline).
    pub human: String,
    /// Machine-readable result.
    pub json: Value,
}

/// Errors reported on stderr with a non-zero exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Reading or parsing an input file failed (the message names file and line).
    #[error(transparent)]
    Io(#[from] preint_io::IoError),
    /// A flag value is invalid.
    #[error("{0}")]
    Usage(String),
    /// The computation failed (message says why).
    #[error("{0}")]
    Failed(String),
    /// The command ran and its result is a refusal (e.g. `audit --strict` found a defect): the
    /// output is printed as on success, then the message, and the exit code is 2.
    #[error("{msg}")]
    Refused {
        /// What the command found.
        output: Box<Output>,
        /// Why that is a failure.
        msg: String,
    },
}

impl From<preint_analysis::Error> for CliError {
    fn from(e: preint_analysis::Error) -> Self {
        match e {
            preint_analysis::Error::Io(e) => CliError::Io(e),
            preint_analysis::Error::Usage(m) => CliError::Usage(m),
            preint_analysis::Error::Failed(m) => CliError::Failed(m),
        }
    }
}

impl CliError {
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
