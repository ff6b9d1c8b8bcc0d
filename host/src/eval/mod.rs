//! `eval` as a whole (DESIGN §1.4, §1.5): every method's scores on a labelled test set
//! (and an out-of-distribution set), and every metric of each.
//!
//! The methods are the [`Method`]s: the baselines of [`baselines`]
//! and the heads of the layer, whose scores come from the table itself (through
//! [`DynTable`]), in `f32` as on the device.

use std::path::Path;

use super::baselines::{self, Baseline, Isotonic, Rows};
use super::data::{at, check_classes, Loaded};
use super::error::HostError;
use super::metrics::{self, Metrics, MetricsConfig};
use super::names::{Name, Named};
use super::DynTable;
use mlmap_core::Head;

mod results;

pub use results::{
    Column, EnergyResult, Evaluation, GroupResult, MethodResult, Ranking, Temperature,
};

/// A way of turning logits into scores, compared by `eval`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Method {
    /// `OS * sigma(x_i)`.
    Sigmoid,
    /// `OS * softmax(x)_i`.
    Softmax,
    /// `OS * softmax(x / T)_i`, `T` fitted on validation data.
    Temperature,
    /// `g_i(OS * softmax(x)_i)`, per-class isotonic maps fitted on validation data.
    Isotonic,
    /// The energy score `-logsumexp(x)`: a ranking of unknown objects, not a
    /// probability, so only its ranking metrics are reported.
    Energy,
    /// The layer's ML head.
    Ml,
    /// The layer's MAP head.
    Map,
    /// The layer's Bayes head (DESIGN §1.6), when the table has one.
    Bayes,
    /// The layer's open head (DESIGN §1.8), when the table has one.
    Open,
}

impl Named for Method {
    const WHAT: &'static str = "method";
    const NAMES: &'static [Name<Self>] = &[
        Name::new(
            Self::Sigmoid,
            "sigmoid",
            "OS times the sigmoid of each logit",
        ),
        Name::new(
            Self::Softmax,
            "softmax",
            "OS times the softmax of the logits",
        ),
        Name::new(
            Self::Temperature,
            "temperature",
            "OS times the softmax of the logits over a fitted temperature",
        ),
        Name::new(
            Self::Isotonic,
            "isotonic",
            "Per-class isotonic maps of the softmax scores, fitted on validation rows",
        ),
        Name::new(
            Self::Energy,
            "energy",
            "The energy score, a ranking of unknown objects (ranking metrics only)",
        ),
        Name::new(Self::Ml, "ml", "The layer's ML head"),
        Name::new(Self::Map, "map", "The layer's MAP head"),
        Name::new(Self::Bayes, "bayes", "The layer's Bayes head"),
        Name::new(Self::Open, "open", "The layer's open head"),
    ];
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Self; 9] = [
        Self::Sigmoid,
        Self::Softmax,
        Self::Temperature,
        Self::Isotonic,
        Self::Energy,
        Self::Ml,
        Self::Map,
        Self::Bayes,
        Self::Open,
    ];

    /// The layer head behind the method, if it is one.
    pub fn head(self) -> Option<Head> {
        match self {
            Self::Sigmoid | Self::Softmax | Self::Temperature | Self::Isotonic | Self::Energy => {
                None
            }
            Self::Ml => Some(Head::Ml),
            Self::Map => Some(Head::Map),
            Self::Bayes => Some(Head::Bayes),
            Self::Open => Some(Head::Open),
        }
    }

    /// Whether the method's values are a ranking, not probabilities (the energy
    /// score): only `auroc`, `ood_auroc` and `ood_fpr95` are defined for it.
    pub fn ranks_only(self) -> bool {
        self == Self::Energy
    }

    /// The name in prose: the baselines' names, the heads' titles (`ML`, `MAP`,
    /// `Bayes`).
    pub fn title(self) -> String {
        self.head()
            .map_or_else(|| self.name().to_string(), |h| h.to_string())
    }
}

crate::names::display_and_parse!(Method);

/// The scores of one head of `table` for every row of `data` (read from `path`),
/// through the layer in `f32`; `N x K`, row-major.
///
/// # Errors
///
/// [`HostError::Input`] naming the file and line of a row the layer refuses.
pub fn head_scores(
    table: &DynTable,
    head: Head,
    data: &Loaded,
    path: &Path,
) -> Result<Vec<f64>, HostError> {
    let k = table.k();
    let mut out = Vec::with_capacity(data.logits.len());
    // Scratch: K floats, or one per category for the Bayes head.
    let cats = table.bayes_head().map_or(k, |b| b.categories().max(k));
    let (mut x, mut s, mut scratch) = (vec![0f32; k], vec![0f32; k], vec![0f32; cats]);
    let view = table.view();
    let rows = data.logits.chunks_exact(k).zip(&data.objectness);
    for ((xs, &os), loc) in rows.zip(&data.locations) {
        for (d, &v) in x.iter_mut().zip(xs) {
            *d = v as f32;
        }
        // Each head with the device's default backend (`Table::ml`, `map`, `bayes`,
        // `open`).
        let scored = view.score_into(head, &x, os as f32, &mut s, &mut scratch);
        scored.map_err(|e| HostError::Input(format!("{}: {e}", at(path, *loc))))?;
        out.extend(s.iter().map(|&v| f64::from(v)));
    }
    Ok(out)
}

fn baseline(b: Baseline, d: &Loaded, k: usize, path: &Path) -> Result<Vec<f64>, HostError> {
    let rows =
        Rows::new(&d.logits, k, &[], &d.objectness).map_err(|e| HostError::input(path, e))?;
    baselines::score_rows(b, &rows).map_err(|e| HostError::input(path, e))
}

/// What [`evaluate`] fitted on the validation rows.
struct Fitted {
    temperature: Option<f64>,
    isotonic: Option<Isotonic>,
}

/// The scores of `method` on `data`; `None` for the baselines fitted on validation
/// rows without such rows, for the energy score (not a score in `[0, 1]`: see
/// [`EnergyResult`]), and for the Bayes or open head of a table without one.
fn method_scores(
    method: Method,
    table: &DynTable,
    fitted: &Fitted,
    data: &Loaded,
    path: &Path,
) -> Result<Option<Vec<f64>>, HostError> {
    let k = table.k();
    let b = match method {
        Method::Sigmoid => Baseline::Sigmoid,
        Method::Softmax => Baseline::Softmax,
        Method::Temperature => match fitted.temperature {
            Some(t) => Baseline::Temperature(t),
            None => return Ok(None),
        },
        Method::Isotonic => {
            let Some(iso) = &fitted.isotonic else {
                return Ok(None);
            };
            let rows = Rows::new(&data.logits, k, &[], &data.objectness)
                .map_err(|e| HostError::input(path, e))?;
            return baselines::score_isotonic(iso, &rows)
                .map(Some)
                .map_err(|e| HostError::input(path, e));
        }
        Method::Energy => return Ok(None),
        Method::Ml => return head_scores(table, Head::Ml, data, path).map(Some),
        Method::Map => return head_scores(table, Head::Map, data, path).map(Some),
        Method::Bayes if table.bayes_head().is_none() => return Ok(None),
        Method::Bayes => return head_scores(table, Head::Bayes, data, path).map(Some),
        Method::Open if table.open_params().is_none() => return Ok(None),
        Method::Open => return head_scores(table, Head::Open, data, path).map(Some),
    };
    baseline(b, data, k, path).map(Some)
}

/// The most distinct values `eval --group-by` accepts (DESIGN §4): more are refused,
/// as a column that is not a grouping (an identifier, a continuous value).
pub const MAX_GROUPS: usize = 1000;

/// The inputs of [`evaluate`]: a table, a labelled test set, and optionally a
/// labelled validation set (fits the temperature and the isotonic maps), an
/// out-of-distribution set and a group value per test row.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// The table.
    pub table: &'a DynTable,
    /// Test rows and their file.
    pub test: (&'a Loaded, &'a Path),
    /// Validation rows and their file.
    pub val: Option<(&'a Loaded, &'a Path)>,
    /// Out-of-distribution rows and their file.
    pub ood: Option<(&'a Loaded, &'a Path)>,
    /// ECE bins and binning.
    pub config: MetricsConfig,
    /// The group of each test row (`eval --group-by`), one per row: every metric is
    /// also computed per distinct value.
    pub groups: Option<&'a [String]>,
}

/// The rows `idx` of an `N x k` matrix.
fn pick(values: &[f64], k: usize, idx: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(idx.len() * k);
    for &i in idx {
        if let Some(row) = values.get(i * k..(i + 1) * k) {
            out.extend_from_slice(row);
        }
    }
    out
}

/// The metrics of one method on a set of rows, with the out-of-distribution ones
/// (the known rows of the set against every unseen row) when there are unseen rows.
fn set_metrics(
    scores: &[f64],
    logits: &[f64],
    labels: &[Option<usize>],
    ood: Option<&[f64]>,
    k: usize,
    config: &MetricsConfig,
) -> Result<Metrics, metrics::MetricsError> {
    let m = metrics::evaluate_with_logits(scores, logits, k, labels, config)?;
    match ood {
        Some(o) => {
            let known = metrics::known_confidences(scores, k, labels);
            Ok(m.with_ood(metrics::ood_metrics_against(o, k, &known)?))
        }
        None => Ok(m),
    }
}

/// The energy score's ranking metrics on a set of rows: `correct[i]` whether row `i`'s
/// decision (the largest logit) is its label.
fn energy_ranking(
    energy: &[f64],
    correct: &[bool],
    labels: &[Option<usize>],
    ood: Option<&[f64]>,
) -> Ranking {
    let split = |keep: &dyn Fn(usize) -> bool| -> Vec<f64> {
        energy
            .iter()
            .enumerate()
            .filter(|&(i, _)| keep(i))
            .map(|(_, &e)| e)
            .collect()
    };
    let tp = split(&|i| correct.get(i).copied().unwrap_or(false));
    let fp = split(&|i| !correct.get(i).copied().unwrap_or(false));
    let known = split(&|i| labels.get(i).is_some_and(Option::is_some));
    Ranking {
        auroc: metrics::separation_auroc(&tp, &fp),
        ood_auroc: ood.and_then(|o| metrics::separation_auroc(&known, o)),
        ood_fpr95: ood.and_then(|o| metrics::fpr_at_95_tpr(&known, o)),
    }
}

/// The distinct values of `groups` and the rows of each, in the order DESIGN §4 gives:
/// as numbers when every value is a finite number, else as text (byte order).
fn group_rows(groups: &[String]) -> Vec<(String, Vec<usize>)> {
    let mut map: std::collections::BTreeMap<&str, Vec<usize>> = std::collections::BTreeMap::new();
    for (i, g) in groups.iter().enumerate() {
        map.entry(g.as_str()).or_default().push(i);
    }
    let mut out: Vec<(String, Vec<usize>)> =
        map.into_iter().map(|(g, v)| (g.to_string(), v)).collect();
    let numbers: Option<Vec<f64>> = out
        .iter()
        .map(|(g, _)| g.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    if numbers.is_some() {
        out.sort_by(|a, b| {
            let (x, y) = (a.0.parse::<f64>(), b.0.parse::<f64>());
            match (x, y) {
                (Ok(x), Ok(y)) => x.total_cmp(&y).then_with(|| a.0.cmp(&b.0)),
                _ => a.0.cmp(&b.0),
            }
        });
    }
    out
}

/// Scores every method and computes every metric.
///
/// # Errors
///
/// [`HostError::Input`] naming the file at fault: classes that differ from the
/// table's, missing labels, a validation set the temperature cannot be fitted on, or
/// rows a method refuses; groups that are not one per test row, or more than
/// [`MAX_GROUPS`] of them.
pub fn evaluate(inp: &Inputs<'_>) -> Result<Evaluation, HostError> {
    let table = inp.table;
    let k = table.k();
    let (test, test_path) = inp.test;
    let names: Vec<String> = table.class_names().map(str::to_string).collect();
    check_classes(test_path, &test.classes, table.class_names())?;
    let labels = test.class_labels(test_path)?;
    let mut fitted = Fitted {
        temperature: None,
        isotonic: None,
    };
    let mut temperature = None;
    if let Some((val, path)) = inp.val {
        check_classes(path, &val.classes, table.class_names())?;
        let vlabels = val.class_labels(path)?;
        let rows = Rows::new(&val.logits, k, &vlabels, &val.objectness)
            .map_err(|e| HostError::input(path, e))?;
        let fit =
            baselines::fit_temperature_detailed(&rows).map_err(|e| HostError::input(path, e))?;
        temperature = Some(Temperature {
            t: fit.t,
            nll: fit.nll,
        });
        fitted.temperature = Some(fit.t);
        fitted.isotonic =
            Some(baselines::fit_isotonic(&rows).map_err(|e| HostError::input(path, e))?);
    }
    if let Some((ood, path)) = inp.ood {
        check_classes(path, &ood.classes, table.class_names())?;
    }
    let groups = match inp.groups {
        Some(g) if g.len() != test.len() => {
            return Err(HostError::input(
                test_path,
                format!("{} group values for {} rows", g.len(), test.len()),
            ))
        }
        Some(g) => {
            let rows = group_rows(g);
            if rows.len() > MAX_GROUPS {
                return Err(HostError::input(
                    test_path,
                    format!(
                        "the group column holds {} distinct values; at most {MAX_GROUPS} \
                         groups are reported",
                        rows.len()
                    ),
                ));
            }
            rows
        }
        None => Vec::new(),
    };
    let mut methods = Vec::new();
    for method in Method::ALL {
        let Some(scores) = method_scores(method, table, &fitted, test, test_path)? else {
            continue;
        };
        let ood = match inp.ood {
            Some((d, p)) => method_scores(method, table, &fitted, d, p)?,
            None => None,
        };
        let m = set_metrics(
            &scores,
            &test.logits,
            &labels,
            ood.as_deref(),
            k,
            &inp.config,
        )
        .map_err(|e| HostError::input(test_path, format!("{method}: {e}")))?;
        methods.push(MethodResult {
            method,
            test: scores,
            ood,
            metrics: m,
        });
    }
    // The energy score: ranked by its negative, split as softmax decides.
    let energy_of = |d: &Loaded, path: &Path| {
        let rows = Rows::new(&d.logits, k, &[], &[]).map_err(|e| HostError::input(path, e))?;
        baselines::negative_energies(&rows).map_err(|e| HostError::input(path, e))
    };
    let energy_test = energy_of(test, test_path)?;
    let energy_ood = inp.ood.map(|(d, p)| energy_of(d, p)).transpose()?;
    let softmax = methods
        .iter()
        .find(|r| r.method == Method::Softmax)
        .map(|r| r.test.as_slice())
        .unwrap_or_default();
    let correct: Vec<bool> = metrics::outcomes_with_logits(softmax, &test.logits, k, &labels)
        .map_err(|e| HostError::input(test_path, e))?
        .iter()
        .map(|o| o.correct)
        .collect();
    let energy = EnergyResult {
        ranking: energy_ranking(&energy_test, &correct, &labels, energy_ood.as_deref()),
        test: energy_test,
        ood: energy_ood,
    };
    let mut group_results = Vec::with_capacity(groups.len());
    for (value, idx) in groups {
        let g_labels: Vec<Option<usize>> = idx
            .iter()
            .map(|&i| labels.get(i).copied().flatten())
            .collect();
        let g_logits = pick(&test.logits, k, &idx);
        let mut g_methods = Vec::with_capacity(methods.len());
        for r in &methods {
            let m = set_metrics(
                &pick(&r.test, k, &idx),
                &g_logits,
                &g_labels,
                r.ood.as_deref(),
                k,
                &inp.config,
            )
            .map_err(|e| {
                HostError::input(test_path, format!("{}, group {value}: {e}", r.method))
            })?;
            g_methods.push((r.method, m));
        }
        let g_energy = pick(&energy.test, 1, &idx);
        let g_correct: Vec<bool> = idx
            .iter()
            .map(|&i| correct.get(i).copied().unwrap_or(false))
            .collect();
        group_results.push(GroupResult {
            labelled: g_labels.iter().flatten().count(),
            rows: idx.len(),
            energy: energy_ranking(&g_energy, &g_correct, &g_labels, energy.ood.as_deref()),
            methods: g_methods,
            value,
        });
    }
    Ok(Evaluation {
        class_names: names,
        labels,
        logits: test.logits.clone(),
        ood_logits: inp.ood.map(|(d, _)| d.logits.clone()),
        methods,
        energy,
        temperature,
        isotonic: fitted.isotonic,
        rows: test.len(),
        ood_rows: inp.ood.map(|(d, _)| d.len()),
        config: inp.config,
        groups: group_results,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_have_names_and_titles() {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(
            names,
            [
                "sigmoid",
                "softmax",
                "temperature",
                "isotonic",
                "energy",
                "ml",
                "map",
                "bayes",
                "open"
            ]
        );
        let titles: Vec<String> = Method::ALL.iter().map(|m| m.title()).collect();
        assert_eq!(
            titles,
            [
                "sigmoid",
                "softmax",
                "temperature",
                "isotonic",
                "energy",
                "ML",
                "MAP",
                "Bayes",
                "open"
            ]
        );
        assert_eq!("map".parse(), Ok(Method::Map));
        assert_eq!("bayes".parse(), Ok(Method::Bayes));
        assert!("softmax2".parse::<Method>().is_err());
        assert!(Method::Energy.ranks_only() && !Method::Isotonic.ranks_only());
    }

    #[test]
    fn groups_sort_as_numbers_or_as_text() {
        let g = |v: &[&str]| -> Vec<(String, Vec<usize>)> {
            group_rows(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>())
        };
        let got = g(&["10", "9", "10", "-1.5"]);
        let order: Vec<&str> = got.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(order, ["-1.5", "9", "10"]);
        assert_eq!(got[2].1, [0, 2]);
        let got = g(&["moderate", "easy", "10", "hard"]);
        let order: Vec<&str> = got.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(order, ["10", "easy", "hard", "moderate"]);
    }
}
