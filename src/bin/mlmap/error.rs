//! The CLI's error: a message that names the file (and line), and an exit code.

use std::fmt;
use std::path::Path;

/// Why a command failed, and whose fault it is.
#[derive(Debug)]
pub enum CliError {
    /// Bad input or usage (exit 2): a malformed file, a missing file, a bad flag value.
    Input(String),
    /// A failure of the machine or of mlmap itself (exit 1): an I/O error on output.
    Internal(String),
}

impl CliError {
    /// Bad input about `path`.
    pub fn input(path: &Path, msg: impl fmt::Display) -> Self {
        Self::Input(format!("{}: {msg}", path.display()))
    }

    /// An internal failure about `path`.
    pub fn internal(path: &Path, msg: impl fmt::Display) -> Self {
        Self::Internal(format!("{}: {msg}", path.display()))
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Input(_) => 2,
            Self::Internal(_) => 1,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input(m) | Self::Internal(m) => f.write_str(m),
        }
    }
}

/// Result of a command.
pub type Result<T> = std::result::Result<T, CliError>;
