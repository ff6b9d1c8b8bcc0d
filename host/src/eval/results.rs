//! What [`evaluate`](super::evaluate) returns: every method's scores and metrics, the
//! energy ranking, the fitted temperature and the per-group results, and the columns of
//! the reports written from them.

use super::Method;
use crate::baselines::Isotonic;
use crate::error::HostError;
use crate::metrics::{self, Metrics, MetricsConfig};
use crate::tune::{Guards, Objective, Reference};

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

/// The ranking metrics of a method whose values are not probabilities (the energy
/// score, DESIGN §1.5); `None` when undefined.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Ranking {
    /// `auroc`: true positives (the decision of the largest logit is the label)
    /// against false positives.
    pub auroc: Option<f64>,
    /// `ood_auroc`: known test rows against out-of-distribution rows.
    pub ood_auroc: Option<f64>,
    /// `ood_fpr95`: the share of out-of-distribution rows at or above the value that
    /// keeps 95 % of the known test rows.
    pub ood_fpr95: Option<f64>,
}

/// The energy score of every row and its ranking metrics.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyResult {
    /// The negative energy `logsumexp(x)` of each test row (larger: more like a known
    /// object).
    pub test: Vec<f64>,
    /// The negative energy of each out-of-distribution row.
    pub ood: Option<Vec<f64>>,
    /// Its ranking metrics.
    pub ranking: Ranking,
}

/// A fitted temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Temperature {
    /// `T`.
    pub t: f64,
    /// The validation NLL at `T`.
    pub nll: f64,
}

/// Every metric of the test rows of one group value (`eval --group-by`).
#[derive(Debug, Clone, PartialEq)]
pub struct GroupResult {
    /// The group's value, as written in the data file.
    pub value: String,
    /// Number of test rows in the group.
    pub rows: usize,
    /// Number of them labelled with a class.
    pub labelled: usize,
    /// Each method's metrics on the group's rows (the out-of-distribution metrics
    /// against every out-of-distribution row), in [`Evaluation::methods`] order.
    pub methods: Vec<(Method, Metrics)>,
    /// The energy score's ranking metrics on the group's rows.
    pub energy: Ranking,
}

/// Everything [`evaluate`](super::evaluate) computes.
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
    /// Every method with scores in `[0, 1]` evaluated, in [`Method::ALL`] order
    /// (temperature and isotonic only with a validation set, Bayes and open only when
    /// the table has that head).
    pub methods: Vec<MethodResult>,
    /// The energy score.
    pub energy: EnergyResult,
    /// The fitted temperature, with a validation set.
    pub temperature: Option<Temperature>,
    /// The fitted isotonic maps, with a validation set.
    pub isotonic: Option<Isotonic>,
    /// Number of test rows.
    pub rows: usize,
    /// Number of out-of-distribution rows.
    pub ood_rows: Option<usize>,
    /// ECE bins and binning.
    pub config: MetricsConfig,
    /// The metrics per group value, with groups: in the order of the values, as
    /// numbers when every value is one, else as text.
    pub groups: Vec<GroupResult>,
}

/// One column of a report: a method and its `(key, value)` pairs, in report order.
pub type Column = (Method, Vec<(String, Option<f64>)>);

impl Evaluation {
    /// Number of test rows labelled with a class.
    pub fn labelled(&self) -> usize {
        self.labels.iter().filter(|l| l.is_some()).count()
    }

    /// The metrics of `r` as `(key, value)`, in report order: [`Metrics::entries`],
    /// then `T` for the temperature baseline.
    pub fn entries(&self, r: &MethodResult) -> Vec<(String, Option<f64>)> {
        self.entries_of(r.method, &r.metrics)
    }

    fn entries_of(&self, method: Method, m: &Metrics) -> Vec<(String, Option<f64>)> {
        let mut entries = m.entries(&self.class_names);
        if let (Method::Temperature, Some(t)) = (method, self.temperature) {
            entries.push(("T".into(), Some(t.t)));
        }
        entries
    }

    /// The columns of a report from the methods' metrics and the energy score's
    /// ranking, in [`Method::ALL`] order: the energy score has every key of the others
    /// (except `T`), `null` but for `auroc`, `ood_auroc` and `ood_fpr95`.
    fn columns_of(&self, methods: &[(Method, &Metrics)], energy: &Ranking) -> Vec<Column> {
        let mut out: Vec<Column> = Vec::with_capacity(methods.len() + 1);
        for &(method, m) in methods {
            if method > Method::Energy && !out.iter().any(|c| c.0 == Method::Energy) {
                out.push((Method::Energy, Vec::new()));
            }
            out.push((method, self.entries_of(method, m)));
        }
        if !out.iter().any(|c| c.0 == Method::Energy) {
            out.push((Method::Energy, Vec::new()));
        }
        let keys: Vec<String> = methods
            .first()
            .map(|(_, m)| m.entries(&self.class_names))
            .unwrap_or_default()
            .into_iter()
            .map(|(k, _)| k)
            .collect();
        if let Some(col) = out.iter_mut().find(|c| c.0 == Method::Energy) {
            col.1 = keys
                .into_iter()
                .map(|key| {
                    let v = match key.as_str() {
                        "auroc" => energy.auroc,
                        "ood_auroc" => energy.ood_auroc,
                        "ood_fpr95" => energy.ood_fpr95,
                        _ => None,
                    };
                    (key, v)
                })
                .collect();
        }
        out
    }

    /// Every method's `(key, value)` pairs on the whole test set, in [`Method::ALL`]
    /// order, the energy score included.
    pub fn columns(&self) -> Vec<Column> {
        let methods: Vec<(Method, &Metrics)> = self
            .methods
            .iter()
            .map(|r| (r.method, &r.metrics))
            .collect();
        self.columns_of(&methods, &self.energy.ranking)
    }

    /// As [`columns`](Self::columns), on the rows of one group.
    pub fn group_columns(&self, g: &GroupResult) -> Vec<Column> {
        let methods: Vec<(Method, &Metrics)> = g.methods.iter().map(|(m, x)| (*m, x)).collect();
        self.columns_of(&methods, &g.energy)
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
            .map_err(|e| HostError::Input(format!("{}: {e}", r.method)))
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

    /// The value of metric `key` of `method` on the whole test set; `None` when
    /// undefined or absent.
    pub fn value(&self, method: Method, key: &str) -> Option<f64> {
        self.columns()
            .into_iter()
            .find(|c| c.0 == method)?
            .1
            .into_iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v)
    }
}
