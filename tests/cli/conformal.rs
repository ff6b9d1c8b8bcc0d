use super::*;

/// The numpy reference's case for `head` and `alpha` (tools/conformal_ref.py).
fn reference_case(head: &str, alpha: f64) -> Value {
    let text = std::fs::read_to_string(repo("tests/golden/conformal/reference.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    v["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["head"] == head && c["alpha"].as_f64() == Some(alpha))
        .unwrap()
        .clone()
}

/// `conformal` then `inspect`, `apply` and `eval` on the shipped data: the thresholds
/// are numpy's, `apply` writes the set columns, `eval` reports coverage and the LAC
/// baseline, and the file still decodes as the table.
#[test]
fn conformal_apply_eval() {
    let dir = tempdir();
    let d = dir.path();
    let run = ok(
        d,
        &[
            "conformal",
            "--table",
            &bayes_table(),
            "--val",
            &data("val"),
            "--alpha",
            "0.1",
            "--head",
            "open",
            "-o",
            "sets.mlmap",
        ],
    );
    assert!(run.stdout.contains("rank 38 of 385"), "{}", run.stdout);
    assert_eq!(
        read_table(&d.join("sets.mlmap")),
        read_table(Path::new(&bayes_table()))
    );
    let info = ok_json(d, &["inspect", "--format", "json", "sets.mlmap"]);
    let want = reference_case("open", 0.1);
    assert_eq!(info["conformal"]["head"], "open");
    for c in 0..3 {
        let t = info["conformal"]["classes"][c]["threshold"]
            .as_f64()
            .unwrap();
        let w = want["thresholds"][c].as_f64().unwrap();
        assert!((t - w).abs() < 1e-5, "{t} vs {w}");
        assert_eq!(
            info["conformal"]["classes"][c]["calibration_rows"],
            want["rows"][c]
        );
    }
    ok(d, &apply_args("sets.mlmap", &data("test"), "out.csv"));
    let (header, records) = read_csv(&d.join("out.csv"));
    let at: Vec<usize> = ["set_car", "set_cyclist", "set_pedestrian"]
        .iter()
        .map(|n| header.iter().position(|h| h == n).unwrap())
        .collect();
    let sets = want["test_sets"].as_array().unwrap();
    let margins = want["test_margin"].as_array().unwrap();
    for (i, (r, (w, m))) in records.iter().zip(sets.iter().zip(margins)).enumerate() {
        if m.as_f64().unwrap() < 1e-5 {
            continue;
        }
        for c in 0..3 {
            assert_eq!(r[at[c]], w[c].to_string(), "row {i} class {c}");
        }
    }
    // The NPY output: the sets of the open head as a uint8 array, the same sets; none
    // when the open head is not asked for.
    let test = data("test");
    let mut args = apply_args("sets.mlmap", &test, "npy/");
    args.extend(["--heads", "ml,open"]);
    ok(d, &args);
    let bytes = std::fs::read(d.join("npy/sets.npy")).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.dtype().descr(), "'|u1'");
    assert_eq!(npy.shape(), [records.len() as u64, 3]);
    let set_bits: Vec<u8> = npy.into_vec().unwrap();
    for (i, (w, m)) in sets.iter().zip(margins).enumerate() {
        if m.as_f64().unwrap() < 1e-5 {
            continue;
        }
        for c in 0..3 {
            assert_eq!(
                u64::from(set_bits[i * 3 + c]),
                w[c].as_u64().unwrap(),
                "row {i} class {c}"
            );
        }
    }
    let mut args = apply_args("sets.mlmap", &test, "nosets.csv");
    args.extend(["--heads", "ml,map"]);
    ok(d, &args);
    let (header, _) = read_csv(&d.join("nosets.csv"));
    assert!(!header.iter().any(|h| h.starts_with("set_")), "{header:?}");
    let ev = ok_json(
        d,
        &eval_args(
            "sets.mlmap",
            &data("test"),
            &[
                "--val",
                &data("val"),
                "--ood",
                &data("ood"),
                "--format",
                "json",
            ],
        ),
    );
    let cf = &ev["conformal"];
    assert_eq!(cf["head"], "open");
    for (c, name) in ["car", "cyclist", "pedestrian"].iter().enumerate() {
        let got = cf["sets"]["coverage"][name]["coverage"].as_f64().unwrap();
        let w = want["eval"]["coverage"][c].as_f64().unwrap();
        assert!((got - w).abs() < 3e-3, "{name}: {got} vs {w}");
    }
    assert!(cf["lac"]["qhat"].as_f64().unwrap() > 0.0);
    assert!(cf["lac"]["empty_unseen"].as_f64().is_some());
    // Text: the block with both methods.
    let text = ok(
        d,
        &eval_args("sets.mlmap", &data("test"), &["--ood", &data("ood")]),
    )
    .stdout;
    assert!(
        text.contains("conformal class sets") && text.contains("give --val"),
        "{text}"
    );
    // A table without the section: no set columns, no block.
    ok(d, &apply_args(&bayes_table(), &data("test"), "plain.csv"));
    let (header, _) = read_csv(&d.join("plain.csv"));
    assert!(!header.iter().any(|h| h.starts_with("set_")));
}

#[test]
fn conformal_refusals() {
    let dir = tempdir();
    let d = dir.path();
    let base = |alpha: &'static str, head: &'static str, table: String| {
        vec![
            "conformal".to_string(),
            "--table".into(),
            table,
            "--val".into(),
            data("val"),
            "--alpha".into(),
            alpha.into(),
            "--head".into(),
            head.into(),
            "-o".into(),
            "x.mlmap".into(),
        ]
    };
    for a in ["0", "1", "-0.1", "nan"] {
        refused(d, &base(a, "map", bayes_table()), &["--alpha"]);
    }
    refused(
        d,
        &base("0.1", "open", golden_table()),
        &["has no open head"],
    );
    refused(
        d,
        &base("0.1", "bayes", golden_table()),
        &["has no Bayes head"],
    );
    write(
        d,
        "nolabels.csv",
        "objectness,car,cyclist,pedestrian\n1,1,2,3\n",
    );
    let mut args = base("0.1", "map", bayes_table());
    args[4] = "nolabels.csv".into();
    refused(d, &args, &["nolabels.csv", "has no labels"]);
}
