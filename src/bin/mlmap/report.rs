//! Rendering an evaluation: one row per metric, one column per method, as aligned text,
//! JSON (DESIGN §4 keys) or markdown.

use std::fmt::Write as _;

/// Metrics of one method: `(key, value)` in a stable order; `None` when undefined.
pub struct MethodReport {
    /// `sigmoid`, `softmax`, `temperature`, `ml` or `map`.
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

fn fmt_value(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(v) if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e4) => format!("{v:.3e}"),
        Some(v) => format!("{v:.4}"),
    }
}

/// Aligned text, metrics as rows; the best value of the calibration metrics is marked.
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
