use super::*;

/// Splits `examples/data/train.csv` into `n` CSV shards in `dir` (row `i` in shard
/// `i % n`), named `s0.csv`, `s1.csv`, ...
fn shards(dir: &Path, n: usize) -> Vec<String> {
    let text = std::fs::read_to_string(data("train")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let mut parts = vec![format!("{header}\n"); n];
    for (i, line) in lines.enumerate() {
        parts[i % n] += &format!("{line}\n");
    }
    (0..n)
        .map(|i| {
            let name = format!("s{i}.csv");
            write(dir, &name, &parts[i]);
            name
        })
        .collect()
}

/// Runs the whole sharded fit: pass (a) on each shard with `settings`, merged in
/// `order_a`; pass (b) on each shard, merged in `order_b` into the table `out`.
fn sharded_fit(
    dir: &Path,
    shards: &[String],
    settings: &[&str],
    order_a: &[usize],
    order_b: &[usize],
    out: &str,
) {
    for (i, s) in shards.iter().enumerate() {
        let a = format!("a{i}.stats");
        let mut args = vec!["stats", "--train", s, "--output", &a];
        args.extend_from_slice(settings);
        let run = ok(dir, &args);
        assert!(
            run.stdout.starts_with(&format!("wrote {a} (")),
            "{}",
            run.stdout
        );
    }
    let mut args = vec!["merge".to_string()];
    args.extend(order_a.iter().map(|i| format!("a{i}.stats")));
    args.extend(["-o".into(), "a.stats".into()]);
    let run = ok(dir, &args);
    assert!(
        run.stdout.contains("pass-(a) statistics of 20000 rows"),
        "{}",
        run.stdout
    );
    for (i, s) in shards.iter().enumerate() {
        let b = format!("b{i}.stats");
        ok(
            dir,
            &["stats", "--stats", "a.stats", "--train", s, "--output", &b],
        );
    }
    let mut args = vec!["merge".to_string(), "--stats".into(), "a.stats".into()];
    args.extend(order_b.iter().map(|i| format!("b{i}.stats")));
    args.extend(["--output".into(), out.into()]);
    ok(dir, &args);
}

#[test]
fn shards_merged_in_two_orders_give_the_bytes_of_fit() {
    let dir = tempdir();
    let d = dir.path();
    let s = shards(d, 3);
    for (settings, name) in [
        (vec![], "default"),
        (
            vec!["--edges", "matlab", "--no-bayes", "--bins-ml", "9"],
            "matlab",
        ),
    ] {
        let train = data("train");
        let mut fit_args = vec!["fit", "--train", &train];
        fit_args.extend_from_slice(&settings);
        let want_path = format!("{name}.mlmap");
        fit_args.extend_from_slice(&["-o", &want_path]);
        ok(d, &fit_args);
        let want = std::fs::read(d.join(&want_path)).unwrap();
        sharded_fit(d, &s, &settings, &[0, 1, 2], &[2, 0, 1], "t1.mlmap");
        sharded_fit(d, &s, &settings, &[2, 1, 0], &[1, 2, 0], "t2.mlmap");
        assert_eq!(std::fs::read(d.join("t1.mlmap")).unwrap(), want, "{name}");
        assert_eq!(std::fs::read(d.join("t2.mlmap")).unwrap(), want, "{name}");
    }
    // The default settings: the shipped table, and merged statistics are the same bytes
    // whatever the order.
    assert_eq!(
        std::fs::read(d.join("default.mlmap")).unwrap(),
        std::fs::read(bayes_table()).unwrap()
    );
    ok(
        d,
        &["merge", "a1.stats", "a0.stats", "a2.stats", "-o", "x.stats"],
    );
    ok(
        d,
        &["merge", "a2.stats", "a1.stats", "a0.stats", "-o", "y.stats"],
    );
    assert_eq!(
        std::fs::read(d.join("x.stats")).unwrap(),
        std::fs::read(d.join("y.stats")).unwrap()
    );
    // Counts merge into counts; merged counts give the same table.
    ok(d, &["merge", "b0.stats", "b2.stats", "-o", "b02.stats"]);
    ok(
        d,
        &[
            "merge",
            "--stats",
            "a.stats",
            "b1.stats",
            "b02.stats",
            "-o",
            "t3.mlmap",
        ],
    );
    assert_eq!(
        std::fs::read(d.join("t3.mlmap")).unwrap(),
        std::fs::read(d.join("t2.mlmap")).unwrap()
    );
}

#[test]
fn mismatched_or_bad_statistics_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    let s = shards(d, 2);
    ok(d, &["stats", "--train", &s[0], "-o", "a0.stats"]);
    ok(d, &["stats", "--train", &s[1], "-o", "a1.stats"]);
    ok(
        d,
        &[
            "stats",
            "--train",
            &s[1],
            "--bins-ml",
            "5",
            "-o",
            "a1x.stats",
        ],
    );
    ok(d, &["merge", "a0.stats", "a1.stats", "-o", "a.stats"]);
    ok(
        d,
        &[
            "stats", "--stats", "a.stats", "--train", &s[0], "-o", "b0.stats",
        ],
    );
    ok(
        d,
        &[
            "stats", "--stats", "a.stats", "--train", &s[1], "-o", "b1.stats",
        ],
    );

    // Other settings, other kinds of file, other classes.
    refused(
        d,
        &["merge", "a0.stats", "a1x.stats", "-o", "x.stats"],
        &["a1x.stats", "other fit settings"],
    );
    refused(
        d,
        &["merge", "a0.stats", "b0.stats", "-o", "x.stats"],
        &["b0.stats: holds pass-(b) counts"],
    );
    refused(
        d,
        &["merge", "--stats", "a.stats", "a0.stats", "-o", "x.mlmap"],
        &["a0.stats: holds pass-(a) statistics"],
    );
    refused(
        d,
        &["merge", "--stats", "b0.stats", "b1.stats", "-o", "x.mlmap"],
        &["b0.stats: holds pass-(b) counts"],
    );
    write(d, "other.csv", "label,a,b\na,1,2\nb,0,3\n");
    ok(d, &["stats", "--train", "other.csv", "-o", "o.stats"]);
    refused(
        d,
        &["merge", "a0.stats", "o.stats", "-o", "x.stats"],
        &["o.stats", "[car, cyclist, pedestrian]", "[a, b]"],
    );
    refused(
        d,
        &[
            "stats",
            "--stats",
            "a.stats",
            "--train",
            "other.csv",
            "-o",
            "x.stats",
        ],
        &["other.csv", "differ from"],
    );
    // Pass (b) over the edges of one shard only: a row outside them, named by line.
    refused(
        d,
        &[
            "stats", "--stats", "a0.stats", "--train", &s[1], "-o", "x.stats",
        ],
        &["s1.csv:", "outside the edges of a0.stats"],
    );
    // Counts of one shard: other rows than the statistics.
    refused(
        d,
        &["merge", "--stats", "a.stats", "b0.stats", "-o", "x.mlmap"],
        &["a.stats", "not those of pass (a)"],
    );
    // Counts over edges of other statistics.
    refused(
        d,
        &[
            "merge", "--stats", "a0.stats", "b0.stats", "b1.stats", "-o", "x.mlmap",
        ],
        &["a0.stats", "edges of other statistics"],
    );
    // Settings come from the statistics in pass (b).
    refused(
        d,
        &[
            "stats",
            "--stats",
            "a.stats",
            "--bins-ml",
            "5",
            "--train",
            &s[0],
            "-o",
            "x.stats",
        ],
        &["cannot be used with"],
    );
    // Truncated, corrupt, newer and foreign files.
    let bytes = std::fs::read(d.join("a0.stats")).unwrap();
    std::fs::write(d.join("trunc.stats"), &bytes[..bytes.len() / 2]).unwrap();
    refused(
        d,
        &["merge", "trunc.stats", "a1.stats", "-o", "x.stats"],
        &["trunc.stats", "corrupt or truncated"],
    );
    let mut newer = bytes.clone();
    newer[8] = 9;
    std::fs::write(d.join("newer.stats"), &newer).unwrap();
    refused(
        d,
        &["merge", "a1.stats", "newer.stats", "-o", "x.stats"],
        &["newer.stats", "format version 9 is newer"],
    );
    refused(
        d,
        &["merge", "a1.stats", &data("train"), "-o", "x.stats"],
        &["train.csv", "unknown magic"],
    );
    refused(
        d,
        &["merge", "missing.stats", "-o", "x.stats"],
        &["missing.stats"],
    );
    // The output may not overwrite an input; labels are needed; bad settings.
    refused(
        d,
        &["merge", "a0.stats", "a1.stats", "-o", "a1.stats"],
        &["same file as the input"],
    );
    write(d, "nolabel.csv", "a,b\n1,2\n");
    refused(
        d,
        &["stats", "--train", "nolabel.csv", "-o", "x.stats"],
        &["nolabel.csv", "no labels"],
    );
    refused(
        d,
        &[
            "stats",
            "--train",
            &s[0],
            "--bins-map",
            "0",
            "-o",
            "x.stats",
        ],
        &["--bins-map 0 is out of range"],
    );
}
