//! `mlmap`: the host companion of the ML/MAP layer. It fits tables from training
//! logits, tunes their hyper-parameters, scores and evaluates data, inspects tables and
//! runs the end-to-end demo (DESIGN §4).
//!
//! Exit codes: 0 success, 2 bad input or usage, 1 internal failure. Every error names
//! the file (and line) involved; outputs are written to a temporary file and renamed
//! into place, so a failed run leaves nothing half-written.

#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod args;
mod cmd;
mod error;
mod output;
mod report;
mod shared;
mod signals;

use std::io::{self, Write};
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    if let Err(e) = signals::install() {
        eprintln!("mlmap: cannot install the signal handlers: {e}");
        return ExitCode::from(1);
    }
    let cli = match args::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            if e.use_stderr() {
                let _ = e.print();
                return ExitCode::from(2);
            }
            // `--help` and `--version`: a failed write is a failure.
            let printed = e.print().and_then(|()| io::stdout().flush());
            return match printed {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("mlmap: stdout: {e}");
                    ExitCode::from(1)
                }
            };
        }
    };
    match cmd::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mlmap: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
