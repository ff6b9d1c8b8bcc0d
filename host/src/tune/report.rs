//! The report of a search as data: the object `mlmap tune --format json` prints (with
//! the written table added) and the dict `mlmap.tune` returns, built here once and
//! rendered by each.

use super::{Candidate, Comparison, TuneParams, Tuned};
use crate::eval::{Method, Ranking};
use crate::metrics::Metrics;
use crate::names::Named;

/// A value of a report: what JSON and Python both hold.
///
/// Numbers keep their type: [`ReportValue::Float`] is an `f64` the search computed,
/// [`ReportValue::Single`] an `f32` the table stores (a lambda, a temperature, a knot),
/// so each rendering writes it as it writes that type. Undefined metrics are
/// [`ReportValue::Null`]; a `Float` may still be NaN or infinite where the search
/// reports one (JSON writes `null`, Python a float).
#[derive(Debug, Clone, PartialEq)]
pub enum ReportValue {
    /// No value (`null`, `None`).
    Null,
    /// A truth value.
    Bool(bool),
    /// A count, a bin count or a rank.
    Int(u64),
    /// A metric or a bound, in `f64`.
    Float(f64),
    /// A parameter as the table stores it, in `f32`.
    Single(f32),
    /// A name.
    Text(String),
    /// A list.
    List(Vec<ReportValue>),
    /// Named values, in the order of the report (a JSON object, a dict).
    Map(Vec<(String, ReportValue)>),
}

impl ReportValue {
    /// A finite number, else [`ReportValue::Null`].
    pub fn finite(v: Option<f64>) -> Self {
        v.filter(|x| x.is_finite()).map_or(Self::Null, Self::Float)
    }
}

impl From<bool> for ReportValue {
    fn from(v: bool) -> Self {
        Self::Bool(v)
    }
}

impl From<usize> for ReportValue {
    fn from(v: usize) -> Self {
        Self::Int(u64::try_from(v).unwrap_or(u64::MAX))
    }
}

impl From<f64> for ReportValue {
    fn from(v: f64) -> Self {
        Self::Float(v)
    }
}

impl From<f32> for ReportValue {
    fn from(v: f32) -> Self {
        Self::Single(v)
    }
}

impl From<&str> for ReportValue {
    fn from(v: &str) -> Self {
        Self::Text(v.to_string())
    }
}

impl<T: Into<ReportValue>> From<Option<T>> for ReportValue {
    fn from(v: Option<T>) -> Self {
        v.map_or(Self::Null, Into::into)
    }
}

/// Named values built in order.
#[derive(Default)]
struct Entries(Vec<(String, ReportValue)>);

impl Entries {
    fn add(&mut self, key: &str, value: impl Into<ReportValue>) {
        self.0.push((key.to_string(), value.into()));
    }

    fn done(self) -> ReportValue {
        ReportValue::Map(self.0)
    }
}

/// The metrics of the comparison of every method, in report order.
pub const COMPARED: [&str; 6] = ["ece", "nll", "brier", "accuracy", "mean_ap", "auroc"];

/// The metrics of the comparison: [`COMPARED`], then `ood_mean`, `ood_auroc` and
/// `ood_fpr95` when never-seen objects were scored.
pub fn compared_keys(c: &Comparison) -> Vec<&'static str> {
    let mut keys = COMPARED.to_vec();
    if c.ood_rows.is_some() {
        keys.extend(["ood_mean", "ood_auroc", "ood_fpr95"]);
    }
    keys
}

/// The value of metric `key` (of [`compared_keys`]) of one method; `None` when
/// undefined or not a key.
pub fn compared_value(m: &Metrics, key: &str) -> Option<f64> {
    match key {
        "ece" => Some(m.ece),
        "nll" => m.nll,
        "brier" => Some(m.brier),
        "accuracy" => m.accuracy,
        "mean_ap" => m.mean_ap(),
        "auroc" => m.auroc,
        "ood_mean" => m.ood.map(|o| o.ood_mean),
        "ood_auroc" => m.ood.and_then(|o| o.auroc),
        "ood_fpr95" => m.ood.and_then(|o| o.fpr95),
        _ => None,
    }
}

/// The energy score's value of metric `key`: its ranking metrics only.
pub fn energy_value(r: &Ranking, key: &str) -> Option<f64> {
    match key {
        "auroc" => r.auroc,
        "ood_auroc" => r.ood_auroc,
        "ood_fpr95" => r.ood_fpr95,
        _ => None,
    }
}

/// One candidate of a head's list, ranked `rank` (1 the best).
fn candidate(c: &Candidate, rank: usize) -> ReportValue {
    let mut d = Entries::default();
    d.add("bins", c.bins);
    d.add("lambda", c.lambda);
    d.add("objective", ReportValue::finite(Some(c.objective)));
    d.add("ece", c.ece);
    d.add("nll", c.nll);
    d.add("brier", c.brier);
    d.add("accuracy", c.accuracy);
    d.add("mean_ap", c.mean_ap);
    d.add("within_guards", c.eligible());
    if let (Some(t), Some(e)) = (c.temperature, c.epsilon) {
        d.add("temperature", t);
        d.add("epsilon", e);
    }
    d.add("rank", rank);
    d.done()
}

/// The comparison on the validation rows: every method's metrics (and settings, for a
/// head), the energy score's, the temperature, the guards and the best head.
fn validation(c: &Comparison, params: &TuneParams) -> ReportValue {
    let keys = compared_keys(c);
    let mut methods = Entries::default();
    for m in &c.methods {
        let mut d = Entries::default();
        for &key in &keys {
            d.add(key, ReportValue::finite(compared_value(&m.metrics, key)));
        }
        if let Some(ch) = &m.chosen {
            d.add("bins", ch.bins);
            d.add("lambda", ch.lambda);
            if let (Some(t), Some(e)) = (ch.temperature, ch.epsilon) {
                d.add("temperature", t);
                d.add("epsilon", e);
            }
            d.add("within_guards", m.excess == 0.0);
        }
        methods.add(m.method.name(), d.done());
    }
    let mut energy = Entries::default();
    for &key in &keys {
        energy.add(key, ReportValue::finite(energy_value(&c.energy, key)));
    }
    methods.add(Method::Energy.name(), energy.done());
    let mut v = Entries::default();
    v.add("rows", c.rows);
    v.add("ood_rows", c.ood_rows);
    v.add("temperature", c.temperature);
    v.add("max_accuracy_loss", params.guards.max_accuracy_loss);
    v.add("max_map_loss", params.guards.max_map_loss);
    v.add("methods", methods.done());
    v.add("best", c.best.map(|m| m.name()));
    v.done()
}

/// The report of a search with `params`, each head's best `top` candidates listed:
/// `objective`, `candidates` (the number searched per head), one list per head,
/// `validation` (the comparison) and, when maps were fitted, `maps` (each head's
/// verdict on its recalibration map, DESIGN §1.9).
pub fn report(tuned: &Tuned, params: &TuneParams, top: usize) -> ReportValue {
    let mut out = Entries::default();
    out.add("objective", params.objective.name());
    let mut counts = Entries::default();
    for h in &tuned.result.heads {
        counts.add(h.head.name(), params.candidates(h.head));
    }
    out.add("candidates", counts.done());
    for h in &tuned.result.heads {
        let list = h
            .candidates
            .iter()
            .take(top)
            .enumerate()
            .map(|(i, c)| candidate(c, i + 1))
            .collect();
        out.add(h.head.name(), ReportValue::List(list));
    }
    out.add("validation", validation(&tuned.comparison, params));
    if params.maps {
        let mut maps = Entries::default();
        for m in &tuned.maps {
            let mut d = Entries::default();
            d.add("kept", m.kept);
            d.add("cv_ece_without", ReportValue::finite(Some(m.ece_without)));
            d.add("cv_ece_with", ReportValue::finite(Some(m.ece_with)));
            d.add("within_guards", m.excess == 0.0);
            d.add("adds_no_loss", m.excess <= m.excess_without);
            // Pairs `[x, y]`.
            let knots = m
                .knots
                .iter()
                .map(|k| ReportValue::List(vec![k.x.into(), k.y.into()]))
                .collect();
            d.add("knots", ReportValue::List(knots));
            maps.add(m.head.name(), d.done());
        }
        out.add("maps", maps.done());
    }
    out.done()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_their_type_and_undefined_is_null() {
        assert_eq!(ReportValue::finite(Some(f64::NAN)), ReportValue::Null);
        assert_eq!(ReportValue::finite(None), ReportValue::Null);
        assert_eq!(ReportValue::finite(Some(0.25)), ReportValue::Float(0.25));
        assert_eq!(ReportValue::from(0.1f32), ReportValue::Single(0.1));
        assert_eq!(ReportValue::from(Some(3usize)), ReportValue::Int(3));
        assert_eq!(ReportValue::from(None::<f64>), ReportValue::Null);
        // A non-finite metric stays a number where the search reports one.
        assert!(
            matches!(ReportValue::from(Some(f64::INFINITY)), ReportValue::Float(x) if x.is_infinite())
        );
    }

    #[test]
    fn entries_keep_their_order() {
        let mut d = Entries::default();
        d.add("b", true);
        d.add("a", "x");
        let ReportValue::Map(entries) = d.done() else {
            panic!("not a map");
        };
        let keys: Vec<&str> = entries.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(keys, ["b", "a"]);
    }
}
