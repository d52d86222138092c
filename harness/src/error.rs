//! The harness's errors: each is one line, and says which exit code it means.

use std::fmt;

/// What went wrong, as the user should read it.
#[derive(Debug)]
pub enum Error {
    /// Bad input: a wrong option, value or file (exit code 2).
    Input(String),
    /// Something failed while running (exit code 1).
    Run(String),
}

impl Error {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Input(_) => 2,
            Error::Run(_) => 1,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input(m) | Error::Run(m) => f.write_str(m),
        }
    }
}
