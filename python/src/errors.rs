//! Rust errors as Python exceptions, with the messages the `mlmap` command prints.
//!
//! * bad input (arrays, settings, data that breaks DESIGN §2): `ValueError`;
//! * a table that does not decode or validate: `mlmap.TableError`, a `ValueError`;
//! * a file that cannot be read or written: the matching `OSError` subclass
//!   (`FileNotFoundError`, `PermissionError`, ...), its message naming the file;
//! * a failure of mlmap itself: `RuntimeError`.

use std::io::Write as _;
use std::path::Path;

use mlmap::host::HostError;
use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError,
    PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;

pyo3::create_exception!(
    mlmap,
    TableError,
    PyValueError,
    "A table that does not decode or breaks a table invariant (a ValueError)."
);

/// `mlmap.TableError(msg)`.
pub fn table_error(msg: impl Into<String>) -> PyErr {
    TableError::new_err(msg.into())
}

/// An I/O error about `path`: `PATH: reason`, as the matching `OSError` subclass.
pub fn io_error(path: &Path, e: &std::io::Error) -> PyErr {
    let msg = format!("{}: {e}", path.display());
    match e.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
        std::io::ErrorKind::AlreadyExists => PyFileExistsError::new_err(msg),
        std::io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(msg),
        _ => PyOSError::new_err(msg),
    }
}

/// A host pipeline's error: `ValueError` when the input is at fault, else
/// `RuntimeError`; the message is the CLI's.
pub fn host_error(e: &HostError) -> PyErr {
    if e.is_bad_input() {
        PyValueError::new_err(e.to_string())
    } else {
        PyRuntimeError::new_err(e.to_string())
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory, renamed
/// into place once complete.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> PyResult<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| io_error(path, &e))?;
    tmp.write_all(bytes)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| io_error(path, &e))?;
    tmp.persist(path).map_err(|e| io_error(path, &e.error))?;
    Ok(())
}
