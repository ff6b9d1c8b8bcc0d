//! `tune` as a whole: from a training set and a validation file to the table of the
//! best candidates.

use std::path::Path;
use std::prelude::rust_2021::*;

use super::{search, Objective, SearchParams, TuneError, TuneResult, ValRows};
use crate::host::data::{check_classes, Loaded};
use crate::host::error::HostError;
use crate::host::fit::{build_table, FitError, TrainingSet};
use crate::host::DynTable;
use crate::{EdgeMode, Gaussian, Head, Histogram, Settings, UpperTail};

/// The grid and policies of [`tune`].
///
/// # Parameters
///
/// | Name | Purpose |
/// |---|---|
/// | `bins` | bin counts to try per head; the table needs a candidate of `ML` and `MAP` |
/// | `lambdas` | smoothing values to try (e.g. from [`lambda_grid`](super::lambda_grid)) |
/// | `objective` | what to minimise on the validation set |
/// | `edges`, `tail` | the fit's edge placement and tail policy |
/// | `detail` | how many of the best candidates per head get every metric |
#[derive(Debug, Clone, PartialEq)]
pub struct TuneParams {
    /// Bin counts to try, per head.
    pub bins: Vec<(Head, Vec<usize>)>,
    /// Lambdas to try.
    pub lambdas: Vec<f32>,
    /// What to minimise.
    pub objective: Objective,
    /// Edge placement.
    pub edges: EdgeMode,
    /// Likelihood above the last edge.
    pub tail: UpperTail,
    /// How many of the best candidates per head get every metric.
    pub detail: usize,
}

impl TuneParams {
    /// Number of candidates searched for `head`.
    pub fn candidates(&self, head: Head) -> usize {
        self.bins
            .iter()
            .find(|(h, _)| *h == head)
            .map_or(0, |(_, b)| b.len() * self.lambdas.len())
    }
}

/// What [`tune`] found: every candidate, and the table of the best ones.
#[derive(Debug, Clone)]
pub struct Tuned {
    /// Every candidate of each head, best first.
    pub result: TuneResult,
    /// The table built from the best candidate of each head.
    pub table: DynTable,
}

/// Searches the grid of `params` on the validation rows `val` (read from `val_path`)
/// and builds the table of the best candidates from `train`. `progress(done, total)`
/// is called as bin counts complete.
///
/// # Errors
///
/// [`HostError`] naming the file at fault: classes that differ from the training
/// data's, missing labels, an `nll` objective without labelled rows, training data a
/// table cannot hold, or an empty grid.
pub fn tune(
    train: &TrainingSet,
    val: &Loaded,
    val_path: &Path,
    params: &TuneParams,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<Tuned, HostError> {
    let names: Vec<&str> = train.moments().iter().map(|m| m.name()).collect();
    check_classes(val_path, &val.classes, names.iter().copied())?;
    let labels = val.class_labels(val_path)?;
    if params.objective == Objective::Nll && labels.iter().all(Option::is_none) {
        return Err(HostError::input(
            val_path,
            "no row is labelled with a class: the nll objective is undefined \
             (choose --objective ece or brier)",
        ));
    }
    let logits = val.logits_f32();
    let objectness = val.objectness_f32();
    let priors = train
        .moments()
        .iter()
        .map(|m| {
            Gaussian::new(m.mean() as f32, m.prior_variance() as f32).map_err(|_| {
                let class = m.name().to_string();
                HostError::fit(train.path(), FitError::OutOfF32 { class })
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let histograms = |b: usize| -> Result<Vec<Histogram<Vec<f32>>>, String> {
        train
            .histograms(b, params.edges)
            .map_err(|e| e.to_string())?
            .iter()
            .map(|h| {
                Histogram::new(h.lo(), h.hi(), h.frequencies())
                    .map_err(|e| format!("{b} bins: {e:?}"))
            })
            .collect()
    };
    let search_params = SearchParams {
        val: ValRows {
            k: names.len(),
            logits: &logits,
            objectness: &objectness,
            labels: &labels,
        },
        priors: &priors,
        tail: params.tail,
        bins: &params.bins,
        lambdas: &params.lambdas,
        objective: params.objective,
        detail: params.detail,
    };
    let result = search(&search_params, histograms, progress).map_err(|e| match e {
        TuneError::BadValidationSet(_) => HostError::input(val_path, e),
        TuneError::Histogram(_) => HostError::input(train.path(), e),
        TuneError::EmptyGrid => HostError::Input(format!("tune: {e}")),
    })?;
    let best = |head: Head| {
        result
            .candidates(head)
            .first()
            .copied()
            .ok_or_else(|| HostError::Input("tune: the search grid is empty".into()))
    };
    let (best_ml, best_map) = (best(Head::Ml)?, best(Head::Map)?);
    let fit = |e| HostError::fit(train.path(), e);
    let ml = train.histograms(best_ml.bins, params.edges).map_err(fit)?;
    let map = train.histograms(best_map.bins, params.edges).map_err(fit)?;
    let settings = Settings {
        lambda_ml: best_ml.lambda,
        lambda_map: best_map.lambda,
        edge_mode: params.edges,
        upper_tail: params.tail,
    };
    let table = build_table(train.moments(), &ml, &map, settings).map_err(fit)?;
    // The Bayes head with its fit defaults (not searched yet).
    let bayes = crate::host::fit::BayesParams::default();
    let table = train
        .bayes_counts(bayes.bins)
        .and_then(|counts| crate::host::fit::with_bayes(table, &counts, bayes.lambda))
        .map_err(fit)?;
    Ok(Tuned { result, table })
}
