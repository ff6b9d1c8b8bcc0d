//! One module per subcommand; `run` dispatches. A command parses its flags, calls the
//! library and prints; what commands share is in `shared` and `report`, never in
//! another command.

pub mod apply;
pub mod conformal;
pub mod demo;
pub mod eval;
pub mod export_c;
pub mod fit;
pub mod inspect;
pub mod lidar_maps;
pub mod merge;
pub mod monitor;
pub mod quantize;
pub mod stats;
pub mod tune;

use crate::args::{Cli, Command};
use crate::error::Result;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match &cli.command {
        Command::Fit(a) => fit::run(a),
        Command::Stats(a) => stats::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Tune(a) => tune::run(a),
        Command::Apply(a) => apply::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Demo(a) => demo::run(a),
        Command::ExportC(a) => export_c::run(a),
        Command::Quantize(a) => quantize::run(a),
        Command::Monitor(a) => monitor::run(a),
        Command::Conformal(a) => conformal::run(a),
        Command::LidarMaps(a) => lidar_maps::run(a),
    }
}
