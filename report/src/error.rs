//! The one error type of the crate: every variant names the file it is about.

use std::fmt;
use std::path::PathBuf;

/// Why a report could not be written.
#[derive(Debug)]
pub enum Error {
    /// A file could not be read or parsed.
    Read { path: PathBuf, message: String },
    /// `runs.csv` lacks a column the report needs.
    MissingColumn { path: PathBuf, column: String },
    /// `runs.csv` has no rows.
    NoRows { path: PathBuf },
    /// A file could not be written.
    Write { path: PathBuf, message: String },
    /// Two files that should describe the same experiment do not (`report::check`).
    Mismatch { path: PathBuf, message: String },
}

impl Error {
    pub(crate) fn read(path: impl Into<PathBuf>, message: impl fmt::Display) -> Self {
        Error::Read { path: path.into(), message: one_line(message) }
    }

    pub(crate) fn write(path: impl Into<PathBuf>, message: impl fmt::Display) -> Self {
        Error::Write { path: path.into(), message: one_line(message) }
    }
}

/// Collapses a multi-line message (polars errors often have several lines) into one.
fn one_line(message: impl fmt::Display) -> String {
    message.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Read { path, message } => write!(f, "cannot read {}: {message}", path.display()),
            Error::MissingColumn { path, column } => {
                write!(f, "{} has no column `{column}` (see report/ROWS.md)", path.display())
            }
            Error::NoRows { path } => write!(f, "{} has no rows", path.display()),
            Error::Write { path, message } => write!(f, "cannot write {}: {message}", path.display()),
            Error::Mismatch { path, message } => write!(f, "{}: {message}", path.display()),
        }
    }
}

impl std::error::Error for Error {}
