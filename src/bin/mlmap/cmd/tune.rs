//! `mlmap tune`: search bin counts and lambdas of both heads on validation data.

use indicatif::{ProgressBar, ProgressStyle};
use mlmap::host::data;
use mlmap::host::data::Loaded;
use mlmap::host::fit::TrainingSet;
use mlmap::host::tune::{self, TuneParams};
use mlmap::Head;

use crate::args::{TuneArgs, TuneFormat};
use crate::error::{fit_error, CliError, Result};
use crate::output;
use crate::report::{candidates, candidates_json, table_summary};
use crate::shared::write_table;

pub fn run(a: &TuneArgs) -> Result<()> {
    let bins_ml =
        tune::parse_bins(&a.bins_ml).map_err(|e| CliError::Input(format!("--bins-ml: {e}")))?;
    let bins_map =
        tune::parse_bins(&a.bins_map).map_err(|e| CliError::Input(format!("--bins-map: {e}")))?;
    let lambdas = tune::lambda_grid(a.lambda_min, a.lambda_max, a.lambdas_per_decade)
        .map_err(|e| CliError::Input(format!("--lambda-min/--lambda-max: {e}")))?;
    let params = TuneParams {
        bins: vec![(Head::Ml, bins_ml), (Head::Map, bins_map)],
        lambdas,
        objective: a.objective,
        edges: a.edges,
        tail: a.upper_tail,
        detail: a.top,
    };
    output::check_outputs(&a.output, &[&a.train, &a.val])?;
    let train = TrainingSet::read(&data::open(&a.train)?).map_err(|e| fit_error(&a.train, e))?;
    let val = Loaded::read(&a.val)?;
    let bar = ProgressBar::new(0).with_message("bin counts");
    if let Ok(style) = ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} [{elapsed}]") {
        bar.set_style(style);
    }
    let tuned = tune::tune(&train, &val, &a.val, &params, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    let size = write_table(&a.output, &tuned.table)?;
    let searched = |head| params.candidates(head);
    let text = match a.format {
        TuneFormat::Text => {
            let mut text = candidates(&tuned.result, params.objective, a.top, searched);
            text.push_str(&table_summary(&a.output, &tuned.table, size));
            text
        }
        TuneFormat::Json => candidates_json(
            &tuned.result,
            params.objective,
            a.top,
            searched,
            &a.output,
            size,
        ),
    };
    output::print(&text)
}
