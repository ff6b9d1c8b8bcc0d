use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use serde_json::Value;

use super::*;

#[test]
fn inspect_text_and_json() {
    let dir = tempdir();
    let d = dir.path();
    let path = golden_table();
    let table = read_table(Path::new(&path));
    let bytes = std::fs::read(&path).unwrap();
    let run = ok(d, &["inspect", &path]);
    let crc = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().unwrap());
    for line in [
        format!("table       {path}"),
        format!(
            "format      version {}, {} bytes, CRC-32 {crc:08x} (verified)",
            bytes[4],
            bytes.len()
        ),
        "classes     3: car, cyclist, pedestrian".to_string(),
        "edges       linspace, upper tail zero".to_string(),
        "ML head     22 bins, lambda 5.5e-3".to_string(),
        "MAP head    17 bins, lambda 1.2e-4".to_string(),
    ] {
        assert!(
            run.stdout.lines().any(|l| l == line),
            "no line {line:?}:\n{}",
            run.stdout
        );
    }
    for (name, rows) in CLASSES.iter().zip(table.rows()) {
        assert!(run.stdout.lines().any(|l| l
            .split_whitespace()
            .take(2)
            .eq([*name, rows.to_string().as_str()])));
    }
    assert!(!run.stdout.contains(" bin "));

    let run = ok(d, &["inspect", &path, "--bins"]);
    let bin_lines = run
        .stdout
        .lines()
        .filter(|l| l.trim_start().starts_with("bin "))
        .count();
    assert_eq!(bin_lines, 3 * (22 + 17));

    let v = ok_json(d, &["inspect", &path, "--format", "json"]);
    assert_eq!(v["crc_ok"], true);
    assert_eq!(v["bytes"], bytes.len());
    // The file's own version (the golden table is a version-1 file: ML and MAP only).
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["open"], Value::Null);
    assert_eq!(v["bins_ml"], 22);
    assert_eq!(v["bins_map"], 17);
    assert_eq!(v["edge_mode"], "linspace");
    assert_eq!(v["upper_tail"], "zero");
    assert_eq!(v["lambda_ml"].as_f64().unwrap() as f32, 0.0055f32);
    assert_eq!(v["lambda_map"].as_f64().unwrap() as f32, 0.00012f32);
    let classes = v["classes"].as_array().unwrap();
    assert_eq!(classes.len(), 3);
    for (i, c) in classes.iter().enumerate() {
        assert_eq!(c["name"], CLASSES[i]);
        assert_eq!(c["rows"], table.rows()[i]);
        let g = &table.priors()[i];
        assert_eq!(c["prior"]["mean"].as_f64().unwrap() as f32, g.mean());
        assert_eq!(
            c["prior"]["variance"].as_f64().unwrap() as f32,
            g.variance()
        );
        for (head, h) in [
            ("ml", &table.ml_histograms()[i]),
            ("map", &table.map_histograms()[i]),
        ] {
            let f32s = |v: &Value| -> Vec<f32> {
                v.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect()
            };
            let edges: Vec<f32> = (0..=h.bins()).map(|k| h.edge(k)).collect();
            assert_eq!(f32s(&c[head]["edges"]), edges);
            assert_eq!(f32s(&c[head]["frequencies"]), h.frequencies());
        }
    }
}

#[test]
fn a_closed_stdout_is_not_an_error() {
    let dir = tempdir();
    let d = dir.path();
    // A table whose `inspect --bins` report is far larger than a pipe's buffer.
    ok(
        d,
        &[
            "fit",
            "--train",
            &data("train"),
            "--bins-ml",
            "3000",
            "--bins-map",
            "3000",
            "-o",
            "big.mlmap",
        ],
    );
    let mut child = Command::new(env!("CARGO_BIN_EXE_mlmap"))
        .args(["inspect", "big.mlmap", "--bins"])
        .current_dir(d)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // `mlmap inspect big.mlmap --bins | head -1`
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert_eq!(first, "table       big.mlmap\n");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr, "");
}

#[test]
fn a_failing_stdout_is_an_internal_failure() {
    // Exit code 1: the machine failed (here, a full device), not the input.
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return; // No /dev/full on this system.
    };
    let out = Command::new(env!("CARGO_BIN_EXE_mlmap"))
        .args(["inspect", &golden_table()])
        .stdout(full)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.starts_with("mlmap: stdout: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn inspect_shows_the_bayes_head() {
    let dir = tempdir();
    let d = dir.path();
    let path = bayes_table();
    let t = read_table(Path::new(&path));
    let b = t.bayes_head().unwrap();
    let v = ok_json(d, &["inspect", &path, "--format", "json"]);
    let j = &v["bayes"];
    assert_eq!(j["bins"], 22);
    assert_eq!(j["lambda"].as_f64().unwrap() as f32, b.lambda());
    assert_eq!(j["background"], true);
    let cats = j["categories"].as_array().unwrap();
    let names: Vec<&str> = cats.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["car", "cyclist", "pedestrian", "background"]);
    let total: u64 = (0..4).map(|c| b.rows(c).unwrap()).sum();
    for (c, cat) in cats.iter().enumerate() {
        let rows = b.rows(c).unwrap();
        assert_eq!(cat["rows"], rows);
        let prior = cat["prior"].as_f64().unwrap();
        assert!((prior - rows as f64 / total as f64).abs() < 1e-12);
        // One histogram per logit, its frequencies summing to 1.
        let freqs = cat["frequencies"].as_array().unwrap();
        assert_eq!(freqs.len(), 3);
        for f in freqs {
            let f: Vec<f64> = f
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert_eq!(f.len(), 22);
            assert!((f.iter().sum::<f64>() - 1.0).abs() < 1e-4, "{f:?}");
        }
    }
    for (j, axis) in j["axes"].as_array().unwrap().iter().enumerate() {
        let edges = axis["edges"].as_array().unwrap();
        assert_eq!(edges.len(), 23);
        assert_eq!(edges[0].as_f64().unwrap() as f32, b.axis(j).unwrap().lo());
        assert_eq!(edges[22].as_f64().unwrap() as f32, b.axis(j).unwrap().hi());
    }

    let run = ok(d, &["inspect", &path]);
    assert!(run.stdout.contains(
        "Bayes head  22 bins per logit, lambda 1e-3, 4 categories (the classes and background)\n"
    ));
    // A sparkline per category and logit.
    let sparklines = run
        .stdout
        .lines()
        .filter(|l| l.starts_with("  ") && l.ends_with('|') && !l.contains('['))
        .count();
    assert_eq!(sparklines, 4 * 3, "{}", run.stdout);
    // A version-1 table has none.
    let run = ok(d, &["inspect", &golden_table()]);
    assert!(run.stdout.contains("\nBayes head  none\n"));
}

#[test]
fn inspect_shows_the_open_head() {
    let dir = tempdir();
    let d = dir.path();
    let path = bayes_table();
    let run = ok(d, &["inspect", &path]);
    assert!(
        run.stdout.contains("format      version 3, 1704 bytes"),
        "{}",
        run.stdout
    );
    assert!(
        run.stdout
            .lines()
            .any(|l| l.starts_with("open head   temperature 1, epsilon 0e0")),
        "{}",
        run.stdout
    );
    let v = ok_json(d, &["inspect", &path, "--format", "json"]);
    assert_eq!(v["format_version"], 3);
    assert_eq!(v["open"]["temperature"], 1.0);
    assert_eq!(v["open"]["epsilon"], 0.0);
    // A version-2 table (a Bayes head, no open head).
    let v2 = repo("tests/golden/layer/small_bayes.mlmap");
    let v = ok_json(d, &["inspect", v2.to_str().unwrap(), "--format", "json"]);
    assert_eq!(v["format_version"], 2);
    assert_eq!(v["open"], Value::Null);
    // The small open table: T = 1.75, epsilon = 0.05 as the reference encoder wrote them.
    let open = repo("tests/golden/layer/small_open.mlmap");
    let v = ok_json(d, &["inspect", open.to_str().unwrap(), "--format", "json"]);
    assert_eq!(v["open"]["temperature"].as_f64().unwrap() as f32, 1.75);
    assert_eq!(v["open"]["epsilon"].as_f64().unwrap() as f32, 0.05);
}
