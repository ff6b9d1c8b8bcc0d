//! The temporary files of the outputs being written, removed when SIGINT, SIGTERM or
//! SIGHUP ends a run (DESIGN §4, Outputs): the process then exits with 128 plus the
//! signal's number (130, 143, 129), as a shell reports a process killed by it.

use std::fs;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard, PoisonError};

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

/// The temporary files that exist now.
static TEMPORARY: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn temporary() -> MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARY.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Starts the thread that waits for the signals; call once, first thing.
pub fn install() -> std::io::Result<()> {
    let mut signals = Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // Held until the process ends: no file is renamed into place meanwhile.
                let files = temporary();
                for file in files.iter() {
                    // A file, or the temporary directory of an NPY output.
                    if fs::remove_file(file).is_err() {
                        let _ = fs::remove_dir_all(file);
                    }
                }
                std::process::exit(128 + signal);
            }
        })?;
    Ok(())
}

/// A temporary file (or directory) registered for removal on a signal, for as long as
/// this lives.
pub struct Registered(PathBuf);

impl Registered {
    /// Registers `path`.
    pub fn new(path: PathBuf) -> Self {
        temporary().push(path.clone());
        Self(path)
    }

    /// Runs `f` (the rename of the file into place) while no signal can remove it, and
    /// unregisters it.
    pub fn finish<T>(self, f: impl FnOnce() -> T) -> T {
        let files = temporary();
        let out = f();
        drop(files);
        out
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        temporary().retain(|p| *p != self.0);
    }
}
