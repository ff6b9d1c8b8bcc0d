//! `tune` as a whole: from a training set, a validation file (and never-seen objects)
//! to the table of the chosen candidates and the comparison of every head with the
//! baselines on the validation rows.

use std::path::Path;

use super::{
    search, search_bayes, search_open, BayesSearchParams, Candidate, Guards, Judge, MapChoice,
    Objective, OpenSearchParams, Reference, SearchParams, TuneError, TuneResult, ValRows,
};
use crate::baselines::{self, Baseline, Rows};
use crate::data::{check_classes, Loaded};
use crate::error::HostError;
use crate::eval::{head_scores, Method, Ranking};
use crate::fit::{build_table, FitError, TrainingSet};
use crate::metrics::{self, Metrics, MetricsConfig};
use crate::names::Named;
use crate::DynTable;
use mlmap_core::{EdgeMode, Gaussian, Head, Histogram, Settings, UpperTail};

/// The grid of the Bayes head.
#[derive(Debug, Clone, PartialEq)]
pub struct BayesGrid {
    /// Bin counts per logit to try.
    pub bins: Vec<usize>,
    /// Lambdas to try, each in `(0, 1]`.
    pub lambdas: Vec<f32>,
    /// Whether the categories also model the objectness logit (DESIGN §1.6).
    pub objectness: bool,
}

/// The grid and policies of [`tune`].
///
/// # Parameters
///
/// | Name | Purpose |
/// |---|---|
/// | `bins` | bin counts to try per head; the table needs a candidate of `ML` and `MAP` |
/// | `lambdas` | smoothing values to try for ML and MAP (e.g. from [`lambda_grid`](super::lambda_grid)) |
/// | `bayes` | the Bayes head's grid; `None` leaves the head out of the table |
/// | `epsilons` | the open head's `epsilon` grid (e.g. [`epsilon_grid`](super::epsilon_grid)), searched with the Bayes head; empty: the untuned open head (`T = 1`, `epsilon = 0`) |
/// | `objective` | what to minimise on the validation set |
/// | `guards` | how much accuracy and mAP a chosen candidate may lose against softmax |
/// | `edges`, `tail` | the fit's edge placement and tail policy |
/// | `detail` | how many of the best candidates per head get every metric |
/// | `maps` | whether to fit a recalibration map per head (DESIGN §1.9), kept where it lowers the ECE |
#[derive(Debug, Clone, PartialEq)]
pub struct TuneParams {
    /// Bin counts to try, per head (ML and MAP).
    pub bins: Vec<(Head, Vec<usize>)>,
    /// Lambdas to try (ML and MAP).
    pub lambdas: Vec<f32>,
    /// The Bayes head's grid, or `None` for a table without that head.
    pub bayes: Option<BayesGrid>,
    /// The open head's `epsilon` grid (searched when the Bayes head is).
    pub epsilons: Vec<f32>,
    /// What to minimise.
    pub objective: Objective,
    /// The allowed losses against softmax.
    pub guards: Guards,
    /// Edge placement.
    pub edges: EdgeMode,
    /// Likelihood above the last edge.
    pub tail: UpperTail,
    /// How many of the best candidates per head get every metric.
    pub detail: usize,
    /// Whether to fit recalibration maps (DESIGN §1.9).
    pub maps: bool,
}

impl TuneParams {
    /// Refuses a grid of more than [`MAX_CANDIDATES`](super::MAX_CANDIDATES) candidates
    /// over every head (DESIGN §4), before any is built.
    ///
    /// # Errors
    ///
    /// A message with the number of candidates of each head and the cap.
    pub fn check_size(&self) -> Result<(), String> {
        let heads = [Head::Ml, Head::Map, Head::Bayes, Head::Open];
        let total: usize = heads.iter().map(|&h| self.candidates(h)).sum();
        if total <= super::MAX_CANDIDATES {
            return Ok(());
        }
        let each: Vec<String> = heads
            .iter()
            .filter(|&&h| self.candidates(h) > 0)
            .map(|&h| format!("{} {}", h.name(), self.candidates(h)))
            .collect();
        Err(format!(
            "the grid holds {total} candidates ({}: bin counts times lambdas); at most {} \
             are searched: give fewer bin counts or fewer lambdas per decade",
            each.join(", "),
            super::MAX_CANDIDATES
        ))
    }

    /// Number of candidates searched for `head`.
    pub fn candidates(&self, head: Head) -> usize {
        if head == Head::Bayes {
            return self
                .bayes
                .as_ref()
                .map_or(0, |g| g.bins.len() * g.lambdas.len());
        }
        if head == Head::Open {
            return if self.bayes.is_some() {
                self.epsilons.len()
            } else {
                0
            };
        }
        self.bins
            .iter()
            .find(|(h, _)| *h == head)
            .map_or(0, |(_, b)| b.len() * self.lambdas.len())
    }
}

/// One method in the comparison of [`tune`]: its metrics on the validation rows (with
/// the never-seen objects as background rows, and their `ood_mean`).
#[derive(Debug, Clone, PartialEq)]
pub struct Compared {
    /// The method.
    pub method: Method,
    /// The chosen candidate, for a head.
    pub chosen: Option<Candidate>,
    /// Every metric of DESIGN §1.5.
    pub metrics: Metrics,
    /// How much more accuracy or mAP than the guards allow it loses against softmax.
    pub excess: f64,
}

/// Every head at its chosen settings, softmax and temperature scaling, on the rows the
/// candidates were scored on.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Validation rows.
    pub rows: usize,
    /// Never-seen rows among them.
    pub ood_rows: Option<usize>,
    /// The temperature fitted on the validation rows; `None` when it cannot be (no
    /// row labelled with a class), and temperature scaling is then left out.
    pub temperature: Option<f64>,
    /// Softmax's accuracy and mAP, which the guards compare against.
    pub reference: Reference,
    /// The methods: softmax, temperature, isotonic, then every head in the table.
    pub methods: Vec<Compared>,
    /// The energy score's ranking metrics on the same rows (DESIGN §1.5).
    pub energy: Ranking,
    /// The head with the best objective among the heads within the guards; `None`
    /// when no head is.
    pub best: Option<Method>,
}

/// What [`tune`] found: every candidate, the table of the chosen ones, and the
/// comparison of every head with the baselines.
#[derive(Debug, Clone)]
pub struct Tuned {
    /// Every candidate of each head, best first.
    pub result: TuneResult,
    /// The table built from the chosen candidate of each head.
    pub table: DynTable,
    /// The heads and the baselines on the validation rows.
    pub comparison: Comparison,
    /// The recalibration map fitted for each head, and whether the table keeps it
    /// (empty when maps were not asked for).
    pub maps: Vec<MapChoice>,
}

/// The rows candidates are scored on: the validation rows, then the never-seen ones
/// as background.
struct Scored {
    logits: Vec<f64>,
    objectness: Vec<f64>,
    labels: Vec<Option<usize>>,
}

impl Scored {
    fn new(val: &Loaded, labels: Vec<Option<usize>>, ood: Option<&Loaded>) -> Self {
        let mut s = Self {
            logits: val.logits.clone(),
            objectness: val.objectness.clone(),
            labels,
        };
        if let Some(o) = ood {
            s.logits.extend_from_slice(&o.logits);
            s.objectness.extend_from_slice(&o.objectness);
            s.labels.extend(std::iter::repeat_n(None, o.len()));
        }
        s
    }

    /// The metrics of `scores` (`N x K`), with `ood_mean` of the never-seen rows.
    fn metrics(
        &self,
        scores: &[f64],
        k: usize,
        val_rows: usize,
        with_ood: bool,
    ) -> Result<Metrics, String> {
        let cfg = MetricsConfig::default();
        let m = metrics::evaluate_with_logits(scores, &self.logits, k, &self.labels, &cfg)
            .map_err(|e| e.to_string())?;
        if !with_ood {
            return Ok(m);
        }
        let ood = scores.get(val_rows * k..).unwrap_or(&[]);
        let known = metrics::known_confidences(
            scores.get(..val_rows * k).unwrap_or(&[]),
            k,
            self.labels.get(..val_rows).unwrap_or(&[]),
        );
        Ok(m.with_ood(metrics::ood_metrics_against(ood, k, &known).map_err(|e| e.to_string())?))
    }
}

/// Searches the grid of `params` on the validation rows `val` (read from `val_path`),
/// and the never-seen objects `ood` as background rows, builds the table of the chosen
/// candidates from `train`, and compares every head at its chosen settings with
/// softmax and temperature scaling on the same rows. `progress(done, total)` is called
/// as bin counts complete.
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
    ood: Option<(&Loaded, &Path)>,
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
    params
        .guards
        .validate()
        .map_err(|e| HostError::Input(format!("tune: {e}")))?;
    if let Some((o, path)) = ood {
        check_classes(path, &o.classes, names.iter().copied())?;
    }
    let k = names.len();
    let rows = Scored::new(val, labels, ood.map(|(o, _)| o));
    let fail = |e: String| HostError::input(val_path, e);
    // Softmax on the same rows: the reference of the guards.
    let softmax = score_baseline(Baseline::Softmax, &rows, k).map_err(&fail)?;
    let softmax_m = rows
        .metrics(&softmax, k, val.len(), ood.is_some())
        .map_err(&fail)?;
    let judge = Judge {
        objective: params.objective,
        guards: params.guards,
        reference: Reference {
            accuracy: softmax_m.accuracy,
            mean_ap: softmax_m.mean_ap(),
        },
    };
    let logits: Vec<f32> = rows.logits.iter().map(|&v| v as f32).collect();
    let objectness: Vec<f32> = rows.objectness.iter().map(|&v| v as f32).collect();
    let val_rows = ValRows {
        k,
        logits: &logits,
        objectness: &objectness,
        labels: &rows.labels,
    };
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
        val: val_rows,
        priors: &priors,
        tail: params.tail,
        bins: &params.bins,
        lambdas: &params.lambdas,
        judge,
        detail: params.detail,
    };
    let first = search_params.distinct_bins().len();
    let bayes_bins = params.bayes.as_ref().map_or(0, |g| g.bins.len());
    let total = first + bayes_bins;
    let map_err = |e: TuneError| match e {
        TuneError::BadValidationSet(_) => HostError::input(val_path, e),
        TuneError::Histogram(_) => HostError::input(train.path(), e),
        TuneError::EmptyGrid => HostError::Input(format!("tune: {e}")),
    };
    let mut result =
        search(&search_params, histograms, |d, _| progress(d, total)).map_err(map_err)?;
    let best = |result: &TuneResult, head: Head| {
        result
            .candidates(head)
            .first()
            .copied()
            .ok_or_else(|| HostError::Input("tune: the search grid is empty".into()))
    };
    let (best_ml, best_map) = (best(&result, Head::Ml)?, best(&result, Head::Map)?);
    let fit = |e| HostError::fit(train.path(), e);
    let ml = train.histograms(best_ml.bins, params.edges).map_err(fit)?;
    let map = train.histograms(best_map.bins, params.edges).map_err(fit)?;
    let settings = Settings {
        lambda_ml: best_ml.lambda,
        lambda_map: best_map.lambda,
        edge_mode: params.edges,
        upper_tail: params.tail,
    };
    let mut table = build_table(train.moments(), &ml, &map, settings).map_err(fit)?;
    if let Some(grid) = &params.bayes {
        let bayes_params = BayesSearchParams {
            val: val_rows,
            base: &table,
            bins: &grid.bins,
            lambdas: &grid.lambdas,
            judge,
            detail: params.detail,
        };
        let counts = |b: usize| {
            train
                .bayes_counts_with(b, grid.objectness)
                .map_err(|e| e.to_string())
        };
        let found = search_bayes(&bayes_params, counts, |d, _| progress(first + d, total))
            .map_err(map_err)?;
        result.heads.push(found);
        let chosen = best(&result, Head::Bayes)?;
        let counts = train
            .bayes_counts_with(chosen.bins, grid.objectness)
            .map_err(fit)?;
        table = crate::fit::with_bayes(table, &counts, chosen.lambda).map_err(fit)?;
        if !params.epsilons.is_empty() {
            // The temperature as the baseline fits it: by NLL on the labelled
            // validation rows (1 when there is none to fit it on).
            let fit_rows = Rows::new(
                &val.logits,
                k,
                rows.labels.get(..val.len()).unwrap_or(&[]),
                &val.objectness,
            )
            .map_err(|e| HostError::input(val_path, e))?;
            let temperature = baselines::fit_temperature_detailed(&fit_rows)
                .map_or(crate::fit::UNTUNED_TEMPERATURE, |f| f.t as f32)
                .clamp(mlmap_core::MIN_TEMPERATURE, mlmap_core::MAX_TEMPERATURE);
            let open_params = OpenSearchParams {
                val: val_rows,
                table: &table,
                temperature,
                epsilons: &params.epsilons,
                judge,
                detail: params.detail,
            };
            result
                .heads
                .push(search_open(&open_params).map_err(map_err)?);
            let chosen = best(&result, Head::Open)?;
            table = table
                .with_open(temperature, chosen.epsilon.unwrap_or(0.0))
                .map_err(|e| HostError::fit(train.path(), FitError::Table(e)))?;
        }
    }
    let (table, maps) = if params.maps {
        super::choose_maps(table, &val_rows, &judge)
    } else {
        (table, Vec::new())
    };
    let comparison = compare(
        &table, &result, &rows, val, val_path, ood, softmax, softmax_m, judge,
    )?;
    Ok(Tuned {
        result,
        table,
        comparison,
        maps,
    })
}

/// The scores of a baseline on every row.
fn score_baseline(b: Baseline, rows: &Scored, k: usize) -> Result<Vec<f64>, String> {
    let r = Rows::new(&rows.logits, k, &[], &rows.objectness).map_err(|e| e.to_string())?;
    baselines::score_rows(b, &r).map_err(|e| e.to_string())
}

/// Softmax, temperature scaling and isotonic regression (fitted on the rows of the
/// validation file), the energy score, and every head of `table` on `rows`; names the
/// best head within the guards.
#[allow(clippy::too_many_arguments)]
fn compare(
    table: &DynTable,
    result: &TuneResult,
    rows: &Scored,
    val: &Loaded,
    val_path: &Path,
    ood: Option<(&Loaded, &Path)>,
    softmax: Vec<f64>,
    softmax_m: Metrics,
    judge: Judge,
) -> Result<Comparison, HostError> {
    let k = table.k();
    let fail = |e: String| HostError::input(val_path, e);
    let n_val = val.len();
    let val_labels = rows.labels.get(..n_val).unwrap_or(&[]);
    let fit_rows = Rows::new(&val.logits, k, val_labels, &val.objectness)
        .map_err(|e| HostError::input(val_path, e))?;
    let t = baselines::fit_temperature_detailed(&fit_rows)
        .ok()
        .map(|f| f.t);
    let with_ood = ood.is_some();
    // The energy score, split into true and false positives as softmax decides.
    let energy = {
        let all = Rows::new(&rows.logits, k, &[], &[]).map_err(|e| fail(e.to_string()))?;
        let e = baselines::negative_energies(&all).map_err(|e| fail(e.to_string()))?;
        let outcomes = metrics::outcomes_with_logits(&softmax, &rows.logits, k, &rows.labels)
            .map_err(|e| fail(e.to_string()))?;
        let pick = |keep: &dyn Fn(usize) -> bool| -> Vec<f64> {
            e.iter()
                .enumerate()
                .filter(|&(i, _)| keep(i))
                .map(|(_, &v)| v)
                .collect()
        };
        let correct = |i: usize| outcomes.get(i).is_some_and(|o| o.correct);
        let known = pick(&|i| i < n_val && val_labels.get(i).is_some_and(Option::is_some));
        let unseen = pick(&|i| i >= n_val);
        Ranking {
            auroc: metrics::separation_auroc(&pick(&correct), &pick(&|i| !correct(i))),
            ood_auroc: with_ood
                .then(|| metrics::separation_auroc(&known, &unseen))
                .flatten(),
            ood_fpr95: with_ood
                .then(|| metrics::fpr_at_95_tpr(&known, &unseen))
                .flatten(),
        }
    };
    let mut methods = vec![(Method::Softmax, softmax, Some(softmax_m))];
    if let Some(t) = t {
        let temperature = score_baseline(Baseline::Temperature(t), rows, k).map_err(&fail)?;
        methods.push((Method::Temperature, temperature, None));
    }
    // Isotonic maps fitted on the same rows as the temperature (the validation file).
    let iso = baselines::fit_isotonic(&fit_rows).map_err(|e| HostError::input(val_path, e))?;
    let all = Rows::new(&rows.logits, k, &[], &rows.objectness).map_err(|e| fail(e.to_string()))?;
    let isotonic = baselines::score_isotonic(&iso, &all).map_err(|e| fail(e.to_string()))?;
    methods.push((Method::Isotonic, isotonic, None));
    for method in [Method::Ml, Method::Map, Method::Bayes, Method::Open] {
        let Some(head) = method.head() else { continue };
        if (head == Head::Bayes && table.bayes_head().is_none())
            || (head == Head::Open && table.open_params().is_none())
        {
            continue;
        }
        let mut scores = head_scores(table, head, val, val_path)?;
        if let Some((o, path)) = ood {
            scores.extend(head_scores(table, head, o, path)?);
        }
        methods.push((method, scores, None));
    }
    let mut out = Vec::with_capacity(methods.len());
    for (method, scores, known) in methods {
        let metrics = match known {
            Some(m) => m,
            None => rows.metrics(&scores, k, n_val, with_ood).map_err(&fail)?,
        };
        let chosen = method
            .head()
            .and_then(|h| result.candidates(h).first().copied());
        let excess = judge
            .guards
            .excess(metrics.accuracy, metrics.mean_ap(), &judge.reference);
        out.push(Compared {
            method,
            chosen,
            metrics,
            excess,
        });
    }
    let best = out
        .iter()
        .filter(|c| c.method.head().is_some() && c.excess == 0.0)
        .filter_map(|c| judge.objective.of(&c.metrics).map(|v| (c.method, v)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(m, _)| m);
    Ok(Comparison {
        rows: rows.labels.len(),
        ood_rows: ood.map(|(o, _)| o.len()),
        temperature: t,
        reference: judge.reference,
        methods: out,
        energy,
        best,
    })
}
