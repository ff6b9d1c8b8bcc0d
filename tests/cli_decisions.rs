//! Decisions on ties through the binary (DESIGN §1.7): a detection whose logits are
//! outside every histogram scores `OS / K` for every class under both heads, and its
//! predicted class is the one with the largest logit, in `apply`'s `*_pred` columns and
//! in `eval`'s `accuracy`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::Value;

/// The golden table: classes car, cyclist, pedestrian; every histogram's support lies
/// within [-7.1, 9.4], and no likelihood above the last edge (upper tail `zero`).
fn table() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/train_linspace.mlmap")
}

/// Rows 1, 2 and 4 have every logit outside every histogram (above the supports, or
/// below them); row 3 is an ordinary car. Without the tie rule all three would be
/// predicted `car` (the lowest index); with it they are cyclist (30 is the largest
/// logit), pedestrian (-10) and car (30), so rows 1, 2 and 3 are correct and row 4 is
/// not: accuracy 3 / 4 for both heads, 1 / 4 if ties went to the lowest index.
const DATA: &str = "\
id,label,objectness,car,cyclist,pedestrian
1,cyclist,0.9,20.0,30.0,25.0
2,pedestrian,0.6,-20.0,-30.0,-10.0
3,car,0.8,5.0,-5.0,-5.0
4,cyclist,0.5,30.0,10.0,20.0
";

fn mlmap(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_mlmap"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "mlmap {args:?}: {stderr}");
    String::from_utf8(out.stdout).unwrap()
}

fn setup() -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("rows.csv"), DATA).unwrap();
    (dir, table().to_str().unwrap().to_string())
}

#[test]
fn unknown_detections_score_os_over_k_and_go_to_the_largest_logit() {
    let (dir, table) = setup();
    let d = dir.path();
    mlmap(
        d,
        &[
            "apply", "--table", &table, "--input", "rows.csv", "-o", "out.csv",
        ],
    );
    let text = std::fs::read_to_string(d.join("out.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    for (row, os) in [(0, 0.9f32), (1, 0.6), (3, 0.5)] {
        for head in ["ml", "map"] {
            for class in ["car", "cyclist", "pedestrian"] {
                let got: f32 = rows[row][col(&format!("{head}_{class}"))].parse().unwrap();
                assert_eq!(got, os / 3.0, "row {row}, {head}_{class}");
            }
        }
    }
    for head in ["ml_pred", "map_pred"] {
        let preds: Vec<&str> = rows.iter().map(|r| r[col(head)]).collect();
        assert_eq!(preds, ["cyclist", "pedestrian", "car", "car"], "{head}");
    }
}

#[test]
fn accuracy_counts_the_decisions_of_the_tie_rule() {
    let (dir, table) = setup();
    let d = dir.path();
    let json = mlmap(
        d,
        &[
            "eval", "--table", &table, "--test", "rows.csv", "--format", "json",
        ],
    );
    let v: Value = serde_json::from_str(&json).unwrap();
    for head in ["ml", "map"] {
        let m = &v["methods"][head];
        assert_eq!(m["accuracy"].as_f64(), Some(0.75), "{head}");
        // Row 4 is the only false positive: fp_mean is its confidence, OS / K.
        assert_eq!(
            m["fp_mean"].as_f64(),
            Some(f64::from(0.5f32 / 3.0)),
            "{head}"
        );
        assert_eq!(m["fp_var"].as_f64(), Some(0.0), "{head}");
    }
    let text = mlmap(d, &["eval", "--table", &table, "--test", "rows.csv"]);
    let line = text
        .lines()
        .find(|l| l.starts_with("accuracy "))
        .unwrap_or_else(|| panic!("no accuracy row:\n{text}"));
    let values: Vec<&str> = line.split_whitespace().skip(1).collect();
    // sigmoid, softmax, energy (a ranking only: no accuracy), ml, map (no temperature
    // or isotonic regression without --val).
    assert_eq!(values.len(), 5, "{line}");
    assert_eq!(values[2], "-", "{line}");
    assert_eq!(&values[3..], ["0.7500", "0.7500"], "{line}");
    let md = mlmap(
        d,
        &[
            "eval", "--table", &table, "--test", "rows.csv", "--format", "markdown",
        ],
    );
    assert!(md.contains("| `accuracy` |"), "{md}");
}
