//! Writing outputs atomically, and printing to stdout without panicking.

use std::fs;
use std::io::{self, Write};
use std::path::Path;

use crate::error::{CliError, Result};
use crate::signals;

/// Checks that `path` can be an output file: its directory exists, `path` is not a
/// directory, and an existing regular file there may be replaced: it is not
/// write-protected. Commands call it before any long work, so a mistyped output fails
/// fast.
pub fn check_target(path: &Path) -> Result<()> {
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(CliError::input(path, "the output directory does not exist"));
    }
    if path.is_dir() {
        return Err(CliError::input(
            path,
            "is a directory; the output must be a file path (an NPY directory output of \
             `apply`: end the path in `/`)",
        ));
    }
    if let Ok(meta) = fs::metadata(path) {
        if meta.is_file() && write_protected(path, &meta) {
            return Err(CliError::input(
                path,
                format!(
                    "is write-protected (mode {:04o}); make it writable or remove it to \
                     replace it",
                    mode(&meta)
                ),
            ));
        }
    }
    Ok(())
}

/// The permission bits of a file.
#[cfg(unix)]
fn mode(meta: &fs::Metadata) -> u32 {
    use std::os::unix::fs::PermissionsExt;
    meta.permissions().mode() & 0o7777
}

#[cfg(not(unix))]
fn mode(meta: &fs::Metadata) -> u32 {
    if meta.permissions().readonly() {
        0o444
    } else {
        0o644
    }
}

/// Whether the existing file `path` is write-protected: no write bit at all (checked on
/// the bits, since the superuser may open any file), or not writable by this process.
fn write_protected(path: &Path, meta: &fs::Metadata) -> bool {
    mode(meta) & 0o222 == 0
        || fs::OpenOptions::new()
            .write(true)
            .open(path)
            .is_err_and(|e| e.kind() == io::ErrorKind::PermissionDenied)
}

/// Files of an NPY directory input (docs/DESIGN.md §2) that an output could replace.
const NPY_FILES: [&str; 4] = ["logits.npy", "labels.npy", "objectness.npy", "classes.txt"];

/// Checks that `output` can be written ([`check_target`]) and names none of `inputs`,
/// symbolic and hard links included: writing scores over the data they come from would
/// destroy it. For an input that is an NPY directory, the output may not be one of its
/// files either. Runs before anything is read.
pub fn check_outputs(output: &Path, inputs: &[&Path]) -> Result<()> {
    check_target(output)?;
    let Ok(out_meta) = fs::metadata(output) else {
        // Nothing there yet, so no input can be that file (an input must exist); but a
        // new file inside an NPY input directory may still shadow nothing: allowed.
        return Ok(());
    };
    for input in inputs {
        let Ok(in_meta) = fs::metadata(input) else {
            continue;
        };
        let clash = if in_meta.is_dir() {
            // The output is one of the directory's data files.
            let in_dir = output
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| NPY_FILES.contains(&n))
                && fs::metadata(parent_dir(output)).is_ok_and(|d| same_file(&d, &in_meta));
            in_dir
        } else {
            same_file(&out_meta, &in_meta)
        };
        if clash {
            return Err(CliError::input(
                output,
                format!(
                    "is the same file as the input {}; write the output elsewhere",
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Whether two metadata describe the same file (device and inode).
#[cfg(unix)]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

/// Whether two metadata describe the same file (no inode numbers here: never).
#[cfg(not(unix))]
fn same_file(_: &fs::Metadata, _: &fs::Metadata) -> bool {
    false
}

/// The directory `path` is written into.
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// `true` when an output location refuses a write (no permission, a read-only file
/// system, a directory where a file should go): the user's fault, exit code 2. Other
/// I/O failures (a full disk, a device error) are the machine's, exit code 1.
pub fn location_refused(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::PermissionDenied
            | io::ErrorKind::ReadOnlyFilesystem
            | io::ErrorKind::IsADirectory
            | io::ErrorKind::NotADirectory
            | io::ErrorKind::DirectoryNotEmpty
    )
}

/// An I/O error on the output `path`, with its exit code (see [`location_refused`]).
fn io_error(path: &Path, what: &str, e: &io::Error) -> CliError {
    let msg = format!("{what}: {e}");
    if location_refused(e) {
        CliError::input(path, msg)
    } else {
        CliError::internal(path, msg)
    }
}

/// Writes `path` through `fill`: into a temporary file in the same directory, renamed
/// into place only when everything was written. On any error, and on SIGINT, SIGTERM
/// or SIGHUP, the temporary file is removed and `path` is untouched. The file has the
/// permission bits of the file it replaces, or those the umask gives a new file.
///
/// An existing `path` that is not a regular file (`/dev/null`, `/dev/stdout`, a FIFO) is
/// written directly instead: renaming over it would replace the device with a file.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    check_target(path)?;
    if fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        let file = fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| io_error(path, "cannot open", &e))?;
        let mut w = io::BufWriter::new(file);
        fill(&mut w)?;
        return w.flush().map_err(|e| io_error(path, "cannot write", &e));
    }
    // A new file gets the mode the umask gives (0666 less the umask, as any program's
    // output); a replaced file keeps its permission bits.
    let existing = fs::metadata(path).ok().filter(fs::Metadata::is_file);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".mlmap-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(parent_dir(path))
        .map_err(|e| io_error(path, "cannot create a temporary file", &e))?;
    let registered = signals::Registered::new(tmp.path().to_path_buf());
    if let Some(meta) = &existing {
        tmp.as_file()
            .set_permissions(meta.permissions())
            .map_err(|e| io_error(path, "cannot set the permissions", &e))?;
    }
    {
        let mut w = io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.flush().map_err(|e| io_error(path, "cannot write", &e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| io_error(path, "cannot sync", &e))?;
    // The target may have become write-protected while the output was computed.
    check_target(path)?;
    registered
        .finish(|| tmp.persist(path))
        .map_err(|e| io_error(path, "cannot rename into place", &e.error))?;
    Ok(())
}

/// Checks that `dir` can be an output directory that holds only files `ours` accepts:
/// its parent exists; `dir` is nothing yet, or a directory holding nothing but such
/// files (an earlier output, replaced as a whole); it is none of `inputs` and holds none
/// of them. Runs before anything is read.
pub fn check_dir_outputs(dir: &Path, ours: fn(&str) -> bool, inputs: &[&Path]) -> Result<()> {
    if let Ok(dir_meta) = fs::metadata(dir) {
        check_dir_inputs(dir, &dir_meta, inputs)?;
    }
    check_dir_target(dir, ours)
}

/// No input is `dir` (of metadata `dir_meta`) or a file in it.
fn check_dir_inputs(dir: &Path, dir_meta: &fs::Metadata, inputs: &[&Path]) -> Result<()> {
    for input in inputs {
        let Ok(in_meta) = fs::metadata(input) else {
            continue;
        };
        let inside = fs::metadata(parent_dir(input)).is_ok_and(|p| same_file(&p, dir_meta));
        if same_file(&in_meta, dir_meta) || inside {
            return Err(CliError::input(
                dir,
                format!(
                    "holds or is the input {}; write the output elsewhere",
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The checks of [`check_dir_outputs`] on `dir` itself.
fn check_dir_target(dir: &Path, ours: fn(&str) -> bool) -> Result<()> {
    if !parent_dir(dir).is_dir() {
        return Err(CliError::input(
            dir,
            "the directory it would be created in does not exist",
        ));
    }
    let Ok(meta) = fs::symlink_metadata(dir) else {
        return Ok(());
    };
    if !meta.is_dir() {
        return Err(CliError::input(
            dir,
            "is not a directory; an NPY output is a directory (a new one, or one written by \
             an earlier run)",
        ));
    }
    let entries = fs::read_dir(dir).map_err(|e| io_error(dir, "cannot list", &e))?;
    for entry in entries {
        let entry = entry.map_err(|e| io_error(dir, "cannot list", &e))?;
        let name = entry.file_name();
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if !(is_file && name.to_str().is_some_and(ours)) {
            return Err(CliError::input(
                dir,
                format!(
                    "holds {:?}, which this output does not write; give a new or empty \
                     directory (an existing output is replaced as a whole)",
                    name
                ),
            ));
        }
    }
    Ok(())
}

/// Writes the directory `dir` through `fill`, which writes its files into the directory
/// it is given: a temporary directory `.mlmap-*.tmp` beside `dir`, renamed into place
/// only when everything was written. An existing `dir` (see [`check_dir_outputs`]) is
/// replaced as a whole and keeps its permission bits; a new one gets those the umask
/// gives. On any error, and on SIGINT, SIGTERM or SIGHUP, the temporary directory is
/// removed and `dir` is untouched.
pub fn write_dir_atomic(
    dir: &Path,
    ours: fn(&str) -> bool,
    fill: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    check_dir_target(dir, ours)?;
    let parent = parent_dir(dir);
    let existing = fs::metadata(dir).ok().filter(fs::Metadata::is_dir);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".mlmap-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(fs::Permissions::from_mode(0o777));
    }
    let tmp = builder
        .tempdir_in(parent)
        .map_err(|e| io_error(dir, "cannot create a temporary directory", &e))?;
    let registered = signals::Registered::new(tmp.path().to_path_buf());
    fill(tmp.path())?;
    if let Some(meta) = &existing {
        fs::set_permissions(tmp.path(), meta.permissions())
            .map_err(|e| io_error(dir, "cannot set the permissions", &e))?;
    }
    // The target may have changed while the output was computed.
    check_dir_target(dir, ours)?;
    // An existing output is first moved aside (over an empty temporary directory),
    // then removed with it once the new one is in place.
    let old = if fs::symlink_metadata(dir).is_ok() {
        let old = builder
            .tempdir_in(parent)
            .map_err(|e| io_error(dir, "cannot create a temporary directory", &e))?;
        fs::rename(dir, old.path()).map_err(|e| io_error(dir, "cannot replace", &e))?;
        Some(old)
    } else {
        None
    };
    registered
        .finish(|| fs::rename(tmp.path(), dir))
        .map_err(|e| {
            if let Some(old) = &old {
                let _ = fs::rename(old.path(), dir);
            }
            io_error(dir, "cannot rename into place", &e)
        })?;
    // In place: no longer temporary.
    let _ = tmp.keep();
    drop(old);
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
