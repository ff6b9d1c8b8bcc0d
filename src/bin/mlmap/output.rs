//! Writing outputs atomically, and printing to stdout without panicking.

use std::io::{self, Write};
use std::path::Path;

use crate::error::{CliError, Result};

/// Writes `path` through `fill`: into a temporary file in the same directory, renamed
/// into place only when everything was written. On any error the temporary file is
/// removed and `path` is untouched.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(CliError::input(path, "the output directory does not exist"));
    }
    let mut tmp = tempfile::Builder::new()
        .prefix(".mlmap-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| CliError::internal(path, format!("cannot create a temporary file: {e}")))?;
    {
        let mut w = io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.flush()
            .map_err(|e| CliError::internal(path, format!("cannot write: {e}")))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| CliError::internal(path, format!("cannot sync: {e}")))?;
    tmp.persist(path)
        .map_err(|e| CliError::internal(path, format!("cannot rename into place: {}", e.error)))?;
    Ok(())
}

/// Writes all of `bytes` to a file atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| {
        w.write_all(bytes)
            .map_err(|e| CliError::internal(path, format!("cannot write: {e}")))
    })
}

/// Prints `text` to stdout; a closed pipe (`mlmap inspect t | head`) is not an error.
pub fn print(text: &str) -> Result<()> {
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(CliError::Internal(format!("stdout: {e}"))),
    }
}
