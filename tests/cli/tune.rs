use std::path::Path;

use mlmap::host::metrics::{self, MetricsConfig};
use mlmap::{EdgeMode, UpperTail};

use super::*;

/// Candidates of [`tune_args`]' grid per head: 3 x 8 (ML), 2 x 8 (MAP).
const CANDIDATES: [(&str, usize); 2] = [("ml", 3 * 8), ("map", 2 * 8)];

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
    args.extend(["--format", "json", "--top", "3"]);
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
        let ece: Vec<f64> = cands.iter().map(|c| c["ece"].as_f64().unwrap()).collect();
        assert!(ece.windows(2).all(|w| w[0] <= w[1]), "{name}: {ece:?}");
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
        for (key, want) in [("ece", m.ece), ("nll", m.nll.unwrap()), ("brier", m.brier)] {
            let got = best[key].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 1e-12,
                "{name} {key}: tuner {got}, metrics {want}"
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
    assert_eq!(rank1.len(), HEADS.len(), "{}", run.stdout);
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
            let values: Vec<f64> = v[head.name]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c[objective].as_f64().unwrap())
                .collect();
            assert_eq!(values.len(), candidates(head));
            assert!(
                values.windows(2).all(|w| w[0] <= w[1]),
                "{}: {values:?}",
                head.name
            );
        }
        let t = read_table(&d.join("t.mlmap"));
        assert_eq!(t.settings().upper_tail, UpperTail::Clamp);
        assert_eq!(t.settings().edge_mode, EdgeMode::Matlab);
    }
}
