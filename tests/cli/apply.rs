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

/// One array of an NPY output: its type string, shape and values.
fn read_npy<T: npyz::Deserialize>(path: &Path) -> (String, Vec<u64>, Vec<T>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    let descr = npy.dtype().descr().trim_matches('\'').to_string();
    let shape = npy.shape().to_vec();
    (descr, shape, npy.into_vec().unwrap())
}

/// The NPY directory output holds what the CSV output holds: every score with the same
/// bits (the CSV's shortest decimals read back as the same `f32`), the decisions as
/// class indices, the labels as an NPY input codes them, the ids and the class names;
/// and the scores are within `GOLDEN_ABS_TOL` of the independent numpy reference on the
/// rows its golden file samples.
#[test]
fn apply_npy_output_holds_the_csv_output() {
    use crate::support::{goldens, GOLDEN_ABS_TOL, TEST_SPLIT_CSV};
    let dir = tempdir();
    let d = dir.path();
    let table_path = bayes_table();
    let table = read_table(Path::new(&table_path));
    let (header, records) = apply(d, &table_path, &data("test"), "out.csv");
    // A trailing slash makes a directory output.
    ok(d, &apply_args(&table_path, &data("test"), "npy/"));
    let npy = d.join("npy");
    let n = records.len() as u64;
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let mut files: Vec<String> = std::fs::read_dir(&npy)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        [
            "bayes.npy",
            "bayes_pred.npy",
            "classes.txt",
            "ids.txt",
            "labels.npy",
            "map.npy",
            "map_pred.npy",
            "ml.npy",
            "ml_pred.npy",
            "open.npy",
            "open_pred.npy",
        ]
    );
    assert_eq!(
        std::fs::read_to_string(npy.join("classes.txt")).unwrap(),
        "car\ncyclist\npedestrian\n"
    );
    let ids: Vec<String> = std::fs::read_to_string(npy.join("ids.txt"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let csv_ids: Vec<String> = records.iter().map(|r| r[0].clone()).collect();
    assert_eq!(ids, csv_ids);
    let (descr, shape, labels) = read_npy::<i32>(&npy.join("labels.npy"));
    assert_eq!((descr.as_str(), shape), ("<i4", vec![n]));
    for (code, rec) in labels.iter().zip(&records) {
        let want = match rec[1].as_str() {
            "background" => -1,
            name => CLASSES.iter().position(|c| *c == name).unwrap() as i32,
        };
        assert_eq!(*code, want);
    }
    let mut by_id = BTreeMap::new();
    for head in ["ml", "map", "bayes", "open"] {
        let (descr, shape, scores) = read_npy::<f32>(&npy.join(format!("{head}.npy")));
        assert_eq!((descr.as_str(), shape), ("<f4", vec![n, 3]));
        for (r, rec) in records.iter().enumerate() {
            for (c, class) in CLASSES.iter().enumerate() {
                let csv: f32 = rec[column(&format!("{head}_{class}"))].parse().unwrap();
                assert_eq!(
                    scores[r * 3 + c].to_bits(),
                    csv.to_bits(),
                    "{head}_{class}, row {r}"
                );
            }
        }
        let (descr, shape, preds) = read_npy::<i32>(&npy.join(format!("{head}_pred.npy")));
        assert_eq!((descr.as_str(), shape), ("<i4", vec![n]));
        for (r, (p, rec)) in preds.iter().zip(&records).enumerate() {
            assert_eq!(
                CLASSES[*p as usize],
                rec[column(&format!("{head}_pred"))],
                "{head}_pred, row {r}"
            );
        }
        by_id.insert(head, scores);
    }
    // The numpy reference, on the NPY arrays themselves.
    let row_of: BTreeMap<&str, usize> = ids
        .iter()
        .enumerate()
        .map(|(i, id)| (id.as_str(), i))
        .collect();
    for g in goldens(TEST_SPLIT_CSV) {
        let r = row_of[g.case.strip_prefix("id ").unwrap()];
        for (head, want) in [("ml", g.ml), ("map", g.map), ("bayes", g.bayes)] {
            for (c, w) in want.unwrap().iter().enumerate() {
                let got = f64::from(by_id[head][r * 3 + c]);
                assert!(
                    (got - w).abs() <= GOLDEN_ABS_TOL,
                    "{head}, {}: {got} vs {w}",
                    g.case
                );
            }
        }
    }
    assert_eq!(table.class_names().count(), 3);
}

/// `--heads`: only the heads named, in the usual column order, with the values of the
/// full output; a head the table lacks, an unknown name and a repeated name are refused.
#[test]
fn apply_heads_writes_only_the_heads_named() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = bayes_table();
    let input = data("val");
    let (full_header, full) = apply(d, &table_path, &input, "full.csv");
    let mut args = apply_args(&table_path, &input, "some.csv");
    args.extend(["--heads", "open,ml"]);
    ok(d, &args);
    let (header, records) = read_csv(&d.join("some.csv"));
    let mut want = vec!["id".to_string(), "label".to_string()];
    for head in ["ml", "open"] {
        want.extend(CLASSES.iter().map(|c| format!("{head}_{c}")));
    }
    want.extend(["ml_pred".to_string(), "open_pred".to_string()]);
    assert_eq!(header, want);
    assert_eq!(records.len(), full.len());
    for (rec, whole) in records.iter().zip(&full) {
        for (h, v) in header.iter().zip(rec) {
            let at = full_header.iter().position(|f| f == h).unwrap();
            assert_eq!(*v, whole[at], "{h}");
        }
    }
    // The same heads as an NPY directory: nothing of the others.
    args = apply_args(&table_path, &input, "some");
    args.extend(["--heads", "map", "--format", "npy"]);
    ok(d, &args);
    let mut files: Vec<String> = std::fs::read_dir(d.join("some"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        [
            "classes.txt",
            "ids.txt",
            "labels.npy",
            "map.npy",
            "map_pred.npy"
        ]
    );

    let golden = golden_table();
    let mut args = apply_args(&golden, &input, "x.csv");
    args.extend(["--heads", "ml,bayes"]);
    refused(
        d,
        &args,
        &["train_linspace.mlmap", "no bayes head", "it has ml, map"],
    );
    let mut args = apply_args(&table_path, &input, "x.csv");
    args.extend(["--heads", "ml,softmax"]);
    refused(d, &args, &["softmax", "ml, map, bayes, open"]);
    let mut args = apply_args(&table_path, &input, "x.csv");
    args.extend(["--heads", "ml,ml"]);
    refused(d, &args, &["ml head twice"]);
    // The quantized section of the shipped int8 table has every head.
    let q8 = repo("tables/default_q8.mlmap")
        .to_string_lossy()
        .into_owned();
    write(d, "codes.csv", "car,cyclist,pedestrian\n12,-3,-40\n");
    let mut args = apply_args(&q8, "codes.csv", "q.csv");
    args.extend(["--quantized", "--heads", "bayes"]);
    ok(d, &args);
    let (header, _) = read_csv(&d.join("q.csv"));
    assert_eq!(
        header,
        [
            "bayes_car",
            "bayes_cyclist",
            "bayes_pedestrian",
            "bayes_pred"
        ]
    );
}

/// The NPY output directory: an earlier output is replaced as a whole (no stale
/// array of a head no longer asked for), a directory holding anything else, the input
/// directory and a CSV format on a directory are refused with nothing changed, an input
/// without rows gives arrays of zero rows, and rows without labels or ids give no
/// `labels.npy` or `ids.txt`; missing labels are coded -2.
#[test]
fn apply_npy_output_directory_rules() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = bayes_table();
    let input = data("val");
    ok(d, &apply_args(&table_path, &input, "out/"));
    assert!(d.join("out/bayes.npy").exists());
    // Replaced, here named by --format rather than by a trailing slash.
    let mut args = apply_args(&table_path, &input, "out");
    args.extend(["--heads", "ml", "--format", "npy"]);
    ok(d, &args);
    assert!(!d.join("out/bayes.npy").exists());
    assert!(d.join("out/ml.npy").exists());
    let leftovers: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".mlmap-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    std::fs::create_dir(d.join("mine")).unwrap();
    write(&d.join("mine"), "notes.txt", "keep me\n");
    refused(
        d,
        &apply_args(&table_path, &input, "mine/"),
        &["mine", "notes.txt", "new or empty directory"],
    );
    let mut args = apply_args(&table_path, &input, "new/");
    args.extend(["--format", "csv"]);
    refused(d, &args, &["new/", "--format csv"]);
    refused(
        d,
        &apply_args(&table_path, &input, "missing/deeper/"),
        &["missing/deeper", "does not exist"],
    );
    // An NPY input directory as the output.
    let npy_in = d.join("in");
    std::fs::create_dir(&npy_in).unwrap();
    write_npy(
        &npy_in.join("logits.npy"),
        &[2, 3],
        &[1.0f32, 2.0, 3.0, -1.0, 0.5, 0.0],
    );
    write(&npy_in, "classes.txt", "car\ncyclist\npedestrian\n");
    refused(d, &apply_args(&table_path, "in", "in/"), &["in", "input"]);

    // No rows; no ids; a missing label.
    write(d, "none.csv", "car,cyclist,pedestrian\n");
    ok(d, &apply_args(&table_path, "none.csv", "none/"));
    let (_, shape, v) = read_npy::<f32>(&d.join("none/open.npy"));
    assert_eq!((shape, v.len()), (vec![0, 3], 0));
    let (_, shape, _) = read_npy::<i32>(&d.join("none/open_pred.npy"));
    assert_eq!(shape, vec![0]);
    assert!(!d.join("none/labels.npy").exists() && !d.join("none/ids.txt").exists());
    write(
        d,
        "labelled.csv",
        "label,car,cyclist,pedestrian\npedestrian,4.1,-2.3,-1.7\n,1,2,3\nbackground,0,0,0\n",
    );
    ok(d, &apply_args(&table_path, "labelled.csv", "labelled/"));
    let (_, _, labels) = read_npy::<i32>(&d.join("labelled/labels.npy"));
    assert_eq!(labels, [2, -2, -1]);
    // An id holding a line break cannot be a line of ids.txt.
    write(
        d,
        "ids.csv",
        "id,car,cyclist,pedestrian\n\"a\nb\",4.1,-2.3,-1.7\n",
    );
    refused(
        d,
        &apply_args(&table_path, "ids.csv", "ids/"),
        &["ids.csv:2", "line break"],
    );
}
