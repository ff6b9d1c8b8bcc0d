use super::*;

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
        refused(d, &eval_args(&table, &test, flags), needles);
    };
    eval(&["--ece-bins", "0"], &["--ece-bins must be in 1..="]);
    eval(&["--ece-bins", "2000000"], &["--ece-bins must be in 1..="]);
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
        &eval_args(&table, &val, &["--plots", "plots"]),
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
fn a_plot_that_cannot_be_written_is_refused_with_its_path() {
    let dir = tempdir();
    let d = dir.path();
    // A directory sits where a plot goes.
    std::fs::create_dir_all(d.join("plots/reliability_ml.svg/x")).unwrap();
    let (table, val) = (golden_table(), data("val"));
    let run = mlmap(d, &eval_args(&table, &val, &["--plots", "plots"]));
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
