use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use mlmap::host::metrics::{self, MetricsConfig};

use super::*;

/// The metric keys of every method (DESIGN §1.5), without the out-of-distribution ones.
const METRIC_KEYS: [&str; 13] = [
    "ece",
    "mce",
    "nll",
    "brier",
    "tp_mean",
    "tp_var",
    "fp_mean",
    "fp_var",
    "auroc",
    "accuracy",
    "ap_car",
    "ap_cyclist",
    "ap_pedestrian",
];

#[test]
fn eval_json_has_the_design_keys_and_the_layer_metrics() {
    // Version 1 (ML and MAP), and version 2 with the Bayes head.
    for table_path in [golden_table(), bayes_table()] {
        eval_json_keys_and_metrics(&table_path);
    }
}

fn eval_json_keys_and_metrics(table_path: &str) {
    let dir = tempdir();
    let d = dir.path();
    let table = read_table(Path::new(table_path));
    let test = data("test");
    let (val, ood) = (data("val"), data("ood"));
    let v = ok_json(
        d,
        &eval_args(
            table_path,
            &test,
            &["--val", &val, "--ood", &ood, "--format", "json"],
        ),
    );
    let methods_json = &v["methods"];
    assert_eq!(keys(methods_json), sorted(&methods(true, &table)));
    let mut with_ood: Vec<&str> = METRIC_KEYS.to_vec();
    with_ood.extend(["ood_mean", "ood_over_0_9"]);
    for (name, m) in methods_json.as_object().unwrap() {
        let mut want = with_ood.clone();
        if name == "temperature" {
            want.push("T");
        }
        assert_eq!(keys(m), sorted(&want), "{name}");
        for (key, value) in m.as_object().unwrap() {
            let x = value
                .as_f64()
                .unwrap_or_else(|| panic!("{name}.{key}: {value}"));
            let range = match key.as_str() {
                "T" | "nll" => 0.0..=f64::MAX,
                // Sigmoid scores need not sum to 1: up to K.
                "brier" => 0.0..=3.0,
                _ => 0.0..=1.0,
            };
            assert!(range.contains(&x), "{name}.{key} = {x}");
        }
    }
    assert!(methods_json["temperature"]["T"].as_f64().unwrap() > 0.0);

    // Each head's metrics are the metrics of the layer's scores.
    let rows = rows_of(Path::new(&test));
    let labels = class_labels(&rows);
    for head in heads_of(&table) {
        let scores = head.flat_scores(&table, &rows);
        let m = metrics::evaluate(&scores, 3, &labels, &MetricsConfig::default()).unwrap();
        let (name, got) = (head.name, &methods_json[head.name]);
        assert_eq!(got["ece"].as_f64(), Some(m.ece), "{name}");
        assert_eq!(got["brier"].as_f64(), Some(m.brier), "{name}");
        assert_eq!(got["auroc"].as_f64(), m.auroc, "{name}");
        assert_eq!(got["ap_cyclist"].as_f64(), m.ap[1], "{name}");
    }
    assert_eq!(v["rows"], rows.len());
    assert_eq!(v["ood_rows"], 2000);

    // Without --val there is no temperature; without --ood no ood keys.
    let v = ok_json(d, &eval_args(table_path, &test, &["--format", "json"]));
    assert_eq!(keys(&v["methods"]), sorted(&methods(false, &table)));
    for m in v["methods"].as_object().unwrap().values() {
        assert_eq!(keys(m), sorted(&METRIC_KEYS));
    }
}

#[test]
fn eval_text_markdown_and_plots() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = bayes_table();
    let table = read_table(Path::new(&table_path));
    let (test, val) = (data("test"), data("val"));
    let run = ok(
        d,
        &eval_args(&table_path, &test, &["--val", &val, "--plots", "plots"]),
    );
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert!(
        lines[0].starts_with("10000 test rows (8000 labelled with a class, 2000 background)"),
        "{}",
        lines[0]
    );
    assert!(lines[1].starts_with("temperature T = "));
    let header: Vec<&str> = lines[3].split_whitespace().collect();
    let mut want = vec!["metric"];
    want.extend(methods(true, &table));
    assert_eq!(header, want);
    for key in METRIC_KEYS.iter().chain(&["T"]) {
        let row = lines
            .iter()
            .find(|l| l.split_whitespace().next() == Some(key))
            .unwrap_or_else(|| panic!("no row {key}:\n{}", run.stdout));
        assert_eq!(row.split_whitespace().count(), want.len(), "{row}");
    }
    // SVG plots: one reliability diagram per method, and more.
    let plots: Vec<PathBuf> = std::fs::read_dir(d.join("plots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(run
        .stdout
        .ends_with(&format!("\nwrote {} plots into plots\n", plots.len())));
    for method in methods(true, &table) {
        assert!(d.join(format!("plots/reliability_{method}.svg")).is_file());
    }
    for p in &plots {
        assert_eq!(p.extension(), Some(OsStr::new("svg")), "{}", p.display());
        let text = std::fs::read_to_string(p).unwrap();
        assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));
    }

    let run = ok(d, &eval_args(&table_path, &test, &["--format", "markdown"]));
    let lines: Vec<&str> = run.stdout.lines().collect();
    let columns = methods(false, &table);
    assert_eq!(lines[0], format!("| metric | {} |", columns.join(" | ")));
    assert_eq!(lines[1], format!("|---|{}", "---:|".repeat(columns.len())));
    assert_eq!(lines.len(), 2 + METRIC_KEYS.len());
    for (line, key) in lines[2..].iter().zip(METRIC_KEYS) {
        assert!(line.starts_with(&format!("| `{key}` |")), "{line}");
        assert_eq!(line.matches('|').count(), 2 + columns.len(), "{line}");
    }

    // The ECE conventions are selectable; the reports say which one was used.
    let v = ok_json(
        d,
        &eval_args(
            &table_path,
            &test,
            &[
                "--format",
                "json",
                "--ece-bins",
                "15",
                "--ece-binning",
                "torchmetrics",
            ],
        ),
    );
    assert_eq!(v["ece_bins"], 15);
    assert_eq!(v["ece_binning"], "torchmetrics");
}
