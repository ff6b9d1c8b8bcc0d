use std::ffi::OsStr;
use std::path::Path;

use mlmap::host::dataset::Label;
use mlmap::{EdgeMode, UpperTail};

use super::*;

#[test]
fn fit_linspace_and_matlab_equal_the_golden_tables_byte_for_byte() {
    let dir = tempdir();
    let d = dir.path();
    let run = ok(
        d,
        &[
            "fit",
            "--train",
            &data("train"),
            "--no-bayes",
            "--output",
            "t.mlmap",
        ],
    );
    // The ML and MAP heads alone: the version-1 golden table.
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
            "--no-bayes",
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
    assert!(ML.score(&c, &high)[0] > ML.score(&g, &high)[0]);
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
