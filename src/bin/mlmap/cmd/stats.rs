//! `mlmap stats`: one shard's pass of a sharded fit (docs/SCALE.md). Without `--stats`,
//! pass (a): the shard's exact statistics, with the fit settings recorded. With
//! `--stats` (the merged pass-(a) statistics of every shard), pass (b): the shard's bin
//! counts over the edges those statistics and settings give.

use mlmap::host::data;
use mlmap::host::dataset::RowSource;
use mlmap::host::fit::{FitCounts, FitError, FitFile, FitStats};

use crate::args::StatsArgs;
use crate::error::{fit_error, CliError, Result};
use crate::output;
use crate::shared::{read_fit_file, write_fit_file};

pub fn run(args: &StatsArgs) -> Result<()> {
    let train = &args.train;
    match &args.stats {
        None => {
            let params = args.settings.params();
            params.validate().map_err(|e| fit_error(train, e))?;
            let mut inputs = vec![train.as_path()];
            inputs.extend(args.background.iter().map(|p| p.as_path()));
            output::check_outputs(&args.output, &inputs)?;
            let plain = data::open(train)?;
            let background = data::open_background(&args.background)?;
            let src = data::WithBackground::new(&plain, &background)?;
            if !src.has_labels() {
                return Err(fit_error(
                    train,
                    FitError::NoLabels {
                        path: train.clone(),
                    },
                ));
            }
            let mut stats = FitStats::new(src.classes())
                .with_params(params)
                .map_err(|e| fit_error(train, e))?;
            RowSource::for_each_row(&src, |row| {
                stats.push(&row);
                Ok::<(), FitError>(())
            })
            .map_err(|e| fit_error(train, e))?;
            write_fit_file(&args.output, &FitFile::Stats(stats))
        }
        Some(stats_path) => {
            let mut inputs = vec![train.as_path(), stats_path.as_path()];
            inputs.extend(args.background.iter().map(|p| p.as_path()));
            output::check_outputs(&args.output, &inputs)?;
            let stats = match read_fit_file(stats_path)? {
                FitFile::Stats(s) => s,
                FitFile::Counts(_) => {
                    return Err(CliError::input(
                        stats_path,
                        "holds pass-(b) counts; --stats takes the merged pass-(a) statistics",
                    ))
                }
            };
            let Some(params) = stats.params().copied() else {
                return Err(CliError::input(
                    stats_path,
                    "records no fit settings; write pass (a) with `mlmap stats`",
                ));
            };
            let edges = stats
                .edges(&params)
                .map_err(|e| CliError::input(stats_path, e))?;
            let plain = data::open(train)?;
            let background = data::open_background(&args.background)?;
            let src = data::WithBackground::new(&plain, &background)?;
            data::check_classes(
                train,
                src.classes(),
                stats.classes().iter().map(String::as_str),
            )?;
            let mut counts = FitCounts::new(&edges);
            RowSource::for_each_row(&src, |row| {
                if counts.push(&row) {
                    Ok(())
                } else {
                    Err(CliError::Input(format!(
                        "{}: a logit is outside the edges of {}: this shard was not in the \
                         pass-(a) statistics merged there (run pass (a) on every shard, merge, \
                         then pass (b))",
                        data::at(train, row.location()),
                        stats_path.display()
                    )))
                }
            })?;
            write_fit_file(&args.output, &FitFile::Counts(counts))
        }
    }
}
