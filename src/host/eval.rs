//! `eval` as a whole (DESIGN §1.4, §1.5): every method's scores on a labelled test set
//! (and an out-of-distribution set), and every metric of each.
//!
//! The methods are the [`Method`]s: the baselines of [`baselines`]
//! and the heads of the layer, whose scores come from the table itself (through
//! [`DynTable`]), in `f32` as on the device.

use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

use super::baselines::{self, Baseline, Rows};
use super::data::{at, check_classes, Loaded};
use super::error::HostError;
use super::metrics::{self, Metrics, MetricsConfig};
use super::names::{Name, Named};
use super::tune::{Guards, Objective, Reference};
use super::DynTable;
use crate::Head;

/// A way of turning logits into scores, compared by `eval`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// `OS * sigma(x_i)`.
    Sigmoid,
    /// `OS * softmax(x)_i`.
    Softmax,
    /// `OS * softmax(x / T)_i`, `T` fitted on validation data.
    Temperature,
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
        Name::new(Self::Ml, "ml", "The layer's ML head"),
        Name::new(Self::Map, "map", "The layer's MAP head"),
        Name::new(Self::Bayes, "bayes", "The layer's Bayes head"),
        Name::new(Self::Open, "open", "The layer's open head"),
    ];
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Self; 7] = [
        Self::Sigmoid,
        Self::Softmax,
        Self::Temperature,
        Self::Ml,
        Self::Map,
        Self::Bayes,
        Self::Open,
    ];

    /// The layer head behind the method, if it is one.
    pub fn head(self) -> Option<Head> {
        match self {
            Self::Sigmoid | Self::Softmax | Self::Temperature => None,
            Self::Ml => Some(Head::Ml),
            Self::Map => Some(Head::Map),
            Self::Bayes => Some(Head::Bayes),
            Self::Open => Some(Head::Open),
        }
    }

    /// The name in prose: the baselines' names, the heads' titles (`ML`, `MAP`,
    /// `Bayes`).
    pub fn title(self) -> String {
        self.head()
            .map_or_else(|| self.name().to_string(), |h| h.to_string())
    }
}

crate::host::names::display_and_parse!(Method);

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
    let cats = table.bayes().map_or(k, |b| b.categories().max(k));
    let (mut x, mut s, mut scratch) = (
        std::vec![0f32; k],
        std::vec![0f32; k],
        std::vec![0f32; cats],
    );
    let view = table.view();
    let rows = data.logits.chunks_exact(k).zip(&data.objectness);
    for ((xs, &os), loc) in rows.zip(&data.locations) {
        for (d, &v) in x.iter_mut().zip(xs) {
            *d = v as f32;
        }
        // Each head with the device's default backend (`Table::ml`, `map`, `bayes`,
        // `open`).
        let scored = view.score_into(head, &x, os as f32, &mut s, &mut scratch);
        scored.map_err(|e| HostError::Input(std::format!("{}: {e}", at(path, *loc))))?;
        out.extend(s.iter().map(|&v| f64::from(v)));
    }
    Ok(out)
}

fn baseline(b: Baseline, d: &Loaded, k: usize, path: &Path) -> Result<Vec<f64>, HostError> {
    let rows =
        Rows::new(&d.logits, k, &[], &d.objectness).map_err(|e| HostError::input(path, e))?;
    baselines::score_rows(b, &rows).map_err(|e| HostError::input(path, e))
}

/// The scores of `method` on `data`; `None` for the temperature baseline without a
/// fitted temperature and for the Bayes or open head of a table without one.
fn method_scores(
    method: Method,
    table: &DynTable,
    temperature: Option<f64>,
    data: &Loaded,
    path: &Path,
) -> Result<Option<Vec<f64>>, HostError> {
    let k = table.k();
    let b = match method {
        Method::Sigmoid => Baseline::Sigmoid,
        Method::Softmax => Baseline::Softmax,
        Method::Temperature => match temperature {
            Some(t) => Baseline::Temperature(t),
            None => return Ok(None),
        },
        Method::Ml => return head_scores(table, Head::Ml, data, path).map(Some),
        Method::Map => return head_scores(table, Head::Map, data, path).map(Some),
        Method::Bayes if table.bayes().is_none() => return Ok(None),
        Method::Bayes => return head_scores(table, Head::Bayes, data, path).map(Some),
        Method::Open if table.open().is_none() => return Ok(None),
        Method::Open => return head_scores(table, Head::Open, data, path).map(Some),
    };
    baseline(b, data, k, path).map(Some)
}

/// The inputs of [`evaluate`]: a table, a labelled test set, and optionally a
/// labelled validation set (fits the temperature) and an out-of-distribution set.
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
}

/// One method's scores and metrics.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodResult {
    /// The method.
    pub method: Method,
    /// Its scores of the test rows: `N x K`, row-major.
    pub test: Vec<f64>,
    /// Its scores of the out-of-distribution rows.
    pub ood: Option<Vec<f64>>,
    /// Its metrics (with the out-of-distribution ones when there is such a set).
    pub metrics: Metrics,
}

/// A fitted temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Temperature {
    /// `T`.
    pub t: f64,
    /// The validation NLL at `T`.
    pub nll: f64,
}

/// Everything [`evaluate`] computes.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// The table's class names.
    pub class_names: Vec<String>,
    /// The test labels.
    pub labels: Vec<Option<usize>>,
    /// The test logits (`N x K`), which decide ties (DESIGN §1.7).
    pub logits: Vec<f64>,
    /// The out-of-distribution logits, with such a set.
    pub ood_logits: Option<Vec<f64>>,
    /// Every method evaluated, in [`Method::ALL`] order (temperature only with a
    /// validation set, Bayes only when the table has that head).
    pub methods: Vec<MethodResult>,
    /// The fitted temperature, with a validation set.
    pub temperature: Option<Temperature>,
    /// Number of test rows.
    pub rows: usize,
    /// Number of out-of-distribution rows.
    pub ood_rows: Option<usize>,
    /// ECE bins and binning.
    pub config: MetricsConfig,
}

impl Evaluation {
    /// Number of test rows labelled with a class.
    pub fn labelled(&self) -> usize {
        self.labels.iter().filter(|l| l.is_some()).count()
    }

    /// The metrics of `r` as `(key, value)`, in report order: [`Metrics::entries`],
    /// then `T` for the temperature baseline.
    pub fn entries(&self, r: &MethodResult) -> Vec<(String, Option<f64>)> {
        let mut entries = r.metrics.entries(&self.class_names);
        if let (Method::Temperature, Some(t)) = (r.method, self.temperature) {
            entries.push(("T".into(), Some(t.t)));
        }
        entries
    }

    /// Every metric of `r` on the test rows and the out-of-distribution rows together,
    /// the latter as background (label none), so that confident scores on never-seen
    /// objects count against calibration and ranking; the test rows alone without
    /// such a set.
    ///
    /// # Errors
    ///
    /// [`HostError::Input`] when the scores do not describe the rows.
    pub fn with_unseen(&self, r: &MethodResult) -> Result<Metrics, HostError> {
        let k = self.class_names.len();
        let (mut scores, mut logits, mut labels) =
            (r.test.clone(), self.logits.clone(), self.labels.clone());
        if let (Some(o), Some(x)) = (&r.ood, &self.ood_logits) {
            scores.extend_from_slice(o);
            logits.extend_from_slice(x);
            labels.extend(std::iter::repeat_n(None, o.len() / k.max(1)));
        }
        metrics::evaluate_with_logits(&scores, &logits, k, &labels, &self.config)
            .map_err(|e| HostError::Input(std::format!("{}: {e}", r.method)))
    }

    /// The head to ship: among the heads whose accuracy and mAP on test + unseen
    /// ([`with_unseen`](Self::with_unseen)) lose no more than `guards` allow against
    /// softmax's, the one with the best `objective` there; `None` when no head is
    /// within the guards.
    ///
    /// # Errors
    ///
    /// As [`with_unseen`](Self::with_unseen).
    pub fn best_head(
        &self,
        objective: Objective,
        guards: &Guards,
    ) -> Result<Option<(Method, Metrics)>, HostError> {
        let Some(softmax) = self.methods.iter().find(|r| r.method == Method::Softmax) else {
            return Ok(None);
        };
        let softmax = self.with_unseen(softmax)?;
        let reference = Reference {
            accuracy: softmax.accuracy,
            mean_ap: softmax.mean_ap(),
        };
        let mut best: Option<(Method, Metrics, f64)> = None;
        for r in self.methods.iter().filter(|r| r.method.head().is_some()) {
            let m = self.with_unseen(r)?;
            if guards.excess(m.accuracy, m.mean_ap(), &reference) > 0.0 {
                continue;
            }
            let Some(v) = objective.of(&m) else { continue };
            if best.as_ref().is_none_or(|b| v < b.2) {
                best = Some((r.method, m, v));
            }
        }
        Ok(best.map(|(method, m, _)| (method, m)))
    }

    /// The value of metric `key` of `method`; `None` when undefined or absent.
    pub fn value(&self, method: Method, key: &str) -> Option<f64> {
        let r = self.methods.iter().find(|r| r.method == method)?;
        self.entries(r)
            .into_iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v)
    }
}

/// Scores every method and computes every metric.
///
/// # Errors
///
/// [`HostError::Input`] naming the file at fault: classes that differ from the
/// table's, missing labels, a validation set the temperature cannot be fitted on, or
/// rows a method refuses.
pub fn evaluate(inp: &Inputs<'_>) -> Result<Evaluation, HostError> {
    let table = inp.table;
    let k = table.k();
    let (test, test_path) = inp.test;
    let names: Vec<String> = table.class_names().map(str::to_string).collect();
    check_classes(test_path, &test.classes, table.class_names())?;
    let labels = test.class_labels(test_path)?;
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
    }
    if let Some((ood, path)) = inp.ood {
        check_classes(path, &ood.classes, table.class_names())?;
    }
    let t = temperature.map(|t| t.t);
    let mut methods = Vec::new();
    for method in Method::ALL {
        let Some(scores) = method_scores(method, table, t, test, test_path)? else {
            continue;
        };
        let ood = match inp.ood {
            Some((d, p)) => method_scores(method, table, t, d, p)?,
            None => None,
        };
        let mut m = metrics::evaluate_with_logits(&scores, &test.logits, k, &labels, &inp.config)
            .map_err(|e| HostError::input(test_path, std::format!("{method}: {e}")))?;
        if let (Some(o), Some((_, path))) = (&ood, inp.ood) {
            m = m.with_ood(
                metrics::ood_metrics(o, k)
                    .map_err(|e| HostError::input(path, std::format!("{method}: {e}")))?,
            );
        }
        methods.push(MethodResult {
            method,
            test: scores,
            ood,
            metrics: m,
        });
    }
    Ok(Evaluation {
        class_names: names,
        labels,
        logits: test.logits.clone(),
        ood_logits: inp.ood.map(|(d, _)| d.logits.clone()),
        methods,
        temperature,
        rows: test.len(),
        ood_rows: inp.ood.map(|(d, _)| d.len()),
        config: inp.config,
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
                "ML",
                "MAP",
                "Bayes",
                "open"
            ]
        );
        assert_eq!("map".parse(), Ok(Method::Map));
        assert_eq!("bayes".parse(), Ok(Method::Bayes));
        assert!("softmax2".parse::<Method>().is_err());
    }
}
