//! Rendering what the library computed: an evaluation (one row per metric, one column
//! per method, as aligned text, JSON with the DESIGN §4 keys, or markdown), the
//! candidates of a search, and a summary of a written table.

use std::fmt::Write as _;
use std::path::Path;

use mlmap::host::eval::{Evaluation, Method};
use mlmap::host::names::Named;
use mlmap::host::tune::{Comparison, Objective, TuneParams, TuneResult, Tuned};
use mlmap::host::DynTable;
use mlmap::Head;

use crate::args::Format;

mod tune;

pub use tune::{candidates, comparison, maps_text, tune_json};

/// Metrics of one method: `(key, value)` in a stable order; `None` when undefined.
pub struct MethodReport {
    /// The method's name.
    pub method: &'static str,
    /// `(metric key, value)` pairs.
    pub metrics: Vec<(String, Option<f64>)>,
}

/// The keys in first-seen order across methods.
fn keys(reports: &[MethodReport]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::new();
    for r in reports {
        for (k, _) in &r.metrics {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    keys
}

fn value(r: &MethodReport, key: &str) -> Option<f64> {
    r.metrics
        .iter()
        .find(|(k, _)| k == key)
        .and_then(|(_, v)| *v)
}

/// A value in four decimals, in scientific notation when tiny or huge, `-` when
/// undefined.
fn fmt_value(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(v) if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e4) => format!("{v:.3e}"),
        Some(v) => format!("{v:.4}"),
    }
}

/// Aligned text, metrics as rows, values as [`fmt_value`] writes them (no value is
/// marked).
pub fn text(reports: &[MethodReport]) -> String {
    let keys = keys(reports);
    let width = keys.iter().map(String::len).max().unwrap_or(6).max(6);
    let mut s = String::new();
    let _ = write!(s, "{:<width$}", "metric");
    for r in reports {
        let _ = write!(s, " {:>12}", r.method);
    }
    s.push('\n');
    for key in &keys {
        let _ = write!(s, "{key:<width$}");
        for r in reports {
            let _ = write!(s, " {:>12}", fmt_value(value(r, key)));
        }
        s.push('\n');
    }
    s
}

/// Markdown table, metrics as rows.
pub fn markdown(reports: &[MethodReport]) -> String {
    let keys = keys(reports);
    let mut s = String::from("| metric |");
    for r in reports {
        let _ = write!(s, " {} |", r.method);
    }
    s.push_str("\n|---|");
    for _ in reports {
        s.push_str("---:|");
    }
    s.push('\n');
    for key in &keys {
        let _ = write!(s, "| `{key}` |");
        for r in reports {
            let _ = write!(s, " {} |", fmt_value(value(r, key)));
        }
        s.push('\n');
    }
    s
}

/// `{"methods": {"sigmoid": {...}, ...}}` with null for undefined values.
pub fn json(reports: &[MethodReport], extra: serde_json::Value) -> serde_json::Value {
    let mut methods = serde_json::Map::new();
    for r in reports {
        let mut m = serde_json::Map::new();
        for (k, v) in &r.metrics {
            let v = v
                .filter(|v| v.is_finite())
                .map_or(serde_json::Value::Null, |v| serde_json::json!(v));
            m.insert(k.clone(), v);
        }
        methods.insert(r.method.to_string(), serde_json::Value::Object(m));
    }
    let mut top = serde_json::Map::new();
    top.insert("methods".into(), serde_json::Value::Object(methods));
    if let serde_json::Value::Object(extra) = extra {
        top.extend(extra);
    }
    serde_json::Value::Object(top)
}

/// The per-method reports of a set of columns.
fn reports_of(columns: Vec<mlmap::host::eval::Column>) -> Vec<MethodReport> {
    columns
        .into_iter()
        .map(|(method, metrics)| MethodReport {
            method: method.name(),
            metrics,
        })
        .collect()
}

/// An evaluation in `format`; with `group_by` (the column's name), each group's
/// metrics follow: one table per group in text and markdown, `"groups"` in JSON.
pub fn evaluation(ev: &Evaluation, format: Format, group_by: Option<&str>) -> String {
    let reports = reports_of(ev.columns());
    let config = &ev.config;
    let column = group_by.map(mlmap::host::escape::visible);
    let column = column.as_deref().unwrap_or("group");
    match format {
        Format::Text => {
            let mut s = String::new();
            let tp = ev.labelled();
            let _ = writeln!(
                s,
                "{} test rows ({} labelled with a class, {} background){}; ECE: {} bins, {} binning",
                ev.rows,
                tp,
                ev.rows - tp,
                ev.ood_rows.map_or(String::new(), |n| format!(", {n} out-of-distribution rows")),
                config.bins,
                config.binning.name(),
            );
            if let Some(t) = ev.temperature {
                let _ = writeln!(
                    s,
                    "temperature T = {:.4} (validation NLL {:.4})",
                    t.t, t.nll
                );
            }
            s.push('\n');
            s.push_str(&text(&reports));
            for g in &ev.groups {
                let _ = writeln!(
                    s,
                    "\n{column} = {}: {} test rows ({} labelled with a class, {} background)\n",
                    mlmap::host::escape::visible(&g.value),
                    g.rows,
                    g.labelled,
                    g.rows - g.labelled
                );
                s.push_str(&text(&reports_of(ev.group_columns(g))));
            }
            s
        }
        Format::Markdown => {
            let mut s = markdown(&reports);
            for g in &ev.groups {
                let _ = writeln!(
                    s,
                    "\n### {column} = {} ({} test rows, {} labelled with a class)\n",
                    mlmap::host::escape::visible(&g.value),
                    g.rows,
                    g.labelled
                );
                s.push_str(&markdown(&reports_of(ev.group_columns(g))));
            }
            s
        }
        Format::Json => {
            let mut extra = serde_json::json!({
                "rows": ev.rows,
                "ood_rows": ev.ood_rows,
                "classes": ev.class_names,
                "ece_bins": config.bins,
                "ece_binning": config.binning.name(),
            });
            if let (Some(o), Some(c)) = (extra.as_object_mut(), group_by) {
                let mut groups = serde_json::Map::new();
                for g in &ev.groups {
                    let counts = serde_json::json!({ "rows": g.rows, "labelled": g.labelled });
                    groups.insert(
                        g.value.clone(),
                        json(&reports_of(ev.group_columns(g)), counts),
                    );
                }
                o.insert("group_by".into(), c.into());
                o.insert("groups".into(), groups.into());
            }
            pretty(&json(&reports, extra))
        }
    }
}

/// Pretty JSON with a final newline.
fn pretty(v: &serde_json::Value) -> String {
    let mut s = serde_json::to_string_pretty(v).unwrap_or_default();
    s.push('\n');
    s
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.5}"))
}

/// A few lines describing a written table.
pub fn table_summary(path: &Path, table: &DynTable, size: usize) -> String {
    let st = table.settings();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wrote {} ({size} bytes): {} classes, edges {}, upper tail {}",
        path.display(),
        table.k(),
        st.edge_mode.name(),
        st.upper_tail.name()
    );
    let _ = writeln!(
        s,
        "  ML  {:>3} bins, lambda {:e}\n  MAP {:>3} bins, lambda {:e}",
        table.bins_ml(),
        st.lambda_ml,
        table.bins_map(),
        st.lambda_map
    );
    match table.bayes_head() {
        Some(b) => {
            let _ = writeln!(
                s,
                "  Bayes {:>3} bins, lambda {:e}, {} categories{}",
                b.bins(),
                b.lambda(),
                b.categories(),
                if b.objectness_axis().is_some() {
                    ", objectness feature"
                } else {
                    ""
                }
            );
        }
        None => {
            let _ = writeln!(s, "  Bayes none");
        }
    }
    match table.open_params() {
        Some(o) => {
            let _ = writeln!(
                s,
                "  open  temperature {}, epsilon {:e}",
                o.temperature(),
                o.epsilon()
            );
        }
        None => {
            let _ = writeln!(s, "  open  none");
        }
    }
    let maps: Vec<String> = [Head::Ml, Head::Map, Head::Bayes, Head::Open]
        .into_iter()
        .filter_map(|h| {
            table
                .recal_map(h)
                .map(|m| format!("{} ({} knots)", h.name(), m.knots().len()))
        })
        .collect();
    if !maps.is_empty() {
        let _ = writeln!(s, "  recalibration maps: {}", maps.join(", "));
    }
    let rows: Vec<String> = table
        .class_names()
        .zip(table.rows())
        .map(|(n, r)| format!("{} {r}", mlmap::host::escape::visible(n)))
        .collect();
    let _ = writeln!(s, "  training rows: {}", rows.join(", "));
    s
}
