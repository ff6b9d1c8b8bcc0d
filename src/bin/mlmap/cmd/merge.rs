//! `mlmap merge`: merges the pass-(a) statistics or the pass-(b) counts of shards
//! (docs/SCALE.md); with `--stats`, the merged pass-(a) statistics, merges pass-(b)
//! counts and writes the table.

use std::path::{Path, PathBuf};

use mlmap::host::fit::{self, FitFile};

use crate::args::MergeArgs;
use crate::error::{CliError, Result};
use crate::output;
use crate::report::table_summary;
use crate::shared::{read_fit_file, write_fit_file, write_table};

pub fn run(args: &MergeArgs) -> Result<()> {
    let mut inputs: Vec<&Path> = args.files.iter().map(PathBuf::as_path).collect();
    if let Some(s) = &args.stats {
        inputs.push(s);
    }
    output::check_outputs(&args.output, &inputs)?;
    let merged = merge_files(&args.files)?;
    let Some(stats_path) = &args.stats else {
        return write_fit_file(&args.output, &merged);
    };
    let stats = match read_fit_file(stats_path)? {
        FitFile::Stats(s) => s,
        FitFile::Counts(_) => {
            return Err(CliError::input(
                stats_path,
                "holds pass-(b) counts; --stats takes the merged pass-(a) statistics",
            ))
        }
    };
    let FitFile::Counts(counts) = merged else {
        return Err(CliError::Input(format!(
            "{}: holds pass-(a) statistics; with --stats, the files are the pass-(b) counts \
             of every shard",
            args.files
                .first()
                .map_or(String::new(), |p| p.display().to_string())
        )));
    };
    let table = fit::finish(&stats, &counts).map_err(|e| {
        CliError::Input(format!(
            "{} and the counts cannot be combined: {e}",
            stats_path.display()
        ))
    })?;
    for w in fit::warnings(&table) {
        eprintln!("mlmap: warning: {}: {w}", stats_path.display());
    }
    let size = write_table(&args.output, &table)?;
    output::print(&table_summary(&args.output, &table, size))
}

/// Reads and merges `files`, all statistics or all counts.
fn merge_files(files: &[PathBuf]) -> Result<FitFile> {
    let mut merged: Option<FitFile> = None;
    for path in files {
        let file = read_fit_file(path)?;
        let Some(acc) = &mut merged else {
            merged = Some(file);
            continue;
        };
        let result = match (acc, &file) {
            (FitFile::Stats(a), FitFile::Stats(b)) => a.merge(b),
            (FitFile::Counts(a), FitFile::Counts(b)) => a.merge(b),
            (FitFile::Stats(_), FitFile::Counts(_)) => {
                return Err(CliError::input(
                    path,
                    "holds pass-(b) counts; they cannot be merged with pass-(a) statistics",
                ))
            }
            (FitFile::Counts(_), FitFile::Stats(_)) => {
                return Err(CliError::input(
                    path,
                    "holds pass-(a) statistics; they cannot be merged with pass-(b) counts",
                ))
            }
        };
        result.map_err(|e| CliError::input(path, e))?;
    }
    merged.ok_or_else(|| CliError::Input("no files to merge".to_string()))
}
