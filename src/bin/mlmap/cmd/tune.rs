//! `mlmap tune`: search bin counts and lambdas of every head on validation data (and
//! never-seen objects), within the accuracy and mAP guards, and compare the heads with
//! the baselines.

use indicatif::{ProgressBar, ProgressStyle};
use mlmap::host::data;
use mlmap::host::data::Loaded;
use mlmap::host::fit::TrainingSet;
use mlmap::host::tune::{self, BayesGrid, Guards, TuneParams};
use mlmap::Head;

use crate::args::{TuneArgs, TuneFormat};
use crate::error::{fit_error, CliError, Result};
use crate::output;
use crate::report::{candidates, comparison, maps_text, table_summary, tune_json};
use crate::shared::write_table;

/// The grid of the Bayes head from the flags.
fn bayes_grid(a: &TuneArgs) -> Result<Option<BayesGrid>> {
    if a.no_bayes {
        return Ok(None);
    }
    let bins = tune::parse_bins(&a.bins_bayes)
        .map_err(|e| CliError::Input(format!("--bins-bayes: {e}")))?;
    let (min, max) = (
        a.lambda_bayes_min.unwrap_or(a.lambda_min),
        a.lambda_bayes_max.unwrap_or(a.lambda_max),
    );
    let lambdas = tune::bayes_lambda_grid(min, max, a.lambdas_per_decade)
        .map_err(|e| CliError::Input(format!("--lambda-bayes-min/--lambda-bayes-max: {e}")))?;
    Ok(Some(BayesGrid {
        bins,
        lambdas,
        objectness: a.objectness_feature,
    }))
}

pub fn run(a: &TuneArgs) -> Result<()> {
    let bins_ml =
        tune::parse_bins(&a.bins_ml).map_err(|e| CliError::Input(format!("--bins-ml: {e}")))?;
    let bins_map =
        tune::parse_bins(&a.bins_map).map_err(|e| CliError::Input(format!("--bins-map: {e}")))?;
    let lambdas = tune::lambda_grid(a.lambda_min, a.lambda_max, a.lambdas_per_decade)
        .map_err(|e| CliError::Input(format!("--lambda-min/--lambda-max: {e}")))?;
    let guards = Guards {
        max_accuracy_loss: a.max_accuracy_loss,
        max_map_loss: a.max_map_loss,
    };
    guards.validate().map_err(CliError::Input)?;
    let params = TuneParams {
        bins: vec![(Head::Ml, bins_ml), (Head::Map, bins_map)],
        lambdas,
        bayes: bayes_grid(a)?,
        epsilons: tune::epsilon_grid(),
        objective: a.objective,
        guards,
        edges: a.edges,
        tail: a.upper_tail,
        detail: a.top,
        maps: !a.no_maps,
    };
    params.check_size().map_err(CliError::Input)?;
    let mut inputs = vec![a.train.as_path(), a.val.as_path()];
    inputs.extend(a.ood.as_deref());
    inputs.extend(a.background.iter().map(|p| p.as_path()));
    output::check_outputs(&a.output, &inputs)?;
    let background = data::open_background(&a.background)?;
    let train_src = data::open(&a.train)?;
    let train = TrainingSet::read(&data::WithBackground::new(&train_src, &background)?)
        .map_err(|e| fit_error(&a.train, e))?;
    let val = Loaded::read(&a.val)?;
    let ood = a.ood.as_deref().map(Loaded::read).transpose()?;
    let bar = ProgressBar::new(0).with_message("bin counts");
    if let Ok(style) = ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} [{elapsed}]") {
        bar.set_style(style);
    }
    let tuned = tune::tune(
        &train,
        &val,
        &a.val,
        ood.as_ref().zip(a.ood.as_deref()),
        &params,
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    let size = write_table(&a.output, &tuned.table)?;
    let searched = |head| params.candidates(head);
    let text = match a.format {
        TuneFormat::Text => {
            let mut text = candidates(&tuned.result, params.objective, a.top, searched);
            text.push('\n');
            text.push_str(&comparison(&tuned.comparison, params.objective));
            text.push('\n');
            if params.maps {
                text.push_str(&maps_text(&tuned.maps));
                text.push('\n');
            }
            text.push_str(&table_summary(&a.output, &tuned.table, size));
            text
        }
        TuneFormat::Json => tune_json(&tuned, &params, a.top, &a.output, size),
    };
    output::print(&text)
}
