//! `mlmap.tune`: the search of `mlmap tune` on numpy arrays, and its report as a dict.

use super::*;

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

/// The keys of the comparison of `tune`, as the CLI's JSON report names them.
const COMPARED: [&str; 6] = ["ece", "nll", "brier", "accuracy", "mean_ap", "auroc"];

fn compared(m: &mlmap::host::metrics::Metrics, key: &str) -> Option<f64> {
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
    .filter(|v| v.is_finite())
}

/// The energy score's value of `key` in the comparison: its ranking metrics only.
fn energy_compared(r: &mlmap::host::eval::Ranking, key: &str) -> Option<f64> {
    match key {
        "auroc" => r.auroc,
        "ood_auroc" => r.ood_auroc,
        "ood_fpr95" => r.ood_fpr95,
        _ => None,
    }
    .filter(|v| v.is_finite())
}

/// `tune`'s report as a dict with the keys of `mlmap tune --format json`.
fn tune_report<'py>(
    py: Python<'py>,
    tuned: &host_tune::Tuned,
    params: &TuneParams,
    top: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("objective", params.objective.name())?;
    let counts = PyDict::new(py);
    for h in &tuned.result.heads {
        counts.set_item(h.head.name(), params.candidates(h.head))?;
    }
    out.set_item("candidates", counts)?;
    for h in &tuned.result.heads {
        let list = pyo3::types::PyList::empty(py);
        for (i, c) in h.candidates.iter().take(top).enumerate() {
            let d = PyDict::new(py);
            d.set_item("bins", c.bins)?;
            d.set_item("lambda", c.lambda)?;
            d.set_item("objective", Some(c.objective).filter(|v| v.is_finite()))?;
            d.set_item("ece", c.ece)?;
            d.set_item("nll", c.nll)?;
            d.set_item("brier", c.brier)?;
            d.set_item("accuracy", c.accuracy)?;
            d.set_item("mean_ap", c.mean_ap)?;
            d.set_item("within_guards", c.eligible())?;
            if let (Some(t), Some(e)) = (c.temperature, c.epsilon) {
                d.set_item("temperature", t)?;
                d.set_item("epsilon", e)?;
            }
            d.set_item("rank", i + 1)?;
            list.append(d)?;
        }
        out.set_item(h.head.name(), list)?;
    }
    let c = &tuned.comparison;
    let methods = PyDict::new(py);
    let mut keys = COMPARED.to_vec();
    if c.ood_rows.is_some() {
        keys.extend(["ood_mean", "ood_auroc", "ood_fpr95"]);
    }
    for m in &c.methods {
        let d = PyDict::new(py);
        for &key in &keys {
            d.set_item(key, compared(&m.metrics, key))?;
        }
        if let Some(ch) = &m.chosen {
            d.set_item("bins", ch.bins)?;
            d.set_item("lambda", ch.lambda)?;
            if let (Some(t), Some(e)) = (ch.temperature, ch.epsilon) {
                d.set_item("temperature", t)?;
                d.set_item("epsilon", e)?;
            }
            d.set_item("within_guards", m.excess == 0.0)?;
        }
        methods.set_item(m.method.name(), d)?;
    }
    let energy = PyDict::new(py);
    for &key in &keys {
        energy.set_item(key, energy_compared(&c.energy, key))?;
    }
    methods.set_item(mlmap::host::eval::Method::Energy.name(), energy)?;
    let v = PyDict::new(py);
    v.set_item("rows", c.rows)?;
    v.set_item("ood_rows", c.ood_rows)?;
    v.set_item("temperature", c.temperature)?;
    v.set_item("max_accuracy_loss", params.guards.max_accuracy_loss)?;
    v.set_item("max_map_loss", params.guards.max_map_loss)?;
    v.set_item("methods", methods)?;
    v.set_item("best", c.best.map(|m| m.name()))?;
    out.set_item("validation", v)?;
    if params.maps {
        let maps = PyDict::new(py);
        for m in &tuned.maps {
            let d = PyDict::new(py);
            d.set_item("kept", m.kept)?;
            d.set_item(
                "cv_ece_without",
                Some(m.ece_without).filter(|v| v.is_finite()),
            )?;
            d.set_item("cv_ece_with", Some(m.ece_with).filter(|v| v.is_finite()))?;
            d.set_item("within_guards", m.excess == 0.0)?;
            d.set_item("adds_no_loss", m.excess <= m.excess_without)?;
            // Lists `[x, y]`, as the JSON report has them.
            let knots: Vec<[f32; 2]> = m.knots.iter().map(|k| [k.x, k.y]).collect();
            d.set_item("knots", knots)?;
            maps.set_item(m.head.name(), d)?;
        }
        out.set_item("maps", maps)?;
    }
    Ok(out)
}
