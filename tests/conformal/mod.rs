//! The conformal class sets (DESIGN §8) against the numpy reference
//! (tools/conformal_ref.py): thresholds, sets, coverage and the LAC baseline; the
//! section's checks; and the properties of the sets (coverage on exchangeable rows,
//! monotone in alpha, empty exactly when every score is below its threshold).

use std::path::Path;
use std::sync::OnceLock;

use mlmap::host::conformal::{
    coverage, evaluate, fit, scores, sets, softmax_scores, with_conformal, Fitted, Lac, Rows,
};
use mlmap::host::data::Loaded;
use mlmap::host::monitor::with_monitor;
use mlmap::host::DynTable;
use mlmap::{
    conformal_section_len, section_of, table_of, write_conformal_section, ConformalError,
    ConformalSpec, Head, InferError, MonitorParams, MonitorSpec, Table, Thresholds,
    CONFORMAL_MAGIC, FAST_MATH_MAX_SCORE_ERROR,
};
use proptest::prelude::*;
use serde_json::Value;

fn root(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn golden() -> &'static Value {
    static G: OnceLock<Value> = OnceLock::new();
    G.get_or_init(|| {
        let text = std::fs::read_to_string(root("tests/golden/conformal/reference.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    })
}

fn default_table() -> (DynTable, Vec<u8>) {
    let bytes = std::fs::read(root("tables/default.mlmap")).unwrap();
    (DynTable::from_bytes(&bytes).unwrap(), bytes)
}

struct Data {
    loaded: Loaded,
    labels: Vec<Option<usize>>,
}

fn data(name: &str) -> &'static Data {
    static CACHE: OnceLock<std::sync::Mutex<Vec<(String, &'static Data)>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let mut c = cache.lock().unwrap();
    if let Some((_, d)) = c.iter().find(|(n, _)| n == name) {
        return d;
    }
    let path = root(&format!("examples/data/{name}.csv"));
    let loaded = Loaded::read(&path).unwrap();
    let labels = loaded.class_labels(&path).unwrap();
    let d: &'static Data = Box::leak(Box::new(Data { loaded, labels }));
    c.push((name.to_string(), d));
    d
}

fn head_of(name: &str) -> Head {
    match name {
        "ml" => Head::Ml,
        "map" => Head::Map,
        "bayes" => Head::Bayes,
        "open" => Head::Open,
        _ => unreachable!(),
    }
}

/// The largest difference between the layer's `f32` score and the reference's `f64` one:
/// rounding for ML and MAP, the fast `exp` bound for the Bayes and open heads.
fn tolerance(head: Head) -> f64 {
    match head {
        Head::Ml | Head::Map => 2e-6,
        Head::Bayes | Head::Open => f64::from(FAST_MATH_MAX_SCORE_ERROR) + 2e-6,
    }
}

fn head_scores(table: &DynTable, head: Head, d: &Data) -> Vec<f32> {
    scores(
        table,
        head,
        &d.loaded.logits_f32(),
        &d.loaded.objectness_f32(),
    )
    .unwrap()
}

fn fitted(head: Head, alpha: f32, rows: Vec<u32>, thresholds: Vec<f32>) -> Fitted {
    Fitted {
        head,
        alpha,
        rows,
        thresholds,
    }
}

/// A table of the given classes without a Bayes head, fitted on a few rows (for the
/// shape only).
fn wide_table(names: &[String]) -> DynTable {
    use mlmap::host::dataset::Label;
    use mlmap::host::fit::{fit as fit_table, FitParams};
    let k = names.len();
    let mut rows = Loaded {
        classes: names.to_vec(),
        labels: Vec::new(),
        objectness: Vec::new(),
        logits: Vec::new(),
        locations: Vec::new(),
        has_labels: true,
        first_missing_label: None,
    };
    for r in 0..3 * k {
        rows.labels.push(Label::Class(r % k));
        rows.objectness.push(1.0);
        for c in 0..k {
            let d = r as f64 * 0.01;
            rows.logits
                .push(if c == r % k { 2.0 + d } else { -1.0 - d });
        }
    }
    let params = FitParams {
        bins_ml: 4,
        bins_map: 4,
        bayes: None,
        ..FitParams::default()
    };
    fit_table(&rows, &params).unwrap()
}

/// Thresholds, sets, coverage and the LAC baseline against the numpy reference
/// (tools/conformal_ref.py).
mod numpy;
/// Properties of the sets on exchangeable rows: coverage, monotone in alpha, empty
/// exactly when every score is below its threshold.
mod properties;
/// The conformal section: kept with the table and the other sections, every check of its
/// bytes, and the errors of the sets.
mod section;
