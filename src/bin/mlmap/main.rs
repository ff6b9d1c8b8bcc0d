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

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = match args::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
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
