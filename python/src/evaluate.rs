//! `mlmap.evaluate`: the metrics of DESIGN §1.5 for every method, from numpy arrays,
//! through the library's `eval` pipeline (the numbers `mlmap eval` prints).

use std::path::Path;

use mlmap::host::data::Loaded;
use mlmap::host::dataset::{DataError, DataErrorKind, Label, Location};
use mlmap::host::eval::{self, Inputs};
use mlmap::host::metrics::{self, Binning, MetricsConfig};
use mlmap::host::names::Named;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use crate::arrays::{self, value_error, Rows};
use crate::errors::host_error;
use crate::table::PyTable;

/// Rows of one data set from arrays, checked as the data files are (DESIGN §2): finite
/// logits, labels `0..K-1` or `-1`, objectness in `[0, 1]`. `name` prefixes the
/// messages (`"logits"`, `"val.logits"`, ...).
pub fn loaded(
    classes: &[String],
    logits: &Bound<'_, PyAny>,
    labels: Option<&Bound<'_, PyAny>>,
    objectness: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<Loaded> {
    let what = |part: &str| {
        if name.is_empty() {
            part.to_string()
        } else {
            format!("{name}.{part}")
        }
    };
    let x = arrays::logits(logits, &what("logits"))?;
    let (n, k) = (x.rows, x.cols);
    if k != classes.len() {
        return Err(value_error(format!(
            "{}: has {k} columns but there are {} classes ({})",
            what("logits"),
            classes.len(),
            classes.join(", ")
        )));
    }
    if n == 0 {
        return Err(value_error(format!("{}: holds no rows", what("logits"))));
    }
    let mut values = Vec::with_capacity(n * k);
    match x.rows()? {
        Rows::F32(s) => values.extend(s.iter().map(|&v| f64::from(v))),
        Rows::F64(s) => values.extend_from_slice(s),
    }
    check_finite(&values, k, classes, &what("logits"))?;
    let os = arrays::objectness(objectness, &what("objectness"), n)?;
    let col = os.column()?;
    let labels = match labels {
        Some(l) if !l.is_none() => Some(arrays::labels(l, &what("labels"), n, k)?),
        _ => None,
    };
    Ok(Loaded {
        classes: classes.to_vec(),
        labels: match &labels {
            Some(l) => l
                .iter()
                .map(|&v| usize::try_from(v).map_or(Label::Background, Label::Class))
                .collect(),
            None => vec![Label::Missing; n],
        },
        objectness: (0..n).map(|i| col.get(i)).collect(),
        logits: values,
        locations: (0..n as u64).map(Location::Row).collect(),
        has_labels: labels.is_some(),
        first_missing_label: None,
    })
}

/// Refuses a NaN or infinite logit with the data files' message.
pub fn check_finite(values: &[f64], k: usize, classes: &[String], what: &str) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(p) => {
            let (row, col) = (p / k.max(1), p % k.max(1));
            let text = format!("{}", values.get(p).copied().unwrap_or(f64::NAN));
            let e = DataError::new(what, DataErrorKind::NotFinite { text })
                .at(Location::Row(row as u64))
                .in_column(classes.get(col).map_or("", String::as_str));
            Err(value_error(e.to_string()))
        }
    }
}

/// A data set given as a tuple `(logits, labels)` or `(logits, labels, objectness)`
/// (for the out-of-distribution set, labels may be `None`), or a bare logit array.
pub fn data_set(classes: &[String], obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Loaded> {
    let parts: Vec<Bound<'_, PyAny>> = if let Ok(t) = obj.cast::<PyTuple>() {
        t.iter().collect()
    } else if let Ok(l) = obj.cast::<PyList>() {
        // A list of arrays is a tuple too; a list of rows is one logit matrix.
        if l.len() <= 3
            && l.iter()
                .all(|p| p.hasattr("shape").unwrap_or(false) || p.is_none())
        {
            l.iter().collect()
        } else {
            vec![obj.clone()]
        }
    } else {
        vec![obj.clone()]
    };
    match parts.as_slice() {
        [x] => loaded(classes, x, None, None, name),
        [x, y] => loaded(classes, x, Some(y), None, name),
        [x, y, o] => loaded(classes, x, Some(y), Some(o), name),
        _ => Err(value_error(format!(
            "{name}: expected (logits, labels) or (logits, labels, objectness)"
        ))),
    }
}

/// Every method's metrics on a labelled test set (DESIGN §1.5), as `mlmap eval
/// --format json` reports them: `{"methods": {"sigmoid": {...}, ...}, "rows": ...,
/// "ood_rows": ..., "classes": [...], "ece_bins": ..., "ece_binning": ...}`.
///
/// `labels` are integers: `0..K-1` a class (the table's order), `-1` background (a
/// false positive of the detector). `val=(logits, labels[, objectness])` fits the
/// temperature baseline; `ood=logits` or `(logits, None, objectness)` adds the
/// never-seen objects' `ood_mean`, `ood_over_0_9`, `ood_auroc` and `ood_fpr95`.
/// `classes`, when given, must be the table's class names in order. `group_by`, one
/// value per test row (any objects, taken by `str()`), adds `"groups": {value:
/// {"methods": ..., "rows": ..., "labelled": ...}}`, as `mlmap eval --group-by`.
#[pyfunction]
#[pyo3(signature = (table, logits, labels, objectness=None, *, val=None, ood=None,
                    ece_bins=arrays::Count::new(10), ece_binning="design", classes=None,
                    group_by=None),
    text_signature = "(table, logits, labels, objectness=None, *, val=None, ood=None, \
                      ece_bins=10, ece_binning='design', classes=None, group_by=None)")]
#[allow(clippy::too_many_arguments)]
pub fn evaluate<'py>(
    py: Python<'py>,
    table: &Bound<'py, PyTable>,
    logits: &Bound<'py, PyAny>,
    labels: &Bound<'py, PyAny>,
    objectness: Option<&Bound<'py, PyAny>>,
    val: Option<&Bound<'py, PyAny>>,
    ood: Option<&Bound<'py, PyAny>>,
    ece_bins: arrays::Count,
    ece_binning: &str,
    classes: Option<Vec<String>>,
    group_by: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let t = &table.get().table;
    let names: Vec<String> = t.class_names().map(str::to_string).collect();
    let data_classes = classes.unwrap_or_else(|| names.clone());
    let expected = format!("an integer from 1 to {}", metrics::MAX_BINS);
    let ece_bins = ece_bins.get("ece_bins", 1..=metrics::MAX_BINS, &expected)?;
    let binning = Binning::from_name(ece_binning).map_err(|e| value_error(e.to_string()))?;
    let test = loaded(&data_classes, logits, Some(labels), objectness, "")?;
    let val = val
        .filter(|v| !v.is_none())
        .map(|v| data_set(&data_classes, v, "val"))
        .transpose()?;
    let ood = ood
        .filter(|v| !v.is_none())
        .map(|v| data_set(&data_classes, v, "ood"))
        .transpose()?;
    let groups = match group_by.filter(|g| !g.is_none()) {
        None => None,
        Some(g) => {
            let mut values = Vec::with_capacity(test.len());
            for item in g.try_iter()? {
                let text = item?.str()?.to_string();
                if text.is_empty() {
                    return Err(value_error(format!(
                        "group_by: row index {}: the group value is empty",
                        values.len()
                    )));
                }
                values.push(text);
            }
            if values.len() != test.len() {
                return Err(value_error(format!(
                    "group_by: has {} values but the logits have {} rows",
                    values.len(),
                    test.len()
                )));
            }
            Some(values)
        }
    };
    let (test_path, val_path, ood_path) = (Path::new("test"), Path::new("val"), Path::new("ood"));
    let inputs = Inputs {
        table: t,
        test: (&test, test_path),
        val: val.as_ref().map(|v| (v, val_path)),
        ood: ood.as_ref().map(|o| (o, ood_path)),
        config: MetricsConfig {
            bins: ece_bins,
            binning,
        },
        groups: groups.as_deref(),
    };
    let ev = py
        .detach(|| eval::evaluate(&inputs))
        .map_err(|e| host_error(&e))?;
    let columns = |cols: Vec<eval::Column>| -> PyResult<Bound<'py, PyDict>> {
        let methods = PyDict::new(py);
        for (method, entries) in cols {
            let m = PyDict::new(py);
            for (key, v) in entries {
                m.set_item(key, v.filter(|v| v.is_finite()))?;
            }
            methods.set_item(method.name(), m)?;
        }
        Ok(methods)
    };
    let out = PyDict::new(py);
    out.set_item("methods", columns(ev.columns())?)?;
    out.set_item("rows", ev.rows)?;
    out.set_item("ood_rows", ev.ood_rows)?;
    out.set_item("classes", ev.class_names.clone())?;
    out.set_item("ece_bins", ev.config.bins)?;
    out.set_item("ece_binning", ev.config.binning.name())?;
    if groups.is_some() {
        let all = PyDict::new(py);
        for g in &ev.groups {
            let d = PyDict::new(py);
            d.set_item("methods", columns(ev.group_columns(g))?)?;
            d.set_item("rows", g.rows)?;
            d.set_item("labelled", g.labelled)?;
            all.set_item(&g.value, d)?;
        }
        out.set_item("groups", all)?;
    }
    Ok(out)
}
