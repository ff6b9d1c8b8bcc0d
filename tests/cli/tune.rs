use std::path::Path;

use mlmap::host::metrics::{self, MetricsConfig};
use mlmap::{EdgeMode, Head, UpperTail};

use super::*;

/// Candidates of [`tune_args`]' grid per head: 3 x 9 (ML), 2 x 9 (MAP), 2 x 9 (Bayes):
/// lambdas from 1e-8 to 1, one per decade; and the open head's 50 epsilons (0 and 1e-16
/// to 1e8, two per decade, DESIGN §4).
const CANDIDATES: [(&str, usize); 4] = [
    ("ml", 3 * 9),
    ("map", 2 * 9),
    ("bayes", 2 * 9),
    ("open", 50),
];

/// Candidates are ordered within the guards first, each group by the objective's
/// value (within the guards) or by how much they lose (beyond them).
fn check_order(name: &str, cands: &[Value], objective: &str) {
    let within: Vec<bool> = cands
        .iter()
        .map(|c| c["within_guards"].as_bool().unwrap())
        .collect();
    assert!(
        within.windows(2).all(|w| w[0] >= w[1]),
        "{name}: {within:?}"
    );
    let values: Vec<f64> = cands
        .iter()
        .filter(|c| c["within_guards"] == true)
        .map(|c| c[objective].as_f64().unwrap())
        .collect();
    assert!(
        values.windows(2).all(|w| w[0] <= w[1]),
        "{name}: {values:?}"
    );
}

fn candidates(head: &LayerHead) -> usize {
    CANDIDATES
        .iter()
        .find(|(name, _)| *name == head.name)
        .unwrap_or_else(|| panic!("no grid for head {}", head.name))
        .1
}

#[test]
fn tune_writes_the_best_candidates_and_its_objective_matches_the_metrics() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val) = (data("train"), data("val"));
    let mut args = tune_args("j.mlmap", &train, &val);
    // The heads' own scores: the candidates' metrics are the written table's.
    args.extend(["--format", "json", "--top", "3", "--no-maps"]);
    let v = ok_json(d, &args);
    let t = read_table(&d.join("j.mlmap"));
    assert_eq!(v["objective"], "ece");
    assert_eq!(v["table"]["path"], "j.mlmap");

    let val_rows = rows_of(Path::new(&val));
    let labels = class_labels(&val_rows);
    for head in &HEADS {
        let name = head.name;
        assert_eq!(v["candidates"][name], candidates(head), "{name}");
        let cands = v[name].as_array().unwrap();
        assert_eq!(cands.len(), 3);
        check_order(name, cands, "ece");
        let best = &cands[0];
        assert_eq!(best["rank"], 1);
        assert_eq!(
            best["bins"].as_u64().unwrap() as usize,
            (head.bins)(&t),
            "{name}"
        );
        assert_eq!(
            best["lambda"].as_f64().unwrap() as f32,
            (head.lambda)(&t),
            "{name}"
        );
        // The tuner accumulates its objectives on the fly; the metrics module computes
        // them from the scores of the written table.
        let scores = head.flat_scores(&t, &val_rows);
        let m = metrics::evaluate(&scores, 3, &labels, &MetricsConfig::default()).unwrap();
        let map = m.mean_ap().unwrap();
        for (key, want) in [
            ("ece", m.ece),
            ("nll", m.nll.unwrap()),
            ("brier", m.brier),
            ("mean_ap", map),
        ] {
            let got = best[key].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 1e-12,
                "{name} {key}: tuner {got}, metrics {want}"
            );
        }
    }

    // The text report: the rank-1 rows and the summary name the written settings.
    let mut text_args = tune_args("t.mlmap", &train, &val);
    text_args.push("--no-maps");
    let run = ok(d, &text_args);
    assert_eq!(
        std::fs::read(d.join("t.mlmap")).unwrap(),
        std::fs::read(d.join("j.mlmap")).unwrap()
    );
    assert!(run
        .stdout
        .starts_with("ML head: best 5 of 27 candidates by ece, within the guards first\n"));
    assert!(run
        .stdout
        .contains("MAP head: best 5 of 18 candidates by ece, within the guards first\n"));
    assert!(run
        .stdout
        .contains("Bayes head: best 5 of 18 candidates by ece, within the guards first\n"));
    let rank1: Vec<Vec<&str>> = run
        .stdout
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("1"))
        .map(|l| l.split_whitespace().collect())
        .collect();
    // One rank-1 line per head the table holds, in the order of HEADS.
    let heads = HEADS.iter().filter(|h| (h.present)(&t)).count();
    assert_eq!(rank1.len(), heads, "{}", run.stdout);
    for (line, head) in rank1.iter().zip(&HEADS) {
        assert_eq!(line[1], (head.bins)(&t).to_string(), "{line:?}");
        let printed: f64 = line[2].parse().unwrap();
        let lambda = f64::from((head.lambda)(&t));
        assert!((printed / lambda - 1.0).abs() < 1e-3, "{line:?}");
    }
    let st = t.settings();
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
        let v = ok_json(d, &args);
        assert_eq!(v["objective"], objective);
        for head in &HEADS {
            let cands = v[head.name].as_array().unwrap();
            assert_eq!(cands.len(), candidates(head));
            check_order(head.name, cands, objective);
        }
        let t = read_table(&d.join("t.mlmap"));
        assert_eq!(t.settings().upper_tail, UpperTail::Clamp);
        assert_eq!(t.settings().edge_mode, EdgeMode::Matlab);
    }
}

#[test]
fn tune_with_never_seen_objects_guards_and_compares_every_head() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val, ood) = (data("train"), data("val"), data("ood"));
    let mut args = tune_args("t.mlmap", &train, &val);
    args.extend([
        "--no-maps",
        "--ood",
        &ood,
        "--max-accuracy-loss",
        "0",
        "--max-map-loss",
        "0",
        "--format",
        "json",
        "--top",
        "100",
    ]);
    let v = ok_json(d, &args);
    let t = read_table(&d.join("t.mlmap"));
    let cmp = &v["validation"];
    let val_rows = rows_of(Path::new(&val));
    assert_eq!(cmp["rows"], val_rows.len() + 2000);
    assert_eq!(cmp["ood_rows"], 2000);
    let methods = &cmp["methods"];
    let mut compared = vec![
        "softmax",
        "temperature",
        "isotonic",
        "energy",
        "ml",
        "map",
        "bayes",
    ];
    if t.open_params().is_some() {
        compared.push("open");
    }
    assert_eq!(keys(methods), sorted(&compared));
    // The energy score reports its ranking metrics only; every method has the
    // separation of known from never-seen rows.
    for (name, m) in methods.as_object().unwrap() {
        for key in ["ood_auroc", "ood_fpr95"] {
            let x = m[key].as_f64().unwrap_or_else(|| panic!("{name}.{key}"));
            assert!((0.0..=1.0).contains(&x), "{name}.{key} = {x}");
        }
    }
    assert!(methods["energy"]["ece"].is_null());
    assert!(methods["isotonic"]["ece"].as_f64().is_some());
    // Softmax's accuracy, counted by hand: its decision is the largest logit (the
    // never-seen rows are background and do not count).
    let labels = class_labels(&val_rows);
    let correct = val_rows
        .iter()
        .zip(&labels)
        .filter(|(r, l)| {
            let top = (0..3)
                .max_by(|&a, &b| r.logits[a].total_cmp(&r.logits[b]))
                .unwrap();
            **l == Some(top)
        })
        .count();
    let labelled = labels.iter().filter(|l| l.is_some()).count();
    let softmax_acc = methods["softmax"]["accuracy"].as_f64().unwrap();
    assert!((softmax_acc - correct as f64 / labelled as f64).abs() < 1e-12);
    let softmax_map = methods["softmax"]["mean_ap"].as_f64().unwrap();
    for head in &HEADS {
        let name = head.name;
        let cands = v[name].as_array().unwrap();
        assert_eq!(cands.len(), candidates(head));
        check_order(name, cands, "ece");
        // With no loss allowed, a candidate is within the guards exactly when it keeps
        // softmax's accuracy and mAP.
        for c in cands {
            let keeps = c["accuracy"].as_f64().unwrap() >= softmax_acc - 1e-12
                && c["mean_ap"].as_f64().unwrap() >= softmax_map - 1e-12;
            assert_eq!(c["within_guards"].as_bool().unwrap(), keeps, "{name}: {c}");
        }
        // The comparison reports the written head, whose metrics are the chosen
        // candidate's (same rows, same scores).
        let chosen = &methods[name];
        assert_eq!(chosen["bins"], cands[0]["bins"], "{name}");
        assert_eq!(chosen["bins"].as_u64().unwrap() as usize, (head.bins)(&t));
        assert_eq!(chosen["lambda"].as_f64().unwrap() as f32, (head.lambda)(&t));
        for key in ["ece", "accuracy", "mean_ap"] {
            let (a, b) = (
                chosen[key].as_f64().unwrap(),
                cands[0][key].as_f64().unwrap(),
            );
            assert!((a - b).abs() <= 1e-12, "{name} {key}: {a} vs {b}");
        }
        assert!(chosen["ood_mean"].as_f64().unwrap() > 0.0);
    }
    // The best head is the one with the lowest ECE among those within the guards.
    let within: Vec<(&str, f64)> = ["ml", "map", "bayes", "open"]
        .into_iter()
        .filter(|h| methods[*h]["within_guards"] == true)
        .map(|h| (h, methods[h]["ece"].as_f64().unwrap()))
        .collect();
    let best = within
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|b| b.0);
    assert_eq!(cmp["best"].as_str(), best);

    // The text report prints the same comparison and names the best head.
    let mut args = tune_args("t2.mlmap", &train, &val);
    args.extend(["--ood", &ood]);
    let run = ok(d, &args);
    assert!(run.stdout.contains("(2000 never-seen, as background)"));
    let header = run
        .stdout
        .lines()
        .find(|l| l.starts_with("metric "))
        .unwrap();
    let cols: Vec<&str> = header.split_whitespace().collect();
    let mut want = vec!["metric"];
    want.extend(&compared);
    assert_eq!(cols, want);
    for key in [
        "ece",
        "nll",
        "brier",
        "accuracy",
        "mAP",
        "auroc",
        "ood_mean",
        "ood_auroc",
        "ood_fpr95",
    ] {
        assert!(
            run.stdout
                .lines()
                .any(|l| l.split_whitespace().next() == Some(key)),
            "{key}:\n{}",
            run.stdout
        );
    }
    assert!(
        run.stdout
            .contains("best head by ece within the accuracy and mAP guards: ")
            || run
                .stdout
                .contains("no head is within the accuracy and mAP guards"),
        "{}",
        run.stdout
    );
    assert!(run.stdout.contains("  Bayes "));
}

#[test]
fn tune_without_the_bayes_head_and_bad_guards() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val) = (data("train"), data("val"));
    let mut args = tune_args("t.mlmap", &train, &val);
    args.retain(|a| *a != "--bins-bayes" && *a != "6,20");
    args.extend(["--no-bayes", "--format", "json"]);
    let v = ok_json(d, &args);
    assert!(read_table(&d.join("t.mlmap")).bayes_head().is_none());
    assert!(v.get("bayes").is_none());
    assert!(v["validation"]["methods"].get("bayes").is_none());
    assert!(v["validation"]["methods"]["softmax"]
        .get("ood_mean")
        .is_none());

    for (flag, value) in [
        ("--max-accuracy-loss", "-0.1"),
        ("--max-map-loss", "nan"),
        ("--lambda-bayes-max", "2"),
    ] {
        let mut args = tune_args("u.mlmap", &train, &val);
        args.extend([flag, value]);
        refused(d, &args, &[flag]);
    }
}

/// DESIGN §1.9: a map per head, kept only where it lowers the cross-fitted ECE within
/// the guards; the written table holds exactly the kept maps, and they lower the ECE the
/// comparison reports against the same run without maps.
#[test]
fn tune_keeps_a_map_only_where_it_lowers_the_ece() {
    let dir = tempdir();
    let d = dir.path();
    let (train, val) = (data("train"), data("val"));
    let mut with = tune_args("m.mlmap", &train, &val);
    with.extend(["--format", "json"]);
    let v = ok_json(d, &with);
    let mut without = tune_args("n.mlmap", &train, &val);
    without.extend(["--format", "json", "--no-maps"]);
    let w = ok_json(d, &without);
    assert!(w.get("maps").is_none());
    let t = read_table(&d.join("m.mlmap"));
    let maps = v["maps"].as_object().unwrap();
    let mut kept = 0;
    for (name, head) in [
        ("ml", Head::Ml),
        ("map", Head::Map),
        ("bayes", Head::Bayes),
        ("open", Head::Open),
    ] {
        let m = &maps[name];
        let knots: Vec<(f32, f32)> = m["knots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| (k[0].as_f64().unwrap() as f32, k[1].as_f64().unwrap() as f32))
            .collect();
        assert!((2..=32).contains(&knots.len()), "{name}");
        assert_eq!(knots[0].0, 0.0);
        assert_eq!(knots[knots.len() - 1].0, 1.0);
        assert!(knots
            .windows(2)
            .all(|p| p[0].0 < p[1].0 && p[0].1 <= p[1].1));
        let (before, after) = (
            m["cv_ece_without"].as_f64().unwrap(),
            m["cv_ece_with"].as_f64().unwrap(),
        );
        let stored = t.recal_map(head);
        if m["kept"] == true {
            kept += 1;
            assert!(after < before, "{name}: {after} vs {before}");
            assert_eq!(m["adds_no_loss"], true, "{name}");
            let stored: Vec<(f32, f32)> =
                stored.unwrap().knots().iter().map(|k| (k.x, k.y)).collect();
            assert_eq!(stored, knots, "{name}");
            let ece =
                |j: &serde_json::Value| j["validation"]["methods"][name]["ece"].as_f64().unwrap();
            assert!(ece(&v) < ece(&w), "{name}: {} vs {}", ece(&v), ece(&w));
        } else {
            assert!(stored.is_none(), "{name}");
            assert!(after >= before || m["adds_no_loss"] == false, "{name}");
        }
    }
    assert!(kept >= 1, "{maps:?}");
    // The same table without its maps is the run without maps, byte for byte.
    let n = std::fs::read(d.join("n.mlmap")).unwrap();
    assert_eq!(t.without_maps().to_vec().unwrap(), n);
}
