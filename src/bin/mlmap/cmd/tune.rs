//! `mlmap tune`: search bin counts and lambdas of both heads on validation data.

use std::fmt::Write as _;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};
use mlmap::host::fit::{build_table, FitError, TrainingSet};
use mlmap::host::tune::{self, Candidate, Objective, TuneError, TuneResult, ValRows};
use mlmap::host::DynTable;
use mlmap::{EdgeMode, Gaussian, Histogram, Settings, UpperTail};

use crate::args::{self, TuneArgs, TuneFormat};
use crate::cmd::fit::{fit_error, summary, write_table};
use crate::error::{CliError, Result};
use crate::load::{self, Loaded};
use crate::output;

/// The grid and policies of a search.
pub struct Grid {
    pub bins_ml: Vec<usize>,
    pub bins_map: Vec<usize>,
    pub lambdas: Vec<f32>,
    pub objective: Objective,
    pub edges: EdgeMode,
    pub tail: UpperTail,
    /// How many of the best candidates per head get all three metrics.
    pub detail: usize,
}

/// The objective's name as printed.
pub fn objective_name(o: Objective) -> &'static str {
    match o {
        Objective::Ece => "ece",
        Objective::Nll => "nll",
        Objective::Brier => "brier",
    }
}

/// Runs the search and builds the table of the best candidates.
pub fn search(
    train: &TrainingSet,
    val: &Loaded,
    val_path: &Path,
    grid: &Grid,
) -> Result<(TuneResult, DynTable)> {
    let names: Vec<&str> = train.moments().iter().map(|m| m.name()).collect();
    load::check_classes(val_path, &val.classes, names.iter().copied())?;
    let labels = val.class_labels(val_path)?;
    if grid.objective == Objective::Nll && labels.iter().all(Option::is_none) {
        return Err(CliError::input(
            val_path,
            "no row is labelled with a class: the nll objective is undefined \
             (choose --objective ece or brier)",
        ));
    }
    let logits = val.logits_f32();
    let objectness = val.objectness_f32();
    let rows = ValRows {
        k: names.len(),
        logits: &logits,
        objectness: &objectness,
        labels: &labels,
    };
    let priors = train
        .moments()
        .iter()
        .map(|m| {
            Gaussian::new(m.mean() as f32, m.prior_variance() as f32).map_err(|_| {
                let class = m.name().to_string();
                fit_error(train.path(), FitError::OutOfF32 { class })
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let histograms = |b: usize| -> std::result::Result<Vec<Histogram<Vec<f32>>>, String> {
        train
            .histograms(b, grid.edges)
            .map_err(|e| e.to_string())?
            .iter()
            .map(|h| {
                Histogram::new(h.lo(), h.hi(), h.frequencies())
                    .map_err(|e| format!("{b} bins: {e:?}"))
            })
            .collect()
    };
    let total = {
        let mut all: Vec<usize> = grid.bins_ml.iter().chain(&grid.bins_map).copied().collect();
        all.sort_unstable();
        all.dedup();
        all.len() as u64
    };
    let bar = ProgressBar::new(total).with_message("bin counts");
    if let Ok(style) = ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} [{elapsed}]") {
        bar.set_style(style);
    }
    let result = tune::search(
        histograms,
        &priors,
        grid.tail,
        &rows,
        &grid.bins_ml,
        &grid.bins_map,
        &grid.lambdas,
        grid.objective,
        grid.detail,
        |done, _| bar.set_position(done as u64),
    )
    .map_err(|e| match e {
        TuneError::BadValidationSet(_) => CliError::input(val_path, e),
        TuneError::Histogram(_) => CliError::input(train.path(), e),
        TuneError::EmptyGrid => CliError::Input(format!("tune: {e}")),
    })?;
    bar.finish_and_clear();
    let (best_ml, best_map) = match (result.ml.first(), result.map.first()) {
        (Some(a), Some(b)) => (*a, *b),
        _ => return Err(CliError::Input("tune: the search grid is empty".into())),
    };
    let ml = train
        .histograms(best_ml.bins, grid.edges)
        .map_err(|e| fit_error(train.path(), e))?;
    let map = train
        .histograms(best_map.bins, grid.edges)
        .map_err(|e| fit_error(train.path(), e))?;
    let settings = Settings {
        lambda_ml: best_ml.lambda,
        lambda_map: best_map.lambda,
        edge_mode: grid.edges,
        upper_tail: grid.tail,
    };
    let table = build_table(train.moments(), &ml, &map, settings)
        .map_err(|e| fit_error(train.path(), e))?;
    // The Bayes head with its fit defaults (not tuned yet).
    let bayes = mlmap::host::fit::BayesParams::default();
    let table = train
        .bayes_counts(bayes.bins)
        .and_then(|counts| mlmap::host::fit::with_bayes(table, &counts, bayes.lambda))
        .map_err(|e| fit_error(train.path(), e))?;
    Ok((result, table))
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.5}"))
}

/// The best `top` candidates of each head as an aligned table.
pub fn render(
    result: &TuneResult,
    objective: Objective,
    top: usize,
    n_candidates: (usize, usize),
) -> String {
    let mut s = String::new();
    let heads: [(&str, &[Candidate], usize); 2] = [
        ("ML", &result.ml, n_candidates.0),
        ("MAP", &result.map, n_candidates.1),
    ];
    for (head, cands, n) in heads {
        let _ = writeln!(
            s,
            "{head} head: best {} of {n} candidates by {}",
            top.min(cands.len()),
            objective_name(objective)
        );
        let _ = writeln!(
            s,
            "  {:>4} {:>5} {:>11} {:>9} {:>9} {:>9}",
            "rank", "bins", "lambda", "ece", "nll", "brier"
        );
        for (i, c) in cands.iter().take(top).enumerate() {
            let _ = writeln!(
                s,
                "  {:>4} {:>5} {:>11.3e} {:>9} {:>9} {:>9}",
                i + 1,
                c.bins,
                c.lambda,
                fmt_opt(c.ece),
                fmt_opt(c.nll),
                fmt_opt(c.brier)
            );
        }
    }
    s
}

/// The best `top` candidates of each head as one JSON object, values at full precision.
pub fn render_json(
    result: &TuneResult,
    objective: Objective,
    top: usize,
    n_candidates: (usize, usize),
    table_path: &Path,
    table_bytes: usize,
) -> String {
    let head = |cands: &[Candidate]| -> Vec<serde_json::Value> {
        cands
            .iter()
            .take(top)
            .enumerate()
            .map(|(i, c)| {
                serde_json::json!({
                    "rank": i + 1,
                    "bins": c.bins,
                    "lambda": c.lambda,
                    "ece": c.ece,
                    "nll": c.nll,
                    "brier": c.brier,
                })
            })
            .collect()
    };
    let v = serde_json::json!({
        "objective": objective_name(objective),
        "candidates": { "ml": n_candidates.0, "map": n_candidates.1 },
        "ml": head(&result.ml),
        "map": head(&result.map),
        "table": { "path": table_path.display().to_string(), "bytes": table_bytes },
    });
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

pub fn run(a: &TuneArgs) -> Result<()> {
    let bins_ml =
        tune::parse_bins(&a.bins_ml).map_err(|e| CliError::Input(format!("--bins-ml: {e}")))?;
    let bins_map =
        tune::parse_bins(&a.bins_map).map_err(|e| CliError::Input(format!("--bins-map: {e}")))?;
    let lambdas = tune::lambda_grid(a.lambda_min, a.lambda_max, a.lambdas_per_decade)
        .map_err(|e| CliError::Input(format!("--lambda-min/--lambda-max: {e}")))?;
    let grid = Grid {
        bins_ml,
        bins_map,
        lambdas,
        objective: match a.objective {
            args::Objective::Ece => Objective::Ece,
            args::Objective::Nll => Objective::Nll,
            args::Objective::Brier => Objective::Brier,
        },
        edges: super::edge_mode(a.edges),
        tail: super::upper_tail(a.upper_tail),
        detail: a.top,
    };
    output::check_outputs(&a.output, &[&a.train, &a.val])?;
    let train = TrainingSet::read(&load::open(&a.train)?).map_err(|e| fit_error(&a.train, e))?;
    let val = load::load(&a.val)?;
    let (result, table) = search(&train, &val, &a.val, &grid)?;
    let size = write_table(&a.output, &table)?;
    let n = (
        grid.bins_ml.len() * grid.lambdas.len(),
        grid.bins_map.len() * grid.lambdas.len(),
    );
    let text = match a.format {
        TuneFormat::Text => {
            let mut text = render(&result, grid.objective, a.top, n);
            text.push_str(&summary(&a.output, &table, size));
            text
        }
        TuneFormat::Json => render_json(&result, grid.objective, a.top, n, &a.output, size),
    };
    output::print(&text)
}
