//! The error of the host pipelines ([`data`](super::data), [`eval`](super::eval),
//! [`tune`](super::tune)): a message naming the file (and line) involved, and whose
//! fault it is.

use core::fmt;
use std::path::{Path, PathBuf};

use super::dataset::DataError;
use super::fit::FitError;

/// Why a host pipeline failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum HostError {
    /// Bad input (a malformed or mismatched file, a bad setting); the message names
    /// the file.
    Input(String),
    /// A failure of the machine (an I/O error) or of mlmap itself.
    Internal(String),
    /// Fitting on the training data `train` failed.
    Fit {
        /// The training input.
        train: PathBuf,
        /// What went wrong.
        error: FitError,
    },
}

impl HostError {
    /// Bad input about `path`: `PATH: msg`.
    pub fn input(path: &Path, msg: impl fmt::Display) -> Self {
        Self::Input(format!("{}: {msg}", path.display()))
    }

    /// An internal failure about `path`: `PATH: msg`.
    pub fn internal(path: &Path, msg: impl fmt::Display) -> Self {
        Self::Internal(format!("{}: {msg}", path.display()))
    }

    /// A failure to fit on the training data `train`.
    pub fn fit(train: &Path, error: FitError) -> Self {
        Self::Fit {
            train: train.to_path_buf(),
            error,
        }
    }

    /// `true` when the input is at fault, `false` for a machine or internal failure.
    pub fn is_bad_input(&self) -> bool {
        match self {
            Self::Input(_) => true,
            Self::Internal(_) => false,
            Self::Fit { error, .. } => error.is_bad_input(),
        }
    }
}

/// The message of a fitting error on the training data `train`: the error itself when
/// it names its file, else prefixed with `train`.
pub fn fit_message(train: &Path, e: &FitError) -> String {
    match e {
        FitError::Data(_)
        | FitError::NoLabels { .. }
        | FitError::EmptyClasses { .. }
        | FitError::Changed { .. }
        | FitError::OutsideEdges { .. }
        | FitError::Param { .. } => e.to_string(),
        _ => format!("{}: {e}", train.display()),
    }
}

impl fmt::Display for HostError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input(m) | Self::Internal(m) => f.write_str(m),
            Self::Fit { train, error } => f.write_str(&fit_message(train, error)),
        }
    }
}

impl std::error::Error for HostError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Fit { error, .. } => Some(error),
            _ => None,
        }
    }
}

impl From<DataError> for HostError {
    fn from(e: DataError) -> Self {
        if e.is_bad_input() {
            Self::Input(e.to_string())
        } else {
            Self::Internal(e.to_string())
        }
    }
}
