//! The Bayes head checkers: the shipped head passes, each axis and term violation is
//! reported, and a head checked by hand.

use super::*;

/// Asserts that `got` is `Err(want)` and that its message cites DESIGN §1.6 and holds
/// `needle`.
fn fails_bayes(got: Result<(), Violation>, want: Violation, needle: &str) {
    assert_eq!(got, Err(want));
    let msg = want.to_string();
    assert!(msg.starts_with("DESIGN §1.6: "), "{msg}");
    assert!(msg.contains(needle), "{msg}");
}

fn shipped() -> Table<3, 22, 17, 22, 4> {
    Table::from_bytes(include_bytes!("../../../tables/default.mlmap")).unwrap()
}

#[test]
fn shipped_bayes_head_passes_and_needs_its_k() {
    let t = shipped();
    let head = t.bayes_head().unwrap();
    assert_eq!(check_bayes(&head, 3), Ok(()));
    assert_eq!(bayes_sum(&head), Sum::AtMost);
    fails_bayes(
        check_bayes(&head, 2),
        Violation::BayesCategories {
            classes: 2,
            logits: 3,
            categories: 4,
        },
        "Bayes head with 3 logits and 4 categories in a table of 2 classes",
    );
    assert!(check_bayes(&head, 4).is_err());
    // Scores: at most OS (the background takes a share), and the prior's shares
    // without evidence.
    let s = t.bayes(&[5.1, -2.0, -1.3], 0.93).unwrap();
    assert_eq!(check_scores(&s.0, 0.93, bayes_sum(&head)), Ok(()));
    let unknown = t.bayes(&[1e30, -1e30, f32::INFINITY], 0.93).unwrap();
    assert_eq!(check_prior_share(&unknown.0, 0.93, &head), Ok(()));
    let mut off = unknown.0;
    off[1] *= 1.001;
    assert!(matches!(
        check_prior_share(&off, 0.93, &head),
        Err(Violation::NotPriorShare { class: 1, .. })
    ));
    assert_eq!(
        check_prior_share(&off[..2], 0.93, &head),
        Err(Violation::ClassCount {
            expected: 3,
            found: 2
        })
    );
}

#[test]
fn each_bayes_axis_and_term_violation_is_reported() {
    assert_eq!(check_bayes_axis(0, [-1.0, 0.0, 2.0], 2), Ok(()));
    fails_bayes(
        check_bayes_axis(1, [-1.0, f32::INFINITY, 2.0], 2),
        Violation::BayesEdge {
            logit: 1,
            edge: 1,
            previous: -1.0,
            value: f32::INFINITY,
        },
        "Bayes axis of logit 1: edge 1 = inf is not finite or not above -1e0",
    );
    fails_bayes(
        check_bayes_axis(2, [-1.0, 0.0, 0.0], 2),
        Violation::BayesEdge {
            logit: 2,
            edge: 2,
            previous: 0.0,
            value: 0.0,
        },
        "edge 2 = 0e0",
    );
    fails_bayes(
        check_bayes_axis(0, [-1.0, 0.0], 2),
        Violation::BayesBins {
            logit: 0,
            expected: 2,
            found: 1,
        },
        "Bayes axis of logit 0 has 1 bins (or terms), the head 2",
    );
    // lambda = 0.5, frequencies 0.25 and 0.75: terms ln 0.75 and ln 1.25.
    let ok = [0.75f64.ln() as f32, 1.25f64.ln() as f32];
    assert_eq!(check_bayes_terms(1, 2, 0.5, ok, 2), Ok(()));
    fails_bayes(
        check_bayes_terms(1, 2, 0.5, [f32::INFINITY, 0.0], 2),
        Violation::BayesTerm {
            category: 1,
            logit: 2,
            bin: 0,
            term: f32::INFINITY,
        },
        "Bayes term of category 1, logit 2, bin 0 = inf is not finite",
    );
    let nan = check_bayes_terms(1, 2, 0.5, [0.0, f32::NAN], 2);
    assert!(
        matches!(nan, Err(Violation::BayesTerm { bin: 1, term, .. }) if term.is_nan()),
        "{nan:?}"
    );
    // Frequency -0.1 (term ln 0.4), then 1.1 (ln 1.6).
    let negative = check_bayes_terms(0, 0, 0.5, [0.4f32.ln(), 1.6f32.ln()], 2);
    assert!(
        matches!(negative, Err(Violation::BayesFrequency { category: 0, logit: 0, bin: 0, frequency })
            if (frequency + 0.1).abs() < 1e-6),
        "{negative:?}"
    );
    // Within the stated tolerance: -1.5e-5 and 1 + 1.5e-5 pass.
    let edge = [(0.5f64 - 1.5e-5).ln() as f32, (1.5f64 + 1.5e-5).ln() as f32];
    assert_eq!(check_bayes_terms(0, 0, 0.5, edge, 2), Ok(()));
    // Sum 0.9: out of 1e-4 + 2 * 2e-5.
    let low = check_bayes_terms(3, 1, 0.5, [0.75f32.ln(), 1.15f32.ln()], 2);
    assert!(
        matches!(low, Err(Violation::BayesFrequencySum { category: 3, logit: 1, sum })
            if (sum - 0.9).abs() < 1e-6),
        "{low:?}"
    );
    assert!(low
        .unwrap_err()
        .to_string()
        .contains("frequencies of category 3, logit 1 sum to "));
    // Two bins: a sum of 1.00015 is out (tolerance 1.4e-4), 1.00013 in.
    let near = |d: f64| [0.75f64.ln() as f32, (1.25f64 + d).ln() as f32];
    assert!(check_bayes_terms(0, 0, 0.5, near(1.5e-4), 2).is_err());
    assert_eq!(check_bayes_terms(0, 0, 0.5, near(1.3e-4), 2), Ok(()));
    assert!((bayes_frequency_sum_tolerance(3) - 1.6e-4).abs() < 1e-10);
    fails_bayes(
        check_bayes_terms(0, 4, 0.5, ok, 3),
        Violation::BayesBins {
            logit: 4,
            expected: 3,
            found: 2,
        },
        "logit 4 has 2 bins",
    );
    for (v, needle) in [
        (
            Violation::BayesLambda { lambda: 2.0 },
            "Bayes lambda = 2e0 is not in (0, 1e0]",
        ),
        (
            Violation::CategoryRows {
                category: 3,
                rows: 0,
            },
            "Bayes category 3 has 0 training rows",
        ),
        (
            Violation::NotPriorShare {
                class: 1,
                score: 0.5,
                expected: 0.25,
            },
            "score of class 1 = 5e-1 is not OS * pi = 2.5e-1",
        ),
        (
            Violation::BayesFrequency {
                category: 1,
                logit: 0,
                bin: 2,
                frequency: -0.5,
            },
            "category 1, logit 0, bin 2 = -5e-1 is below 0",
        ),
    ] {
        let msg = v.to_string();
        assert!(
            msg.starts_with("DESIGN §1.6: ") && msg.contains(needle),
            "{msg}"
        );
    }
}

/// A K = 2 table whose Bayes head has 2 bins over [0, 2] per logit, lambda 0.5, rows
/// 1 and 3 (and 4 background rows with `background`); class 0 puts logit 0 in bin 0
/// and logit 1 in bin 1, class 1 (and background) half and half.
#[cfg(feature = "std")]
fn hand_table(background: bool) -> crate::host::DynTable {
    use std::vec;
    use std::vec::Vec;
    let class = |name| ClassSpec {
        name,
        rows: 10,
        mean: 0.5,
        variance: 0.25,
        ml_range: (0.0, 1.0),
        ml_freqs: vec![0.25, 0.75],
        map_range: (-1.0, 1.0),
        map_freqs: vec![1.0],
    };
    let t =
        crate::host::DynTable::new(settings(1e-3, 1e-3), vec![class("car"), class("bus")]).unwrap();
    let mut rows = vec![1, 3];
    // h per category for (logit 0, bin 0), (0, 1), (1, 0), (1, 1).
    let mut h: Vec<[f64; 4]> = vec![[1.0, 0.0, 0.0, 1.0], [0.5; 4]];
    if background {
        rows.push(4);
        h.push([0.5; 4]);
    }
    let mut terms = Vec::new();
    for i in 0..4 {
        for hc in &h {
            terms.push(libm::log(hc[i] + 0.5) as f32);
        }
    }
    t.with_bayes(crate::host::BayesSpec {
        lambda: 0.5,
        rows,
        ranges: vec![(0.0, 2.0); 2],
        terms,
        objectness: None,
    })
    .unwrap()
}

#[cfg(feature = "std")]
#[test]
fn bayes_checks_by_hand() {
    for background in [false, true] {
        let t = hand_table(background);
        assert_eq!(check_dyn_table(&t), Ok(()));
        let head = t.bayes_head().unwrap();
        let sum = bayes_sum(&head);
        assert_eq!(sum, if background { Sum::AtMost } else { Sum::Equal });
        // Outside both axes: OS * pi = 0.8 * [1/4, 3/4] or 0.8 * [1/8, 3/8].
        let (mut out, mut scratch) = ([0.0f32; 2], [0.0f32; 3]);
        let scratch = &mut scratch[..head.categories()];
        t.bayes_into::<crate::Libm>(&[-1.0, 3.0], 0.8, &mut out, scratch)
            .unwrap();
        let want: [f32; 2] = if background { [0.1, 0.3] } else { [0.2, 0.6] };
        for (o, w) in out.iter().zip(want) {
            assert!((o - w).abs() < 1e-7, "{out:?}");
        }
        assert_eq!(check_prior_share(&out, 0.8, &head), Ok(()));
        assert_eq!(check_scores(&out, 0.8, sum), Ok(()));
        // Logit 0 in bin 0, logit 1 in bin 1: masses 1/4 * 1.5 * 1.5 = 0.5625 for
        // class 0, 3/4 * 1 * 1 = 0.75 for class 1 (and 1 for background): scores
        // 0.8 * [3/7, 4/7], or 0.8 * [0.5625, 0.75] / 2.3125 with background.
        let x = [0.5f32, 1.5];
        t.bayes_into::<crate::Libm>(&x, 0.8, &mut out, scratch)
            .unwrap();
        let want = if background {
            [0.8 * 0.5625 / 2.3125, 0.8 * 0.75 / 2.3125]
        } else {
            [0.8 * 3.0 / 7.0, 0.8 * 4.0 / 7.0]
        };
        let mut reference = [0.0f64; 2];
        let mut s64 = [0.0f64; 3];
        assert!(bayes_reference(
            &head,
            &x,
            0.8,
            &mut reference,
            &mut s64[..head.categories()]
        ));
        for i in 0..2 {
            // The stored terms are f32: about 1e-8 from the exact values.
            assert!((reference[i] - want[i]).abs() < 1e-7, "{reference:?}");
            assert!((f64::from(out[i]) - want[i]).abs() < 1e-7, "{out:?}");
        }
        assert_eq!(bayes_mismatch(&head, &out, &reference, 0.8), None);
        assert_eq!(check_scores(&out, 0.8, sum), Ok(()));
        // Without evidence the rule is the prior, not these scores.
        assert!(check_prior_share(&out, 0.8, &head).is_err());
        let mut off = out;
        off[1] *= 1.01;
        assert_eq!(bayes_mismatch(&head, &off, &reference, 0.8), Some(1));
        assert!(!bayes_reference(
            &head,
            &x[..1],
            0.8,
            &mut reference,
            &mut s64
        ));
        // The tolerance: K = 2, lambda = 0.5, |ln(1/8)| = 2.08 with background.
        let tol = bayes_score_tolerance(&head);
        assert!(tol > 1e-5 && tol < 1e-4, "{tol:e}");
    }
}
