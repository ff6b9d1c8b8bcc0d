use super::*;

/// `monitor fit` then `monitor` on the shipped data: the thresholds are the numpy
/// reference's (tools/monitor_ref.py), every window is printed, the out-of-distribution
/// log alarms from its first window, the test log in few windows.
#[test]
fn fit_and_replay() {
    let dir = tempdir();
    let d = dir.path();
    let run = ok(
        d,
        &[
            "monitor",
            "fit",
            "--table",
            &bayes_table(),
            "--val",
            &data("val"),
            "--window",
            "50",
            "--false-alarm",
            "0.05",
            "-o",
            "mon.mlmap",
        ],
    );
    assert!(run.stdout.contains("psi_max >"), "{}", run.stdout);
    // The written file is the shipped example byte for byte (same inputs, same seed).
    assert_eq!(
        std::fs::read(d.join("mon.mlmap")).unwrap(),
        std::fs::read(repo("tests/golden/monitor_small.mlmap")).unwrap()
    );
    // It still decodes as the table.
    assert_eq!(
        read_table(&d.join("mon.mlmap")),
        read_table(Path::new(&bayes_table()))
    );
    let run = ok(
        d,
        &[
            "monitor",
            "--table",
            "mon.mlmap",
            "--input",
            &data("ood"),
            "--format",
            "jsonl",
        ],
    );
    let lines: Vec<Value> = run
        .stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2000 / 50);
    let want = {
        let text = std::fs::read_to_string(repo("tests/golden/monitor/windows_ood.json")).unwrap();
        serde_json::from_str::<Value>(&text).unwrap()
    };
    for (i, (l, w)) in lines
        .iter()
        .zip(want["windows"].as_array().unwrap())
        .enumerate()
    {
        assert_eq!(l["window"], i);
        assert_eq!(l["rows"], 50);
        assert_eq!(l["alarm"], true);
        for key in ["psi_max", "oos_rate", "q_mean"] {
            let (g, e) = (l[key].as_f64().unwrap(), w[key].as_f64().unwrap());
            assert!(
                (g - e).abs() <= 1e-5 * (1.0 + e.abs()),
                "{key}: {g} against {e}"
            );
        }
        assert!(l["psi"]["car"].is_f64());
    }
    let run = ok(
        d,
        &["monitor", "--table", "mon.mlmap", "--input", &data("test")],
    );
    let last = run.stdout.lines().rev().nth(1).unwrap();
    assert!(last.starts_with("200 windows (10000 rows)"), "{last}");
    assert_eq!(run.stdout.lines().count(), 200 + 2);
}

/// Without a section, `--window` is needed and nothing alarms; with one, another window
/// is refused; a table without the Bayes head has no monitor; bad flags are refused
/// before anything is written.
#[test]
fn refusals() {
    let dir = tempdir();
    let d = dir.path();
    let run = ok(
        d,
        &[
            "monitor",
            "--table",
            &bayes_table(),
            "--input",
            &data("ood"),
            "--window",
            "500",
        ],
    );
    assert!(
        run.stdout
            .contains("4 windows (2000 rows), 0 with an alarm"),
        "{}",
        run.stdout
    );
    refused(
        d,
        &[
            "monitor",
            "--table",
            &bayes_table(),
            "--input",
            &data("ood"),
        ],
        &["default.mlmap", "no monitor section", "--window"],
    );
    let small = repo("tests/golden/monitor_small.mlmap");
    let small = small.to_str().unwrap();
    refused(
        d,
        &[
            "monitor",
            "--table",
            small,
            "--input",
            &data("ood"),
            "--window",
            "60",
        ],
        &["monitor_small.mlmap", "windows of 50", "not 60"],
    );
    refused(
        d,
        &[
            "monitor",
            "--table",
            &golden_table(),
            "--input",
            &data("ood"),
            "--window",
            "60",
        ],
        &["train_linspace.mlmap", "no Bayes head"],
    );
    let (table, val) = (bayes_table(), data("val"));
    for (flag, value, needle) in [
        ("--window", "0", "--window 0"),
        ("--false-alarm", "0", "--false-alarm 0"),
        ("--false-alarm", "0.7", "--false-alarm 0.7"),
    ] {
        let mut args = vec![
            "monitor", "fit", "--table", &table, "--val", &val, "-o", "x.mlmap",
        ];
        let w = ["--window", "50"];
        let a = ["--false-alarm", "0.05"];
        for pair in [w, a] {
            if pair[0] != flag {
                args.extend(pair);
            }
        }
        args.extend([flag, value]);
        refused(d, &args, &[needle]);
    }
    // A NaN logit in the log: the file and the line.
    write(d, "bad.csv", "car,cyclist,pedestrian\n1,2,3\n1,nan,3\n");
    refused(
        d,
        &["monitor", "--table", small, "--input", "bad.csv"],
        &["bad.csv:3", "cyclist"],
    );
}

/// `inspect` shows the monitor section, text and JSON, and the table's own size.
#[test]
fn inspect_shows_the_section() {
    let dir = tempdir();
    let small = repo("tests/golden/monitor_small.mlmap");
    let small = small.to_str().unwrap();
    let run = ok(dir.path(), &["inspect", small]);
    assert!(
        run.stdout.contains("monitor    section 308 bytes"),
        "{}",
        run.stdout
    );
    assert!(run.stdout.contains("windows of 50 detections"));
    assert!(run.stdout.contains("1704 bytes"));
    let v = ok_json(dir.path(), &["inspect", small, "--format", "json"]);
    assert_eq!(v["monitor"]["window"], 50);
    assert_eq!(v["monitor"]["bytes"], 308);
    let v = ok_json(dir.path(), &["inspect", &bayes_table(), "--format", "json"]);
    assert!(v["monitor"].is_null());
}
