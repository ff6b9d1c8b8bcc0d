use std::path::Path;

use super::*;

/// Runs `apply --table TABLE --input INPUT -o OUTPUT` in `dir` and reads the output.
fn apply(dir: &Path, table: &str, input: &str, output: &str) -> (Vec<String>, Vec<Vec<String>>) {
    ok(dir, &apply_args(table, input, output));
    read_csv(&dir.join(output))
}

/// `prefix` (the carried-through columns), then [`score_columns`] of `table`.
fn columns(prefix: &[&str], table: &DynTable) -> Vec<String> {
    let mut want: Vec<String> = prefix.iter().map(|c| c.to_string()).collect();
    want.extend(score_columns(table));
    want
}

#[test]
fn apply_writes_the_design_columns_and_the_layer_scores() {
    // Version 1 (ML and MAP), version 2 (with the Bayes head, its columns after the
    // MAP ones) and version 3 (the open head's after the Bayes head's).
    let v2 = repo("tests/golden/layer/small_bayes.mlmap");
    for table_path in [golden_table(), bayes_table()] {
        apply_writes_the_design_columns(&table_path);
    }
    let table = read_table(Path::new(&bayes_table()));
    let header = columns(&[], &table);
    assert_eq!(
        header[6..9],
        ["bayes_car", "bayes_cyclist", "bayes_pedestrian"]
    );
    assert_eq!(
        header[9..12],
        ["open_car", "open_cyclist", "open_pedestrian"]
    );
    assert_eq!(
        header[12..],
        ["ml_pred", "map_pred", "bayes_pred", "open_pred"]
    );
    let table = read_table(&v2);
    assert!(!columns(&[], &table).iter().any(|c| c.starts_with("open")));
}

fn apply_writes_the_design_columns(table_path: &str) {
    let dir = tempdir();
    let d = dir.path();
    let table = read_table(Path::new(table_path));
    let input = data("val");
    ok(
        d,
        &[
            "apply", "--table", table_path, "--input", &input, "--output", "out.csv",
        ],
    );
    let (header, records) = read_csv(&d.join("out.csv"));
    assert_eq!(header, columns(&["id", "label"], &table));
    let rows = rows_of(Path::new(&input));
    check_scores(&table, &rows, &header, &records);
    // id and label are carried through as written.
    let mut src = csv::Reader::from_path(&input).unwrap();
    for (rec, orig) in records.iter().zip(src.records()) {
        let orig = orig.unwrap();
        assert_eq!((&rec[0][..], &rec[1][..]), (&orig[0], &orig[1]));
    }
}

#[test]
fn apply_omits_id_and_label_when_the_input_has_none() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = bayes_table();
    let table = read_table(Path::new(&table_path));
    write(
        d,
        "plain.csv",
        "objectness,car,cyclist,pedestrian\n0.9,4.1,-2.3,-1.7\n1,-30,40,0\n0,1,2,3\n",
    );
    write(
        d,
        "labelled.csv",
        "label,car,cyclist,pedestrian\ncar,4.1,-2.3,-1.7\n,1,2,3\nbackground,0,0,0\n",
    );
    let (header, records) = apply(d, &table_path, "plain.csv", "a.csv");
    assert_eq!(header, score_columns(&table));
    check_scores(&table, &rows_of(&d.join("plain.csv")), &header, &records);

    let (header, records) = apply(d, &table_path, "labelled.csv", "b.csv");
    assert_eq!(header, columns(&["label"], &table));
    let labels: Vec<&str> = records.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(labels, ["car", "", "background"]);
    check_scores(&table, &rows_of(&d.join("labelled.csv")), &header, &records);

    // A header without rows gives a header without rows.
    write(d, "none.csv", "car,cyclist,pedestrian\n");
    let (header, records) = apply(d, &table_path, "none.csv", "c.csv");
    assert_eq!(header, score_columns(&table));
    assert!(records.is_empty());
}

#[test]
fn apply_reads_npy_directories() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = golden_table();
    let table = read_table(Path::new(&table_path));

    // numpy-written, with labels and objectness.
    let npy = repo("tests/fixtures/npy_small");
    let (header, records) = apply(d, &table_path, &npy.to_string_lossy(), "a.csv");
    assert_eq!(header, columns(&["label"], &table));
    let labels: Vec<&str> = records.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        labels,
        ["car", "background", "cyclist", "pedestrian", "car"]
    );
    check_scores(&table, &rows_of(&npy), &header, &records);

    // npyz-written, logits only (float64), classes named.
    let only = d.join("logits_only");
    std::fs::create_dir(&only).unwrap();
    write_npy(
        &only.join("logits.npy"),
        &[3, 3],
        &[4.1f64, -2.3, -1.7, -1.0, 2.5, 0.5, 100.0, 100.0, 100.0],
    );
    write(&only, "classes.txt", "car\ncyclist\npedestrian\n");
    let (header, records) = apply(d, &table_path, "logits_only", "b.csv");
    assert_eq!(header, score_columns(&table));
    check_scores(&table, &rows_of(&only), &header, &records);
    // Logits outside every histogram: the "I don't know" answer, 1/3 each.
    let third: f32 = records[2][0].parse().unwrap();
    assert!((third - 1.0 / 3.0).abs() < 1e-6);
}

/// `apply`'s score columns against the independent numpy reference (not the library):
/// the shipped table on the test split, every row the golden file samples, each score
/// within `GOLDEN_ABS_TOL` of the float64 value.
#[test]
fn apply_scores_match_the_numpy_reference_on_the_test_split() {
    use crate::support::{goldens, GOLDEN_ABS_TOL, TEST_SPLIT_CSV};
    let dir = tempdir();
    let d = dir.path();
    let (header, records) = apply(d, &bayes_table(), &data("test"), "out.csv");
    let by_id: BTreeMap<&str, &Vec<String>> = records.iter().map(|r| (r[0].as_str(), r)).collect();
    let column = |name: String| header.iter().position(|h| *h == name).unwrap();
    let golden = goldens(TEST_SPLIT_CSV);
    assert_eq!(golden.len(), 500);
    let mut worst = 0.0f64;
    for g in &golden {
        let id = g
            .case
            .strip_prefix("id ")
            .expect("the case names the row's id");
        let rec = by_id[id];
        for (head, want) in [("ml", g.ml), ("map", g.map), ("bayes", g.bayes)] {
            let want = want.expect("scores for every row of the test split");
            for (c, w) in CLASSES.iter().zip(want) {
                let got: f32 = rec[column(format!("{head}_{c}"))].parse().unwrap();
                let err = (f64::from(got) - w).abs();
                worst = worst.max(err);
                assert!(
                    err <= GOLDEN_ABS_TOL,
                    "{head}_{c}, id {id}: got {got}, want {w}"
                );
            }
        }
    }
    eprintln!("apply, test split: worst score error {worst:e}");
}
