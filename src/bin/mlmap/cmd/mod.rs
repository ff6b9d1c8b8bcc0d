//! One module per subcommand; `run` dispatches.

pub mod apply;
pub mod demo;
pub mod eval;
pub mod export_c;
pub mod fit;
pub mod inspect;
pub mod tune;

use mlmap::{EdgeMode, UpperTail};

use crate::args::{Cli, Command, Edges, Tail};
use crate::error::Result;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match &cli.command {
        Command::Fit(a) => fit::run(a),
        Command::Tune(a) => tune::run(a),
        Command::Apply(a) => apply::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Demo(a) => demo::run(a),
        Command::ExportC(a) => export_c::run(a),
    }
}

/// The library's edge mode for a flag value.
pub fn edge_mode(e: Edges) -> EdgeMode {
    match e {
        Edges::Linspace => EdgeMode::Linspace,
        Edges::Matlab => EdgeMode::Matlab,
    }
}

/// The library's tail policy for a flag value.
pub fn upper_tail(t: Tail) -> UpperTail {
    match t {
        Tail::Zero => UpperTail::Zero,
        Tail::Clamp => UpperTail::Clamp,
    }
}
