use std::path::Path;

use super::*;

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
        refused(d, &eval_args(&table, file, &["--plots", "p"]), needles);
    });
    // --val and --ood of eval, --val of tune: the same reader, the same messages.
    let dir = tempdir();
    let d = dir.path();
    write(d, "bad.csv", &csv_with(Some("5,car,0.9,1.0,abc,3.0")));
    let test = data("test");
    let needles = ["bad.csv:6: column \"cyclist\": \"abc\" is not a number"];
    refused(
        d,
        &eval_args(&table, &test, &["--val", "bad.csv"]),
        &needles,
    );
    refused(
        d,
        &eval_args(&table, &test, &["--ood", "bad.csv"]),
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
    let (train, test) = (data("train"), data("test"));
    write(d, "nolabels.csv", "car,cyclist,pedestrian\n1,2,3\n");
    write(
        d,
        "emptylabel.csv",
        "label,car,cyclist,pedestrian\ncar,1,2,3\nbackground,1,2,3\n,1,2,3\n",
    );
    let no_labels = ["nolabels.csv: has no labels"];
    let empty = ["emptylabel.csv:4: column \"label\": the label is empty"];
    for (file, needles) in [("nolabels.csv", &no_labels), ("emptylabel.csv", &empty)] {
        refused(d, &eval_args(&table, file, &[]), needles);
        refused(d, &eval_args(&table, &test, &["--val", file]), needles);
        refused(d, &tune_args("t.mlmap", &train, file), needles);
    }
    // Header-only test and validation sets.
    write(d, "empty.csv", "label,car,cyclist,pedestrian\n");
    refused(
        d,
        &eval_args(&table, "empty.csv", &[]),
        &["empty.csv: holds no data rows"],
    );
    refused(
        d,
        &tune_args("t.mlmap", &train, "empty.csv"),
        &["empty.csv: holds no data rows"],
    );
    // The out-of-distribution set needs no labels.
    ok(d, &eval_args(&table, &test, &["--ood", "nolabels.csv"]));
}

#[test]
fn classes_must_match_the_table() {
    let dir = tempdir();
    let d = dir.path();
    let table = golden_table();
    let (train, test) = (data("train"), data("test"));
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
        refused(d, &apply_args(&table, file, "out.csv"), &needles);
        refused(d, &eval_args(&table, file, &[]), &needles);
        refused(d, &eval_args(&table, &test, &["--val", file]), &needles);
        refused(d, &eval_args(&table, &test, &["--ood", file]), &needles);
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
        &apply_args(&table, &npy, "out.csv"),
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
        refused(d, &apply_args(&table, input, "out.csv"), &[needle]);
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
        refused(d, &apply_args(table, &input, "out.csv"), &[needle]);
        refused(d, &eval_args(table, &input, &["--plots", "p"]), &[needle]);
    }
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
        "label,car,cyclist,pedestrian\nbackground,1,2,3\nbackground,3e38,-3e38,3\n",
    );
    let v = ok_json(
        d,
        &eval_args(&table, "background.csv", &["--format", "json"]),
    );
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
        if name == "energy" {
            continue;
        }
        for key in ["ece", "mce", "brier", "fp_mean", "fp_var"] {
            assert!(m[key].as_f64().unwrap().is_finite(), "{name}.{key}");
        }
    }
    // ... and no temperature can be fitted on them, nor an nll minimised.
    let test = data("test");
    refused(
        d,
        &eval_args(&table, &test, &["--val", "background.csv"]),
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
