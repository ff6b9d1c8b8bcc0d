//! Unit tests of the checkers: every `Violation` produced, valid tables passing.

use std::string::ToString;

use super::*;
use crate::{ClassSpec, EdgeMode, UpperTail};

fn settings(lambda_ml: f32, lambda_map: f32) -> Settings {
    Settings {
        lambda_ml,
        lambda_map,
        edge_mode: EdgeMode::Linspace,
        upper_tail: UpperTail::Zero,
    }
}

fn spec(name: &str) -> ClassSpec<'_, [f32; 2], [f32; 1]> {
    ClassSpec {
        name,
        rows: 10,
        mean: 0.5,
        variance: 0.25,
        ml_range: (0.0, 1.0),
        ml_freqs: [0.25, 0.75],
        map_range: (-1.0, 1.0),
        map_freqs: [1.0],
    }
}

/// Asserts that `got` is `Err(want)` and that its message cites invariant `n` and
/// holds `needle`.
fn fails(got: Result<(), Violation>, want: Violation, n: u8, needle: &str) {
    assert_eq!(got, Err(want));
    let msg = want.to_string();
    let cite = std::format!("DESIGN §1.3 ({n}): ");
    assert!(msg.starts_with(&cite), "{msg}");
    assert!(msg.contains(needle), "{msg}");
}

#[test]
fn scores_in_range_summing_to_objectness_pass() {
    assert_eq!(check_scores(&[0.25, 0.5, 0.15], 0.9, Sum::Equal), Ok(()));
    // 1e-5 relative of 0.9 is 9e-6: a sum 8.1e-6 above passes.
    assert_eq!(check_scores(&[0.45, 0.450_008_1], 0.9, Sum::Equal), Ok(()));
    assert_eq!(check_scores(&[0.2, 0.3], 0.9, Sum::AtMost), Ok(()));
    assert_eq!(check_scores(&[0.0, -0.0], 0.0, Sum::Equal), Ok(()));
    // A subnormal objectness: one rounding step per score is allowed.
    let step = f32::from_bits(1);
    assert_eq!(
        check_scores(&[step, step], f32::from_bits(3), Sum::Equal),
        Ok(())
    );
    assert_eq!(check_scores(&[], 0.5, Sum::AtMost), Ok(()));
}

#[test]
fn each_score_violation_is_reported() {
    fails(
        check_scores(&[0.5, 0.6], 0.5, Sum::Equal),
        Violation::ScoreOutOfRange {
            class: 1,
            score: 0.6,
            objectness: 0.5,
        },
        1,
        "score of class 1 = 6e-1 is outside [0, OS = 5e-1]",
    );
    fails(
        check_scores(&[0.0, -1e-30], 1.0, Sum::AtMost),
        Violation::ScoreOutOfRange {
            class: 1,
            score: -1e-30,
            objectness: 1.0,
        },
        1,
        "class 1",
    );
    let nan = check_scores(&[f32::NAN, 1.0], 1.0, Sum::Equal);
    assert!(
        matches!(nan, Err(Violation::ScoreOutOfRange { class: 0, score, .. }) if score.is_nan()),
        "{nan:?}"
    );
    // 1.8e-5 above 0.9: out of the 9e-6 tolerance.
    fails(
        check_scores(&[0.45, 0.450_018], 0.9, Sum::Equal),
        Violation::SumNotObjectness {
            sum: f64::from(0.45f32) + f64::from(0.450_018f32),
            objectness: 0.9,
        },
        1,
        "not to OS = 9e-1",
    );
    fails(
        check_scores(&[0.2, 0.3], 0.9, Sum::Equal),
        Violation::SumNotObjectness {
            sum: f64::from(0.2f32) + f64::from(0.3f32),
            objectness: 0.9,
        },
        1,
        "the scores sum to 5",
    );
    fails(
        check_scores(&[0.45, 0.46], 0.9, Sum::AtMost),
        Violation::SumAboveObjectness {
            sum: f64::from(0.45f32) + f64::from(0.46f32),
            objectness: 0.9,
        },
        1,
        "above OS = 9e-1",
    );
}

#[test]
fn unknown_must_be_exactly_os_over_k() {
    let third = 0.9f32 / 3.0;
    assert_eq!(check_unknown(&[third; 3], 0.9), Ok(()));
    let quarter = 0.25f32;
    let off = quarter.next_up();
    fails(
        check_unknown(&[quarter, quarter, off, quarter], 1.0),
        Violation::NotUnknown {
            class: 2,
            score: off,
            expected: quarter,
        },
        2,
        "score of class 2 = 2.5000003e-1 is not OS / K = 2.5e-1",
    );
    let off = third.next_up();
    fails(
        check_unknown(&[third, off, third], 0.9),
        Violation::NotUnknown {
            class: 1,
            score: off,
            expected: third,
        },
        2,
        "without evidence, score of class 1",
    );
}

#[test]
fn monotone_allows_equal_and_higher_scores_only() {
    assert_eq!(check_monotone(2, 0.25, 0.25), Ok(()));
    assert_eq!(check_monotone(2, 0.25, 0.5), Ok(()));
    let lower = 0.25f32.next_down();
    fails(
        check_monotone(2, 0.25, lower),
        Violation::ScoreLowered {
            class: 2,
            before: 0.25,
            after: lower,
        },
        3,
        "lowered the score of class 2 from 2.5e-1 to 2.4999999e-1",
    );
    assert!(check_monotone(0, 0.25, f32::NAN).is_err());
    assert!(check_monotone(0, f32::NAN, 0.25).is_err());
}

#[test]
fn bad_input_must_be_the_right_error() {
    let nan_logit = InferError::NanLogit { class: 1 };
    // The first NaN logit comes before a bad objectness.
    assert_eq!(
        expected_error(&[0.0, f32::NAN, f32::NAN], 2.0),
        Some(nan_logit)
    );
    // ±inf logits and a -0 objectness are valid.
    assert_eq!(
        expected_error(&[f32::INFINITY, f32::NEG_INFINITY], -0.0),
        None
    );
    for os in [f32::NAN, -1e-45, 1.0f32.next_up(), f32::INFINITY] {
        assert_eq!(
            expected_error(&[0.0, 1.0], os),
            Some(InferError::Objectness)
        );
    }
    assert_eq!(check_error(&[0.0, 1.0], 1.0, None), Ok(()));
    assert_eq!(check_error(&[0.0, f32::NAN], 1.0, Some(nan_logit)), Ok(()));
    fails(
        check_error(&[0.0, f32::NAN], 1.0, None),
        Violation::MissingError {
            expected: nan_logit,
        },
        4,
        "scored instead of refused",
    );
    fails(
        check_error(&[0.0, f32::NAN], 1.5, Some(InferError::Objectness)),
        Violation::WrongError {
            expected: Some(nan_logit),
            found: InferError::Objectness,
        },
        4,
        "instead of",
    );
    fails(
        check_error(&[0.0, 1.0], 1.0, Some(InferError::Objectness)),
        Violation::WrongError {
            expected: None,
            found: InferError::Objectness,
        },
        4,
        "a valid input was refused",
    );
}

#[test]
fn valid_tables_pass() {
    let t = Table::<2, 2, 1>::from_parts(settings(1e-3, 1e-6), [spec("car"), spec("bus")]).unwrap();
    assert_eq!(check_table(&t), Ok(()));
    let shipped =
        Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../../tables/default.mlmap"))
            .unwrap();
    assert_eq!(check_table(&shipped), Ok(()));
    #[cfg(feature = "std")]
    assert_eq!(
        check_dyn_table(&crate::host::DynTable::from_table(&shipped)),
        Ok(())
    );
    let h = Histogram::new(-1.0, 1.0, [0.5f32, 0.0, 0.5]).unwrap();
    assert_eq!(check_histogram(Head::Ml, 0, &h, 3), Ok(()));
}

#[test]
fn each_settings_names_and_prior_violation_is_reported() {
    fails(
        check_settings(&settings(0.0, 1.0)),
        Violation::Lambda {
            head: Head::Ml,
            lambda: 0.0,
        },
        5,
        "ML lambda = 0e0 is not in (0, 1e6]",
    );
    fails(
        check_settings(&settings(1.0, 2e6)),
        Violation::Lambda {
            head: Head::Map,
            lambda: 2e6,
        },
        5,
        "MAP lambda = 2e6",
    );
    let nan = check_settings(&settings(1.0, f32::NAN));
    assert!(
        matches!(nan, Err(Violation::Lambda { head: Head::Map, lambda }) if lambda.is_nan()),
        "{nan:?}"
    );
    assert_eq!(check_settings(&settings(MAX_LAMBDA, 1e-30)), Ok(()));

    assert_eq!(check_names(["car", "bus"]), Ok(()));
    fails(
        check_names(["car", "", "bus"]),
        Violation::Name { class: 1, len: 0 },
        5,
        "name of class 1 (0 bytes)",
    );
    fails(
        check_names(["car", "background"]),
        Violation::Name { class: 1, len: 10 },
        5,
        "or `background`",
    );
    let long = "x".repeat(NAME_MAX + 1);
    fails(
        check_names(["car", long.as_str()]),
        Violation::Name { class: 1, len: 32 },
        5,
        "longer than 31 bytes",
    );
    assert_eq!(check_names(["car", &long[1..]]), Ok(()));
    fails(
        check_names(["car", "bus", "car"]),
        Violation::DuplicateName { class: 2, first: 0 },
        5,
        "name of class 2 repeats the name of class 0",
    );
    fails(
        check_names(["car"]),
        Violation::ClassCount {
            expected: 2,
            found: 1,
        },
        5,
        "1 classes, the table needs 2",
    );

    assert_eq!(check_prior(3, -1e30, f32::MIN_POSITIVE), Ok(()));
    fails(
        check_prior(3, f32::INFINITY, 1.0),
        Violation::Mean {
            class: 3,
            mean: f32::INFINITY,
        },
        5,
        "prior mean of class 3 = inf is not finite",
    );
    for variance in [0.0, -1.0, f32::INFINITY] {
        fails(
            check_prior(3, 0.0, variance),
            Violation::Variance { class: 3, variance },
            5,
            "prior variance of class 3",
        );
    }
    assert!(check_prior(0, f32::NAN, 1.0).is_err());
    assert!(check_prior(0, 0.0, f32::NAN).is_err());
}

#[test]
fn each_histogram_violation_is_reported() {
    let ok = check_bins(Head::Ml, 1, [0.0, 0.5, 1.0], &[0.25, 0.75], 2);
    assert_eq!(ok, Ok(()));
    fails(
        check_bins(Head::Map, 4, [0.0, 0.5, 1.0], &[0.25, 0.75], 3),
        Violation::BinCount {
            head: Head::Map,
            class: 4,
            expected: 3,
            found: 2,
        },
        5,
        "MAP histogram of class 4 has 2 bins, the shape 3",
    );
    fails(
        check_bins(Head::Ml, 1, [0.0, 1.0], &[0.25, 0.75], 2),
        Violation::BinCount {
            head: Head::Ml,
            class: 1,
            expected: 2,
            found: 1,
        },
        5,
        "has 1 bins",
    );
    fails(
        check_bins(Head::Ml, 1, [0.0, f32::INFINITY, 1.0], &[0.25, 0.75], 2),
        Violation::EdgeNotFinite {
            head: Head::Ml,
            class: 1,
            edge: 1,
            value: f32::INFINITY,
        },
        5,
        "ML histogram of class 1: edge 1 = inf is not finite",
    );
    fails(
        check_bins(Head::Map, 0, [0.0, 1.0, 1.0], &[0.25, 0.75], 2),
        Violation::EdgesNotIncreasing {
            head: Head::Map,
            class: 0,
            edge: 2,
            previous: 1.0,
            value: 1.0,
        },
        5,
        "MAP histogram of class 0: edge 2 = 1e0 is not above edge 1 = 1e0",
    );
    fails(
        check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[1.5, -0.5], 2),
        Violation::Frequency {
            head: Head::Ml,
            class: 2,
            bin: 1,
            value: -0.5,
        },
        5,
        "frequency 1 = -5e-1 is not finite and >= 0",
    );
    assert!(check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[f32::NAN, 1.0], 2).is_err());
    // 1e-4 is the tolerance: 0.25 + 0.7502 is out, 0.25 + 0.75009 in.
    fails(
        check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[0.25, 0.7502], 2),
        Violation::FrequencySum {
            head: Head::Ml,
            class: 2,
            sum: f64::from(0.25f32 + 0.7502f32),
        },
        5,
        "ML histogram of class 2: frequencies sum to 1.0002",
    );
    let edges = [0.0, 0.5, 1.0];
    assert_eq!(check_bins(Head::Ml, 2, edges, &[0.25, 0.750_09], 2), Ok(()));
}

/// Asserts that `got` is `Err(want)` and that its message cites DESIGN §1.6 and holds
/// `needle`.
fn fails_bayes(got: Result<(), Violation>, want: Violation, needle: &str) {
    assert_eq!(got, Err(want));
    let msg = want.to_string();
    assert!(msg.starts_with("DESIGN §1.6: "), "{msg}");
    assert!(msg.contains(needle), "{msg}");
}

fn shipped() -> Table<3, 22, 17, 22, 4> {
    Table::from_bytes(include_bytes!("../../tables/default.mlmap")).unwrap()
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
