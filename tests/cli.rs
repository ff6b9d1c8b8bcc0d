//! The `mlmap` binary, run as a user runs it (DESIGN §4): every subcommand on the
//! shipped data and on small hand-made files, the demo, and every bad-input case (exit
//! code 2, a message naming the file and line, and no output file left behind).

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use mlmap::host::dataset::{DataError, DataSource, Label};
use mlmap::host::metrics::{self, MetricsConfig};
use mlmap::host::DynTable;
use mlmap::{EdgeMode, Libm, UpperTail};
use npyz::WriterBuilder;
use serde_json::Value;

// ---------------------------------------------------------------------------------------
// Running the binary
// ---------------------------------------------------------------------------------------

/// What a run of the binary left: exit code, stdout, stderr.
#[derive(Debug)]
struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Runs `mlmap ARGS` in `dir`. Whatever the outcome, the binary must not panic.
fn mlmap<S: AsRef<OsStr>>(dir: &Path, args: &[S]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_mlmap"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("the mlmap binary runs");
    let run = Run {
        code: out.status.code().expect("mlmap exits with a code"),
        stdout: String::from_utf8(out.stdout).expect("stdout is UTF-8"),
        stderr: String::from_utf8(out.stderr).expect("stderr is UTF-8"),
    };
    assert!(
        !run.stderr.contains("panicked") && run.code != 101,
        "mlmap panicked: {run:?}"
    );
    run
}

/// Runs `mlmap ARGS` in `dir` and expects success.
fn ok<S: AsRef<OsStr>>(dir: &Path, args: &[S]) -> Run {
    let run = mlmap(dir, args);
    assert_eq!(run.code, 0, "mlmap {:?} failed: {run:?}", os_args(args));
    run
}

fn os_args<S: AsRef<OsStr>>(args: &[S]) -> Vec<String> {
    args.iter()
        .map(|a| a.as_ref().to_string_lossy().into_owned())
        .collect()
}

/// Every file under `dir` with its contents (the directories too, as `None`).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                out.insert(p.clone(), None);
                stack.push(p);
            } else {
                out.insert(p.clone(), Some(std::fs::read(&p).unwrap()));
            }
        }
    }
    out
}

/// Runs `mlmap ARGS` in `dir` and expects a refusal: exit code 2, nothing on stdout, a
/// message on stderr holding every one of `needles` (the file, the line, what is
/// wrong), and `dir` exactly as before: no output, no temporary file, no file changed.
fn refused<S: AsRef<OsStr>>(dir: &Path, args: &[S], needles: &[&str]) {
    let before = snapshot(dir);
    let run = mlmap(dir, args);
    let args = os_args(args);
    assert_eq!(
        run.code, 2,
        "mlmap {args:?}: expected exit code 2, got {run:?}"
    );
    assert_eq!(run.stdout, "", "mlmap {args:?} printed to stdout");
    for needle in needles {
        assert!(
            run.stderr.contains(needle),
            "mlmap {args:?}: the message does not contain {needle:?}:\n{}",
            run.stderr
        );
    }
    let after = snapshot(dir);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>(),
        "mlmap {args:?} left files behind or removed some"
    );
    assert!(before == after, "mlmap {args:?} changed a file");
}

// ---------------------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------------------

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A shipped data file, `examples/data/NAME.csv`, as an absolute path string.
fn data(name: &str) -> String {
    repo(&format!("examples/data/{name}.csv"))
        .to_string_lossy()
        .into_owned()
}

/// The linspace fit of `examples/data/train.csv` with the default settings, written by
/// the independent numpy fit in `tools/mlmap_ref.py`.
fn golden_table() -> String {
    repo("tests/golden/train_linspace.mlmap")
        .to_string_lossy()
        .into_owned()
}

fn read_table(path: &Path) -> DynTable {
    let bytes = std::fs::read(path).unwrap();
    DynTable::from_bytes(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

/// Writes one `.npy` array.
fn write_npy<T: npyz::AutoSerialize + Clone>(path: &Path, shape: &[u64], values: &[T]) {
    let mut file = std::fs::File::create(path).unwrap();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut file)
        .begin_nd()
        .unwrap();
    w.extend(values.iter().cloned()).unwrap();
    w.finish().unwrap();
}

/// One row of a data file, owned.
#[derive(Debug, Clone, PartialEq)]
struct DataRow {
    label: Label,
    objectness: f64,
    logits: Vec<f64>,
}

fn rows_of(path: &Path) -> Vec<DataRow> {
    let src = DataSource::open(path).unwrap();
    let mut rows = Vec::new();
    src.for_each_row(|r| {
        rows.push(DataRow {
            label: r.label,
            objectness: r.objectness,
            logits: r.logits.to_vec(),
        });
        Ok::<(), DataError>(())
    })
    .unwrap();
    rows
}

/// ML and MAP scores of one row through the layer, as the device computes them.
fn layer(table: &DynTable, row: &DataRow) -> (Vec<f32>, Vec<f32>) {
    let k = table.k();
    let x: Vec<f32> = row.logits.iter().map(|&v| v as f32).collect();
    let os = row.objectness as f32;
    let (mut ml, mut map, mut scratch) = (vec![0f32; k], vec![0f32; k], vec![0f32; k]);
    table.ml_into(&x, os, &mut ml, &mut scratch).unwrap();
    table
        .map_into::<Libm>(&x, os, &mut map, &mut scratch)
        .unwrap();
    (ml, map)
}

fn class_labels(rows: &[DataRow]) -> Vec<Option<usize>> {
    rows.iter()
        .map(|r| match r.label {
            Label::Class(c) => Some(c),
            Label::Background => None,
            Label::Missing => panic!("unlabelled row"),
        })
        .collect()
}

/// A small valid CSV (lines 2 to 5), with `bad` as line 6 when given, then one more
/// valid row: the error comes after rows that `apply` has already written.
fn csv_with(bad: Option<&str>) -> String {
    let mut s = String::from(
        "id,label,objectness,car,cyclist,pedestrian\n\
         1,car,0.9,4.1,-2.3,-1.7\n\
         2,cyclist,0.8,-1.0,2.5,0.5\n\
         3,pedestrian,0.7,0.25,-0.5,3.75\n\
         4,background,0.5,1.2,0.3,-0.4\n",
    );
    if let Some(bad) = bad {
        s.push_str(bad);
        s.push('\n');
    }
    s.push_str("7,car,1.0,3.0,-1.0,-2.0\n");
    s
}

const CLASSES: [&str; 3] = ["car", "cyclist", "pedestrian"];

// ---------------------------------------------------------------------------------------
// fit
// ---------------------------------------------------------------------------------------

#[test]
fn fit_linspace_and_matlab_equal_the_golden_tables_byte_for_byte() {
    let dir = tempdir();
    let d = dir.path();
    let run = ok(
        d,
        &["fit", "--train", &data("train"), "--output", "t.mlmap"],
    );
    let golden = std::fs::read(golden_table()).unwrap();
    assert_eq!(std::fs::read(d.join("t.mlmap")).unwrap(), golden);
    assert!(run.stdout.starts_with(&format!(
        "wrote t.mlmap ({} bytes): 3 classes, edges linspace, upper tail zero\n",
        golden.len()
    )));
    assert!(run.stdout.contains("ML   22 bins, lambda 5.5e-3"));
    assert!(run.stdout.contains("MAP  17 bins, lambda 1.2e-4"));

    ok(
        d,
        &[
            "fit",
            "--train",
            &data("train"),
            "--edges",
            "matlab",
            "-o",
            "m.mlmap",
        ],
    );
    // tests/golden/train_matlab.mlmap: tools/matlab_fit_ref.py, MATLAB's bin picker.
    let golden = std::fs::read(repo("tests/golden/train_matlab.mlmap")).unwrap();
    assert_eq!(std::fs::read(d.join("m.mlmap")).unwrap(), golden);
    // No temporary file stays next to the outputs.
    let names: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn fit_records_the_requested_settings() {
    let dir = tempdir();
    let d = dir.path();
    ok(
        d,
        &[
            "fit",
            "--train",
            &data("train"),
            "--edges",
            "matlab",
            "--upper-tail",
            "clamp",
            "--bins-ml",
            "7",
            "--lambda-ml",
            "0.25",
            "--bins-map",
            "5",
            "--lambda-map",
            "1e-3",
            "--output",
            "t.mlmap",
        ],
    );
    let t = read_table(&d.join("t.mlmap"));
    assert_eq!(t.class_names().collect::<Vec<_>>(), CLASSES);
    assert_eq!((t.bins_ml(), t.bins_map()), (7, 5));
    let st = t.settings();
    assert_eq!((st.lambda_ml, st.lambda_map), (0.25f32, 1e-3f32));
    assert_eq!(st.edge_mode, EdgeMode::Matlab);
    assert_eq!(st.upper_tail, UpperTail::Clamp);
    // Provenance: the labelled rows of each class.
    let rows = rows_of(Path::new(&data("train")));
    let count = |c| rows.iter().filter(|r| r.label == Label::Class(c)).count() as u64;
    assert_eq!(t.rows(), [count(0), count(1), count(2)]);
    // The upper tail is the only difference from the default linspace fit.
    ok(
        d,
        &[
            "fit",
            "--train",
            &data("train"),
            "--upper-tail",
            "clamp",
            "-o",
            "c.mlmap",
        ],
    );
    let c = read_table(&d.join("c.mlmap"));
    let g = read_table(Path::new(&golden_table()));
    assert_eq!(c.settings().upper_tail, UpperTail::Clamp);
    assert_eq!(c.ml_histograms(), g.ml_histograms());
    // A car logit above every training car logit: the zero tail forgets it, the clamp
    // keeps the last bin.
    let high = DataRow {
        label: Label::Missing,
        objectness: 1.0,
        logits: vec![f64::from(g.ml_histograms()[0].hi()) + 1.0, -20.0, -20.0],
    };
    assert!(layer(&c, &high).0[0] > layer(&g, &high).0[0]);
}

#[test]
fn fit_reads_npy_directories() {
    let dir = tempdir();
    let d = dir.path();
    let npy = repo("tests/fixtures/npy_small");
    ok(
        d,
        &[
            OsStr::new("fit"),
            OsStr::new("--train"),
            npy.as_os_str(),
            OsStr::new("--bins-ml"),
            OsStr::new("3"),
            OsStr::new("--bins-map"),
            OsStr::new("2"),
            OsStr::new("-o"),
            OsStr::new("t.mlmap"),
        ],
    );
    let t = read_table(&d.join("t.mlmap"));
    // classes.txt names them; labels [0, -1, 1, 2, 0].
    assert_eq!(t.class_names().collect::<Vec<_>>(), CLASSES);
    assert_eq!(t.rows(), [2, 1, 1]);
    assert_eq!((t.bins_ml(), t.bins_map()), (3, 2));
}

// ---------------------------------------------------------------------------------------
// tune
// ---------------------------------------------------------------------------------------

/// A small grid: 3 x 9 ML and 2 x 9 MAP candidates.
fn tune_args<'a>(output: &'a str, train: &'a str, val: &'a str) -> Vec<&'a str> {
    vec![
        "tune",
        "--train",
        train,
        "--val",
        val,
        "--bins-ml",
        "10..12",
        "--bins-map",
        "8,9",
        "--lambdas-per-decade",
        "1",
        "--output",
        output,
    ]
}

#[test]
fn tune_writes_the_best_candidates_and_its_objective_matches_the_metrics() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val) = (data("train"), data("val"));
    let mut args = tune_args("j.mlmap", &train, &val);
    args.extend(["--format", "json", "--top", "3"]);
    let run = ok(d, &args);
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    let t = read_table(&d.join("j.mlmap"));
    assert_eq!(v["objective"], "ece");
    assert_eq!(v["candidates"]["ml"], 3 * 8);
    assert_eq!(v["candidates"]["map"], 2 * 8);
    assert_eq!(v["table"]["path"], "j.mlmap");

    let val_rows = rows_of(Path::new(&val));
    let labels = class_labels(&val_rows);
    for (head, bins, lambda) in [
        ("ml", t.bins_ml(), t.settings().lambda_ml),
        ("map", t.bins_map(), t.settings().lambda_map),
    ] {
        let cands = v[head].as_array().unwrap();
        assert_eq!(cands.len(), 3);
        let ece: Vec<f64> = cands.iter().map(|c| c["ece"].as_f64().unwrap()).collect();
        assert!(ece.windows(2).all(|w| w[0] <= w[1]), "{head}: {ece:?}");
        let best = &cands[0];
        assert_eq!(best["rank"], 1);
        assert_eq!(best["bins"].as_u64().unwrap() as usize, bins, "{head}");
        assert_eq!(best["lambda"].as_f64().unwrap() as f32, lambda, "{head}");
        // The tuner accumulates its objectives on the fly; the metrics module computes
        // them from the scores of the written table.
        let scores: Vec<f64> = val_rows
            .iter()
            .flat_map(|r| {
                let (ml, map) = layer(&t, r);
                if head == "ml" {
                    ml
                } else {
                    map
                }
            })
            .map(f64::from)
            .collect();
        let m = metrics::evaluate(&scores, 3, &labels, &MetricsConfig::default()).unwrap();
        for (key, want) in [("ece", m.ece), ("nll", m.nll.unwrap()), ("brier", m.brier)] {
            let got = best[key].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 1e-12,
                "{head} {key}: tuner {got}, metrics {want}"
            );
        }
    }

    // The text report: the rank-1 rows and the summary name the written settings.
    let run = ok(d, &tune_args("t.mlmap", &train, &val));
    assert_eq!(
        std::fs::read(d.join("t.mlmap")).unwrap(),
        std::fs::read(d.join("j.mlmap")).unwrap()
    );
    assert!(run
        .stdout
        .starts_with("ML head: best 5 of 24 candidates by ece\n"));
    assert!(run
        .stdout
        .contains("MAP head: best 5 of 16 candidates by ece\n"));
    let rank1: Vec<Vec<&str>> = run
        .stdout
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("1"))
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(rank1.len(), 2, "{}", run.stdout);
    assert_eq!(rank1[0][1], t.bins_ml().to_string());
    assert_eq!(rank1[1][1], t.bins_map().to_string());
    let st = t.settings();
    for (line, lambda) in rank1.iter().zip([st.lambda_ml, st.lambda_map]) {
        let printed: f64 = line[2].parse().unwrap();
        assert!((printed / f64::from(lambda) - 1.0).abs() < 1e-3, "{line:?}");
    }
    assert!(run.stdout.contains(&format!(
        "  ML  {:>3} bins, lambda {:e}\n  MAP {:>3} bins, lambda {:e}\n",
        t.bins_ml(),
        st.lambda_ml,
        t.bins_map(),
        st.lambda_map
    )));
}

#[test]
fn tune_ranks_by_the_chosen_objective() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val) = (data("train"), data("val"));
    for objective in ["nll", "brier"] {
        let mut args = tune_args("t.mlmap", &train, &val);
        args.extend([
            "--objective",
            objective,
            "--format",
            "json",
            "--top",
            "100",
            "--upper-tail",
            "clamp",
            "--edges",
            "matlab",
        ]);
        let v: Value = serde_json::from_str(&ok(d, &args).stdout).unwrap();
        assert_eq!(v["objective"], objective);
        for head in ["ml", "map"] {
            let values: Vec<f64> = v[head]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c[objective].as_f64().unwrap())
                .collect();
            assert_eq!(values.len(), if head == "ml" { 24 } else { 16 });
            assert!(
                values.windows(2).all(|w| w[0] <= w[1]),
                "{head}: {values:?}"
            );
        }
        let t = read_table(&d.join("t.mlmap"));
        assert_eq!(t.settings().upper_tail, UpperTail::Clamp);
        assert_eq!(t.settings().edge_mode, EdgeMode::Matlab);
    }
}

// ---------------------------------------------------------------------------------------
// apply
// ---------------------------------------------------------------------------------------

/// Reads a CSV written by `apply`: the header and the records.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(str::to_string).collect();
    let records = r
        .records()
        .map(|rec| rec.unwrap().iter().map(str::to_string).collect())
        .collect();
    (header, records)
}

fn score_columns() -> Vec<String> {
    let mut cols: Vec<String> = Vec::new();
    cols.extend(CLASSES.iter().map(|c| format!("ml_{c}")));
    cols.extend(CLASSES.iter().map(|c| format!("map_{c}")));
    cols.extend(["ml_pred".to_string(), "map_pred".to_string()]);
    cols
}

/// Checks the score columns of every record against the layer, bit for bit.
fn check_scores(table: &DynTable, rows: &[DataRow], records: &[Vec<String>], skip: usize) {
    assert_eq!(records.len(), rows.len());
    for (rec, row) in records.iter().zip(rows) {
        let (ml, map) = layer(table, row);
        let got: Vec<f32> = rec[skip..skip + 6]
            .iter()
            .map(|v| v.parse().unwrap())
            .collect();
        let want: Vec<f32> = ml.iter().chain(&map).copied().collect();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&want), "{rec:?}");
        // Ties of the top score go to the larger logit (DESIGN §1.7).
        assert_eq!(rec[skip + 6], CLASSES[mlmap::decide(&ml, &row.logits)]);
        assert_eq!(rec[skip + 7], CLASSES[mlmap::decide(&map, &row.logits)]);
    }
}

#[test]
fn apply_writes_the_design_columns_and_the_layer_scores() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = golden_table();
    let table = read_table(Path::new(&table_path));
    let input = data("val");
    ok(
        d,
        &[
            "apply",
            "--table",
            &table_path,
            "--input",
            &input,
            "--output",
            "out.csv",
        ],
    );
    let (header, records) = read_csv(&d.join("out.csv"));
    let mut want = vec!["id".to_string(), "label".to_string()];
    want.extend(score_columns());
    assert_eq!(header, want);
    let rows = rows_of(Path::new(&input));
    check_scores(&table, &rows, &records, 2);
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
    let table_path = golden_table();
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
    ok(
        d,
        &[
            "apply",
            "--table",
            &table_path,
            "--input",
            "plain.csv",
            "-o",
            "a.csv",
        ],
    );
    let (header, records) = read_csv(&d.join("a.csv"));
    assert_eq!(header, score_columns());
    check_scores(&table, &rows_of(&d.join("plain.csv")), &records, 0);

    ok(
        d,
        &[
            "apply",
            "--table",
            &table_path,
            "--input",
            "labelled.csv",
            "-o",
            "b.csv",
        ],
    );
    let (header, records) = read_csv(&d.join("b.csv"));
    let mut want = vec!["label".to_string()];
    want.extend(score_columns());
    assert_eq!(header, want);
    let labels: Vec<&str> = records.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(labels, ["car", "", "background"]);
    check_scores(&table, &rows_of(&d.join("labelled.csv")), &records, 1);

    // A header without rows gives a header without rows.
    write(d, "none.csv", "car,cyclist,pedestrian\n");
    ok(
        d,
        &[
            "apply",
            "--table",
            &table_path,
            "--input",
            "none.csv",
            "-o",
            "c.csv",
        ],
    );
    let (header, records) = read_csv(&d.join("c.csv"));
    assert_eq!(header, score_columns());
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
    let args = |input: &Path, out: &str| -> Vec<std::ffi::OsString> {
        vec![
            "apply".into(),
            "--table".into(),
            table_path.clone().into(),
            "--input".into(),
            input.into(),
            "--output".into(),
            out.into(),
        ]
    };
    ok(d, &args(&npy, "a.csv"));
    let (header, records) = read_csv(&d.join("a.csv"));
    let mut want = vec!["label".to_string()];
    want.extend(score_columns());
    assert_eq!(header, want);
    let labels: Vec<&str> = records.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        labels,
        ["car", "background", "cyclist", "pedestrian", "car"]
    );
    check_scores(&table, &rows_of(&npy), &records, 1);

    // npyz-written, logits only (float64), classes named.
    let only = d.join("logits_only");
    std::fs::create_dir(&only).unwrap();
    write_npy(
        &only.join("logits.npy"),
        &[3, 3],
        &[4.1f64, -2.3, -1.7, -1.0, 2.5, 0.5, 100.0, 100.0, 100.0],
    );
    write(&only, "classes.txt", "car\ncyclist\npedestrian\n");
    ok(d, &args(&only, "b.csv"));
    let (header, records) = read_csv(&d.join("b.csv"));
    assert_eq!(header, score_columns());
    check_scores(&table, &rows_of(&only), &records, 0);
    // Logits outside every histogram: the "I don't know" answer, 1/3 each.
    let third: f32 = records[2][0].parse().unwrap();
    assert!((third - 1.0 / 3.0).abs() < 1e-6);
}

// ---------------------------------------------------------------------------------------
// eval
// ---------------------------------------------------------------------------------------

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

fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

fn sorted(keys: &[&str]) -> Vec<String> {
    let mut k: Vec<String> = keys.iter().map(|s| s.to_string()).collect();
    k.sort();
    k
}

#[test]
fn eval_json_has_the_design_keys_and_the_layer_metrics() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = golden_table();
    let test = data("test");
    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table_path,
            "--test",
            &test,
            "--val",
            &data("val"),
            "--ood",
            &data("ood"),
            "--format",
            "json",
        ],
    );
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    let methods = &v["methods"];
    assert_eq!(
        keys(methods),
        sorted(&["sigmoid", "softmax", "temperature", "ml", "map"])
    );
    let mut with_ood: Vec<&str> = METRIC_KEYS.to_vec();
    with_ood.extend(["ood_mean", "ood_over_0_9"]);
    for (name, m) in methods.as_object().unwrap() {
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
    assert!(methods["temperature"]["T"].as_f64().unwrap() > 0.0);

    // ML and MAP are the metrics of the layer's scores.
    let table = read_table(Path::new(&table_path));
    let rows = rows_of(Path::new(&test));
    let labels = class_labels(&rows);
    for head in ["ml", "map"] {
        let scores: Vec<f64> = rows
            .iter()
            .flat_map(|r| {
                let (ml, map) = layer(&table, r);
                if head == "ml" {
                    ml
                } else {
                    map
                }
            })
            .map(f64::from)
            .collect();
        let m = metrics::evaluate(&scores, 3, &labels, &MetricsConfig::default()).unwrap();
        let got = &methods[head];
        assert_eq!(got["ece"].as_f64(), Some(m.ece), "{head}");
        assert_eq!(got["brier"].as_f64(), Some(m.brier), "{head}");
        assert_eq!(got["auroc"].as_f64(), m.auroc, "{head}");
        assert_eq!(got["ap_cyclist"].as_f64(), m.ap[1], "{head}");
    }
    assert_eq!(v["rows"], rows.len());
    assert_eq!(v["ood_rows"], 2000);

    // Without --val there is no temperature; without --ood no ood keys.
    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table_path,
            "--test",
            &test,
            "--format",
            "json",
        ],
    );
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(
        keys(&v["methods"]),
        sorted(&["sigmoid", "softmax", "ml", "map"])
    );
    for m in v["methods"].as_object().unwrap().values() {
        assert_eq!(keys(m), sorted(&METRIC_KEYS));
    }
}

#[test]
fn eval_text_markdown_and_plots() {
    let dir = tempdir();
    let d = dir.path();
    let table_path = golden_table();
    let (test, val) = (data("test"), data("val"));
    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table_path,
            "--test",
            &test,
            "--val",
            &val,
            "--plots",
            "plots",
        ],
    );
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert!(
        lines[0].starts_with("10000 test rows (8000 labelled with a class, 2000 background)"),
        "{}",
        lines[0]
    );
    assert!(lines[1].starts_with("temperature T = "));
    let header: Vec<&str> = lines[3].split_whitespace().collect();
    assert_eq!(
        header,
        ["metric", "sigmoid", "softmax", "temperature", "ml", "map"]
    );
    for key in METRIC_KEYS.iter().chain(&["T"]) {
        let row = lines
            .iter()
            .find(|l| l.split_whitespace().next() == Some(key))
            .unwrap_or_else(|| panic!("no row {key}:\n{}", run.stdout));
        assert_eq!(row.split_whitespace().count(), 6, "{row}");
    }
    // SVG plots: one reliability diagram per method, and more.
    let plots: Vec<PathBuf> = std::fs::read_dir(d.join("plots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(run
        .stdout
        .ends_with(&format!("\nwrote {} plots into plots\n", plots.len())));
    for method in ["sigmoid", "softmax", "temperature", "ml", "map"] {
        assert!(d.join(format!("plots/reliability_{method}.svg")).is_file());
    }
    for p in &plots {
        assert_eq!(p.extension(), Some(OsStr::new("svg")), "{}", p.display());
        let text = std::fs::read_to_string(p).unwrap();
        assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));
    }

    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table_path,
            "--test",
            &test,
            "--format",
            "markdown",
        ],
    );
    let lines: Vec<&str> = run.stdout.lines().collect();
    assert_eq!(lines[0], "| metric | sigmoid | softmax | ml | map |");
    assert_eq!(lines[1], "|---|---:|---:|---:|---:|");
    assert_eq!(lines.len(), 2 + METRIC_KEYS.len());
    for (line, key) in lines[2..].iter().zip(METRIC_KEYS) {
        assert!(line.starts_with(&format!("| `{key}` |")), "{line}");
        assert_eq!(line.matches('|').count(), 6, "{line}");
    }

    // The ECE conventions are selectable; the reports say which one was used.
    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table_path,
            "--test",
            &test,
            "--format",
            "json",
            "--ece-bins",
            "15",
            "--ece-binning",
            "torchmetrics",
        ],
    );
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(v["ece_bins"], 15);
    assert_eq!(v["ece_binning"], "torchmetrics");
}

// ---------------------------------------------------------------------------------------
// inspect
// ---------------------------------------------------------------------------------------

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
            mlmap::FORMAT_VERSION,
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

    let run = ok(d, &["inspect", &path, "--format", "json"]);
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(v["crc_ok"], true);
    assert_eq!(v["bytes"], bytes.len());
    assert_eq!(v["format_version"], mlmap::FORMAT_VERSION);
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

// ---------------------------------------------------------------------------------------
// demo
// ---------------------------------------------------------------------------------------

#[test]
fn demo_runs_the_whole_job() {
    let dir = tempdir();
    let d = dir.path();
    let data_dir = repo("examples/data");
    let run = ok(
        d,
        &[
            OsStr::new("demo"),
            OsStr::new("--data"),
            data_dir.as_os_str(),
            OsStr::new("--output"),
            OsStr::new("out"),
        ],
    );
    let s = &run.stdout;
    let steps = [
        "\n1. fit (authors' detection settings)\n",
        "\n2. tune lambdas on ",
        "\n3. evaluate on ",
        "\n4. no_std layer: Table<3, 22, 17>::from_bytes(out/tuned.mlmap) scored 10000 test rows: 0 with scores differing from the host's in any bit\n",
        "\nsummary\n",
    ];
    let mut at = 0;
    for step in steps {
        let found = s[at..]
            .find(step)
            .unwrap_or_else(|| panic!("no {step:?} in order:\n{s}"));
        at += found + step.len();
    }
    let out = d.join("out");
    for f in [
        "fitted.mlmap",
        "tuned.mlmap",
        "tune.txt",
        "eval.txt",
        "eval.json",
        "eval.md",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // The fit uses the defaults: the golden table.
    assert_eq!(
        std::fs::read(out.join("fitted.mlmap")).unwrap(),
        std::fs::read(golden_table()).unwrap()
    );
    let tuned = read_table(&out.join("tuned.mlmap"));
    assert_eq!((tuned.bins_ml(), tuned.bins_map()), (22, 17));
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(
        keys(&v["methods"]),
        sorted(&["sigmoid", "softmax", "temperature", "ml", "map"])
    );
    assert!(v["methods"]["map"]["ood_over_0_9"].is_number());
    let plots = std::fs::read_dir(out.join("plots")).unwrap().count();
    assert!(plots >= 5);
    assert!(s.contains(&format!("and {plots} plots into out\n")));
}

// ---------------------------------------------------------------------------------------
// Bad input: exit code 2, the file and line named, nothing written
// ---------------------------------------------------------------------------------------

/// `(line 6 of the file, what the message must say)`.
const MALFORMED_ROWS: [(&str, &str); 11] = [
    (
        "5,car,0.9,1.0,2.0",
        "expected 6 fields (as the header), found 5",
    ),
    (
        "5,car,0.9,1.0,2.0,3.0,4.0",
        "expected 6 fields (as the header), found 7",
    ),
    (
        "5,car,0.9,1.0,abc,3.0",
        "column \"cyclist\": \"abc\" is not a number",
    ),
    (
        "5,truck,0.9,1.0,2.0,3.0",
        "column \"label\": \"truck\" is not a class name",
    ),
    (
        "5,car,0.9,NaN,2.0,3.0",
        "column \"car\": \"NaN\" is not a finite number",
    ),
    (
        "5,car,0.9,1.0,inf,3.0",
        "column \"cyclist\": \"inf\" is not a finite number",
    ),
    (
        "5,car,0.9,1.0,2.0,-inf",
        "column \"pedestrian\": \"-inf\" is not a finite number",
    ),
    (
        "5,car,1.5,1.0,2.0,3.0",
        "column \"objectness\": objectness \"1.5\" is not a number in [0, 1]",
    ),
    (
        "5,car,-0.1,1.0,2.0,3.0",
        "column \"objectness\": objectness \"-0.1\" is not a number in [0, 1]",
    ),
    (
        "5,car,NaN,1.0,2.0,3.0",
        "column \"objectness\": objectness \"NaN\" is not a number in [0, 1]",
    ),
    (
        "5,car,,1.0,2.0,3.0",
        "column \"objectness\": the field is empty",
    ),
];

/// Runs `case(dir, file, needles)` for every malformed file: each malformed row at line 6, an
/// empty file, a missing file, and broken headers.
fn for_each_malformed_file(mut case: impl FnMut(&Path, &str, &[&str])) {
    let dir = tempdir();
    let d = dir.path();
    for (i, (row, what)) in MALFORMED_ROWS.iter().enumerate() {
        let name = format!("bad{i}.csv");
        write(d, &name, &csv_with(Some(row)));
        case(d, &name, &[&format!("{name}:6: "), what]);
        std::fs::remove_file(d.join(&name)).unwrap();
    }
    let headers = [
        ("", ": the file is empty (no header row)"),
        ("\n\n", ": the file is empty (no header row)"),
        ("label,car\ncar,1\n", ":1: found 1 class column(s)"),
        (
            "label,car,car\ncar,1,2\n",
            ":1: column \"car\": the name appears more than once",
        ),
        (
            "label,background,car\ncar,1,2\n",
            ":1: column \"background\": a class cannot be named \"background\"",
        ),
    ];
    for (i, (text, what)) in headers.iter().enumerate() {
        let name = format!("header{i}.csv");
        write(d, &name, text);
        case(d, &name, &[&format!("{name}{what}")]);
        std::fs::remove_file(d.join(&name)).unwrap();
    }
    case(
        d,
        "missing.csv",
        &["missing.csv: no such file or directory"],
    );
}

#[test]
fn fit_refuses_malformed_training_data() {
    for_each_malformed_file(|d, file, needles| {
        refused(d, &["fit", "--train", file, "--output", "t.mlmap"], needles);
    });
    let dir = tempdir();
    let d = dir.path();
    write(d, "header_only.csv", "label,car,cyclist,pedestrian\n");
    refused(
        d,
        &["fit", "--train", "header_only.csv", "-o", "t.mlmap"],
        &["header_only.csv: classes \"car\", \"cyclist\", \"pedestrian\" have no training rows"],
    );
    write(
        d,
        "no_cyclist.csv",
        "label,car,cyclist\ncar,1,2\nbackground,3,4\n",
    );
    refused(
        d,
        &["fit", "--train", "no_cyclist.csv", "-o", "t.mlmap"],
        &["no_cyclist.csv: class \"cyclist\" has no training rows"],
    );
    write(d, "unlabelled.csv", "car,cyclist\n1,2\n");
    refused(
        d,
        &["fit", "--train", "unlabelled.csv", "-o", "t.mlmap"],
        &["unlabelled.csv: the data has no labels"],
    );
    // Values a table cannot hold: named with the training file.
    write(
        d,
        "tight.csv",
        "label,a,b\na,1000000,0\na,1000000.1,0\nb,0,1\nb,0,2\n",
    );
    refused(
        d,
        &[
            "fit",
            "--train",
            "tight.csv",
            "--bins-ml",
            "60000",
            "-o",
            "t.mlmap",
        ],
        &[
            "tight.csv: class \"a\": the range",
            "cannot be split into 60000 bins",
        ],
    );
    write(
        d,
        "huge.csv",
        "label,a,b\na,1e38,0\na,3e38,0\nb,0,1\nb,0,2\n",
    );
    refused(
        d,
        &["fit", "--train", "huge.csv", "-o", "t.mlmap"],
        &["huge.csv: class \"a\": the training logits or their variance exceed the f32 range"],
    );
    // An existing output stays as it was.
    write(d, "t.mlmap", "previous contents");
    write(d, "bad.csv", &csv_with(Some("5,car,0.9,NaN,2.0,3.0")));
    refused(
        d,
        &["fit", "--train", "bad.csv", "-o", "t.mlmap"],
        &["bad.csv:6: "],
    );
}

#[test]
fn apply_refuses_malformed_input_and_leaves_no_partial_output() {
    let table = golden_table();
    for_each_malformed_file(|d, file, needles| {
        refused(
            d,
            &[
                "apply", "--table", &table, "--input", file, "--output", "out.csv",
            ],
            needles,
        );
    });
    // The bad row comes after rows already scored: the earlier output stays untouched.
    let dir = tempdir();
    let d = dir.path();
    write(d, "out.csv", "previous contents\n");
    write(d, "bad.csv", &csv_with(Some("5,car,0.9,1.0,2.0,inf")));
    refused(
        d,
        &[
            "apply", "--table", &table, "--input", "bad.csv", "--output", "out.csv",
        ],
        &["bad.csv:6: column \"pedestrian\""],
    );
}

#[test]
fn eval_and_tune_refuse_malformed_data() {
    let table = golden_table();
    let train = data("train");
    for_each_malformed_file(|d, file, needles| {
        refused(
            d,
            &["eval", "--table", &table, "--test", file, "--plots", "p"],
            needles,
        );
    });
    // --val and --ood of eval, --val of tune: the same reader, the same messages.
    let dir = tempdir();
    let d = dir.path();
    write(d, "bad.csv", &csv_with(Some("5,car,0.9,1.0,abc,3.0")));
    let test = data("test");
    let needles = ["bad.csv:6: column \"cyclist\": \"abc\" is not a number"];
    refused(
        d,
        &[
            "eval", "--table", &table, "--test", &test, "--val", "bad.csv",
        ],
        &needles,
    );
    refused(
        d,
        &[
            "eval", "--table", &table, "--test", &test, "--ood", "bad.csv",
        ],
        &needles,
    );
    refused(d, &tune_args("t.mlmap", &train, "bad.csv"), &needles);
    refused(d, &tune_args("t.mlmap", "bad.csv", &data("val")), &needles);
}

#[test]
fn rows_without_labels_are_refused_where_labels_are_needed() {
    let dir = tempdir();
    let d = dir.path();
    let table = golden_table();
    let train = data("train");
    write(d, "nolabels.csv", "car,cyclist,pedestrian\n1,2,3\n");
    write(
        d,
        "emptylabel.csv",
        "label,car,cyclist,pedestrian\ncar,1,2,3\nbackground,1,2,3\n,1,2,3\n",
    );
    let no_labels = ["nolabels.csv: has no labels"];
    let empty = ["emptylabel.csv:4: column \"label\": the label is empty"];
    for (file, needles) in [("nolabels.csv", &no_labels), ("emptylabel.csv", &empty)] {
        refused(d, &["eval", "--table", &table, "--test", file], needles);
        refused(
            d,
            &[
                "eval",
                "--table",
                &table,
                "--test",
                &data("test"),
                "--val",
                file,
            ],
            needles,
        );
        refused(d, &tune_args("t.mlmap", &train, file), needles);
    }
    // Header-only test and validation sets.
    write(d, "empty.csv", "label,car,cyclist,pedestrian\n");
    refused(
        d,
        &["eval", "--table", &table, "--test", "empty.csv"],
        &["empty.csv: holds no data rows"],
    );
    refused(
        d,
        &tune_args("t.mlmap", &train, "empty.csv"),
        &["empty.csv: holds no data rows"],
    );
    // The out-of-distribution set needs no labels.
    ok(
        d,
        &[
            "eval",
            "--table",
            &table,
            "--test",
            &data("test"),
            "--ood",
            "nolabels.csv",
        ],
    );
}

#[test]
fn classes_must_match_the_table() {
    let dir = tempdir();
    let d = dir.path();
    let table = golden_table();
    let train = data("train");
    write(
        d,
        "reordered.csv",
        "label,car,pedestrian,cyclist\ncar,1,2,3\n",
    );
    write(d, "fewer.csv", "label,car,cyclist\ncar,1,2\n");
    write(d, "renamed.csv", "label,car,bike,pedestrian\ncar,1,2,3\n");
    for file in ["reordered.csv", "fewer.csv", "renamed.csv"] {
        let needles = [
            &format!("{file}: its classes ")[..],
            "differ from the table's [car, cyclist, pedestrian]",
        ];
        refused(
            d,
            &["apply", "--table", &table, "--input", file, "-o", "out.csv"],
            &needles,
        );
        refused(d, &["eval", "--table", &table, "--test", file], &needles);
        refused(
            d,
            &[
                "eval",
                "--table",
                &table,
                "--test",
                &data("test"),
                "--val",
                file,
            ],
            &needles,
        );
        refused(
            d,
            &[
                "eval",
                "--table",
                &table,
                "--test",
                &data("test"),
                "--ood",
                file,
            ],
            &needles,
        );
        refused(
            d,
            &tune_args("t.mlmap", &train, file),
            &[&format!("{file}: its classes ")[..]],
        );
    }
    // An NPY directory whose default class names are not the table's.
    let npy = repo("tests/fixtures/npy_bigendian");
    let npy = npy.to_string_lossy();
    refused(
        d,
        &["apply", "--table", &table, "--input", &npy, "-o", "out.csv"],
        &[&format!("{npy}: its classes [class0, class1, class2] differ")[..]],
    );
}

#[test]
fn npy_inputs_are_refused_with_the_file_and_row() {
    let dir = tempdir();
    let d = dir.path();
    let table = golden_table();
    let classes = "car\ncyclist\npedestrian\n";
    // A NaN logit in row index 2.
    let nan = d.join("nan");
    std::fs::create_dir(&nan).unwrap();
    write_npy(
        &nan.join("logits.npy"),
        &[3, 3],
        &[1f32, 2., 3., 4., 5., 6., 7., f32::NAN, 9.],
    );
    write_npy(&nan.join("labels.npy"), &[3], &[0i32, 1, 2]);
    write(&nan, "classes.txt", classes);
    // A label that is not a class index, in row index 1.
    let label = d.join("label");
    std::fs::create_dir(&label).unwrap();
    write_npy(
        &label.join("logits.npy"),
        &[2, 3],
        &[1f64, 2., 3., 4., 5., 6.],
    );
    write_npy(&label.join("labels.npy"), &[2], &[0i64, 3]);
    write(&label, "classes.txt", classes);
    // An objectness above 1, in row index 0.
    let os = d.join("os");
    std::fs::create_dir(&os).unwrap();
    write_npy(&os.join("logits.npy"), &[2, 3], &[1f64, 2., 3., 4., 5., 6.]);
    write_npy(&os.join("objectness.npy"), &[2], &[1.5f64, 0.5]);
    write(&os, "classes.txt", classes);
    let cases = [
        ("nan", "nan/logits.npy: row index 2: "),
        (
            "label",
            "label/labels.npy: row index 1: label 3 is not a class index",
        ),
        ("os", "os/objectness.npy: row index 0: "),
    ];
    for (input, needle) in cases {
        refused(
            d,
            &[
                "apply", "--table", &table, "--input", input, "-o", "out.csv",
            ],
            &[needle],
        );
        if input != "os" {
            refused(d, &["fit", "--train", input, "-o", "t.mlmap"], &[needle]);
        }
    }
    // A single .npy file is not an NPY input.
    refused(
        d,
        &["fit", "--train", "nan/logits.npy", "-o", "t.mlmap"],
        &["nan/logits.npy: an NPY input is a directory"],
    );
}

#[test]
fn bad_tables_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    let golden = std::fs::read(golden_table()).unwrap();
    let mut flipped = golden.clone();
    flipped[golden.len() / 2] ^= 0x10;
    std::fs::write(d.join("flipped.mlmap"), &flipped).unwrap();
    std::fs::write(d.join("short.mlmap"), &golden[..golden.len() / 2]).unwrap();
    std::fs::write(d.join("empty.mlmap"), b"").unwrap();
    std::fs::copy(data("val"), d.join("data.csv")).unwrap();
    std::fs::create_dir(d.join("dir.mlmap")).unwrap();
    let cases: [(&str, &str); 6] = [
        (
            "flipped.mlmap",
            "flipped.mlmap: table checksum does not match its contents",
        ),
        ("short.mlmap", "short.mlmap: "),
        (
            "empty.mlmap",
            "empty.mlmap: input is too short to be an mlmap table",
        ),
        (
            "data.csv",
            "data.csv: input does not start with the mlmap magic",
        ),
        ("dir.mlmap", "dir.mlmap: "),
        ("missing.mlmap", "missing.mlmap: "),
    ];
    let input = data("val");
    for (table, needle) in cases {
        refused(d, &["inspect", table], &[needle]);
        refused(d, &["inspect", table, "--format", "json"], &[needle]);
        refused(
            d,
            &[
                "apply", "--table", table, "--input", &input, "-o", "out.csv",
            ],
            &[needle],
        );
        refused(
            d,
            &["eval", "--table", table, "--test", &input, "--plots", "p"],
            &[needle],
        );
    }
}

#[test]
fn parameters_out_of_range_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    let train = data("train");
    let fit = |flags: &[&str], needles: &[&str]| {
        let mut args = vec!["fit", "--train", &train, "--output", "t.mlmap"];
        args.extend(flags);
        refused(d, &args, needles);
    };
    fit(&["--bins-ml", "0"], &["--bins-ml 0 is out of range"]);
    fit(
        &["--bins-map", "65536"],
        &["--bins-map 65536 is out of range"],
    );
    fit(&["--lambda-ml", "-1"], &["--lambda-ml -1 is out of range"]);
    fit(
        &["--lambda-map=-0.5"],
        &["--lambda-map -0.5 is out of range"],
    );
    fit(&["--lambda-ml", "0"], &["--lambda-ml 0 is out of range"]);
    fit(
        &["--lambda-ml", "NaN"],
        &["--lambda-ml NaN is out of range"],
    );
    fit(
        &["--lambda-map", "2e6"],
        &["--lambda-map 2000000 is out of range"],
    );

    let val = data("val");
    let tune = |flags: &[&str], needles: &[&str]| {
        let mut args = vec!["tune", "--train", &train, "--val", &val, "-o", "t.mlmap"];
        args.extend(flags);
        refused(d, &args, needles);
    };
    tune(&["--bins-ml", "9..3"], &["--bins-ml: empty range `9..3`"]);
    tune(
        &["--bins-map", "0"],
        &["--bins-map: bin count 0 is not in 1..=65535"],
    );
    tune(
        &["--bins-map", "4,x"],
        &["--bins-map: `x` is not a bin count"],
    );
    tune(&["--lambda-min", "0"], &["--lambda-min/--lambda-max: "]);
    tune(&["--lambda-min", "-1"], &["--lambda-min/--lambda-max: "]);
    tune(
        &["--lambda-min", "1", "--lambda-max", "0.1"],
        &["--lambda-min/--lambda-max: "],
    );
    tune(
        &["--lambdas-per-decade", "0"],
        &["--lambda-min/--lambda-max: "],
    );

    let table = golden_table();
    let test = data("test");
    let eval = |flags: &[&str], needles: &[&str]| {
        let mut args = vec!["eval", "--table", &table, "--test", &test];
        args.extend(flags);
        refused(d, &args, needles);
    };
    eval(&["--ece-bins", "0"], &["--ece-bins must be in 1..="]);
    eval(&["--ece-bins", "2000000"], &["--ece-bins must be in 1..="]);
}

#[test]
fn usage_errors_exit_with_2() {
    let dir = tempdir();
    let d = dir.path();
    let train = data("train");
    let table = golden_table();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![], "Usage: mlmap <COMMAND>"),
        (vec!["frob"], "unrecognized subcommand 'frob'"),
        (vec!["--frob"], "unexpected argument '--frob'"),
        (vec!["fit", "-o", "t.mlmap"], "--train <FILE>"),
        (vec!["fit", "--train", &train], "--output <TABLE>"),
        (
            vec!["fit", "--train", &train, "-o", "t.mlmap", "--edges", "log"],
            "invalid value 'log' for '--edges",
        ),
        (
            vec![
                "fit",
                "--train",
                &train,
                "-o",
                "t.mlmap",
                "--upper-tail",
                "up",
            ],
            "invalid value 'up' for '--upper-tail",
        ),
        (
            vec!["fit", "--train", &train, "-o", "t.mlmap", "--bins-ml", "x"],
            "invalid value 'x' for '--bins-ml",
        ),
        (
            vec!["fit", "--train", &train, "-o", "t.mlmap", "--bins-ml", "-3"],
            "'-3'",
        ),
        (
            vec![
                "fit",
                "--train",
                &train,
                "-o",
                "t.mlmap",
                "--lambda-ml",
                "small",
            ],
            "invalid value 'small' for '--lambda-ml",
        ),
        (
            vec!["tune", "--train", &train, "-o", "t.mlmap"],
            "--val <FILE>",
        ),
        (
            vec![
                "tune",
                "--train",
                &train,
                "--val",
                &train,
                "-o",
                "t.mlmap",
                "--objective",
                "auc",
            ],
            "invalid value 'auc' for '--objective",
        ),
        (
            vec![
                "tune", "--train", &train, "--val", &train, "-o", "t.mlmap", "--format", "markdown",
            ],
            "invalid value 'markdown' for '--format",
        ),
        (
            vec!["apply", "--table", &table, "-o", "out.csv"],
            "--input <FILE>",
        ),
        (vec!["eval", "--table", &table], "--test <FILE>"),
        (
            vec![
                "eval", "--table", &table, "--test", &train, "--format", "yaml",
            ],
            "invalid value 'yaml' for '--format",
        ),
        (
            vec![
                "eval",
                "--table",
                &table,
                "--test",
                &train,
                "--ece-binning",
                "floor",
            ],
            "invalid value 'floor' for '--ece-binning",
        ),
        (
            vec![
                "eval",
                "--table",
                &table,
                "--test",
                &train,
                "--ece-bins",
                "-1",
            ],
            "'-1'",
        ),
        (vec!["inspect"], "<TABLE>"),
        (
            vec!["inspect", &table, "extra"],
            "unexpected argument 'extra'",
        ),
    ];
    for (args, needle) in cases {
        refused(d, &args, &[needle]);
    }
    // Help and version are not errors.
    let run = ok(d, &["--help"]);
    assert!(run.stdout.contains("Usage: mlmap <COMMAND>"));
    for sub in ["fit", "tune", "apply", "eval", "inspect", "demo"] {
        assert!(run.stdout.contains(&format!("\n  {sub} ")), "{sub}");
        assert!(ok(d, &[sub, "--help"])
            .stdout
            .contains(&format!("Usage: mlmap {sub}")));
    }
    let run = ok(d, &["--version"]);
    assert_eq!(run.stdout, format!("mlmap {}\n", env!("CARGO_PKG_VERSION")));
}

#[test]
fn outputs_must_go_to_a_file_in_an_existing_directory() {
    let dir = tempdir();
    let d = dir.path();
    std::fs::create_dir(d.join("taken")).unwrap();
    let (train, val, table) = (data("train"), data("val"), golden_table());
    for out in ["nowhere/t.mlmap", "taken"] {
        let needle = if out == "taken" {
            "taken: is a directory; the output must be a file path"
        } else {
            "nowhere/t.mlmap: the output directory does not exist"
        };
        refused(d, &["fit", "--train", &train, "--output", out], &[needle]);
        refused(d, &tune_args(out, &train, &val), &[needle]);
        refused(
            d,
            &["apply", "--table", &table, "--input", &val, "--output", out],
            &[needle],
        );
    }
    // The output check comes first: no long work before a mistyped output fails.
    refused(
        d,
        &[
            "fit",
            "--train",
            "missing.csv",
            "--output",
            "nowhere/t.mlmap",
        ],
        &["nowhere/t.mlmap: the output directory does not exist"],
    );
    // --plots names a file, not a directory.
    write(d, "plots", "a file");
    refused(
        d,
        &[
            "eval", "--table", &table, "--test", &val, "--plots", "plots",
        ],
        &["plots: cannot create"],
    );
    // The demo reads every input before it creates its output directory.
    refused(
        d,
        &["demo", "--data", "nodata", "--output", "demo-out"],
        &["nodata/train.csv: no such file or directory"],
    );
}

#[test]
fn undefined_metrics_are_null_and_undefined_objectives_refused() {
    let dir = tempdir();
    let d = dir.path();
    let table = golden_table();
    // Only background rows: nothing to average for nll, the true positives, auroc, ap.
    write(
        d,
        "background.csv",
        "label,car,cyclist,pedestrian\nbackground,1,2,3\nbackground,1e308,-1e308,3\n",
    );
    let run = ok(
        d,
        &[
            "eval",
            "--table",
            &table,
            "--test",
            "background.csv",
            "--format",
            "json",
        ],
    );
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    for (name, m) in v["methods"].as_object().unwrap() {
        for key in [
            "nll",
            "tp_mean",
            "tp_var",
            "auroc",
            "ap_car",
            "ap_cyclist",
            "ap_pedestrian",
        ] {
            assert!(m[key].is_null(), "{name}.{key} = {}", m[key]);
        }
        for key in ["ece", "mce", "brier", "fp_mean", "fp_var"] {
            assert!(m[key].as_f64().unwrap().is_finite(), "{name}.{key}");
        }
    }
    // ... and no temperature can be fitted on them, nor an nll minimised.
    refused(
        d,
        &[
            "eval",
            "--table",
            &table,
            "--test",
            &data("test"),
            "--val",
            "background.csv",
        ],
        &["background.csv: no row is labelled with a class"],
    );
    let train = data("train");
    let mut args = tune_args("t.mlmap", &train, "background.csv");
    args.extend(["--objective", "nll"]);
    refused(
        d,
        &args,
        &["background.csv: no row is labelled with a class: the nll objective is undefined"],
    );
    // ECE and Brier are defined on false positives alone.
    let mut args = tune_args("t.mlmap", &train, "background.csv");
    args.extend(["--objective", "brier"]);
    ok(d, &args);
    assert!(d.join("t.mlmap").is_file());
}

#[test]
fn tune_names_the_training_file_for_training_data_a_table_cannot_hold() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "val.csv", "label,a,b\na,1,0\nb,0,1\nbackground,0,0\n");
    write(
        d,
        "tight.csv",
        "label,a,b\na,1000000,0\na,1000000.1,0\nb,0,1\nb,0,2\n",
    );
    write(
        d,
        "huge.csv",
        "label,a,b\na,1e38,0\na,3e38,0\nb,0,1\nb,0,2\n",
    );
    let args = |train: &'static str, bins: &'static str| {
        vec![
            "tune",
            "--train",
            train,
            "--val",
            "val.csv",
            "--bins-ml",
            bins,
            "--bins-map",
            bins,
            "-o",
            "t.mlmap",
        ]
    };
    refused(
        d,
        &args("tight.csv", "60000"),
        &[
            "tight.csv: class \"a\": the range",
            "cannot be split into 60000 bins",
        ],
    );
    refused(
        d,
        &args("huge.csv", "3"),
        &["huge.csv: class \"a\": the training logits or their variance exceed the f32 range"],
    );
}

#[test]
fn a_plot_that_cannot_be_written_is_refused_with_its_path() {
    let dir = tempdir();
    let d = dir.path();
    // A directory sits where a plot goes.
    std::fs::create_dir_all(d.join("plots/reliability_ml.svg/x")).unwrap();
    let run = mlmap(
        d,
        &[
            "eval",
            "--table",
            &golden_table(),
            "--test",
            &data("val"),
            "--plots",
            "plots",
        ],
    );
    assert_eq!(run.code, 2, "{run:?}");
    assert_eq!(run.stdout, "");
    assert!(
        run.stderr.starts_with("mlmap: plots/reliability_ml.svg: "),
        "{}",
        run.stderr
    );
    // The plots written before it are whole files; no temporary file stays.
    for entry in std::fs::read_dir(d.join("plots")).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(name.ends_with(".svg") && !name.starts_with('.'), "{name}");
    }
}
