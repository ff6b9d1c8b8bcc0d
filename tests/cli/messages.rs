//! Messages that say what is true, and limits that refuse before the work: counts of
//! other rows per class, a newer table format, a flag value as written, a logit beyond
//! `f32` in `apply` and `fit` alike, long fields and class lists cut short, the tune
//! grid's cap, help written to a full device.

use super::*;

#[test]
fn counts_of_other_rows_per_class_name_the_class() {
    let dir = tempdir();
    let d = dir.path();
    // Four rows each, but class `a` has two in pass (a) and one in pass (b).
    write(d, "p.csv", "label,a,b\na,1,0\na,2,0\nb,0,1\nb,0,2\n");
    write(d, "q.csv", "label,a,b\na,1.5,0\nb,0,1.5\nb,0,1\nb,0.5,2\n");
    ok(d, &["stats", "--train", "p.csv", "-o", "a.stats"]);
    ok(
        d,
        &[
            "stats", "--stats", "a.stats", "--train", "q.csv", "-o", "b.stats",
        ],
    );
    refused(
        d,
        &["merge", "--stats", "a.stats", "b.stats", "-o", "t.mlmap"],
        &["class \"a\" cover 1 rows but its statistics 2 rows"],
    );
}

#[test]
fn a_newer_table_format_names_the_versions_read() {
    let dir = tempdir();
    let d = dir.path();
    let mut bytes = std::fs::read(bayes_table()).unwrap();
    // The version follows the 4-byte magic; the CRC-32 of the rest ends the file.
    bytes[4] = 5;
    let body = bytes.len() - 4;
    let crc = crate::support::crc32(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
    std::fs::write(d.join("v5.mlmap"), &bytes).unwrap();
    refused(
        d,
        &["inspect", "v5.mlmap"],
        &["version 5 is not supported (this build reads versions 1 to 4)"],
    );
}

#[test]
fn flag_values_are_reported_as_written() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", "label,a,b\na,1,0\nb,0,1\n");
    for flag in ["--lambda-ml", "--lambda-map", "--lambda-bayes"] {
        let run = mlmap(
            d,
            &["fit", "--train", "x.csv", flag, "1e-46", "-o", "t.mlmap"],
        );
        assert_eq!(run.code, 2, "{run:?}");
        assert!(run.stderr.contains("'1e-46'"), "{run:?}");
        assert!(run.stderr.contains("would be 0"), "{run:?}");
        let run = mlmap(
            d,
            &["fit", "--train", "x.csv", flag, "1e39", "-o", "t.mlmap"],
        );
        assert_eq!(run.code, 2, "{run:?}");
        assert!(run.stderr.contains("'1e39'"), "{run:?}");
    }
    assert!(!d.join("t.mlmap").exists());
}

#[test]
fn a_logit_beyond_f32_is_refused_by_apply_and_fit_with_its_line() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", "label,a,b\na,1,0\nb,0,1\n");
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    write(d, "big.csv", "label,a,b\na,1,0\nb,1e39,1\n");
    let needles = ["big.csv:3: column \"a\": \"1e39\" is out of range"];
    refused(d, &apply_args("t.mlmap", "big.csv", "o.csv"), &needles);
    refused(d, &["fit", "--train", "big.csv", "-o", "u.mlmap"], &needles);
    refused(
        d,
        &["eval", "--table", "t.mlmap", "--test", "big.csv"],
        &needles,
    );
}

#[test]
fn an_unterminated_quote_and_long_fields_are_refused_briefly() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", "label,a,b\na,1,0\nb,0,1\n");
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    write(d, "q.csv", "label,a,b\na,1,0\nb,0,\"1");
    refused(
        d,
        &apply_args("t.mlmap", "q.csv", "o.csv"),
        &["q.csv:3: a quoted field has no closing quote"],
    );
    // A 3 MiB field: refused at the record limit, and not echoed whole.
    write(
        d,
        "long.csv",
        &format!("label,a,b\na,{},0\n", "7".repeat(3 << 20)),
    );
    let run = mlmap(d, &apply_args("t.mlmap", "long.csv", "o.csv"));
    assert_eq!(run.code, 2, "{}", &run.stderr[..run.stderr.len().min(500)]);
    assert!(
        run.stderr.len() < 400,
        "{} bytes of stderr",
        run.stderr.len()
    );
    assert!(run
        .stderr
        .contains("long.csv:2: the record is longer than 1048576 bytes"));
    // A long text that is not a number is echoed cut short.
    write(
        d,
        "text.csv",
        &format!("label,a,b\na,{},0\n", "x".repeat(500_000)),
    );
    let run = mlmap(d, &apply_args("t.mlmap", "text.csv", "o.csv"));
    assert_eq!(run.code, 2);
    assert!(
        run.stderr.len() < 400,
        "{} bytes of stderr",
        run.stderr.len()
    );
    assert!(run.stderr.contains("(500000 bytes)"), "{}", run.stderr);
}

#[test]
fn many_classes_are_capped_and_listed_briefly() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", "label,a,b\na,1,0\nb,0,1\n");
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    // 65,532 class columns in one line: refused with the count, briefly.
    let names: Vec<String> = (0..65_532).map(|i| format!("c{i}")).collect();
    write(d, "wide.csv", &format!("{}\n", names.join(",")));
    let run = mlmap(d, &apply_args("t.mlmap", "wide.csv", "o.csv"));
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run
        .stderr
        .contains("found 65532 class column(s); between 2 and 4096"));
    assert!(
        run.stderr.len() < 400,
        "{} bytes of stderr",
        run.stderr.len()
    );
    // Other classes than the table's: both lists, cut short.
    let names: Vec<String> = (0..100).map(|i| format!("c{i}")).collect();
    let zeros = vec!["0"; 100];
    write(
        d,
        "many.csv",
        &format!("{}\n{}\n", names.join(","), zeros.join(",")),
    );
    let run = mlmap(d, &apply_args("t.mlmap", "many.csv", "o.csv"));
    assert_eq!(run.code, 2, "{run:?}");
    assert!(
        run.stderr.contains(
            "[c0, c1, c2, c3, c4, c5, c6, c7, ... and 92 more] differ from the table's [a, b]"
        ),
        "{}",
        run.stderr
    );
}

#[test]
fn a_tune_grid_past_the_cap_is_refused_before_reading() {
    let dir = tempdir();
    let d = dir.path();
    // The inputs do not exist: the grid is refused first.
    let base = [
        "tune", "--train", "no.csv", "--val", "no.csv", "-o", "t.mlmap",
    ];
    let run = mlmap(
        d,
        &[&base[..], &["--lambdas-per-decade", "100000"]].concat(),
    );
    assert_eq!(run.code, 2, "{run:?}");
    assert!(
        run.stderr
            .contains("800001 lambdas (8.000 decades at 100000 per decade)"),
        "{run:?}"
    );
    assert!(run.stderr.contains("at most 20000"), "{run:?}");
    let run = mlmap(d, &[&base[..], &["--bins-ml", "1..65535"]].concat());
    assert_eq!(run.code, 2, "{run:?}");
    // 65535 bin counts x 25 lambdas (1e-8 to 1, three per decade), plus 37 x 25 MAP and
    // 37 x 25 Bayes candidates, and the open head's 50 epsilons.
    assert!(
        run.stderr
            .contains("the grid holds 1640275 candidates (ml 1638375, map 925, bayes 925, open 50"),
        "{run:?}"
    );
    assert!(run.stderr.contains("at most 20000"), "{run:?}");
}

#[cfg(target_os = "linux")]
#[test]
fn help_to_a_full_device_fails() {
    let dir = tempdir();
    for args in [&["--help"][..], &["--version"], &["fit", "--help"]] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_mlmap"))
            .args(args)
            .current_dir(dir.path())
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(stderr.contains("No space left on device"), "{stderr}");
    }
}
