//! The `mlmap` binary, run as a user runs it (DESIGN §4): every subcommand on the
//! shipped data and on small hand-made files, the demo, and every bad-input case (exit
//! code 2, a message naming the file and line, and no output file left behind).
//!
//! This file holds what the command modules share: running the binary and asserting its
//! outcome, the data files, and the heads of the layer ([`HEADS`]): the columns,
//! methods and scores each head contributes to the outputs, so that a head is one entry
//! of that list, not new code in every test.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use mlmap::host::dataset::{DataError, DataSource, Label};
use mlmap::host::DynTable;
use mlmap::{FastMath, Libm};
use npyz::WriterBuilder;
use serde_json::Value;

/// `fit`: the golden tables byte for byte, the recorded settings, NPY training data.
mod fit;

/// `tune`: the written table is the best candidate, ranked by each objective, and the
/// tuner's objectives equal the metrics module's on the written table's scores.
mod tune;

/// `apply`: the output columns of every input layout, every score bit for bit with the
/// library, and the scores against the numpy reference.
mod apply;

/// `eval`: the JSON keys and the layer's metrics, the text and markdown reports, the
/// plots and the selectable ECE convention.
mod eval;

/// `quantize` and `apply --quantized`: the output equals `apply` on the dequantized
/// logits byte for byte (CSV, NPY int8 and int16); bad codes, tables and parameters.
mod quantize;

/// `export-c`: the header compiles as C and C++ with one definition of the array, holds
/// the table's bytes, escapes class names and takes only a safe `--name`.
mod export_c;

/// Class names at every reader and writer: unprintable names refused with the rule
/// they break, names of older tables escaped on the terminal, CSV quoting.
mod names;

/// `inspect`: the text and JSON reports of a table; stdout closed early or failing.
mod inspect;

/// `demo`: the whole job in order, its files and the golden fit.
mod demo;

/// `stats` and `merge`: sharded fits in any merge order give the bytes of `fit`;
/// mismatched, truncated, corrupt and newer statistics are refused.
mod shards;

/// Bad data and bad tables: malformed CSV and NPY inputs, missing labels, classes
/// other than the table's, corrupted tables, data a table cannot hold, undefined
/// metrics. Exit code 2, the file and line named, nothing written.
mod bad_input;

/// Bad command lines and outputs: usage errors, parameters out of range, outputs in a
/// missing directory or over a directory, a plot that cannot be written; help and
/// version.
mod usage;

/// Outputs that must not destroy anything: an output naming an input is refused;
/// devices and FIFOs are written directly; fit's warnings.
#[cfg(unix)]
mod outputs;

/// Inputs read once (FIFOs, pipes), outputs that keep their modes or are refused when
/// write-protected, runs ended by a signal, and export-c over its own table.
#[cfg(unix)]
mod streams;

/// `monitor fit` and `monitor`: the numpy reference's thresholds and windows, refusals.
mod monitor;

/// `lidar-maps`: the maps, PNGs, sparse maps and crops against the numpy reference;
/// truncated scans, NaN points, broken calibrations and labels refused.
mod lidar_maps;

/// `conformal`, and the sets in `inspect`, `apply` and `eval`: numpy's thresholds and
/// sets, the coverage report, refusals.
mod conformal;

/// Messages that say what is true, and limits that refuse before the work.
mod messages;

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

/// Runs `mlmap ARGS` in `dir`, expects success and JSON on stdout, and returns it.
fn ok_json<S: AsRef<OsStr>>(dir: &Path, args: &[S]) -> Value {
    let run = ok(dir, args);
    serde_json::from_str(&run.stdout)
        .unwrap_or_else(|e| panic!("mlmap {:?}: {e}:\n{}", os_args(args), run.stdout))
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

/// `apply --table TABLE --input INPUT -o OUTPUT`.
fn apply_args<'a>(table: &'a str, input: &'a str, output: &'a str) -> Vec<&'a str> {
    vec!["apply", "--table", table, "--input", input, "-o", output]
}

/// `eval --table TABLE --test TEST`, then `more`.
fn eval_args<'a>(table: &'a str, test: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["eval", "--table", table, "--test", test];
    args.extend(more);
    args
}

/// `tune` on a small grid: 3 x 9 ML, 2 x 9 MAP and 2 x 9 Bayes candidates.
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
        "--bins-bayes",
        "6,20",
        "--lambdas-per-decade",
        "1",
        "--output",
        output,
    ]
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

/// The fit of `examples/data/train.csv` with every default, the Bayes head included
/// (format version 2), as shipped in `tables/`.
fn bayes_table() -> String {
    repo("tables/default.mlmap").to_string_lossy().into_owned()
}

/// The linspace fit of `examples/data/train.csv` with the default settings, written by
/// the independent numpy fit in `tools/mlmap_ref.py` (format version 1: no Bayes head).
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

/// The classes of the shipped data and of the golden table.
const CLASSES: [&str; 3] = ["car", "cyclist", "pedestrian"];

/// The keys of JSON objects, sorted.
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

// ---------------------------------------------------------------------------------------
// The heads of the layer
// ---------------------------------------------------------------------------------------

/// One head of the layer as the CLI reports it: `apply` writes `<name>_<class>` score
/// columns and a `<name>_pred` column, `eval` a `<name>` method, `tune` a `<name>`
/// section of candidates; all of them hold the layer's scores of that head. A head the
/// table does not hold (Bayes in a version-1 table) contributes nothing.
struct LayerHead {
    /// Column, method and JSON prefix: `ml`, `map`, `bayes`.
    name: &'static str,
    /// Whether the table holds this head.
    present: fn(&DynTable) -> bool,
    /// The head's scores of one detection (logits, objectness), as the device
    /// computes them from the table.
    scores: fn(&DynTable, &[f32], f32) -> Vec<f32>,
    /// The table's bin count of this head.
    bins: fn(&DynTable) -> usize,
    /// The table's smoothing lambda of this head.
    lambda: fn(&DynTable) -> f32,
}

/// Every head, in the order of the CLI's columns and reports.
const HEADS: [LayerHead; 4] = [ML, MAP, BAYES, OPEN];

/// The maximum-likelihood head.
const ML: LayerHead = LayerHead {
    name: "ml",
    present: |_| true,
    scores: |t, x, os| {
        let (mut out, mut scratch) = (vec![0f32; t.k()], vec![0f32; t.k()]);
        t.ml_into(x, os, &mut out, &mut scratch).unwrap();
        out
    },
    bins: DynTable::bins_ml,
    lambda: |t| t.settings().lambda_ml,
};

/// The maximum a-posteriori head, with the default `Libm` backend.
const MAP: LayerHead = LayerHead {
    name: "map",
    present: |_| true,
    scores: |t, x, os| {
        let (mut out, mut scratch) = (vec![0f32; t.k()], vec![0f32; t.k()]);
        t.map_into::<Libm>(x, os, &mut out, &mut scratch).unwrap();
        out
    },
    bins: DynTable::bins_map,
    lambda: |t| t.settings().lambda_map,
};

/// The Bayes head, with its device default backend `FastMath` (DESIGN §1.6).
const BAYES: LayerHead = LayerHead {
    name: "bayes",
    present: |t| t.bayes_head().is_some(),
    scores: |t, x, os| {
        let cats = t.bayes_head().map_or(0, |b| b.categories());
        let (mut out, mut scratch) = (vec![0f32; t.k()], vec![0f32; cats]);
        t.bayes_into::<FastMath>(x, os, &mut out, &mut scratch)
            .unwrap();
        out
    },
    bins: |t| t.bayes_head().map_or(0, |b| b.bins()),
    lambda: |t| t.bayes_head().map_or(0.0, |b| b.lambda()),
};

/// The open head, with its device default backend `FastMath` (DESIGN §1.8); its bins and
/// lambda are its Bayes head's.
const OPEN: LayerHead = LayerHead {
    name: "open",
    present: |t| t.open_params().is_some(),
    scores: |t, x, os| {
        let cats = t.bayes_head().map_or(0, |b| b.categories());
        let (mut out, mut scratch) = (vec![0f32; t.k()], vec![0f32; cats]);
        t.open_into::<FastMath>(x, os, &mut out, &mut scratch)
            .unwrap();
        out
    },
    bins: |t| t.bayes_head().map_or(0, |b| b.bins()),
    lambda: |t| t.bayes_head().map_or(0.0, |b| b.lambda()),
};

/// The heads `table` holds, in the order of the CLI's columns and reports.
fn heads_of(table: &DynTable) -> impl Iterator<Item = &'static LayerHead> + '_ {
    HEADS.iter().filter(move |h| (h.present)(table))
}

impl LayerHead {
    /// The head's scores of one row, as the device computes them.
    fn score(&self, table: &DynTable, row: &DataRow) -> Vec<f32> {
        let x: Vec<f32> = row.logits.iter().map(|&v| v as f32).collect();
        (self.scores)(table, &x, row.objectness as f32)
    }

    /// The head's scores of every row, flattened row by row in `f64`, as the metrics
    /// module takes them.
    fn flat_scores(&self, table: &DynTable, rows: &[DataRow]) -> Vec<f64> {
        rows.iter()
            .flat_map(|r| self.score(table, r))
            .map(f64::from)
            .collect()
    }
}

/// The methods `eval` reports: the baselines, then every head of `table`.
fn methods(with_val: bool, table: &DynTable) -> Vec<&'static str> {
    let mut m = vec!["sigmoid", "softmax"];
    if with_val {
        m.extend(["temperature", "isotonic"]);
    }
    m.push("energy");
    m.extend(heads_of(table).map(|h| h.name));
    if table.open_params().is_some() && !m.contains(&"open") {
        m.push("open");
    }
    m
}

/// The score columns `apply` writes after `id` and `label`: every head's class scores,
/// then every head's predicted class (the heads of `table`).
fn score_columns(table: &DynTable) -> Vec<String> {
    let mut cols: Vec<String> = Vec::new();
    for head in heads_of(table) {
        cols.extend(CLASSES.iter().map(|c| format!("{}_{c}", head.name)));
    }
    cols.extend(heads_of(table).map(|h| format!("{}_pred", h.name)));
    cols
}

/// Checks the score columns of every record of `apply`'s output (found by their names
/// in `header`) against the layer, bit for bit, and each head's predicted class.
fn check_scores(table: &DynTable, rows: &[DataRow], header: &[String], records: &[Vec<String>]) {
    let column = |name: String| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    assert_eq!(records.len(), rows.len());
    for head in heads_of(table) {
        let cols: Vec<usize> = CLASSES
            .iter()
            .map(|c| column(format!("{}_{c}", head.name)))
            .collect();
        let pred = column(format!("{}_pred", head.name));
        for (rec, row) in records.iter().zip(rows) {
            let want = head.score(table, row);
            let got: Vec<f32> = cols.iter().map(|&i| rec[i].parse().unwrap()).collect();
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "{}: {rec:?}", head.name);
            // Ties of the top score go to the larger logit (DESIGN §1.7).
            let decided = mlmap::decide(&want, &row.logits);
            assert_eq!(rec[pred], CLASSES[decided], "{rec:?}");
        }
    }
}
