//! Thresholds, sets, coverage and the LAC baseline against the numpy reference
//! (tools/conformal_ref.py).

use super::*;

#[test]
fn thresholds_and_sets_match_numpy() {
    let (table, bytes) = default_table();
    let (val, test, ood) = (data("val"), data("test"), data("ood"));
    for case in golden()["cases"].as_array().unwrap() {
        let head = head_of(case["head"].as_str().unwrap());
        let alpha = case["alpha"].as_f64().unwrap();
        let tol = tolerance(head);
        let f = fit(head, alpha, 3, &head_scores(&table, head, val), &val.labels);
        let rows: Vec<u32> = case["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as u32)
            .collect();
        assert_eq!(f.rows, rows, "{head} {alpha}");
        for (c, want) in case["thresholds"].as_array().unwrap().iter().enumerate() {
            match want.as_f64() {
                None => assert_eq!(f.thresholds[c], f32::NEG_INFINITY),
                Some(w) => assert!(
                    (f64::from(f.thresholds[c]) - w).abs() <= tol,
                    "{head} {alpha} class {c}: {} vs {w}",
                    f.thresholds[c]
                ),
            }
        }
        let file = with_conformal(&bytes, &f).unwrap();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        assert_eq!((spec.head(), spec.alpha()), (head, alpha as f32));
        // The sets of the first rows, where no score is within the tolerance of its
        // threshold (there the two precisions may rightly disagree).
        for (d, key, margin) in [
            (test, "test_sets", "test_margin"),
            (ood, "ood_sets", "ood_margin"),
        ] {
            let want = case[key].as_array().unwrap();
            let margins = case[margin].as_array().unwrap();
            let s = head_scores(&table, head, d);
            let got = sets(&spec, &s[..want.len() * 3]).unwrap();
            let mut compared = 0;
            for (i, (w, m)) in want.iter().zip(margins).enumerate() {
                if m.as_f64().unwrap() <= 2.0 * tol {
                    continue;
                }
                compared += 1;
                let w: Vec<bool> = w
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|b| b.as_u64() == Some(1))
                    .collect();
                assert_eq!(
                    &got[3 * i..3 * i + 3],
                    &w[..],
                    "{head} {alpha} {key} row {i}"
                );
            }
            assert!(
                compared * 10 >= want.len() * 9,
                "{head} {alpha} {key}: {compared}"
            );
        }
    }
}

/// Coverage, set size and empty sets of every test and unseen row, and the LAC
/// baseline, against numpy: equal up to the rows within the tolerance of a threshold.
#[test]
fn evaluation_matches_numpy() {
    let (table, bytes) = default_table();
    let (val, test, ood) = (data("val"), data("test"), data("ood"));
    let rows = |d: &'static Data, unseen: bool| Rows {
        logits: &d.loaded.logits,
        objectness: &d.loaded.objectness,
        labels: if unseen {
            Box::leak(vec![None; d.labels.len()].into_boxed_slice())
        } else {
            &d.labels
        },
    };
    let close = |got: f64, want: &Value, n: f64, what: &str| {
        let want = want.as_f64().unwrap();
        // Two rows' worth: a row or two may sit within the tolerance of a threshold.
        assert!(
            (got - want).abs() <= 2.0 / n + 1e-12,
            "{what}: {got} vs {want}"
        );
    };
    for case in golden()["cases"].as_array().unwrap() {
        let head = head_of(case["head"].as_str().unwrap());
        let alpha = case["alpha"].as_f64().unwrap();
        let f = fit(head, alpha, 3, &head_scores(&table, head, val), &val.labels);
        let file = with_conformal(&bytes, &f).unwrap();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        let ev = evaluate(
            &table,
            &spec,
            rows(test, false),
            Some(rows(val, false)),
            Some(rows(ood, true)),
        )
        .unwrap();
        let want = &case["eval"];
        for c in 0..3 {
            let (n, cov) = ev.sets.per_class[c];
            assert_eq!(n as u64, want["rows"][c].as_u64().unwrap());
            close(cov, &want["coverage"][c], n as f64, "coverage");
        }
        close(ev.sets.mean_size, &want["mean_size"], 8000.0, "mean size");
        close(ev.sets.empty_known, &want["empty_known"], 8000.0, "empty");
        close(
            ev.sets.empty_unseen.unwrap(),
            &want["empty_unseen"],
            2000.0,
            "empty unseen",
        );
        let lac = golden()["lac"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["alpha"].as_f64() == Some(alpha))
            .unwrap();
        let (l, lc) = ev.lac.unwrap();
        assert_eq!(l.rows as u64, lac["rows"].as_u64().unwrap());
        assert!((l.qhat - lac["qhat"].as_f64().unwrap()).abs() < 1e-12);
        for c in 0..3 {
            close(lc.per_class[c].1, &lac["eval"]["coverage"][c], 500.0, "LAC");
        }
        close(lc.mean_size, &lac["eval"]["mean_size"], 8000.0, "LAC size");
        close(
            lc.empty_unseen.unwrap(),
            &lac["eval"]["empty_unseen"],
            2000.0,
            "LAC empty",
        );
    }
}

#[test]
fn lac_and_softmax_scores() {
    // Two classes, logits (0, ln 3): softmax (1/4, 3/4), times OS 0.8.
    let p = softmax_scores(2, &[0.0, 3f64.ln()], &[0.8]).unwrap();
    assert!((p[0] - 0.2).abs() < 1e-12 && (p[1] - 0.6).abs() < 1e-12);
    let l = Lac { qhat: 0.5, rows: 1 };
    assert!(l.contains(0.6) && !l.contains(0.2));
}
