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
    with_ood.extend(["ood_mean", "ood_over_0_9", "ood_auroc", "ood_fpr95"]);
    for (name, m) in methods_json.as_object().unwrap() {
        let mut want = with_ood.clone();
        if name == "temperature" {
            want.push("T");
        }
        assert_eq!(keys(m), sorted(&want), "{name}");
        for (key, value) in m.as_object().unwrap() {
            // The energy score is a ranking: its calibration metrics are null.
            if name == "energy" && !["auroc", "ood_auroc", "ood_fpr95"].contains(&key.as_str()) {
                assert!(value.is_null(), "energy.{key}: {value}");
                continue;
            }
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
        let plot = d.join(format!("plots/reliability_{method}.svg"));
        // The energy score is not a probability: no reliability diagram.
        assert_eq!(plot.is_file(), method != "energy", "{method}");
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

/// `test.csv` with a column `bucket` inserted after `label`: `id % 3` as `0`, `1`, `10`
/// (numbers, so `10` sorts last), and the same file for the validation rows.
fn with_bucket(src: &str, dst: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(src).unwrap();
    let mut out = String::new();
    let mut buckets = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let (id, rest) = line.split_once(',').unwrap();
        let (label, rest) = rest.split_once(',').unwrap();
        let bucket = if i == 0 {
            "bucket".to_string()
        } else {
            ["0", "1", "10"][id.parse::<usize>().unwrap() % 3].to_string()
        };
        out.push_str(&format!("{id},{label},{bucket},{rest}\n"));
        if i > 0 {
            buckets.push(bucket);
        }
    }
    std::fs::write(dst, out).unwrap();
    buckets
}

#[test]
fn eval_group_by_reports_every_metric_per_group() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = golden_table();
    let table = read_table(Path::new(&table_path));
    let test = d.join("test.csv");
    let buckets = with_bucket(&data("test"), &test);
    with_bucket(&data("val"), &d.join("val.csv"));
    let ood = data("ood");
    let args = |format: &'static str| {
        let mut a = eval_args(
            &table_path,
            "test.csv",
            &["--val", "val.csv", "--ood", &ood, "--group-by", "bucket"],
        );
        a.extend(["--format", format]);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let v = ok_json(d, &args("json"));
    assert_eq!(v["group_by"], "bucket");
    let groups = v["groups"].as_object().unwrap();
    assert_eq!(keys(&v["groups"]), ["0", "1", "10"]);
    // The whole set is as without --group-by (the column is not a class).
    let plain = ok_json(
        d,
        &eval_args(
            &table_path,
            &data("test"),
            &["--val", &data("val"), "--ood", &ood, "--format", "json"],
        ),
    );
    assert_eq!(v["methods"], plain["methods"]);
    // Each group's metrics are the metrics of its rows' layer scores, the
    // out-of-distribution ones against every never-seen row.
    let rows = rows_of(Path::new(&data("test")));
    let labels = class_labels(&rows);
    let ood_rows = rows_of(Path::new(&ood));
    for (value, g) in groups {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| buckets[i] == *value).collect();
        assert_eq!(g["rows"], idx.len());
        assert_eq!(keys(&g["methods"]), sorted(&methods(true, &table)));
        for head in heads_of(&table) {
            let all = head.flat_scores(&table, &rows);
            let scores: Vec<f64> = idx
                .iter()
                .flat_map(|&i| all[3 * i..3 * i + 3].to_vec())
                .collect();
            let g_labels: Vec<Option<usize>> = idx.iter().map(|&i| labels[i]).collect();
            let m = metrics::evaluate(&scores, 3, &g_labels, &MetricsConfig::default()).unwrap();
            let got = &g["methods"][head.name];
            let what = format!("{value}/{}", head.name);
            assert_eq!(got["ece"].as_f64(), Some(m.ece), "{what}");
            assert_eq!(got["auroc"].as_f64(), m.auroc, "{what}");
            assert_eq!(got["ap_car"].as_f64(), m.ap[0], "{what}");
            let known = metrics::known_confidences(&scores, 3, &g_labels);
            let unseen: Vec<f64> = head
                .flat_scores(&table, &ood_rows)
                .chunks(3)
                .map(|r| r.iter().copied().fold(0.0, f64::max))
                .collect();
            assert_eq!(
                got["ood_auroc"].as_f64(),
                metrics::separation_auroc(&known, &unseen),
                "{what}"
            );
            assert_eq!(
                got["ood_fpr95"].as_f64(),
                metrics::fpr_at_95_tpr(&known, &unseen),
                "{what}"
            );
        }
        assert!(g["methods"]["energy"]["ood_auroc"].as_f64().is_some());
        assert!(g["methods"]["energy"]["ece"].is_null());
    }

    // Text: the whole set's table, then one per group; markdown: one heading each.
    let run = ok(d, &args("text"));
    for value in ["0", "1", "10"] {
        assert!(
            run.stdout.contains(&format!("\nbucket = {value}: ")),
            "{}",
            run.stdout
        );
    }
    assert_eq!(run.stdout.matches("\nmetric ").count(), 4);
    let run = ok(d, &args("markdown"));
    assert_eq!(run.stdout.matches("\n### bucket = ").count(), 3);
    assert_eq!(run.stdout.matches("| metric |").count(), 4);

    // A test file without the column, an empty value, a reserved name: refused.
    refused(
        d,
        &eval_args(&table_path, &data("test"), &["--group-by", "bucket"]),
        &["column \"bucket\" (--group-by): has no such column"],
    );
    let text = std::fs::read_to_string(&test).unwrap();
    std::fs::write(d.join("empty.csv"), text.replacen(",1,", ",,", 1)).unwrap();
    refused(
        d,
        &eval_args(&table_path, "empty.csv", &["--group-by", "bucket"]),
        &["empty.csv:", "the group value is empty"],
    );
    refused(
        d,
        &eval_args(&table_path, "test.csv", &["--group-by", "label"]),
        &["--group-by \"label\""],
    );
}
