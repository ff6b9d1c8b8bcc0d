//! `mlmap.tune`: the search of `mlmap tune` on numpy arrays, and its report as a dict.

use super::*;
use mlmap::host::tune::ReportValue;
use pyo3::types::{PyFloat, PyList, PyString};

/// Searches bins and lambdas of every head on validation data, as `mlmap tune` does;
/// returns `(table, report)`, the report a dict as `mlmap tune --format json` (without
/// the table's path). With the Bayes head, the open head's temperature is fitted by NLL
/// on the labelled validation rows and its `epsilon` searched on the grid of `mlmap
/// tune`; the report's `"open"` candidates and its `validation.methods.open` carry
/// both. `background` takes more training rows as background, as in `mlmap.fit`.
/// `maps=True` (the default) fits a recalibration map per head (DESIGN §1.9), kept
/// where it lowers the cross-fitted ECE within the guards; the report's `"maps"` gives
/// each head's verdict (`kept`, `cv_ece_without`, `cv_ece_with`, `within_guards`, `adds_no_loss`,
/// `knots`), as `mlmap tune --format json`. `maps=False` is `mlmap tune --no-maps`;
/// `objectness_feature=True` is `mlmap tune --objectness-feature` (DESIGN §1.6).
#[pyfunction]
#[pyo3(signature = (logits, labels, val, objectness=None, *, ood=None, background=None,
                    classes=None,
                    objective="ece", bins_ml=None, bins_map=None, bins_bayes=None,
                    bayes=true, lambda_min=1e-8, lambda_max=1.0,
                    lambdas_per_decade=Count::new(3),
                    lambda_bayes_min=None, lambda_bayes_max=None, max_accuracy_loss=0.005,
                    max_map_loss=0.01, edges="linspace", tail="zero", top=Count::new(5),
                    maps=true, objectness_feature=false),
    text_signature = "(logits, labels, val, objectness=None, *, ood=None, background=None, \
                      classes=None, \
                      objective='ece', bins_ml=None, bins_map=None, bins_bayes=None, \
                      bayes=True, lambda_min=1e-8, lambda_max=1.0, lambdas_per_decade=3, \
                      lambda_bayes_min=None, lambda_bayes_max=None, \
                      max_accuracy_loss=0.005, max_map_loss=0.01, edges='linspace', \
                      tail='zero', top=5, maps=True, objectness_feature=False)")]
#[allow(clippy::too_many_arguments)]
pub fn tune<'py>(
    py: Python<'py>,
    logits: &Bound<'py, PyAny>,
    labels: &Bound<'py, PyAny>,
    val: &Bound<'py, PyAny>,
    objectness: Option<&Bound<'py, PyAny>>,
    ood: Option<&Bound<'py, PyAny>>,
    background: Option<&Bound<'py, PyAny>>,
    classes: Option<Vec<String>>,
    objective: &str,
    bins_ml: Option<Vec<Count>>,
    bins_map: Option<Vec<Count>>,
    bins_bayes: Option<Vec<Count>>,
    bayes: bool,
    lambda_min: f64,
    lambda_max: f64,
    lambdas_per_decade: Count,
    lambda_bayes_min: Option<f64>,
    lambda_bayes_max: Option<f64>,
    max_accuracy_loss: f64,
    max_map_loss: f64,
    edges: &str,
    tail: &str,
    top: Count,
    maps: bool,
    objectness_feature: bool,
) -> PyResult<(PyTable, Bound<'py, PyDict>)> {
    let grid = |b: Option<Vec<Count>>, what: &str| -> PyResult<Vec<usize>> {
        let Some(b) = b else {
            return Ok((4..=40).collect());
        };
        let refuse = |got: &str| {
            value_error(format!(
                "{what}: bin counts must be in 1..=65535, at least one{got}"
            ))
        };
        if b.is_empty() {
            return Err(refuse(""));
        }
        b.iter()
            .map(|n| {
                n.value()
                    .filter(|v| (1..=MAX_BINS).contains(v))
                    .ok_or_else(|| refuse(&format!(" (got {})", n.text())))
            })
            .collect()
    };
    let lambdas_per_decade = lambdas_per_decade.get(
        "lambdas_per_decade",
        1..=MAX_LAMBDAS_PER_DECADE,
        "an integer from 1 to 1000",
    )?;
    let top = top.get("top", 0..=usize::MAX, "an integer >= 0")?;
    let lambdas = host_tune::lambda_grid(lambda_min, lambda_max, lambdas_per_decade)
        .map_err(|e| value_error(format!("lambda_min/lambda_max: {e}")))?;
    let bayes_grid = if bayes {
        let lambdas = host_tune::bayes_lambda_grid(
            lambda_bayes_min.unwrap_or(lambda_min),
            lambda_bayes_max.unwrap_or(lambda_max),
            lambdas_per_decade,
        )
        .map_err(|e| value_error(format!("lambda_bayes_min/lambda_bayes_max: {e}")))?;
        Some(BayesGrid {
            bins: grid(bins_bayes, "bins_bayes")?,
            lambdas,
            objectness: objectness_feature,
        })
    } else {
        None
    };
    let guards = Guards {
        max_accuracy_loss,
        max_map_loss,
    };
    guards.validate().map_err(|e| {
        value_error(
            e.replace("--max-accuracy-loss", "max_accuracy_loss")
                .replace("--max-map-loss", "max_map_loss"),
        )
    })?;
    let params = TuneParams {
        bins: vec![
            (Head::Ml, grid(bins_ml, "bins_ml")?),
            (Head::Map, grid(bins_map, "bins_map")?),
        ],
        lambdas,
        bayes: bayes_grid,
        epsilons: host_tune::epsilon_grid(),
        objective: Objective::from_name(objective).map_err(|e| value_error(e.to_string()))?,
        guards,
        edges: EdgeMode::from_name(edges).map_err(|e| value_error(e.to_string()))?,
        tail: UpperTail::from_name(tail).map_err(|e| value_error(e.to_string()))?,
        detail: top,
        maps,
    };
    params.check_size().map_err(value_error)?;
    let held = Held::new(logits, labels, objectness, classes, background)?;
    let src = held.sources()?;
    let names = held.classes.clone();
    let val = evaluate::data_set(&names, val, "val")?;
    let ood = ood
        .filter(|o| !o.is_none())
        .map(|o| evaluate::data_set(&names, o, "ood"))
        .transpose()?;
    let (val_path, ood_path) = (Path::new("val"), Path::new("ood"));
    let tuned = py.detach(|| -> PyResult<_> {
        let train = TrainingSet::read(&Chained(&src)).map_err(|e| fit_error(&e))?;
        host_tune::tune(
            &train,
            &val,
            val_path,
            ood.as_ref().map(|o| (o, ood_path)),
            &params,
            |_, _| {},
        )
        .map_err(|e| host_error(&e))
    })?;
    let report = tune_report(py, &tuned, &params, top)?;
    Ok((PyTable::new(tuned.table)?, report))
}

/// A value of the host's report as a Python object.
fn to_py<'py>(py: Python<'py>, v: &ReportValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        ReportValue::Null => py.None().into_bound(py),
        ReportValue::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        ReportValue::Int(n) => n.into_pyobject(py)?.into_any(),
        ReportValue::Float(x) => PyFloat::new(py, *x).into_any(),
        ReportValue::Single(x) => PyFloat::new(py, f64::from(*x)).into_any(),
        ReportValue::Text(t) => PyString::new(py, t).into_any(),
        ReportValue::List(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_py(py, item)?)?;
            }
            list.into_any()
        }
        ReportValue::Map(entries) => {
            let d = PyDict::new(py);
            for (key, value) in entries {
                d.set_item(key, to_py(py, value)?)?;
            }
            d.into_any()
        }
    })
}

/// `tune`'s report as a dict with the keys of `mlmap tune --format json` (the host's
/// report, without the table's path).
fn tune_report<'py>(
    py: Python<'py>,
    tuned: &host_tune::Tuned,
    params: &TuneParams,
    top: usize,
) -> PyResult<Bound<'py, PyDict>> {
    Ok(to_py(py, &host_tune::report(tuned, params, top))?.cast_into::<PyDict>()?)
}
