//! The CLI's error: a message that names the file (and line), and an exit code.

use std::fmt;
use std::path::Path;

use mlmap::host::dataset::DataError;
use mlmap::host::fit::FitError;
use mlmap::host::{fit_message, HostError};

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

impl From<HostError> for CliError {
    fn from(e: HostError) -> Self {
        match e {
            HostError::Fit { train, error } => fit_error(&train, error),
            e if e.is_bad_input() => Self::Input(e.to_string()),
            e => Self::Internal(e.to_string()),
        }
    }
}

impl From<DataError> for CliError {
    fn from(e: DataError) -> Self {
        HostError::from(e).into()
    }
}

/// Maps an error of fitting on the training data `train` to exit code 2 (bad input)
/// or 1, naming `train` when the error does not name a file itself, and naming a
/// parameter by its flag.
pub fn fit_error(train: &Path, e: FitError) -> CliError {
    let msg = match &e {
        FitError::Param {
            name,
            value,
            expected,
        } => format!(
            "--{} {value} is out of range: expected {expected}",
            name.replace('_', "-")
        ),
        _ => fit_message(train, &e),
    };
    if e.is_bad_input() {
        CliError::Input(msg)
    } else {
        CliError::Internal(msg)
    }
}
